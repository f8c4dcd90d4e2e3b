#!/usr/bin/env python3
"""Loads the Disney cloud, renders it with mfs and with pathtrace, and compares the two.

    PYTHONPATH=build/python python3 examples/disney_cloud.py --out out/ [--size 160] [--spp 64]

The scene is scenes/disney_cloud.json (the Walt Disney Animation Studios cloud at 1/16 resolution, from
data/volumes/) at a smaller size. Prints each render's mean pixel value and time, and mfs's error against
pathtrace: the relative difference of the means and the relative RMSE over pixels (sqrt(mean((m - p)^2))
/ mean(p)), which at low spp also holds pathtrace's own noise. Writes disney_cloud.png: the two renders
and their difference."""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import nimbus

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def compare(mfs, ref):
    m, p = mfs[..., :3].astype(np.float64), ref[..., :3].astype(np.float64)
    mean_p = p.mean()
    return {"mean_mfs": m.mean(), "mean_pathtrace": mean_p, "rel_mean": (m.mean() - mean_p) / mean_p,
            "rel_rmse": float(np.sqrt(np.mean((m - p) ** 2)) / mean_p)}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", default="out", help="folder for disney_cloud.png")
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes", "disney_cloud.json"))
    p.add_argument("--size", type=int, default=160, help="image width [pixels]; height keeps the aspect")
    p.add_argument("--spp", type=int, default=64, help="pathtrace samples per pixel")
    p.add_argument("--mfs-spp", type=int, default=16)
    p.add_argument("--mfs-photons", type=int, default=None, help="mfs scatter grid photons (default: mfs's)")
    p.add_argument("--mfs-grid", type=int, default=None, help="mfs scatter grid resolution (default: auto)")
    args = p.parse_args()
    scene = nimbus.load_scene(args.scene)
    height = max(1, round(args.size * scene.height / scene.width))
    size = {"camera.width": args.size, "camera.height": height}
    scene = nimbus.load_scene(args.scene, overrides=size)
    # mfs's own settings belong in an mfs integrator block.
    mfs_settings = {"integrator.type": "mfs", "integrator.spp": args.mfs_spp}
    if args.mfs_photons:
        mfs_settings["integrator.photons"] = args.mfs_photons
    if args.mfs_grid:
        mfs_settings["integrator.scatter_grid_resolution"] = args.mfs_grid
    mfs = nimbus.render(nimbus.load_scene(args.scene, overrides={**size, **mfs_settings}))
    ref = nimbus.render(scene, integrator="pathtrace", spp=args.spp)
    c = compare(mfs["rgba"], ref["rgba"])
    print(f"mfs       {mfs['spp']:5d} spp {mfs['seconds']:7.2f} s  mean {c['mean_mfs']:.5f}")
    print(f"pathtrace {ref['spp']:5d} spp {ref['seconds']:7.2f} s  mean {c['mean_pathtrace']:.5f}")
    print(f"mfs - pathtrace: mean {100 * c['rel_mean']:+.2f} %, relative RMSE {100 * c['rel_rmse']:.2f} %")
    os.makedirs(args.out, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.2))
    show = lambda im: np.clip(im[..., :3] / max(1e-9, float(np.percentile(ref["rgba"][..., :3], 99.5))), 0, 1)
    axes[0].imshow(show(mfs["rgba"]) ** (1 / 2.2))
    axes[0].set_title(f"mfs, {mfs['spp']} spp, {mfs['seconds']:.1f} s")
    axes[1].imshow(show(ref["rgba"]) ** (1 / 2.2))
    axes[1].set_title(f"pathtrace, {ref['spp']} spp, {ref['seconds']:.1f} s")
    diff = (mfs["rgba"][..., :3] - ref["rgba"][..., :3]).mean(axis=2)
    lim = max(1e-9, float(np.abs(diff).max()))
    im = axes[2].imshow(diff, cmap="RdBu_r", vmin=-lim, vmax=lim)
    axes[2].set_title("mfs - pathtrace")
    fig.colorbar(im, ax=axes[2], fraction=0.046)
    for ax in axes:
        ax.axis("off")
    fig.tight_layout()
    path = os.path.join(args.out, "disney_cloud.png")
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")
    return c


if __name__ == "__main__":
    main()
