#!/usr/bin/env python3
"""Sweeps the single-scattering albedo of a sphere of cloud and plots the whole-image brightness.

    PYTHONPATH=build/python python3 examples/albedo_sweep.py --out out/ [--size 96] [--spp 16]

Renders the same sphere (sigma_t fixed, albedo = sigma_s / sigma_t swept) with `mfs` and `pathtrace`,
and writes albedo_sweep.png: the mean pixel value (linear, RGB mean) against the albedo, one curve per
integrator, and prints the table. The brightness rises steeply towards albedo 1, where multiple
scattering carries most of the light: the regime where mfs's approximations matter."""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import nimbus


def sphere_scene(albedo, size, sigma_t=8.0):
    return {
        "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 35,
                   "width": size, "height": size},
        "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1},
                   "sigma_s": sigma_t * albedo, "sigma_a": sigma_t * (1 - albedo),
                   "phase": {"type": "hg", "g": 0.85}}],
        "lights": [{"type": "directional", "direction": [-0.5, 0.5, -0.707], "irradiance": 3.0}],
        "integrator": {"type": "pathtrace", "spp": 16, "seed": 1},
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", default="out", help="folder for albedo_sweep.png")
    p.add_argument("--size", type=int, default=96, help="image side [pixels]")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--albedos", default="0.2,0.5,0.8,0.9,0.95,0.99,0.999")
    p.add_argument("--integrators", default="mfs,pathtrace")
    args = p.parse_args()
    albedos = [float(a) for a in args.albedos.split(",")]
    integrators = args.integrators.split(",")
    brightness = {name: [] for name in integrators}
    for a in albedos:
        scene = nimbus.scene_from_dict(sphere_scene(a, args.size))
        for name in integrators:
            r = nimbus.render(scene, integrator=name, spp=args.spp)
            brightness[name].append(float(r["rgba"][..., :3].mean()))
        print(f"albedo {a:6.3f}: " + "  ".join(f"{n} {brightness[n][-1]:.5f}" for n in integrators))
    os.makedirs(args.out, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for name in integrators:
        ax.plot(albedos, brightness[name], "o-", label=name)
    ax.set_xlabel("single-scattering albedo")
    ax.set_ylabel("mean pixel value (linear)")
    ax.set_title(f"HG 0.85 sphere, sigma_t = 8, {args.size}x{args.size}, {args.spp} spp")
    ax.legend()
    fig.tight_layout()
    path = os.path.join(args.out, "albedo_sweep.png")
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")
    return brightness


if __name__ == "__main__":
    main()
