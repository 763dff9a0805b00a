#!/usr/bin/env bash
# Render a simreel scene on a Slurm cluster: one bake job simulates the scene once into a cache
# (simreel bake), an array of render jobs restores frame ranges from it (simreel render --cache,
# one chunk per task, after the bake succeeded), and a final job joins the frames into an MP4
# (after every render task succeeded). The frames are byte-identical to one `simreel render`.
#
# With --vary POINTER=V1,V2,..., a parameter sweep instead: an array of one variant per task
# (each its own simulation and frames), then a job that assembles the contact sheet.
#
# usage: farm.sh SCENE --out DIR [options]
#   --frames N        frames 0..N-1 (default: the scene's)
#   --chunk C         frames per render task (default 50)
#   --partition P     Slurm partition (default: the cluster's default)
#   --simreel PATH    the simreel program on the nodes (default: simreel on PATH)
#   --size WxH        frame size (render only; the bake does not depend on it)
#   --set P=V         scene override (repeatable; baked and rendered alike)
#   --seed S          seed
#   --cpus K          CPUs per task (default 1)
#   --vary P=V1,V2    sweep: one array task per value; --sheet-frames K frames of each on the sheet
#   --wait            wait for the last job and exit with its status
# DIR gets cache/ (the bake), frames/ (PNG), logs/, jobs/ (the job scripts), SCENE.mp4;
# for a sweep: variants/NN/ (frames), sheet.png (one row per value, frames across) and sheet.txt.
set -euo pipefail

die() { echo "farm.sh: $*" >&2; exit 2; }
[[ $# -ge 1 ]] || die "usage: farm.sh SCENE --out DIR [--frames N] [--chunk C] [--partition P] [--simreel PATH] [--size WxH] [--set P=V]... [--seed S] [--vary P=V1,V2,...] [--wait]"
scene=$1; shift
out="" frames="" chunk=50 partition="" simreel=$(command -v simreel || true) size="" seed="" cpus=1 vary="" wait=0
sheet_frames=3
sets=()
# An option's value, or a clear refusal where it is missing (set -u would print "$2: unbound
# variable").
value() { [[ $# -ge 2 && $2 != --* ]] || die "$1: expected a value"; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --wait) wait=1; shift; continue ;;
    --out|--frames|--chunk|--partition|--simreel|--size|--set|--seed|--cpus|--vary|--sheet-frames) value "$@" ;;
  esac
  case $1 in
    --out) out=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --chunk) chunk=$2; shift 2 ;;
    --partition) partition=$2; shift 2 ;;
    --simreel) simreel=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --set) sets+=("$2"); shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --vary) vary=$2; shift 2 ;;
    --sheet-frames) sheet_frames=$2; shift 2 ;;
    *) die "unknown option $1" ;;
  esac
done
[[ -n $out ]] || die "--out DIR is required"
[[ -f $scene ]] || die "$scene: no such scene file"
[[ -n $simreel && -x $simreel ]] || die "--simreel: no simreel program (give its path)"
positive() { [[ $2 =~ ^[1-9][0-9]{0,6}$ ]] || die "$1 $2: expected a positive integer"; }
positive --chunk "$chunk"
positive --cpus "$cpus"
positive --sheet-frames "$sheet_frames"
[[ -z $frames ]] || positive --frames "$frames"
[[ -z $seed || $seed =~ ^[0-9]{1,18}$ ]] || die "--seed $seed: expected an integer >= 0"

# The scene as every job will load it (with the overrides; for a sweep, each variant), checked
# here so that a bad scene or value is refused before anything is submitted, not in a job.
check=("$simreel" validate "$scene")
for s in "${sets[@]}"; do check+=(--set "$s"); done
if [[ -z $vary ]]; then
  "${check[@]}" >/dev/null || die "$scene: not a valid scene (simreel's error above)"
else
  pointer=${vary%%=*}
  IFS=, read -r -a values <<< "${vary#*=}"
  [[ ${#values[@]} -ge 1 && $pointer != "$vary" && $pointer == /* ]] || die "--vary $vary: expected POINTER=V1,V2,..."
  for v in "${values[@]}"; do
    "${check[@]}" --set "$pointer=$v" >/dev/null || die "--vary $pointer=$v: not a valid scene (simreel's error above)"
  done
fi
command -v sbatch >/dev/null || die "sbatch not found: is this a Slurm submit host?"

scene=$(realpath "$scene"); simreel=$(realpath "$simreel")
mkdir -p "$out"; out=$(realpath "$out")
mkdir -p "$out/logs" "$out/jobs"
stem=$(basename "$scene" .json)

# The scene's frame count and fps, as the jobs see them: the file's (simreel validate prints
# nothing we need, so python3, which every Debian node has, reads the JSON it has just
# accepted), then the last --set of /frames or /fps; --frames wins over both.
read -r scene_frames fps < <(python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
print(d.get("frames", 120), d.get("fps", 30))' "$scene")
for s in "${sets[@]}"; do
  case $s in
    /frames=*) scene_frames=${s#/frames=} ;;
    /fps=*) fps=${s#/fps=} ;;
  esac
done
[[ -n $frames ]] || frames=$scene_frames
[[ $frames =~ ^[1-9][0-9]*$ ]] || die "--frames $frames: expected a positive integer"

# Shell-quoted common options (scene overrides and seed: the bake and the renders must agree).
q() { [[ $# -eq 0 ]] || printf '%q ' "$@"; }
common=()
for s in "${sets[@]}"; do common+=(--set "$s"); done
[[ -n $seed ]] && common+=(--seed "$seed")
render_opts=()
[[ -n $size ]] && render_opts+=(--size "$size")
sbatch_opts=(--parsable --chdir "$out" --cpus-per-task "$cpus")
[[ -n $partition ]] && sbatch_opts+=(--partition "$partition")

if [[ -z $vary ]]; then
  tasks=$(( (frames + chunk - 1) / chunk ))
  cat > "$out/jobs/bake.sh" <<JOB
#!/bin/bash
set -euo pipefail
exec $(q "$simreel") bake $(q "$scene") --frames $frames $(q "${common[@]}") --resume -q --cache $(q "$out/cache")
JOB
  cat > "$out/jobs/render.sh" <<JOB
#!/bin/bash
set -euo pipefail
a=\$(( SLURM_ARRAY_TASK_ID * $chunk ))
b=\$(( a + $chunk < $frames ? a + $chunk : $frames ))
exec $(q "$simreel") render $(q "$scene") --frames \$a:\$b $(q "${common[@]}" "${render_opts[@]}") -q --cache $(q "$out/cache") -o $(q "$out/frames")
JOB
  cat > "$out/jobs/join.sh" <<JOB
#!/bin/bash
set -euo pipefail
tmp=$(q "$out/.$stem.mp4.tmp-\$\$.mp4")
ffmpeg -loglevel error -y -framerate $fps -i $(q "$out/frames/frame_%05d.png") -c:v libx264 -pix_fmt yuv420p -crf 18 "\$tmp"
mv "\$tmp" $(q "$out/$stem.mp4")
JOB
  chmod +x "$out/jobs/"*.sh
  bake=$(sbatch "${sbatch_opts[@]}" -J "$stem-bake" -o "$out/logs/bake.log" "$out/jobs/bake.sh")
  render=$(sbatch "${sbatch_opts[@]}" -J "$stem-render" --dependency="afterok:$bake" --kill-on-invalid-dep=yes --array="0-$((tasks - 1))" \
    -o "$out/logs/render-%a.log" "$out/jobs/render.sh")
  join_opts=("${sbatch_opts[@]}" -J "$stem-join" --dependency="afterok:$render" --kill-on-invalid-dep=yes -o "$out/logs/join.log")
  result="$out/$stem.mp4"
  echo "bake job $bake; render array $render (${tasks} tasks of $chunk frames); join job after them -> $out/$stem.mp4"
else
  tasks=${#values[@]}
  printf '%s\n' "${values[@]}" > "$out/jobs/values.txt"
  # The sheet's frames: evenly over the range.
  picks=$(python3 -c 'import sys; n,k=int(sys.argv[1]),int(sys.argv[2]); print(" ".join(str(round(i*(n-1)/max(k-1,1))) for i in range(k)))' "$frames" "$sheet_frames")
  cat > "$out/jobs/variant.sh" <<JOB
#!/bin/bash
set -euo pipefail
i=\$SLURM_ARRAY_TASK_ID
value=\$(sed -n "\$(( i + 1 ))p" $(q "$out/jobs/values.txt"))
dir=\$(printf '%s/variants/%02d' $(q "$out") "\$i")
exec $(q "$simreel") render $(q "$scene") --frames $frames $(q "${common[@]}" "${render_opts[@]}") --set $(printf %q "$pointer")="\$value" -q -o "\$dir"
JOB
  cat > "$out/jobs/sheet.sh" <<JOB
#!/bin/bash
# One row per variant (in the order of values.txt, listed in sheet.txt), its frames $picks
# across (ffmpeg xstack).
set -euo pipefail
cd $(q "$out")
inputs=() layout=() n=0 y=0
for ((i = 0; i < $tasks; i++)); do
  x=0
  for f in $picks; do
    inputs+=(-i "\$(printf 'variants/%02d/frame_%05d.png' \$i \$f)")
    layout+=("\${x}_\${y}")
    x="\$x+w0"; n=\$((n + 1))
  done
  y="\$y+h0"
done
IFS='|'; grid="\${layout[*]}"; unset IFS
tmp=".sheet.png.tmp-\$\$.png"
ffmpeg -loglevel error -y "\${inputs[@]}" -filter_complex "xstack=inputs=\$n:layout=\$grid" -frames:v 1 "\$tmp"
mv "\$tmp" sheet.png
{ echo "rows: $pointer = (top to bottom); columns: frames $picks"; cat jobs/values.txt; } > sheet.txt
JOB
  chmod +x "$out/jobs/"*.sh
  render=$(sbatch "${sbatch_opts[@]}" -J "$stem-sweep" --array="0-$((tasks - 1))" -o "$out/logs/variant-%a.log" \
    "$out/jobs/variant.sh")
  join_opts=("${sbatch_opts[@]}" -J "$stem-sheet" --dependency="afterok:$render" --kill-on-invalid-dep=yes -o "$out/logs/sheet.log")
  echo "sweep array $render ($tasks variants of $pointer); sheet job after it -> $out/sheet.png"
  result="$out/sheet.png"
  cp "$out/jobs/sheet.sh" "$out/jobs/join.sh"
fi

if [[ $wait -eq 1 ]]; then
  # sbatch --wait blocks until the job ends and exits with its status (a job cancelled because a
  # job it depends on failed may still return 0: the result file decides).
  rm -f "$result"
  if sbatch "${join_opts[@]}" --wait "$out/jobs/join.sh" >/dev/null && [[ -s $result ]]; then
    echo "done: $out"
  else
    echo "farm.sh: the final job failed (or a job it depends on); see $out/logs/" >&2
    exit 1
  fi
else
  join=$(sbatch "${join_opts[@]}" "$out/jobs/join.sh")
  echo "final job $join"
fi
