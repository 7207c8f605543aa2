#!/usr/bin/env bash
# A new user's first command: installs what is missing, builds Release, and
# runs polyheal's main job on bundled fixtures. For now that is the exact
# check: a thin-walled tube meshed too coarsely for its clearance
# (self-intersecting) and the same tube meshed finely enough (clean).
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
