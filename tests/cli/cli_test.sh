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
grep_out '"schema": "polyheal.check/1"' "$tmp/out" "json schema tag"
grep_out '"self_intersecting_pairs": 0' "$tmp/out" "json pair count"
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
echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
