#!/usr/bin/env bash
# Installs polyheal's build and test dependencies from Debian bookworm's
# packages. Idempotent: installs only what is missing. apt-get as root, sudo
# otherwise. Nothing is vendored or downloaded from anywhere else.
set -euo pipefail
packages=(libcgal-dev libgmp-dev libmpfr-dev libboost-dev libtbb-dev catch2 libcli11-dev
          nlohmann-json3-dev tetgen cmake g++ make ccache)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all dependencies present"
  exit 0
fi
echo "setup: installing ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
