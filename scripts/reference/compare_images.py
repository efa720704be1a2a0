#!/usr/bin/env python3
"""Compares two renders of one frame by two devices (or drivers), which need not agree bit for bit: the mean
of each channel, and the mean of each cell of an 8x8 grid of regions, as relative differences; and the share of
pixels that differ by more than 8/255. Exits non-zero when the images differ in size, or when the whole-image
mean differs by more than 2% or a region's by more than 10% (noise at 64 spp is well inside both).

    python3 scripts/reference/compare_images.py A.png B.png
"""
import sys

import numpy as np
from PIL import Image


def load(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.float64) / 255.0


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = load(sys.argv[1]), load(sys.argv[2])
    if a.shape != b.shape:
        sys.exit(f"the images differ in size: {a.shape[1]}x{a.shape[0]} and {b.shape[1]}x{b.shape[0]}")
    mean_a, mean_b = a.mean(axis=(0, 1)), b.mean(axis=(0, 1))
    overall = abs(a.mean() - b.mean()) / max(b.mean(), 1e-9)
    print("mean RGB (sRGB-encoded):", np.round(mean_a, 4), "against", np.round(mean_b, 4),
          f"relative difference {100 * overall:.2f}%")
    h, w = a.shape[:2]
    worst, worst_cell = 0.0, None
    for i in range(8):
        for j in range(8):
            ys, xs = slice(i * h // 8, (i + 1) * h // 8), slice(j * w // 8, (j + 1) * w // 8)
            ra, rb = a[ys, xs].mean(), b[ys, xs].mean()
            d = abs(ra - rb) / max(rb, 0.02)
            if d > worst:
                worst, worst_cell = d, (i, j, ra, rb)
    i, j, ra, rb = worst_cell if worst_cell else (0, 0, 0.0, 0.0)
    print(f"largest region difference (8x8 grid): {100 * worst:.2f}% at row {i}, column {j} ({ra:.4f} against {rb:.4f})")
    differing = (np.abs(a - b).max(axis=2) > 8 / 255).mean()
    print(f"pixels differing by more than 8/255: {100 * differing:.2f}%")
    if overall > 0.02 or worst > 0.10:
        sys.exit("the pictures differ by more than noise explains")


if __name__ == "__main__":
    main()
