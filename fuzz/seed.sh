#!/usr/bin/env bash
# Seeds each fuzz target's corpus (fuzz/corpus/TARGET) from the project's fixtures and, when it
# exists, from ../shared/scenes. Run from the project's root: bash fuzz/seed.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
corpus="$root/fuzz/corpus"
mkdir -p "$corpus"/{pbrt,mitsuba,ply,obj,serialized,image,experiment}
fixtures="$root/crates/tempera-scene/tests/fixtures"
shared="$root/../shared/scenes"
copy() { # target, files...
  local target=$1; shift
  for f in "$@"; do
    [ -f "$f" ] || continue
    # Large files make slow inputs: keep the first 64 KiB.
    head -c 65536 "$f" > "$corpus/$target/$(echo "$f" | md5sum | cut -c1-16)"
  done
}
copy pbrt "$fixtures"/pbrt/*.pbrt
copy mitsuba "$fixtures"/mitsuba/*.xml
copy ply $(find "$fixtures" -name '*.ply')
copy serialized $(find "$fixtures" -name '*.serialized')
copy obj $(find "$fixtures" -name '*.obj')
if [ -d "$shared" ]; then
  copy pbrt $(find "$shared" -name '*.pbrt')
  copy mitsuba $(find "$shared" -name 'scene_v0.6.xml')
  copy ply $(find "$shared" -name '*.ply' -size -64k | head -20)
  copy serialized $(find "$shared" -name '*.serialized' -size -64k | head -5)
  copy obj $(find "$shared" -name '*.obj' -size -64k | head -10)
fi
copy experiment "$root"/experiments/*.toml
# Images: the first byte picks the reader (0 PFM, 1 EXR, 2 PNG, 3 TGA, 4 JPEG).
i=0
for f in $(find "$root/crates" "$shared" -name '*.pfm' -size -64k 2>/dev/null | head -5); do
  { printf '\x00'; cat "$f"; } > "$corpus/image/pfm$i"; i=$((i+1)); done
for f in $(find "$shared" -name '*.exr' -size -64k 2>/dev/null | head -3); do
  { printf '\x01'; cat "$f"; } > "$corpus/image/exr$i"; i=$((i+1)); done
for f in $(find "$shared" -name '*.png' -size -64k 2>/dev/null | head -3); do
  { printf '\x02'; cat "$f"; } > "$corpus/image/png$i"; i=$((i+1)); done
for f in $(find "$shared" -name '*.tga' -size -64k 2>/dev/null | head -3); do
  { printf '\x03'; cat "$f"; } > "$corpus/image/tga$i"; i=$((i+1)); done
# Small images of Tempera's own, when it is built.
bin="$root/target/release/tempera"
if [ -x "$bin" ]; then
  tmp=$(mktemp -d)
  "$bin" render --resolution 8x6 --spp 1 -q -o "$tmp/a.exr" -o "$tmp/a.png" -o "$tmp/a.pfm"
  { printf '\x01'; cat "$tmp/a.exr"; } > "$corpus/image/own-exr"
  { printf '\x02'; cat "$tmp/a.png"; } > "$corpus/image/own-png"
  { printf '\x00'; cat "$tmp/a.pfm"; } > "$corpus/image/own-pfm"
  rm -rf "$tmp"
fi
echo "seeded: $(for t in "$corpus"/*; do printf '%s %s  ' "$(basename "$t")" "$(ls "$t" | wc -l)"; done)"
