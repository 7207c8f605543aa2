#!/usr/bin/env bash
# The TetGen hand-off: for every fixture whose input Debian's TetGen refuses
# (`tetgen -pQ` fails), `polyheal repair --for tetgen` must write a surface
# that polyheal certifies TetGen-ready and a .smesh that TetGen meshes:
# `tetgen -pq` (constrained quality tetrahedralisation) for the fixtures of
# fixtures/ (mode "quality", the default), `tetgen -pQ` (TetGen's defaults,
# no quality refinement) for the corpus copies in fixtures/corpus (mode
# "corpus": -pq on a 100k-face CAD part such as vhacd__crank runs for more
# than 8 minutes and 2 GB). Fixtures TetGen already accepts are skipped
# (they are covered by repair_corpus).
set -u
bin=$1; src=$2; mode=${3:-quality}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
command -v tetgen >/dev/null || { echo "FAIL: tetgen is not installed (scripts/setup.sh installs it)"; exit 1; }
fails=0; checked=0
if [ "$mode" = corpus ]; then
  files=("$src"/fixtures/corpus/*.off "$src"/fixtures/corpus/*.obj "$src"/fixtures/corpus/*.stl "$src"/fixtures/corpus/*.STL "$src"/fixtures/corpus/*.ply)
  switches=-pQ; minimum=20
else
  files=("$src"/fixtures/*.off "$src"/fixtures/*.obj "$src"/fixtures/*.stl)
  switches=-pqQ; minimum=5
fi
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  name=$(basename "$f"); stem=${name%.*}; stem=${stem//./_}; ext=${name##*.}
  cp "$f" "$tmp/in_$stem.$ext"
  if (cd "$tmp" && timeout 300 tetgen -pQ "in_$stem.$ext" >/dev/null 2>&1); then continue; fi
  checked=$((checked + 1))
  # --no-tetgen-run: polyheal's own TetGen-readiness test must suffice here (with
  # TetGen run inside the repair, the check below would only repeat it).
  "$bin" repair "$f" -o "$tmp/$stem.off" --for tetgen --no-tetgen-run >"$tmp/$stem.log" 2>&1; code=$?
  if [ "$code" -gt 1 ]; then fails=$((fails + 1)); echo "FAIL $name: repair exit $code"; tail -3 "$tmp/$stem.log"; continue; fi
  if ! "$bin" check --tetgen-ready "$tmp/$stem.off" >/dev/null 2>&1; then
    fails=$((fails + 1)); echo "FAIL $name: output not TetGen-ready"; continue
  fi
  if ! (cd "$tmp" && timeout 900 tetgen "$switches" "$stem.smesh" >/dev/null 2>&1); then
    fails=$((fails + 1)); echo "FAIL $name: tetgen $switches refuses the repaired surface"; continue
  fi
  rm -f "$tmp/$stem".1.* "$tmp/in_$stem".1.*
  echo "PASS $name: TetGen refused the input, meshes the repair (exit $code)"
done
echo "$checked fixtures TetGen refused; $fails failed"
[ "$fails" -eq 0 ] && [ "$checked" -ge "$minimum" ]
