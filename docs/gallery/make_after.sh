#!/usr/bin/env bash
# Renders docs/gallery/after/<scene>.png: a 4x4 contact sheet of 640x360 frames, shrunk to 60 %
# (1164x660) with a 256-colour palette, the same settings as docs/gallery/before/ (the demos as
# they rendered before issue 14's new look), so the two sheets of a demo compare frame for frame.
# docs/gallery/before_after.md shows them side by side.
#
#   docs/gallery/make_after.sh            # every scene that has a before/ sheet
#   docs/gallery/make_after.sh smoke rain # just these
#
# Needs a built simreel (SIMREEL=path overrides build/demos/simreel) and ffmpeg.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
simreel="${SIMREEL:-build/demos/simreel}"
tmp="${GALLERY_TMP:-/tmp/gallery_after}"
[[ -x "$simreel" ]] || { echo "make_after: $simreel not found; build the simreel target first" >&2; exit 1; }
if (($#)); then scenes=("$@"); else
  scenes=(); for f in docs/gallery/before/*.png; do scenes+=("$(basename "$f" .png)"); done
fi
mkdir -p docs/gallery/after "$tmp"
for name in "${scenes[@]}"; do
  scene="demos/scenes/$name.json"
  [[ -f "$scene" ]] || { echo "make_after: no scene $scene" >&2; exit 1; }
  rm -rf "${tmp:?}/$name"
  start=$SECONDS
  "$simreel" render "$scene" --size 640x360 --contact-sheet "$tmp/$name.png" --sheet 4x4 -o "$tmp/$name" -q
  ffmpeg -loglevel error -y -i "$tmp/$name.png" \
      -vf "scale=1164:660:flags=area,split[a][b];[a]palettegen=max_colors=256[p];[b][p]paletteuse=dither=sierra2_4a" \
      "docs/gallery/after/$name.png"
  rm -rf "${tmp:?}/$name"
  echo "$name: docs/gallery/after/$name.png ($((SECONDS - start)) s, $(du -k "docs/gallery/after/$name.png" | cut -f1) KB)"
done
