#!/usr/bin/env bash
# Renders every scene in demos/scenes/ at 320x180 (all of each scene's frames) into OUTDIR/<scene>/
# with the given simreel binary, for byte-for-byte before/after comparison of a refactor:
#   bench/identity/render_all.sh build/demos/simreel /tmp/before
#   ... change the code, rebuild ...
#   bench/identity/render_all.sh build/demos/simreel /tmp/after
#   bench/identity/compare.sh /tmp/before /tmp/after
# Optional third argument: scene names to render (default: all).
set -euo pipefail
bin=${1:?usage: render_all.sh SIMREEL OUTDIR [SCENE...]}
out=${2:?usage: render_all.sh SIMREEL OUTDIR [SCENE...]}
shift 2
cd "$(dirname "$0")/../.."
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  for f in demos/scenes/*.json; do scenes+=("$(basename "$f" .json)"); done
fi
mkdir -p "$out"
for s in "${scenes[@]}"; do
  start=$(date +%s)
  "$bin" render "demos/scenes/$s.json" --size 320x180 -q -o "$out/$s"
  echo "$s: $(ls "$out/$s" | wc -l) frames, $(( $(date +%s) - start )) s"
done
