#!/usr/bin/env bash
# Compares two trees of frames written by render_all.sh with cmp, file by file, for every scene
# rendered into AFTER (a subset of BEFORE is fine); exit 1 on any difference, missing or extra
# frame. Prints one line per scene.
set -uo pipefail
a=${1:?usage: compare.sh BEFORE AFTER}
b=${2:?usage: compare.sh BEFORE AFTER}
status=0
for d in "$b"/*/; do
  s=$(basename "$d")
  n=0; bad=0
  for f in "$a/$s"/*.png; do
    n=$((n + 1))
    if ! cmp -s "$f" "$d$(basename "$f")"; then bad=$((bad + 1)); fi
  done
  extra=$(comm -13 <(ls "$a/$s" 2>/dev/null) <(ls "$d") | wc -l)
  echo "$s: $n frames, $bad differ, $extra extra"
  if [ "$bad" -ne 0 ] || [ "$extra" -ne 0 ]; then status=1; fi
done
exit $status
