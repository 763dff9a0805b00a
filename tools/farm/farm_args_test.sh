#!/usr/bin/env bash
# farm.sh's checks before it submits anything, without a cluster: a stub `sbatch` on PATH records
# each submission and answers a job id. Bad options, a bad scene and a bad sweep value must be
# refused with exit 2, a message naming them, and nothing written; a good run must write job
# scripts that use the scene's frames and fps as the overrides leave them (the join encoded at
# the file's fps when --set /fps changed it, so the video played at the wrong speed).
#
# usage: farm_args_test.sh SIMREEL
set -euo pipefail
[[ $# -eq 1 ]] || { echo "usage: farm_args_test.sh SIMREEL" >&2; exit 2; }
simreel=$(realpath "$1")
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$here/../../demos/scenes/dominoes.json")
work=$(mktemp -d /tmp/simreel-farm-args-XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/bin"
cat > "$work/bin/sbatch" <<'STUB'
#!/bin/bash
echo "$*" >> "$FARM_ARGS_LOG"
echo 4242
STUB
chmod +x "$work/bin/sbatch"
export PATH="$work/bin:$PATH" FARM_ARGS_LOG="$work/sbatch.log"
echo '{"fps": 30, "frames": 12' > "$work/broken.json"

fails=0
refuse() {  # refuse EXPECTED_TEXT FARM_ARGS...
  local expect=$1; shift
  rm -rf "$work/out"
  local err rc=0
  err=$("$here/farm.sh" "$@" 2>&1 >/dev/null) || rc=$?
  if [[ $rc -ne 2 || $err != *"$expect"* || -e $work/out || -e $FARM_ARGS_LOG ]]; then
    echo "FAIL: farm.sh $*: exit $rc, expected 2 with \"$expect\" and nothing written; got: $err" >&2
    fails=$((fails + 1))
  fi
}
refuse "--out: expected a value" "$scene" --simreel "$simreel" --out
refuse "--chunk: expected a value" "$scene" --simreel "$simreel" --out "$work/out" --chunk
refuse "--chunk 0: expected a positive integer" "$scene" --simreel "$simreel" --out "$work/out" --chunk 0
refuse "--cpus two: expected a positive integer" "$scene" --simreel "$simreel" --out "$work/out" --cpus two
refuse "--seed -1: expected an integer >= 0" "$scene" --simreel "$simreel" --out "$work/out" --seed -1
refuse "broken.json: not a valid scene" "$work/broken.json" --simreel "$simreel" --out "$work/out"
refuse "invalid JSON" "$work/broken.json" --simreel "$simreel" --out "$work/out"
refuse "/nope: unknown key" "$scene" --simreel "$simreel" --out "$work/out" --set /nope=1
refuse "--vary /render/msaa=99: not a valid scene" "$scene" --simreel "$simreel" --out "$work/out" --vary /render/msaa=2,99
refuse "--vary msaa=2: expected POINTER=V1,V2" "$scene" --simreel "$simreel" --out "$work/out" --vary msaa=2

# A good run: frames and fps as the overrides leave them.
rm -rf "$work/out" "$FARM_ARGS_LOG"
"$here/farm.sh" "$scene" --simreel "$simreel" --out "$work/out" --set /fps=60 --set /frames=7 --chunk 3 >/dev/null
grep -q -- "-framerate 60 " "$work/out/jobs/join.sh" ||
  { echo "FAIL: the join job does not encode at the overridden 60 fps: $(grep framerate "$work/out/jobs/join.sh")" >&2; fails=$((fails + 1)); }
grep -q -- "--frames 7 " "$work/out/jobs/bake.sh" ||
  { echo "FAIL: the bake does not take the overridden 7 frames: $(grep bake "$work/out/jobs/bake.sh")" >&2; fails=$((fails + 1)); }
grep -q -- "--array=0-2 " "$FARM_ARGS_LOG" ||
  { echo "FAIL: 7 frames in chunks of 3 are not 3 render tasks: $(cat "$FARM_ARGS_LOG")" >&2; fails=$((fails + 1)); }

[[ $fails -eq 0 ]] || exit 1
echo "farm_args_test: 10 bad inputs refused before submitting; overridden frames and fps reach the jobs"
