#!/usr/bin/env bash
# Benchmark of issue 18: the fountain at SIZE, N frames, rendered straight on one machine vs
# baked once + 2 frame ranges rendered in parallel via Slurm (one-node cluster, local_slurm.sh);
# prints wall times, the bake's cost and bytes per frame, and checks the PNGs are identical.
# usage: bench.sh SIMREEL [N=600] [SIZE=1280x720]
set -euo pipefail
simreel=$(realpath "$1"); n=${2:-600}; size=${3:-1280x720}
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$here/../../demos/scenes/fountain.json")
work=$(mktemp -d /tmp/simreel-bench-XXXXXX)
trap 'rm -rf "$work"' EXIT
now() { date +%s.%N; }
t0=$(now)
"$simreel" render "$scene" --frames "$n" --size "$size" -q -o "$work/straight" >/dev/null
t1=$(now)
chunk=$(( (n + 1) / 2 ))
"$here/local_slurm.sh" -- bash -c '
  s=$(date +%s.%N)
  "$1"/farm.sh "$2" --out "$3/farm" --frames "$4" --chunk "$5" --size "$6" --simreel "$7" --wait >/dev/null
  e=$(date +%s.%N)
  awk -v s="$s" -v e="$e" "BEGIN {printf \"farm (bake + 2 ranges + join): %.1f s\\n\", e - s}"
' farm "$here" "$scene" "$work" "$n" "$chunk" "$size" "$simreel" | tee "$work/farm.txt"
awk -v s="$t0" -v e="$t1" -v n="$n" -v z="$size" 'BEGIN {printf "straight render: %.1f s for %d frames at %s\n", e - s, n, z}'
"$simreel" bake "$scene" --frames "$n" -q --cache "$work/cache2" | tail -1 | sed 's/^/bake alone: /'
du -sb "$work/farm/cache/state" | awk -v n="$n" '{printf "cache: %d bytes, %.0f bytes/frame\n", $1, $1 / n}'
for i in 0 1; do grep -h "frames" "$work/farm/logs/render-$i.log" | sed "s/^/render task $i: /"; done
bad=0
for f in "$work"/straight/frame_*.png; do cmp -s "$f" "$work/farm/frames/$(basename "$f")" || bad=$((bad + 1)); done
echo "PNGs differing between straight and farm: $bad of $n"
