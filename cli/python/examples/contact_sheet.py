"""Eight generated plans rendered as one Ray batch, side by side in one
picture (docs/images/python-batch.png):

    python3 cli/python/examples/contact_sheet.py docs/images/python-batch.png
"""

import sys

import numpy as np
import ray

import flatray
from flatray import batch


def main(out):
    ray.init(include_dashboard=False, log_to_driver=False)
    records = batch.render_generated(range(1, 9), rooms=6, lamps=2, spp=64, bounces=1, scale=0.5)
    images = [r["image"] for r in records]
    height = max(i.shape[0] for i in images)
    width = max(i.shape[1] for i in images)
    gap = 6
    sheet = np.zeros((2 * height + gap, 4 * width + 3 * gap, 3), dtype=np.float32)
    for k, image in enumerate(images):
        y, x = (k // 4) * (height + gap), (k % 4) * (width + gap)
        sheet[y : y + image.shape[0], x : x + image.shape[1]] = image
    # Tone-mapped as each plan asks (they share the generator's white).
    white = flatray.generate(rooms=6, lamps=2, seed=1)._loaded.white
    flatray.Rendered(sheet, records[0]["stats"], 0.0, {}, None, white).write(out)
    for r in records:
        print(f"{r['name']}: noise {100 * r['noise']:.1f} %, {r['seconds']:.2f} s")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "python-batch.png")
