#!/usr/bin/env bash
# Renders every picture the docs show, each with the command the docs give
# for it, into FOLDER (default: docs/images, where the docs find them).
#
#   docs/images/render.sh [FOLDER]
#
# Each line that starts with `flatray` makes one picture (an import and
# its render make one together); `tests/tests/pictures.rs` runs those
# same lines and checks that each picture in docs/images is, pixel for
# pixel, what its line writes. The last two steps take pictures that
# are not renders: the live view's, by its browser test, and the Python
# batch's contact sheet, on Ray.
set -euo pipefail
cd "$(dirname "$0")/../.."
out="$(realpath "${1:-docs/images}")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cargo build --quiet --release -p flatray-cli
flatray() { ./target/release/flatray "$@"; }

# README
flatray render scenes/room.ron --spp 500 -o "$out/room-500.png"
flatray render scenes/room.ron --spp 50 -o "$out/room-50.png"
flatray render scenes/colour-bleed.ron --spp 500 -o "$out/colour-bleed-500.png"
flatray render scenes/colour-bleed.ron --spp 50 -o "$out/colour-bleed-50.png"
flatray render scenes/room.ron --draw-walls -o "$out/room-walls.png"
flatray render scenes/room.ron --integrator light --spp 16 -o "$out/room-light.png"
flatray render scenes/soft-shadow.ron -o "$out/soft-shadow.png"
flatray render scenes/prism.ron -o "$out/prism.png"
flatray render scenes/bathroom.ron --spp 256 --specular 0 -o "$out/bathroom-specular-0.png"
flatray render scenes/bathroom.ron --spp 256 -o "$out/bathroom.png"
# docs/tutorial.md
flatray render scenes/first-flat.ron --spp 256 -o "$out/first-flat.png"
flatray render scenes/first-flat.ron --scale 0.5 --spp 4 -o "$out/first-flat-preview.png"
# docs/scene-format.md
flatray render scenes/round-room.ron --draw-walls -o "$out/round-room.png"
flatray render scenes/rough-mirrors.ron -o "$out/rough-mirrors.png"
flatray render scenes/one-sided.ron --draw-walls -o "$out/one-sided.png"
flatray render scenes/lamps.ron -o "$out/lamps.png"
flatray render scenes/optics.ron --draw-walls -o "$out/optics.png"
# docs/daylight.md
flatray render scenes/daylight.ron -o "$out/daylight.png"
flatray day scenes/daylight.ron --from 09:00 --to 16:00 --every 1h --spp 16 --scale 0.5 -o "$out/daylight-day.png"
flatray measure scenes/daylight.ron --quiet --map "$out/daylight-map.png"
flatray render tests/fixtures/daylight/south-sky.ron --spp 16 -o "$out/daylight-south-sky.png"
flatray render scenes/lens.ron --integrator light -o "$out/lens.png"
flatray render scenes/lens-polygon.ron --integrator light -o "$out/lens-polygon.png"
flatray render scenes/rough-lens.ron --draw-walls -o "$out/rough-lens.png"
# docs/model.md
flatray render scenes/lens.ron -o "$out/lens-path.png"
flatray render scenes/room.ron --spp 16 --indirect samples -o "$out/room-samples-16.png"
flatray render scenes/room.ron --spp 16 -o "$out/room-lines-16.png"
# docs/accuracy.md
flatray render scenes/pentagon.ron -o "$out/pentagon.png"
flatray render scenes/round-room.ron --adaptive --spp 512 --scale 0.5 -o "$work/round-room-adaptive.png" --write-spp "$out/round-room-spp.png"
# docs/import.md (and the README)
flatray import tests/fixtures/import/flat.svg -o "$work/flat.ron"
flatray render "$work/flat.ron" --scale 0.6 -o "$out/import-svg.png"
flatray import tests/fixtures/import/level.tmx -o "$work/level.ron"
flatray render "$work/level.ron" -o "$out/import-tiled.png"
flatray import tests/fixtures/import/house-mask.png --scale 4 -o "$work/house.ron"
flatray render "$work/house.ron" --scale 0.5 -o "$out/import-mask.png"
flatray import scenes/maps/tavern.dd2vtt -o "$work/tavern.ron"
flatray render "$work/tavern.ron" --scale 0.5 -o "$out/import-tavern.png"
flatray import scenes/maps/tavern.dd2vtt --doors open -o "$work/tavern-open.ron"
flatray render "$work/tavern-open.ron" --scale 0.5 -o "$out/import-tavern-open.png"
flatray import scenes/maps/corridor.uvtt -o "$work/corridor.ron"
flatray render "$work/corridor.ron" --scale 0.5 -o "$out/import-corridor.png"
# The maps' own pictures, as the imports wrote them beside their scenes.
cp "$work/tavern-floor.png" "$out/import-tavern-map.png"
cp "$work/corridor-floor.png" "$out/import-corridor-map.png"

# docs/serve.md: screenshots of the live view, by its browser test.
FLATRAY_SCREENSHOTS="$out" cargo test --quiet --release -p flatray-cli --test browser
# docs/python.md: eight generated plans as one Ray batch.
python3 cli/python/examples/contact_sheet.py "$out/python-batch.png"
