#!/usr/bin/env bash
# Renders the contact sheets of docs/gallery/: one 3x2 sheet of evenly sampled frames per demo
# scene, at the scene's own frame count, camera and settings (only the size is reduced, to keep
# the PNGs small for the README).
#
#   docs/gallery/make_gallery.sh            # every scene in demos/scenes/
#   docs/gallery/make_gallery.sh smoke rain # just these
#
# Needs a built simreel (SIMREEL=path overrides build/demos/simreel). Frames go to
# $GALLERY_TMP/<scene>/ (default /tmp/gallery), replaced on the next run. Scenes run one after another;
# the heaviest takes about a minute on two cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
simreel="${SIMREEL:-build/demos/simreel}"
size="${GALLERY_SIZE:-480x270}"
tmp="${GALLERY_TMP:-/tmp/gallery}"
# Sheets are kept under ~400 KB; thousands of thin rain streaks compress badly (rain: 476 KB,
# curtain: 420 KB at 480x270).
declare -A size_for=([rain]=400x225 [curtain]=400x225 [rain_on_mesh]=400x225)
[[ -z "${GALLERY_SIZE:-}" ]] || size_for=()
[[ -x "$simreel" ]] || { echo "make_gallery: $simreel not found; build the simreel target first" >&2; exit 1; }

if (($#)); then scenes=("$@"); else
  scenes=(); for f in demos/scenes/*.json; do scenes+=("$(basename "$f" .json)"); done
fi
for name in "${scenes[@]}"; do
  scene="demos/scenes/$name.json"
  [[ -f "$scene" ]] || { echo "make_gallery: no scene $scene" >&2; exit 1; }
  rm -rf "${tmp:?}/$name"
  start=$SECONDS
  "$simreel" render "$scene" --size "${size_for[$name]:-$size}" --contact-sheet "docs/gallery/$name.png" --sheet 3x2 \
      -o "$tmp/$name" -q
  echo "$name: docs/gallery/$name.png ($((SECONDS - start)) s, $(du -k "docs/gallery/$name.png" | cut -f1) KB)"
done
