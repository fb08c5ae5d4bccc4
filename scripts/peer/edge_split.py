#!/usr/bin/env python3
"""Splits `sensorlight compare`'s headline between shadow edges and the rest.

    python3 scripts/peer/edge_split.py IMAGE.exr REFERENCE.exr

Two renderers that put a pixel's point in slightly different places (a ray through the pixel centre, a
rasterized G-buffer, a sensor lifted off its surface) disagree wildly at a hard shadow edge, where a tiny
shift moves the pixel across the edge, and that can dominate a per-pixel RMSE. This prints the relative
RMSE of luminance over lit pixels (reference above 1 % of its mean, emitters and silhouettes left out, as
`sensorlight compare` does; the surface ids and emission come from either image) for all of them, for the
pixels at an edge of the reference's light (a 4-neighbour differs by more than 30 %), and for the rest.
"""
import sys

import numpy as np
import OpenEXR


def channels(path):
    with OpenEXR.File(path) as f:
        return {name: np.array(ch.pixels, copy=True) for name, ch in f.parts[0].channels.items()}


def luminance(rgb):
    return rgb[..., 0] * 0.2126 + rgb[..., 1] * 0.7152 + rgb[..., 2] * 0.0722


a, b = channels(sys.argv[1]), channels(sys.argv[2])
ya, yb = luminance(a["RGB"]), luminance(b["RGB"])
emitter = np.zeros(yb.shape, bool)
silhouette = np.zeros(yb.shape, bool)
for image in (a, b):
    if "emission" in image:
        emitter |= image["emission"].max(-1) > 0
    if "surface_id" in image:
        ids = image["surface_id"]
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                silhouette |= np.roll(np.roll(ids, dy, 0), dx, 1) != ids
kept = ~(emitter | silhouette)
lit = kept & (yb > 0.01 * yb[kept].mean())
error = np.abs(ya - yb) / np.maximum(yb, 1e-30)
gradient = np.zeros_like(yb)
for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
    neighbour = np.roll(np.roll(yb, dy, 0), dx, 1)
    gradient = np.maximum(gradient, np.abs(neighbour - yb) / np.maximum(yb, 1e-30))
edge = gradient > 0.3
for name, mask in (("all lit", lit), ("shadow edges", lit & edge), ("elsewhere", lit & ~edge)):
    rmse = np.sqrt((error[mask] ** 2).mean()) if mask.any() else float("nan")
    print(f"{name:>12}: {mask.sum():6d} pixels, relative RMSE {100 * rmse:.2f} %")
