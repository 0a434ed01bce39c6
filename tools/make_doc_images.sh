#!/usr/bin/env bash
# Remakes the pictures of README.md and docs/ from the repository alone:
#   docs/images/render.png        scenes/street.ron (10 280 lights), 640×480, 256 spp
#   docs/images/samplers.png      a comparison's contact sheet: offices.ron (768 lamps, most
#                                 behind walls), five samplers at equal time (2 s each),
#                                 renders above their error maps
#   docs/images/compare-page.png  that comparison's report.html in headless Chromium
#   docs/images/glass-guiding-{off,on}.png  tests/data/blender/glass.glb, 320×240, 64 spp,
#                                 seed 2, without and with path guiding
#   docs/images/glass-caustics-{off,on}.png the same without and with light through
#                                 smooth glass solved for (--caustics)
# Needs Chromium for compare-page.png (Debian: apt-get install chromium). Takes about two
# minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
myriad=target/release/myriad
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p docs/images

"$myriad" render scenes/street.ron --resolution 640x480 --spp 256 --seed 1 -q \
    -o "$work/street.exr" --png docs/images/render.png
"$myriad" compare scenes/offices.ron --samplers uniform,power,tree,learned,cells --time 2 --seeds 1 \
    --resolution 320x240 --reference-spp 1024 --out-dir "$work/compare" -q
cp "$work/compare/contact-sheet.png" docs/images/samplers.png
for guiding in off on; do
    "$myriad" render tests/data/blender/glass.glb --resolution 320x240 --spp 64 --max-depth 9 --seed 2 \
        --guiding "$guiding" -q -o "$work/glass-$guiding.exr" --png "docs/images/glass-guiding-$guiding.png"
done
for caustics in off on; do
    "$myriad" render tests/data/blender/glass.glb --resolution 320x240 --spp 64 --max-depth 9 --seed 2 \
        --caustics "$caustics" -q -o "$work/glass-caustics-$caustics.exr" \
        --png "docs/images/glass-caustics-$caustics.png"
done

chromium=$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)
if [ -z "$chromium" ]; then
    echo "no Chromium: docs/images/compare-page.png not remade (apt-get install chromium)" >&2
    exit 1
fi
# The page decodes its images in JavaScript: give it virtual time to finish before the shot.
"$chromium" --headless=new --no-sandbox --disable-gpu --hide-scrollbars --no-first-run \
    --disable-background-networking --user-data-dir="$work/profile" --window-size=1200,900 \
    --force-device-scale-factor=1 --virtual-time-budget=15000 \
    --screenshot="$PWD/docs/images/compare-page.png" "file://$work/compare/report.html" 2>/dev/null
echo "wrote docs/images/render.png, samplers.png, glass-guiding-{off,on}.png, glass-caustics-{off,on}.png, compare-page.png"
