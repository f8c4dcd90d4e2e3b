#!/usr/bin/env python3
"""Rings of an `mfs` render against a reference on a lit sphere's near, far and middle thirds (issue 12;
docs/validation/render.md, "Far sides: the traced beam's loss against the straight beam").

For a scene of validation/mfs_validation.py's suite at RES x RES: renders `mfs` (4 spp) with each --variant's
options, and the reference `pathtrace` at --pt-spp (with --orders, also `max_wide_scatters` K and `mfs`
`large_angle_scatters` K for K = 0..3). Prints, per image, the ratio of its light to the reference's, minus 1,
in rings of pixels from the disc's rim (0-4, 4-12, 12-30, 30-80, 80+ at 512 x 512, scaled with RES) on the
side towards the light (x < -0.3 r from the disc's centre, the light coming from -x in the image), the far
side (x > +0.3 r) and between. Renders already in --out are kept.

    nice validation/far_side_rings.py --out /tmp/rings --variant b0=beam_photons=0 --orders
"""
import argparse, json, os, sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mfs_validation as mv  # noqa: E402
from cloud_edge import lum  # noqa: E402

RINGS = ((0, 4), (4, 12), (12, 30), (30, 80), (80, 10000))  # pixels at 512 x 512


def render(scene, base, block, spp, out, seed):
    """mfs_validation's render, unless `out` is already there."""
    if not os.path.exists(out):
        mv.render(scene, base, block, spp, out, seed=seed)


def luminance(path):
    return lum(path).astype(float)


def rings(image, ref, scale):
    """{side: [ratio - 1 per ring]} of `image` against `ref` (luminance arrays)."""
    h, w = ref.shape
    yy, xx = np.mgrid[0:h, 0:w]
    disc = ref > 0.05 * ref.mean()
    cy, cx = yy[disc].mean(), xx[disc].mean()
    r = np.sqrt(disc.sum() / np.pi)
    depth = r - np.hypot(yy - cy, xx - cx)
    sides = {"near": xx < cx - 0.3 * r, "far": xx > cx + 0.3 * r, "mid": abs(xx - cx) <= 0.3 * r}
    out = {}
    for name, sel in sides.items():
        row = []
        for lo, hi in RINGS:
            s = sel & disc & (depth >= lo * scale) & (depth < hi * scale)
            row.append(image[s].sum() / ref[s].sum() - 1.0 if ref[s].sum() > 0 else float("nan"))
        out[name] = row
    return out


def show(label, rr):
    print(f"{label:28s} " + " ; ".join(f"{k}: " + " ".join(f"{v:+.3f}" for v in row) for k, row in rr.items()),
          flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--scene", default="sphere_r2_a0.99_hg0.85_side")
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--pt-spp", type=int, default=2048)
    ap.add_argument("--variant", action="append", default=[], help="TAG=FIELD=JSON (repeatable)")
    ap.add_argument("--orders", action="store_true", help="also K <= 0..3 of both renderers")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    scene, base, _ = mv.suite()[args.scene]
    sc = mv.sized(scene, args.res, args.res)
    tag = os.path.join(args.out, f"{args.scene}_{args.res}")
    ref_path = f"{tag}_pt.exr"
    render(sc, base, {"type": "pathtrace"}, args.pt_spp, ref_path, 7)
    ref, scale = luminance(ref_path), args.res / 512.0
    print(f"rings (pixels at 512 x 512, scaled by {scale:g}): " + ", ".join(f"{a}-{b}" for a, b in RINGS))
    variants = [("defaults", {})]
    for v in args.variant:
        t, field, value = v.split("=", 2)
        variants.append((t, {field: json.loads(value)}))
    for t, opts in variants:
        out = f"{tag}_mfs_{t}.exr"
        render(sc, base, dict({"type": "mfs"}, **opts), 4, out, 1)
        show(f"mfs {t}", rings(luminance(out), ref, scale))
    if args.orders:
        for k in range(4):
            pt = f"{tag}_pt_K{k}.exr"
            render(sc, base, {"type": "pathtrace", "max_wide_scatters": k}, args.pt_spp, pt, 7)
            for t, opts in variants:
                out = f"{tag}_mfs_{t}_K{k}.exr"
                render(sc, base, dict({"type": "mfs", "large_angle_scatters": k}, **opts), 4, out, 1)
                show(f"K <= {k} mfs {t}", rings(luminance(out), luminance(pt), scale))


if __name__ == "__main__":
    main()
