"""Equal-time comparison from Python: the default scene rendered with MMLT and tempered MMLT
for the same number of seconds, over several seeds, against a BDPT reference; prints the
relMSE table and, when matplotlib is installed, saves a side-by-side PNG.

    pip install ./crates/tempera-py      # once
    python examples/equal_time.py [SECONDS] [SEEDS]
"""

import sys

import numpy as np

import tempera

seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
seeds = range(1, 1 + (int(sys.argv[2]) if len(sys.argv) > 2 else 4))
resolution = (128, 128)

scene = tempera.default_scene()
print(f"reference: BDPT for {4 * seconds:g} s")
reference = tempera.render(scene, "bdpt", time=4 * seconds, resolution=resolution, seed=1000, maxdepth=10).image

rows, images = [], {}
for method in ("mmlt", "tempered"):
    for seed in seeds:
        result = tempera.render(scene, method, time=seconds, resolution=resolution, seed=seed, maxdepth=10)
        c = tempera.compare(result, reference, metrics=("relmse", "flip", "mean_ratio"))
        mpp = result.stats["mutations"] / (resolution[0] * resolution[1])
        rows.append((method, seed, c["relmse"], c["flip"], c["mean_ratio"], mpp))
        images.setdefault(method, result.image)

print(f"\n{'method':<10} {'seed':>4} {'relMSE':>10} {'FLIP':>7} {'mean/ref':>9} {'mut/px':>8}")
for method, seed, relmse, flip, ratio, mpp in rows:
    print(f"{method:<10} {seed:>4} {relmse:>10.4g} {flip:>7.4f} {ratio:>9.4f} {mpp:>8.1f}")
for method in images:
    values = [r[2] for r in rows if r[0] == method]
    print(f"{method}: relMSE mean {np.mean(values):.4g} (min {min(values):.4g}, max {max(values):.4g})")

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no side-by-side image")
else:
    panels = [("reference (BDPT)", reference)] + [(f"{m}, seed {seeds[0]}", img) for m, img in images.items()]
    fig, axes = plt.subplots(1, len(panels), figsize=(4 * len(panels), 4))
    for ax, (title, image) in zip(axes, panels):
        ax.imshow(np.clip(image, 0, 1) ** (1 / 2.2))
        ax.set_title(title)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig("equal_time.png", dpi=100)
    print("saved equal_time.png")
