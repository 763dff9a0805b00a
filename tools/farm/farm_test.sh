#!/usr/bin/env bash
# End-to-end check of the Slurm farm (docs/cache.md): stands up a one-node cluster
# (local_slurm.sh), renders the fountain through farm.sh (bake job -> render array -> join job)
# and compares every PNG byte for byte with a one-machine `simreel render`; then a two-variant
# sweep on the farm and its contact sheet. Exit 0 when identical, 1 otherwise, 77 (skipped)
# without Slurm or root.
#
# usage: farm_test.sh SIMREEL [--frames N] [--size WxH] [--chunk C] [--install] [--no-sweep]
set -euo pipefail
[[ $# -ge 1 ]] || { echo "usage: farm_test.sh SIMREEL [--frames N] [--size WxH] [--chunk C] [--install] [--no-sweep]" >&2; exit 2; }
simreel=$(realpath "$1"); shift
frames=30 size=320x180 chunk=10 install=() sweep=1
while [[ $# -gt 0 ]]; do
  case $1 in
    --frames) frames=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --chunk) chunk=$2; shift 2 ;;
    --install) install=(--install); shift ;;
    --no-sweep) sweep=0; shift ;;
    *) echo "farm_test.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$here/../../demos/scenes/fountain.json")
work=$(mktemp -d /tmp/simreel-farm-test-XXXXXX)
trap 'rm -rf "$work"' EXIT

t0=$(date +%s.%N)
"$simreel" render "$scene" --frames "$frames" --size "$size" -q -o "$work/straight" >/dev/null
t1=$(date +%s.%N)
"$here/local_slurm.sh" "${install[@]}" -- bash -c '
  set -euo pipefail
  s=$(date +%s.%N)
  "$1"/farm.sh "$2" --out "$3/farm" --frames "$4" --chunk "$5" --size "$6" --simreel "$7" --wait
  e=$(date +%s.%N)
  echo "farm wall time: $(awk "BEGIN {print $e - $s}") s"
  if [[ $8 -eq 1 ]]; then
    "$1"/farm.sh "$2" --out "$3/sweep" --frames 40 --size 160x90 --simreel "$7" \
      --vary /emitters/0/rate=200,800 --sheet-frames 3 --wait
  fi
' farm "$here" "$scene" "$work" "$frames" "$chunk" "$size" "$simreel" "$sweep"
echo "one-machine render: $(awk "BEGIN {print $t1 - $t0}") s for $frames frames at $size"

n=0 bad=0
for f in "$work"/straight/frame_*.png; do
  g="$work/farm/frames/$(basename "$f")"
  if ! cmp -s "$f" "$g"; then echo "differs: $(basename "$f")" >&2; bad=$((bad + 1)); fi
  n=$((n + 1))
done
m=$(ls "$work"/farm/frames/frame_*.png | wc -l)
[[ $n -eq $frames && $m -eq $frames ]] || { echo "farm_test: $m farm frames, $n straight, expected $frames" >&2; exit 1; }
[[ $bad -eq 0 ]] || { echo "farm_test: $bad of $n PNGs differ" >&2; exit 1; }
[[ -s $work/farm/fountain.mp4 ]] || { echo "farm_test: no fountain.mp4 from the join job" >&2; exit 1; }
echo "farm_test: $n PNGs from the farm are byte-identical to the one-machine render; fountain.mp4 joined"
if [[ $sweep -eq 1 ]]; then
  [[ -s $work/sweep/sheet.png ]] || { echo "farm_test: no sweep sheet" >&2; exit 1; }
  echo "farm_test: sweep of 2 variants -> sheet.png ($(stat -c %s "$work/sweep/sheet.png") bytes)"
fi
