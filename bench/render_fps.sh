#!/usr/bin/env bash
# Frames per second of the whole `simreel render` command (simulate + render + read back +
# PNG + MP4) on a scene, at a size. Usage: bench/render_fps.sh [SCENE] [WxH] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-demos/scenes/fountain.json}
size=${2:-1280x720}
frames=${3:-150}
bin=build/demos/simreel
[ -x "$bin" ] || cmake --build build -j2 --target simreel >/dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
run() {
  local label=$1; shift
  local t0 t1
  t0=$(date +%s.%N)
  "$bin" render "$scene" -q --frames "$frames" --size "$size" "$@" >/dev/null
  t1=$(date +%s.%N)
  awk -v l="$label" -v n="$frames" -v a="$t0" -v b="$t1" \
    'BEGIN { printf "%-22s %4d frames in %6.2f s = %6.2f frames/s\n", l, n, b - a, n / (b - a) }'
}
echo "$scene at $size"
run "PNG + MP4" -o "$tmp/png" -o "$tmp/v.mp4"
run "MP4 only" -o "$tmp/v2.mp4"
