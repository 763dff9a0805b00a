#!/usr/bin/env bash
# Frames per second of the whole `simreel render` command (simulate + render + read back +
# PNG + MP4) for every demo scene at 1280x720 and 640x360, with the writer threads (default)
# and with --sync-writes (everything on the render thread), plus the PNG compression level.
# Usage: bench/render_fps.sh [FRAMES] [SCENE...]   (default 60 frames, demos/scenes/*.json)
# Wall-clock numbers: run it on an otherwise idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-60}
shift || true
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(demos/scenes/*.json)
bin=build/demos/simreel
[ -x "$bin" ] || cmake --build build -j2 --target simreel >/dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# Wall time and CPU time (user + sys of simreel and its ffmpeg child): on a shared machine the
# CPU time per frame is the steadier figure; the wall time shows what the writer threads overlap.
run() {
  local label=$1 scene=$2 size=$3; shift 3
  local t0 t1 cpu
  rm -rf "${tmp:?}"/*
  t0=$(date +%s.%N)
  cpu=$( { TIMEFORMAT='%U %S'; time "$bin" render "$scene" -q --frames "$frames" --size "$size" "$@" >/dev/null; } 2>&1 )
  t1=$(date +%s.%N)
  awk -v l="$label" -v n="$frames" -v a="$t0" -v b="$t1" -v c="$cpu" \
    'BEGIN { split(c, u, " "); printf "  %-36s %4d frames: wall %6.2f s = %6.2f frames/s, cpu %6.1f ms/frame\n",
             l, n, b - a, n / (b - a), 1000 * (u[1] + u[2]) / n }'
}
for scene in "${scenes[@]}"; do
  for size in 1280x720 640x360; do
    echo "$scene at $size"
    # A sheet with a cell per frame renders every frame and writes one small PNG.
    run "simulate + render (sheet only)" "$scene" "$size" --contact-sheet "$tmp/s.png" --sheet "10x$(( (frames + 9) / 10 ))"
    run "PNG + MP4, writer threads" "$scene" "$size" -o "$tmp/png" -o "$tmp/v.mp4"
    run "PNG + MP4, --sync-writes" "$scene" "$size" -o "$tmp/png" -o "$tmp/v.mp4" --sync-writes
    run "PNG level 8 + MP4, writer threads" "$scene" "$size" -o "$tmp/png" -o "$tmp/v.mp4" --png-compression 8
    run "PNG level 8 + MP4, --sync-writes" "$scene" "$size" -o "$tmp/png" -o "$tmp/v.mp4" --png-compression 8 --sync-writes
    run "MP4 only, writer threads" "$scene" "$size" -o "$tmp/v.mp4"
  done
done
