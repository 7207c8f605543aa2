#!/usr/bin/env bash
# CLI contract of `polyheal check`: exit codes 0/1/2, one-line errors, JSON schema.
set -u
bin=$1; src=$2; fails=0; passes=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
expect() {  # expect CODE DESCRIPTION -- command...
  local want=$1 what=$2; shift 3
  "$@" >"$tmp/out" 2>"$tmp/err"; local got=$?
  if [ "$got" -eq "$want" ]; then passes=$((passes+1)); else
    fails=$((fails+1)); echo "FAIL: $what: exit $got, expected $want"; cat "$tmp/out" "$tmp/err"; fi
}
grep_out() {  # grep_out PATTERN FILE DESCRIPTION
  if grep -q -- "$1" "$2"; then passes=$((passes+1)); else fails=$((fails+1)); echo "FAIL: $3"; cat "$2"; fi
}
expect 0 "clean tube is certified" -- "$bin" check "$src/fixtures/tube_edge2.42.off"
grep_out "CERTIFIED CLEAN" "$tmp/out" "clean verdict printed"
expect 1 "coarse tube has defects" -- "$bin" check "$src/fixtures/tube_edge3.0.off"
grep_out "528 self-intersecting pairs" "$tmp/out" "pair count printed"
expect 1 "dirty box has defects" -- "$bin" check --list "$src/fixtures/dirty_box.obj"
grep_out "boundary edges:" "$tmp/out" "--list names boundary edges"
expect 0 "json on clean mesh" -- "$bin" check --json "$src/fixtures/torus.off"
printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 3 1\n3 0 2 3\n3 1 3 2\n' > "$tmp/inside_out.off"
expect 0 "an inside-out tetrahedron is clean (consistently oriented)" -- "$bin" check "$tmp/inside_out.off"
grep_out "note: the surface is inside out (negative volume, exact sign, inside no other component)" "$tmp/out" "check notes an inside-out surface"
expect 0 "check --json on it" -- "$bin" check --json "$tmp/inside_out.off"
grep_out '"volume_sign": -1' "$tmp/out" "check json gives the exact volume sign"
grep_out '"inside_out_components": 1' "$tmp/out" "check json counts inside-out components"
grep_out '"schema": "polyheal.check/1"' "$tmp/out" "json schema tag"
grep_out '"self_intersecting_pairs": 0' "$tmp/out" "json pair count"
expect 0 "repair turns an inside-out tetrahedron outwards" -- "$bin" repair "$tmp/inside_out.off" -o "$tmp/inside_out_r.off"
grep_out "orient      kept" "$tmp/out" "repair reports the orient stage"
expect 0 "its output" -- "$bin" check --json "$tmp/inside_out_r.off"
grep_out '"volume_sign": 1' "$tmp/out" "repair's output encloses positive volume"
expect 0 "repair --keep-orientation" -- "$bin" repair --keep-orientation "$tmp/inside_out.off" -o "$tmp/inside_out_k.off"
grep_out "written unchanged" "$tmp/out" "--keep-orientation writes a clean inside-out input unchanged"
expect 1 "tetgen-ready fails on a coarse tube" -- "$bin" check --tetgen-ready "$src/fixtures/tube_edge3.0.off"
printf 'OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n' > "$tmp/bad.off"
expect 2 "malformed file" -- "$bin" check "$tmp/bad.off"
grep_out "bad.off:line 4: non-numeric coordinate 'x'" "$tmp/err" "one-line error with file and line"
[ "$(wc -l < "$tmp/err")" -eq 1 ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: error is not one line"; }
expect 2 "missing file" -- "$bin" check "$tmp/none.off"
mkdir "$tmp/dir.off"
expect 2 "directory" -- "$bin" check "$tmp/dir.off"
grep_out "is a directory" "$tmp/err" "directory named in the error"
expect 2 "bad option" -- "$bin" check --cap-angle 500 "$src/fixtures/torus.off"
expect 0 "help" -- "$bin" check --help
grep_out "Exit 0 when the mesh is a certified clean" "$tmp/out" "help explains exit codes"
# polyheal degenerate
printf 'OFF\n5 6 0\n0 0 0\n2 0 0\n0 2 0\n0 0 2\n1 0 0\n3 2 1 4\n3 2 4 0\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 1 0 4\n' > "$tmp/tjunction.off"
expect 0 "degenerate removes a zero-area face" -- "$bin" degenerate "$tmp/tjunction.off" -o "$tmp/tj_out.off"
grep_out "CERTIFIED" "$tmp/out" "degenerate verdict printed"
expect 0 "degenerate output checks clean" -- "$bin" check "$tmp/tj_out.off"
expect 2 "degenerate refuses to overwrite an existing output" -- "$bin" degenerate "$tmp/tjunction.off" -o "$tmp/tj_out.off"
expect 2 "degenerate never writes over its input" -- "$bin" degenerate "$tmp/tjunction.off" -o "$tmp/tjunction.off" --overwrite
# The output is checked before any work: an existing output (or an unknown
# extension, or a certificate file that exists) is named even when the input
# would fail to parse, which is read first otherwise.
for cmd in degenerate regularize rebuild repair; do
  expect 2 "$cmd refuses an existing output before reading" -- "$bin" $cmd "$tmp/bad.off" -o "$tmp/tj_out.off"
  grep_out "tj_out.off: exists; refusing to overwrite" "$tmp/err" "$cmd names the existing output, not the input"
done
expect 2 "unknown output extension refused before reading" -- "$bin" regularize "$tmp/bad.off" -o "$tmp/new.xyz"
grep_out "new.xyz" "$tmp/err" "the output with an unknown extension is named"
expect 2 "repair refuses an existing certificate before reading" -- \
  "$bin" repair "$tmp/bad.off" -o "$tmp/new.off" --certificate "$tmp/tj_out.off"
grep_out "tj_out.off: exists" "$tmp/err" "repair names the existing certificate file"
cmp -s "$tmp/tjunction.off" <(printf 'OFF\n5 6 0\n0 0 0\n2 0 0\n0 2 0\n0 0 2\n1 0 0\n3 2 1 4\n3 2 4 0\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 1 0 4\n') \
  && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: input was modified"; }
expect 0 "degenerate --json" -- "$bin" degenerate --json "$tmp/tjunction.off" -o "$tmp/tj_out2.stl" --tolerance 0.5%
grep_out '"schema": "polyheal.degenerate/1"' "$tmp/out" "degenerate json schema tag"
grep_out '"zero_area": 1' "$tmp/out" "degenerate json counts the zero-area face"
printf 'OFF\n5 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n3 0 1 2\n3 0 1 3\n3 0 1 4\n3 1 2 3\n3 0 2 3\n' > "$tmp/nonmanifold.off"
expect 2 "degenerate refuses a non-manifold soup" -- "$bin" degenerate "$tmp/nonmanifold.off" -o "$tmp/nm_out.off"
grep_out "nonmanifold.off: not an oriented 2-manifold mesh" "$tmp/err" "non-manifold refusal names the file"
grep_out "; .polyheal repair. makes one" "$tmp/err" "non-manifold refusal says what makes a manifold mesh"
expect 2 "degenerate bad tolerance" -- "$bin" degenerate "$tmp/tjunction.off" -o "$tmp/x.off" --tolerance abc
expect 2 "degenerate malformed input" -- "$bin" degenerate "$tmp/bad.off" -o "$tmp/x.off"
[ ! -e "$tmp/x.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: output written on error"; }
# A CAD STL with pinch vertices and intersections: degenerate must end with a
# verdict (0 or 1), never a crash (a pinch-identity default once aliased new
# vertices to vertex 0 and crashed the pair test).
expect 1 "degenerate --weld 0 leaves angle_block's needles at its cracks" -- "$bin" degenerate --weld 0 "$src/fixtures/angle_block.stl" -o "$tmp/ab_deg0.off"
grep_out "it intersects another face, as in the input" "$tmp/out" "degenerate names the intersections it may not touch"
# Its intersections are cracks between vertices 6e-17 apart: check says so, and points to the weld.
expect 1 "check finds angle_block's intersecting pairs" -- "$bin" check "$src/fixtures/angle_block.stl"
grep_out "102 of the pairs meet at 22 pairs of corners closer than" "$tmp/out" "check counts the pairs at unwelded cracks"
grep_out "polyheal degenerate. and .polyheal repair. weld them" "$tmp/out" "check names the commands that weld cracks"
expect 1 "check --json on angle_block" -- "$bin" check --json "$src/fixtures/angle_block.stl"
grep_out '"crack_pairs": 102' "$tmp/out" "check json counts the crack pairs"
# Welded by default, it is certified.
expect 0 "degenerate welds angle_block's rounding cracks and certifies it" -- "$bin" degenerate --json "$src/fixtures/angle_block.stl" -o "$tmp/ab_deg.off"
grep_out '"near_vertices_welded": 46' "$tmp/out" "degenerate json counts the welded vertices"
grep_out '"refused": false' "$tmp/out" "degenerate json: the weld was kept"
expect 0 "degenerate's welded output checks clean" -- "$bin" check "$tmp/ab_deg.off"
expect 2 "degenerate bad weld distance" -- "$bin" degenerate "$tmp/tjunction.off" -o "$tmp/x.off" --weld -1
# polyheal deintersect
expect 0 "deintersect frees the coarse tube" -- "$bin" deintersect "$src/fixtures/tube_edge3.0.off" -o "$tmp/tube_out.off"
grep_out "intersecting faces: 220 -> 0" "$tmp/out" "deintersect reports faces before and after"
expect 0 "deintersect output checks clean" -- "$bin" check "$tmp/tube_out.off"
expect 0 "deintersect --json" -- "$bin" deintersect --json --clearance 0.01 "$src/fixtures/tube_edge3.0.off" -o "$tmp/tube_out2.stl"
grep_out '"schema": "polyheal.deintersect/1"' "$tmp/out" "deintersect json schema tag"
grep_out '"clearance_mode": "absolute"' "$tmp/out" "deintersect json names the clearance mode"
expect 0 "deintersect --clearance local frees the coarse tube" -- "$bin" deintersect --json --clearance local "$src/fixtures/tube_edge3.0.off" -o "$tmp/tube_local.off"
grep_out '"clearance_mode": "local"' "$tmp/out" "deintersect json names the local clearance"
expect 0 "deintersect --tet-aspect frees the 4.0 tube" -- "$bin" deintersect --tet-aspect 100 "$src/fixtures/tube_edge4.0.off" -o "$tmp/tube_tet.off"
grep_out "clearance tet-aspect 100" "$tmp/out" "deintersect text names the tet-aspect clearance"
expect 0 "deintersect tet-aspect output checks clean" -- "$bin" check "$tmp/tube_tet.off"
expect 1 "deintersect leaves deeply crossing spheres, exit 1" -- "$bin" deintersect "$src/fixtures/spheres_intersecting.off" -o "$tmp/sph.off"
grep_out "still intersecting (output face ids)" "$tmp/out" "deintersect lists the faces left"
expect 0 "deintersect re-check agrees: spheres output still intersects" -- test -s "$tmp/sph.off"
expect 1 "deintersect output of the spheres does not check clean" -- "$bin" check "$tmp/sph.off"
expect 1 "deintersect --max-trials stops the bones' moves short, exit 1" -- "$bin" deintersect --json --max-trials 500 "$src/fixtures/bones.off" -o "$tmp/bones_budget.off"
grep_out '"out_of_trials": true' "$tmp/out" "deintersect json says the work budget stopped it"
grep_out '"max_trials": 500' "$tmp/out" "deintersect json gives the work budget"
expect 1 "deintersect --max-trials output still intersects (checked on the file)" -- "$bin" check "$tmp/bones_budget.off"
expect 2 "deintersect refuses a negative --max-trials" -- "$bin" deintersect --max-trials -5 "$src/fixtures/bones.off" -o "$tmp/bones_neg.off"
expect 2 "repair refuses a negative --max-move-trials" -- "$bin" repair --max-move-trials -5 "$src/fixtures/bones.off" -o "$tmp/bones_neg.off"
expect 2 "repair refuses a negative --max-hole-edges" -- "$bin" repair --max-hole-edges -3 "$src/fixtures/bones.off" -o "$tmp/bones_neg.off"
expect 2 "deintersect refuses a non-manifold soup" -- "$bin" deintersect "$tmp/nonmanifold.off" -o "$tmp/nm_out.off"
grep_out "deintersect needs a manifold mesh" "$tmp/err" "deintersect non-manifold refusal says why"
expect 2 "deintersect bad clearance" -- "$bin" deintersect "$src/fixtures/tube_edge3.0.off" -o "$tmp/y.off" --clearance abc
expect 2 "deintersect clearance and tet-aspect together" -- "$bin" deintersect "$src/fixtures/tube_edge3.0.off" -o "$tmp/y.off" --clearance 0.1 --tet-aspect 10
expect 2 "deintersect bad --ops" -- "$bin" deintersect "$src/fixtures/tube_edge3.0.off" -o "$tmp/y.off" --ops swap,drill
expect 2 "deintersect malformed input" -- "$bin" deintersect "$tmp/bad.off" -o "$tmp/y.off"
[ ! -e "$tmp/y.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: deintersect wrote output on error"; }
expect 2 "deintersect never writes over its input" -- "$bin" deintersect "$tmp/tube_out.off" -o "$tmp/tube_out.off" --overwrite
expect 0 "deintersect help" -- "$bin" deintersect --help
grep_out "Exit 0 when the written file has no self-intersection" "$tmp/out" "deintersect help explains exit codes"
# polyheal regularize
expect 0 "regularize resolves the overlapping spheres" -- "$bin" regularize "$src/fixtures/spheres_intersecting.off" -o "$tmp/sph_union.off"
grep_out "CERTIFIED: closed, 2-manifold" "$tmp/out" "regularize verdict printed"
grep_out "88 partially valid" "$tmp/out" "regularize reports the triangle groups"
expect 0 "regularize output checks clean" -- "$bin" check "$tmp/sph_union.off"
expect 0 "regularize --json" -- "$bin" regularize --json "$src/fixtures/knot_tube_r1.2.off" -o "$tmp/knot.stl"
grep_out '"schema": "polyheal.regularize/1"' "$tmp/out" "regularize json schema tag"
grep_out '"partially_valid"' "$tmp/out" "regularize json triangle groups"
grep_out '"peak_memory_mb"' "$tmp/out" "regularize json peak memory"
expect 0 "regularize stl output checks clean" -- "$bin" check "$tmp/knot.stl"
expect 0 "regularize leaves a zero-area face out and splits its T-junction" -- "$bin" regularize "$tmp/tjunction.off" -o "$tmp/tj_reg.off"
grep_out "1 zero-area faces left out" "$tmp/out" "regularize reports the zero-area face"
printf 'OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 3\n' > "$tmp/open.off"
expect 2 "regularize refuses an open mesh" -- "$bin" regularize "$tmp/open.off" -o "$tmp/z.off"
grep_out "open.off: edge (0, 1) is used 1 more times in one direction than in the other: the surface is not closed" "$tmp/err" "regularize names the file, the edge and the reason"
[ "$(wc -l < "$tmp/err")" -eq 1 ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: regularize error is not one line"; }
[ ! -e "$tmp/z.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: regularize wrote output on error"; }
expect 0 "regularize leaves out the walls between glued convex pieces" -- "$bin" regularize "$src/fixtures/deer_bound.off" -o "$tmp/deer.off"
grep_out "6 faces left out first: walls or faces doubled in one direction" "$tmp/out" "regularize reports the walls it left out"
expect 2 "regularize malformed input" -- "$bin" regularize "$tmp/bad.off" -o "$tmp/z.off"
expect 2 "regularize never writes over its input" -- "$bin" regularize "$tmp/sph_union.off" -o "$tmp/sph_union.off" --overwrite
expect 0 "regularize help" -- "$bin" regularize --help
grep_out "winding number >= 1" "$tmp/out" "regularize help explains what is kept"
# polyheal offset
printf 'OFF\n8 12 0\n0 0 0\n2 0 0\n2 2 0\n0 2 0\n0 0 2\n2 0 2\n2 2 2\n0 2 2\n3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 1 2 6\n3 1 6 5\n3 2 3 7\n3 2 7 6\n3 3 0 4\n3 3 4 7\n' > "$tmp/cube.off"
expect 0 "offset rounds a cube outwards" -- "$bin" offset "$tmp/cube.off" -d 0.5 -o "$tmp/cube_out.off"
grep_out "12 sharp edges, 8 corners" "$tmp/out" "offset reports the strips and patches"
expect 0 "offset output checks clean" -- "$bin" check "$tmp/cube_out.off"
expect 0 "offset inwards --json" -- "$bin" offset --json "$tmp/cube.off" -d -0.5 --tolerance 2% -o "$tmp/cube_in.off"
grep_out '"schema": "polyheal.offset/1"' "$tmp/out" "offset json schema tag"
grep_out '"pockets_removed": 8' "$tmp/out" "offset json counts the corner pockets"
grep_out '"tolerance": 0.01' "$tmp/out" "offset --tolerance in percent of |d|"
expect 1 "offset --raw is not certified" -- "$bin" offset --raw "$tmp/cube.off" -d -0.5 -o "$tmp/cube_raw.off"
expect 1 "the raw inward offset self-intersects" -- "$bin" check "$tmp/cube_raw.off"
expect 2 "offset needs a distance" -- "$bin" offset "$tmp/cube.off" -o "$tmp/w.off"
expect 2 "offset refuses an open mesh" -- "$bin" offset "$tmp/open.off" -d 0.1 -o "$tmp/w.off"
grep_out "offset needs a closed, oriented 2-manifold; .polyheal repair. makes one" "$tmp/err" "offset's refusal says what closes the mesh"
grep_out "open.off: not an oriented 2-manifold mesh: edge" "$tmp/err" "offset names the file and the edge"
# a tetrahedron 1e-160 across: the raw offset's double normals would underflow
printf 'OFF\n4 4 0\n0 0 0\n1e-160 0 0\n0 1e-160 0\n0 0 1e-160\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > "$tmp/tiny.off"
expect 0 "a tetrahedron 1e-160 across is clean (exact predicates at any scale)" -- "$bin" check "$tmp/tiny.off"
expect 2 "offset refuses a mesh too small for its doubles" -- "$bin" offset "$tmp/tiny.off" -d 2e-161 -o "$tmp/w.off"
grep_out "the mesh spans 1e-160: offset builds its raw surface in doubles" "$tmp/err" "offset says why it refuses the scale"
expect 2 "offset refuses a distance the coordinates cannot resolve" -- "$bin" offset "$src/fixtures/torus.off" -d 1e-20 -o "$tmp/w.off"
grep_out "is below 1e-12 of the mesh's extent" "$tmp/err" "offset says the distance is below resolution"
printf 'OFF\n4 4 0\n0 0 0\n1e300 0 0\n0 1e300 0\n0 0 1e300\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > "$tmp/huge.off"
expect 2 "check --tetgen-ready refuses coordinates beyond 1e150 (was SIGFPE)" -- "$bin" check --tetgen-ready "$tmp/huge.off"
grep_out "huge.off:line 4: coordinate '1e300' is beyond" "$tmp/err" "the refusal names file, line and value"
[ ! -e "$tmp/w.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: offset wrote output on error"; }
expect 0 "offset help" -- "$bin" offset --help
grep_out "spherical patches" "$tmp/out" "offset help explains the raw offset"
# polyheal union
printf 'OFF\n8 12 0\n1 0.5 0.25\n3 0.5 0.25\n3 2.5 0.25\n1 2.5 0.25\n1 0.5 2.25\n3 0.5 2.25\n3 2.5 2.25\n1 2.5 2.25\n3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 1 2 6\n3 1 6 5\n3 2 3 7\n3 2 7 6\n3 3 0 4\n3 3 4 7\n' > "$tmp/cube_b.off"
expect 0 "union of two overlapping cubes" -- "$bin" union "$tmp/cube.off" "$tmp/cube_b.off" -o "$tmp/union.off"
grep_out "volume 13.375, 1 components" "$tmp/out" "union encloses 8 + 8 - 2.625"
expect 0 "union output checks clean" -- "$bin" check "$tmp/union.off"
awk '$1 == 3 && NF == 4 {print 3, $2, $4, $3; next} {print}' "$tmp/cube_b.off" > "$tmp/cube_b_inside_out.off"
expect 0 "union of a cube and an inside-out cube" -- "$bin" union "$tmp/cube.off" "$tmp/cube_b_inside_out.off" -o "$tmp/union_io.off"
grep_out "volume 13.375, 1 components" "$tmp/out" "the inside-out input is turned: still the union"
grep_out "cube_b_inside_out.off encloses negative volume (inside out): turned outwards" "$tmp/err" "union notes the input it turned"
expect 0 "union --keep-orientation takes it as given" -- "$bin" union --keep-orientation "$tmp/cube.off" "$tmp/cube_b_inside_out.off" -o "$tmp/union_keep.off"
grep_out "volume 5.375, 1 components" "$tmp/out" "as given, the inside-out cube subtracts: 8 - 2.625"
expect 2 "union needs two inputs" -- "$bin" union "$tmp/cube.off" -o "$tmp/u2.off"
expect 2 "union never writes over an input" -- "$bin" union "$tmp/cube.off" "$tmp/cube_b.off" -o "$tmp/cube_b.off" --overwrite
# polyheal rebuild
expect 0 "rebuild closes the dirty box" -- "$bin" rebuild "$src/fixtures/dirty_box.obj" -o "$tmp/box_rebuilt.obj"
grep_out "CERTIFIED: closed" "$tmp/out" "rebuild reports the certificate"
grep_out "interpolated across" "$tmp/out" "rebuild reports the gap and hole fills"
expect 0 "rebuild output checks clean" -- "$bin" check "$tmp/box_rebuilt.obj"
grep -q "^g face" "$tmp/box_rebuilt.obj" && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: rebuild OBJ has no face groups"; }
expect 0 "rebuild --json --cell" -- "$bin" rebuild --json --cell 2% "$src/fixtures/dirty_box.obj" -o "$tmp/box_rebuilt2.off"
grep_out '"schema": "polyheal.rebuild/1"' "$tmp/out" "rebuild json schema tag"
grep_out '"cell_rule": "--cell, relative to the diagonal"' "$tmp/out" "rebuild --cell in percent"
grep_out '"halvings": 2' "$tmp/out" "rebuild refines the grid by default"
expect 0 "rebuild --refine 0 keeps the cells uniform" -- "$bin" rebuild --json --refine 0 "$src/fixtures/deer_bound.off" -o "$tmp/deer_uniform.off"
grep_out '"refined_tets": 0,' "$tmp/out" "rebuild --refine 0 bisects nothing"
expect 0 "rebuild follows the deer's tips" -- "$bin" rebuild "$src/fixtures/deer_bound.off" -o "$tmp/deer_refined.off"
grep_out "tetrahedra missed the surface" "$tmp/out" "rebuild says what it refined"
expect 2 "rebuild rejects --refine 9" -- "$bin" rebuild --refine 9 "$src/fixtures/dirty_box.obj" -o "$tmp/rb9.off"
printf 'OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n' > "$tmp/sheet.off"
expect 1 "rebuild --sheets drop invents no volume for an open sheet" -- "$bin" rebuild --sheets drop "$tmp/sheet.off" -o "$tmp/sheet_out.off"
grep_out "encloses no volume" "$tmp/out" "rebuild says the sheet encloses nothing"
grep_out "open loops: " "$tmp/out" "rebuild says where the sheet's open loop is"
expect 0 "rebuild wraps an open sheet in a shell" -- "$bin" rebuild "$tmp/sheet.off" -o "$tmp/sheet_shell.off"
grep_out "wrapped in a shell" "$tmp/out" "rebuild says the sheet is wrapped"
expect 2 "rebuild rejects an unknown --sheets" -- "$bin" rebuild --sheets keep "$tmp/sheet.off" -o "$tmp/sheet_x.off"
expect 0 "rebuild keeps a clean input" -- "$bin" rebuild "$src/fixtures/torus.off" -o "$tmp/torus_same.off"
grep_out "written unchanged" "$tmp/out" "rebuild says the clean input is unchanged"
expect 2 "rebuild malformed input" -- "$bin" rebuild "$tmp/bad.off" -o "$tmp/rb.off"
[ "$(wc -l < "$tmp/err")" -eq 1 ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: rebuild error is not one line"; }
[ ! -e "$tmp/rb.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: rebuild wrote output on error"; }
expect 2 "rebuild rejects a bad --cell" -- "$bin" rebuild "$src/fixtures/dirty_box.obj" --cell -1 -o "$tmp/rb.off"
expect 2 "rebuild refuses a grid beyond the limit" -- "$bin" rebuild "$src/fixtures/dirty_box.obj" --cell 0.00001 -o "$tmp/rb.off"
grep_out "choose a larger --cell" "$tmp/err" "rebuild says how to fix the grid size"
expect 2 "rebuild never writes over its input" -- "$bin" rebuild "$tmp/sheet.off" -o "$tmp/sheet.off" --overwrite
expect 0 "rebuild help" -- "$bin" rebuild --help
grep_out "winding" "$tmp/out" "rebuild help explains the classification"
# polyheal repair, certificates, compare
printf 'OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n' > "$tmp/no_faces.off"
expect 2 "repair refuses a file with no faces" -- "$bin" repair "$tmp/no_faces.off" -o "$tmp/nf_out.off"
grep_out "no_faces.off: no faces: nothing to repair" "$tmp/err" "repair says there is nothing to repair"
[ ! -e "$tmp/nf_out.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: repair wrote an output for an input with no faces"; }
expect 0 "repair frees the coarse tube" -- "$bin" repair "$src/fixtures/tube_edge3.0.off" -o "$tmp/rp_tube.off" --certificate "$tmp/rp_tube.json" --provenance "$tmp/rp_tube.prov"
grep_out "deintersect" "$tmp/out" "repair names the stage it ran"
grep_out "CERTIFIED CLEAN" "$tmp/out" "repair verdict printed"
expect 0 "repair output checks clean" -- "$bin" check "$tmp/rp_tube.off"
expect 0 "the output matches its certificate" -- "$bin" check "$tmp/rp_tube.off" --certificate "$tmp/rp_tube.json"
grep_out "MATCHES" "$tmp/out" "certificate match printed"
[ "$(wc -l < "$tmp/rp_tube.prov")" -eq 220 ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: provenance has not one line per face"; }
grep -q '^new$' "$tmp/rp_tube.prov" && grep -q '^[0-9]' "$tmp/rp_tube.prov" && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: provenance lacks kept or new faces"; }
cp "$tmp/rp_tube.off" "$tmp/rp_tampered.off"; printf '# edited\n' >> "$tmp/rp_tampered.off"
expect 1 "a changed file does not match the certificate" -- "$bin" check "$tmp/rp_tampered.off" --certificate "$tmp/rp_tube.json"
grep_out "DOES NOT MATCH" "$tmp/out" "certificate mismatch printed"
expect 1 "another file's certificate does not match" -- "$bin" check "$src/fixtures/tube_edge3.0.off" --certificate "$tmp/rp_tube.json"
printf '{"schema": "x"}' > "$tmp/notcert.json"
expect 2 "a JSON file that is not a certificate" -- "$bin" check "$tmp/rp_tube.off" --certificate "$tmp/notcert.json"
printf '{"schema": ' > "$tmp/broken.json"
expect 2 "a broken certificate" -- "$bin" check "$tmp/rp_tube.off" --certificate "$tmp/broken.json"
grep_out "broken.json:byte" "$tmp/err" "broken certificate error names the byte"
expect 0 "repair --json" -- "$bin" repair --json "$src/fixtures/torus.off" -o "$tmp/rp_torus.off"
grep_out '"schema": "polyheal.repair/1"' "$tmp/out" "repair json schema tag"
grep_out '"certified_clean": true' "$tmp/out" "repair json: clean input reported"
cmp -s "$src/fixtures/torus.off" "$tmp/rp_torus.off" && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: clean input not written unchanged"; }
expect 1 "repair exits 1 when the surface moves beyond --max-deviation" -- "$bin" repair "$src/fixtures/dirty_box.obj" -o "$tmp/rp_box.off" --max-deviation 0.01%
grep_out "more than --max-deviation" "$tmp/out" "repair says the bound was exceeded"
expect 0 "repaired dirty box still checks clean" -- "$bin" check "$tmp/rp_box.off"
expect 1 "repair with --steps clean cannot free the tube" -- "$bin" repair "$src/fixtures/tube_edge3.0.off" -o "$tmp/rp_tube2.off" --steps clean
expect 2 "repair rejects an unknown step" -- "$bin" repair "$src/fixtures/tube_edge3.0.off" -o "$tmp/rp_x.off" --steps clean,polish
grep_out "unknown step 'polish'" "$tmp/err" "unknown step named"
expect 2 "repair never writes over its input" -- "$bin" repair "$tmp/rp_tube.off" -o "$tmp/rp_tube.off" --overwrite
expect 2 "repair malformed input" -- "$bin" repair "$tmp/bad.off" -o "$tmp/rp_bad.off"
[ ! -e "$tmp/rp_bad.off" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: repair wrote output on error"; }
# T-junction cracks (a CAD STL: seams where one side has a vertex the other lacks) close
# in the clean stage without moving the surface: no local moves, no grid.
expect 0 "repair closes the T-junction cracks of a CAD STL" -- "$bin" repair "$src/fixtures/angle_block.stl" -o "$tmp/rp_ab.off"
grep_out "T-junctions closed" "$tmp/out" "repair reports the T-junctions"
expect 0 "the closed CAD STL is within 1e-7% of the input" -- "$bin" compare "$src/fixtures/angle_block.stl" "$tmp/rp_ab.off" --max-deviation 1e-7%
# An STL output holds floats only: repair and regularize round their result
# to floats and repair what that breaks (local moves on Generic_Twin, a union
# on self_intersectA: both failed the check of their STL file before).
expect 0 "repair to STL certifies the rounded surface" -- "$bin" repair "$src/fixtures/corpus/manifold__Generic_Twin_7863.1.t0_left.obj" -o "$tmp/rp_gt.stl"
grep_out "round to floats kept" "$tmp/out" "repair reports its rounding to floats"
expect 0 "the repaired STL checks clean" -- "$bin" check "$tmp/rp_gt.stl"
expect 0 "regularize to STL certifies the rounded union" -- "$bin" regularize "$src/fixtures/corpus/manifold__self_intersectA.obj" -o "$tmp/rg_sa.stl"
grep_out "rounding to floats (STL)" "$tmp/out" "regularize reports its rounding to floats"
expect 0 "the regularized STL checks clean" -- "$bin" check "$tmp/rg_sa.stl"
expect 0 "repair help" -- "$bin" repair --help
grep_out "regularize" "$tmp/out" "repair help lists the stages"
expect 0 "compare: a certified repair within bounds" -- "$bin" compare "$src/fixtures/tube_edge3.0.off" "$tmp/rp_tube.off" --max-deviation 1%
grep_out "Hausdorff" "$tmp/out" "compare prints the distance"
expect 1 "compare: a defective B" -- "$bin" compare "$tmp/rp_tube.off" "$src/fixtures/tube_edge3.0.off"
expect 1 "compare: beyond --max-deviation" -- "$bin" compare "$src/fixtures/tube_edge3.0.off" "$tmp/rp_tube.off" --max-deviation 0.0001%
expect 0 "compare --json" -- "$bin" compare --json "$src/fixtures/torus.off" "$src/fixtures/torus.off"
grep_out '"schema": "polyheal.compare/1"' "$tmp/out" "compare json schema tag"
grep_out '"topology_changed": false' "$tmp/out" "compare json topology"
expect 2 "compare a missing file" -- "$bin" compare "$src/fixtures/torus.off" "$tmp/none.off"
# polyheal batch
printf '# a list\n%s\n\n%s\n%s\n' "$src/fixtures/tube_edge3.0.off" "$src/fixtures/torus.off" "$tmp/bad.off" > "$tmp/list.txt"
expect 1 "batch goes on past a bad file and exits 1" -- "$bin" batch "$tmp/list.txt" -o "$tmp/batch" -j 2
grep_out "2 certified, 1 error" "$tmp/out" "batch counts by status"
grep_out "bad.off:line 4: non-numeric coordinate" "$tmp/batch/summary.csv" "batch summary keeps the error line"
grep_out '"schema": "polyheal.batch/1"' "$tmp/batch/summary.json" "batch json summary"
expect 0 "a batch output checks clean" -- "$bin" check "$tmp/batch/tube_edge3.0.off"
expect 1 "batch shard 1/2 (the tube and the bad file)" -- "$bin" batch "$tmp/list.txt" -o "$tmp/shard1" --shard 1/2
expect 0 "batch shard 2/2 (the torus)" -- "$bin" batch "$tmp/list.txt" -o "$tmp/shard2" --shard 2/2
[ "$(cat "$tmp/shard1/summary.csv" "$tmp/shard2/summary.csv" | grep -vc '^input,')" -eq 3 ] && \
  ! cut -d, -f1 "$tmp/shard1/summary.csv" | grep -qxF -f <(cut -d, -f1 "$tmp/shard2/summary.csv" | tail -n +2) \
  && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: shards do not split the list exactly"; }
expect 1 "batch stops a file at its time limit" -- "$bin" batch "$src/fixtures/dirty_box.obj" -o "$tmp/batch_t" --timeout 0.05
expect 2 "batch rejects a bad shard" -- "$bin" batch "$tmp/list.txt" -o "$tmp/batch_x" --shard 3/2
expect 2 "batch rejects a missing list" -- "$bin" batch "$tmp/nolist.txt" -o "$tmp/batch_y"
# check --tetgen: TetGen's verdict beside ours
expect 1 "check --tetgen on the coarse tube" -- "$bin" check --tetgen "$src/fixtures/tube_edge3.0.off"
grep_out "tetgen -d: Found .* pairs of faces are intersecting.*verdicts agree" "$tmp/out" "tetgen -d finds the intersections too"
expect 0 "check --tetgen on the clean torus" -- "$bin" check --tetgen "$src/fixtures/torus.off"
grep_out "tetgen -d: No faces are intersecting.*verdicts agree" "$tmp/out" "tetgen -d agrees the torus is clean"
expect 1 "check --tetgen reads OBJ for TetGen" -- "$bin" check --tetgen --json "$src/fixtures/dirty_box.obj"
grep_out '"ran": true' "$tmp/out" "tetgen ran on an OBJ input"
# polyheal perturb
expect 0 "perturb near-collinear" -- "$bin" perturb "$src/fixtures/torus.off" -o "$tmp/pt1.off" --kind near-collinear --seed 5
expect 0 "perturb again with the same seed" -- "$bin" perturb "$src/fixtures/torus.off" -o "$tmp/pt2.off" --kind near-collinear --seed 5
cmp -s "$tmp/pt1.off" "$tmp/pt2.off" && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: perturb is not reproducible"; }
expect 1 "a perturbed mesh is not TetGen-ready" -- "$bin" check --tetgen-ready "$tmp/pt1.off"
expect 2 "perturb rejects an unknown kind" -- "$bin" perturb "$src/fixtures/torus.off" -o "$tmp/pt3.off" --kind noise
expect 2 "perturb never writes over its input" -- "$bin" perturb "$tmp/pt1.off" -o "$tmp/pt1.off" --kind slivers --overwrite
# duplicates, about half of them reversed: repair drops the stray copies and
# keeps every face of the closed anchor (1050 faces) as it was; before, a
# reversed copy cancelled its face too and the holes were filled anew,
# 4.3% of the diagonal away (exit 1)
expect 0 "perturb duplicates" -- "$bin" perturb "$src/fixtures/anchor.off" -o "$tmp/dup.off" --kind duplicates --fraction 0.2
expect 0 "repair drops stray duplicates of either orientation" -- "$bin" repair "$tmp/dup.off" -o "$tmp/dup_rep.off"
grep_out "reversed stray copies), .* 0 of 0 holes filled" "$tmp/out" "reversed copies dropped alone, no hole left"
grep_out "output: 1050 faces, .* kept 1050 input faces exactly" "$tmp/out" "every face of the anchor kept"
# repair --for tetgen
expect 0 "repair --for tetgen removes what trips TetGen" -- "$bin" repair "$tmp/pt1.off" -o "$tmp/pt1_tg.off" --for tetgen
grep_out "TetGen-ready" "$tmp/out" "repair --for tetgen verdict"
grep_out "TetGen itself: tetgen -pQ meshed the written file" "$tmp/out" "TetGen itself was run on the written file"
expect 0 "its output is TetGen-ready" -- "$bin" check --tetgen-ready "$tmp/pt1_tg.off"
[ -s "$tmp/pt1_tg.smesh" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: no .smesh written"; }
expect 1 "without --for tetgen the same input stays as it is (caps are not defects)" -- "$bin" check --tetgen-ready "$tmp/pt1.off"
ls "$tmp"/pt1_tg.1.* >/dev/null 2>&1 && { fails=$((fails+1)); echo "FAIL: TetGen's files left beside the output"; } || passes=$((passes+1))
expect 0 "repair --for tetgen --json reports the TetGen run" -- \
  "$bin" repair "$tmp/pt1.off" -o "$tmp/pt1_tgj.off" --for tetgen --json
grep_out '"written_file_status": 0' "$tmp/out" "json: TetGen's exit status on the written file"
expect 1 "repair names the input's defects by kind" -- "$bin" repair "$src/fixtures/dirty_box.obj" -o "$tmp/db.off" --steps clean
grep_out "input: 176 faces, 141 defects (72 boundary edges, 3 non-manifold vertices, 66 intersecting pairs)" "$tmp/out" \
  "the input line lists the defects by kind"
expect 0 "repair --for tetgen --no-tetgen-run" -- \
  "$bin" repair "$tmp/pt1.off" -o "$tmp/pt1_tgn.off" --for tetgen --no-tetgen-run
grep_out "TetGen itself: not run (--no-tetgen-run)" "$tmp/out" "--no-tetgen-run says TetGen was not run"
# A TetGen that refuses everything (a stand-in first on PATH): a surface our
# test calls ready is then not called TetGen-ready, exit 1, and the
# certificate still matches the file (TetGen's verdict is kept beside its checks).
mkdir "$tmp/fakebin"; printf '#!/bin/sh\necho "stand-in TetGen: refusing"\nexit 3\n' > "$tmp/fakebin/tetgen"; chmod +x "$tmp/fakebin/tetgen"
expect 1 "repair --for tetgen when TetGen refuses every surface" -- \
  env PATH="$tmp/fakebin:$PATH" "$bin" repair "$tmp/pt1_tg.off" -o "$tmp/pt1_refused.off" --for tetgen --certificate "$tmp/pt1_refused.json"
grep_out "refused by TetGen itself" "$tmp/out" "the refusal is named as the defect left"
grep_out "TetGen itself: tetgen -pQ refused (exit 3) the written file" "$tmp/out" "TetGen's verdict on the written file"
grep_out '"written_file_status": 3' "$tmp/pt1_refused.json" "the certificate records TetGen's verdict"
expect 0 "that certificate matches its file" -- "$bin" check "$tmp/pt1_refused.off" --certificate "$tmp/pt1_refused.json"
expect 2 "repair --for rejects an unknown tool" -- "$bin" repair "$tmp/pt1.off" -o "$tmp/pt1_x.off" --for gmsh
echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
