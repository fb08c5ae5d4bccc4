#!/usr/bin/env python3
"""Per-pixel agreement of an image with a reference on lit, non-silhouette, non-emitter pixels.

    /work/venv-mitsuba/bin/python scripts/peer/compare.py IMAGE.exr REFERENCE.exr --ids AOVS.exr [--json F]

Both images are linear EXRs with channels R, G, B (sensorlight's `render`/`reference` output, or
`mitsuba_direct.py`'s). Pixels are compared only where all of these hold:

* not a silhouette: `--ids` names an EXR with a `surface_id` channel (`sensorlight render --aovs`); a
  pixel is dropped when any pixel of its 3×3 neighbourhood has a different id (this also drops pixels on
  creases between two surfaces, and the background, id 0). sensorlight point-samples pixel centres, a
  box-filtered render averages over the pixel: the two cannot agree on pixels straddling an edge.
* not an emitter: pixels with Le > 0 are dropped, Le taken from an `emission.R/G/B` layer in either
  file (`mitsuba_direct.py` writes one) or `--emission` (their value is mostly Le, which every renderer
  gets right; leaving them in would dilute the error).
* lit: the reference's mean over R, G, B exceeds `--lit-threshold` times the 99th percentile of that
  mean over the non-emitter, non-background pixels (default 0.01). With ε = 0 unlit pixels are exactly
  0 in the exact solution, and a relative error there means nothing.

Reported, over those pixels:

* per-pixel relative RMSE: sqrt(mean_p (|a_p − b_p| / |b_p|)²), |·| the Euclidean norm over R, G, B:
  every lit pixel counts equally, however dark;
* the median and 95th percentile of |a_p − b_p| / |b_p|;
* sensorlight's `compare` figures over the same pixels: sqrt(Σ|a − b|² / Σ|b|²) ("energy-weighted
  relative RMSE", bright pixels count more) and the relative bias (Σa − Σb) / Σb.

The noise of a Monte Carlo reference is estimated by comparing two renders with different seeds: their
per-pixel relative RMSE divided by √2 is the noise of one.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

try:
    import numpy as np
except ImportError:
    sys.exit("error: compare.py needs numpy (and mitsuba to read EXR): run it with /work/venv-mitsuba/bin/python")


class CompareError(Exception):
    pass


def read_exr(path: Path) -> dict[str, np.ndarray]:
    """All channels of an EXR as float32 (h, w) arrays, by name."""
    if not path.is_file():
        raise CompareError(f"{path}: no such file")
    try:
        import mitsuba as mi
    except ImportError:
        raise CompareError("reading EXR needs mitsuba (run with /work/venv-mitsuba/bin/python)") from None
    if not mi.variant():
        mi.set_variant("scalar_rgb")
    try:
        bitmap = mi.Bitmap(str(path))
    except Exception as e:  # noqa: BLE001 - mitsuba raises plain RuntimeError with its own message
        raise CompareError(f"cannot read {path}: {e}") from None
    data = np.array(bitmap, dtype=np.float32, copy=True)
    if data.ndim == 2:
        data = data[:, :, None]
    names = [bitmap.struct_()[i].name for i in range(data.shape[2])]
    return {name: data[:, :, i] for i, name in enumerate(names)}


def rgb(channels: dict[str, np.ndarray], path: Path, layer: str = "") -> np.ndarray:
    prefix = f"{layer}." if layer else ""
    try:
        return np.stack([channels[prefix + c] for c in "RGB"], axis=2)
    except KeyError as e:
        raise CompareError(f"{path}: no channel {e}") from None


def silhouette_mask(ids: np.ndarray) -> np.ndarray:
    """True where every pixel of the 3×3 neighbourhood has the pixel's own (non-zero) surface id."""
    ids = np.rint(ids).astype(np.int64)
    padded = np.pad(ids, 1, mode="edge")
    h, w = ids.shape
    same = ids != 0
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            same &= padded[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w] == ids
    return same


def compare(
    image: np.ndarray,
    reference: np.ndarray,
    keep: np.ndarray,
    emission: np.ndarray | None,
    lit_threshold: float,
) -> tuple[dict, np.ndarray, np.ndarray]:
    """The metrics, the per-pixel relative error map (NaN where not compared) and the mask used."""
    ref_mean = reference.mean(axis=2)
    candidates = keep.copy()
    if emission is not None:
        candidates &= emission.max(axis=2) <= 0
    lit_level = float(np.percentile(ref_mean[candidates], 99)) if candidates.any() else 0.0
    mask = candidates & (ref_mean > lit_threshold * lit_level)
    if not mask.any():
        raise CompareError("no lit, non-silhouette, non-emitter pixels to compare")
    a, b = image[mask].astype(np.float64), reference[mask].astype(np.float64)
    diff = np.linalg.norm(a - b, axis=1)
    rel = diff / np.linalg.norm(b, axis=1)
    error_map = np.full(ref_mean.shape, np.nan, dtype=np.float32)
    error_map[mask] = rel
    metrics = {
        "pixels": int(mask.sum()),
        "pixels_total": int(mask.size),
        "lit_level_p99": lit_level,
        "per_pixel_rel_rmse": float(np.sqrt(np.mean(rel**2))),
        "per_pixel_rel_median": float(np.median(rel)),
        "per_pixel_rel_p95": float(np.percentile(rel, 95)),
        "energy_rel_rmse": float(np.sqrt(np.sum((a - b) ** 2) / np.sum(b**2))),
        "rel_bias": float((a.sum() - b.sum()) / b.sum()),
    }
    return metrics, error_map, mask


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], epilog=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("image", type=Path, help="the image judged (EXR, R G B)")
    parser.add_argument("reference", type=Path, help="the reference (EXR, R G B)")
    parser.add_argument("--ids", type=Path, help="EXR with a surface_id channel (sensorlight render --aovs) for the silhouette mask")
    parser.add_argument("--emission", type=Path, help="EXR with an emission.R/G/B layer, if neither input has one")
    parser.add_argument("--lit-threshold", type=float, default=0.01, help="lit: reference mean > this × its 99th percentile (default 0.01)")
    parser.add_argument("--layer", default="", help="channel group compared in both files (default: the main R, G, B)")
    parser.add_argument("--error-map", type=Path, help="write the per-pixel relative error as a one-channel EXR here (NaN where not compared)")
    parser.add_argument("--json", type=Path, help="also write the metrics as JSON here")
    parser.add_argument("--label", default="", help="a label printed before the figures")
    args = parser.parse_args(argv)
    if args.lit_threshold < 0:
        parser.error("--lit-threshold must be ≥ 0")
    try:
        a_ch, b_ch = read_exr(args.image), read_exr(args.reference)
        image, reference = rgb(a_ch, args.image, args.layer), rgb(b_ch, args.reference, args.layer)
        if image.shape != reference.shape:
            raise CompareError(f"{args.image} is {image.shape[1]}x{image.shape[0]} but {args.reference} is {reference.shape[1]}x{reference.shape[0]}")
        keep = np.ones(reference.shape[:2], dtype=bool)
        if args.ids:
            id_ch = read_exr(args.ids)
            if "surface_id" not in id_ch:
                raise CompareError(f"{args.ids}: no surface_id channel (render it with --aovs)")
            if id_ch["surface_id"].shape != keep.shape:
                raise CompareError(f"{args.ids}: size differs from the images")
            keep = silhouette_mask(id_ch["surface_id"])
        emission = None
        for source, channels in ((args.reference, b_ch), (args.image, a_ch)):
            if "emission.R" in channels:
                emission = rgb(channels, source, "emission")
                break
        if args.emission:
            emission = rgb(read_exr(args.emission), args.emission, "emission")
        metrics, error_map, _ = compare(image, reference, keep, emission, args.lit_threshold)
    except CompareError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    metrics.update(image=str(args.image), reference=str(args.reference), silhouettes_masked=bool(args.ids), emitters_masked=emission is not None)
    label = f"{args.label}: " if args.label else ""
    print(
        f"{label}per-pixel rel RMSE {metrics['per_pixel_rel_rmse']:.4f} (median {metrics['per_pixel_rel_median']:.4f}, "
        f"p95 {metrics['per_pixel_rel_p95']:.4f}), energy rel RMSE {metrics['energy_rel_rmse']:.4f}, "
        f"bias {metrics['rel_bias']:+.4f}, over {metrics['pixels']} of {metrics['pixels_total']} pixels"
    )
    if args.error_map:
        import mitsuba as mi

        mi.Bitmap(error_map[:, :, None], pixel_format=mi.Bitmap.PixelFormat.Y).write(str(args.error_map))
    if args.json:
        args.json.write_text(json.dumps(metrics, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
