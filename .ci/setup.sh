#!/usr/bin/env bash
# Installs simreel's build and run-time dependencies from Debian's packages.
# Idempotent: installs only what is missing; prints the exact apt line when not root.
# `--sanitize` adds what CI's sanitizer and fuzzing job (.ci/sanitize.sh) needs: clang and its
# sanitizer/libFuzzer runtimes.
set -euo pipefail
PKGS=(cmake g++ make pkg-config libeigen3-dev libosmesa6-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev libstb-dev libdeflate-dev
      libassimp-dev nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev ffmpeg
      assimp-testmodels python3-jsonschema libbullet-dev slurm-wlm munge)
if [ "${1:-}" = "--sanitize" ]; then
  PKGS=(clang libclang-rt-14-dev)
fi
missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all dependencies present"
  exit 0
fi
line="apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive $line
    exit 0
  fi
  echo "setup: missing packages; run as root:" >&2
  echo "  apt-get update && $line" >&2
  exit 2
fi
echo "setup: installing ${missing[*]}"
apt-get update -qq
DEBIAN_FRONTEND=noninteractive $line -qq
