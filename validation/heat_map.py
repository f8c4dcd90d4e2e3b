#!/usr/bin/env python3
"""Heat maps of `mfs` against a cached reference (issue 12; docs/validation/render.md, "512 x 512"): for a
scene of validation/mfs_validation.py's suite at RES x RES, renders `mfs` (seed 1) with each --variant's
options and draws (mfs - reference) / mean(reference) over 4 x 4-pixel bins, full colour at +-50 % (red:
`mfs` brighter), one panel per variant. The reference is validation/refs/NAME_RESxRES_ptSPP.exr (made by
mfs_validation.py --size-frontier or the suite run); prints each panel's binned rel RMSE and mean error.

    nice validation/heat_map.py sphere_r10_a0.99_hg0.85_back --res 512 --ref-spp 2048 --spp 1 \\
        --variant edge_samples=1 --variant edge_samples=16 --out docs/validation/render/backlit_r10_512_edges.png
"""
import argparse, json, os, sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import mfs_validation as mv  # noqa: E402
from cloud_edge import lum  # noqa: E402


def bins(a, k=4):
    h, w = a.shape
    return a[:h // k * k, :w // k * k].reshape(h // k, k, w // k, k).mean(axis=(1, 3))


def options(text):
    """'key=value,key=value' -> {key: JSON value (or the text)}."""
    out = {}
    for kv in filter(None, text.split(",")):
        k, v = kv.split("=", 1)
        try:
            out[k] = json.loads(v)
        except json.JSONDecodeError:
            out[k] = v
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--variant", action="append", default=[], help="mfs options, key=value,...")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    scene, base, _ = mv.suite()[args.scene]
    sc = mv.sized(scene, args.res, args.res)
    ref = bins(lum(os.path.join(mv.REFS, f"{args.scene}_{args.res}x{args.res}_pt{args.ref_spp}.exr")).astype(float))
    sel = ref >= 0.05 * ref.mean()
    variants = args.variant or [""]
    fig, axes = plt.subplots(1, len(variants), figsize=(4.2 * len(variants), 4.2), squeeze=False)
    os.makedirs(mv.TMP, exist_ok=True)
    for ax, v in zip(axes[0], variants):
        out = os.path.join(mv.TMP, f"heat_{args.scene}_{args.res}_{v.replace('=', '-').replace(',', '_')}.exr")
        mv.render(sc, base, dict({"type": "mfs"}, **options(v)), args.spp, out, seed=1)
        a = bins(lum(out).astype(float))
        err = np.sqrt(np.mean((a - ref)[sel] ** 2)) / ref[sel].mean()
        mean = a.mean() / ref.mean() - 1.0
        print(f"{v or 'default'}: binned rel RMSE {100 * err:.1f} %, mean {100 * mean:+.1f} %")
        ax.imshow((a - ref) / ref.mean(), cmap="bwr", vmin=-0.5, vmax=0.5)
        ax.set_title(f"{v or 'default'}: {100 * err:.1f} %", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    plt.savefig(args.out, dpi=72, bbox_inches="tight")


if __name__ == "__main__":
    main()
