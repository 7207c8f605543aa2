#!/usr/bin/env bash
# A new user's first command: installs what is missing, builds Release, and
# runs polyheal's main jobs on bundled fixtures: the exact check of a
# thin-walled tube meshed too coarsely for its clearance (self-intersecting)
# and of the same tube meshed finely enough (clean); then degenerate-face
# removal on the fan-tessellated CAD cylinder of Botsch & Kobbelt's Fig. 1.
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
