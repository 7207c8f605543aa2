#!/usr/bin/env bash
# A new user's first command: installs what is missing, builds Release, and
# runs polyheal's main job — `polyheal repair` — on bundled fixtures of each
# kind: a thin-walled tube meshed too coarsely for its clearance (its walls
# cross: freed by local moves), two interpenetrating spheres (their union), a
# box of six separate patches with gaps, overlaps and a hole (rebuilt), and a
# mechanical part with holes (filled). Each output is written with a
# certificate, then checked again by `polyheal check --certificate` and
# compared with its input by `polyheal compare`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
"$root/scripts/build.sh" --target polyheal
ph="$root/build/polyheal"
out="$root/build/demo"
mkdir -p "$out"
run() {  # run ARGS... : echo the command, run it, report the exit code
  echo
  echo "\$ polyheal $*"
  set +e
  "$ph" "$@"
  local code=$?
  set -e
  echo "(exit code $code: 0 certified clean within bounds, 1 defects or bounds exceeded (said above), 2 error)"
}
for f in tube_edge3.0.off spheres_intersecting.off dirty_box.obj mech-holes-shark.off; do
  name=${f%.*}
  run repair "$root/fixtures/$f" -o "$out/$name.off" --certificate "$out/$name.cert.json" --overwrite
done
run check "$out/tube_edge3.0.off" --certificate "$out/tube_edge3.0.cert.json"
run compare "$root/fixtures/tube_edge3.0.off" "$out/tube_edge3.0.off"
echo
echo "Outputs and certificates are in build/demo/. The single-method commands"
echo "(degenerate, deintersect, regularize, offset, union, rebuild) are described in README.md."
