#!/usr/bin/env bash
# A new user's first command: installs what is missing, builds Release, and
# runs polyheal's main jobs on bundled fixtures: the exact check of a
# thin-walled tube meshed too coarsely for its clearance (self-intersecting)
# and of the same tube meshed finely enough (clean); then degenerate-face
# removal on the fan-tessellated CAD cylinder of Botsch & Kobbelt's Fig. 1, and
# self-intersection removal on the coarse tube (Yamakawa & Shimada's Fig. 3),
# whose output is checked again.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
"$root/scripts/build.sh" --target polyheal
ph="$root/build/polyheal"
for f in tube_edge3.0.off tube_edge2.42.off; do
  echo
  echo "\$ polyheal check fixtures/$f"
  set +e
  "$ph" check "$root/fixtures/$f"
  code=$?
  set -e
  echo "(exit code $code: 0 certified clean, 1 defects remain, 2 error)"
done
echo
echo "\$ polyheal degenerate fixtures/cad_cylinder.off -o build/demo_cylinder.off --overwrite"
set +e
"$ph" degenerate "$root/fixtures/cad_cylinder.off" -o "$root/build/demo_cylinder.off" --overwrite
code=$?
set -e
echo "(exit code $code: 0 certified, 1 faces left (listed), 2 error)"
echo
echo "\$ polyheal deintersect fixtures/tube_edge3.0.off -o build/demo_tube.off --overwrite"
set +e
"$ph" deintersect "$root/fixtures/tube_edge3.0.off" -o "$root/build/demo_tube.off" --overwrite
code=$?
set -e
echo "(exit code $code: 0 certified, 1 faces left (listed), 2 error)"
echo
echo "\$ polyheal check build/demo_tube.off"
set +e
"$ph" check "$root/build/demo_tube.off"
code=$?
set -e
echo "(exit code $code)"
echo
echo "\$ polyheal regularize fixtures/knot_tube_r1.2.off -o build/demo_knot.off --overwrite"
set +e
"$ph" regularize "$root/fixtures/knot_tube_r1.2.off" -o "$root/build/demo_knot.off" --overwrite
code=$?
set -e
echo "(exit code $code: 0 certified, 1 defects remain (listed), 2 error)"
echo
echo "\$ polyheal offset fixtures/thingi10k_65004.stl -d 0.69 -o build/demo_offset.off --overwrite"
set +e
"$ph" offset "$root/fixtures/thingi10k_65004.stl" -d 0.69 -o "$root/build/demo_offset.off" --overwrite
code=$?
set -e
echo "(exit code $code)"
echo
echo "\$ polyheal rebuild fixtures/dirty_box.obj -o build/demo_box.obj --overwrite"
set +e
"$ph" rebuild "$root/fixtures/dirty_box.obj" -o "$root/build/demo_box.obj" --overwrite
code=$?
set -e
echo "(exit code $code: 0 certified, 1 not certified or input lost, 2 error)"
