#!/usr/bin/env python3
"""Draws docs/images/architecture.png: the layers of nimbus (left, the folder include graph measured by
scripts/check_layers.py --graph) and the life of one camera ray through the code (right).

    /usr/bin/python3 scripts/architecture_diagram.py
"""
import os, subprocess, sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyBboxPatch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAYERS = [  # (folder, row, column, what it holds)
    ("apps", 6, 0.5, "the CLI: render, compare, info,\nbeam, slab, convert (prints, exits)"),
    ("io", 5, 0.0, "scene JSON, VDB/NanoVDB files,\nEXR/PNG, atomic writes"),
    ("render", 5, 1.0, "the driver: camera rays,\ntiles, the film, the header"),
    ("integrators", 4, 0.5, "registry; pathtrace, single, mfs, octave;\ntracking, photon tracer, grids"),
    ("scene", 3, 0.5, "camera, lights, SceneContext"),
    ("transport", 2, 0.5, "MFS kernel, small-angle propagators,\nphase split, photon MC for beams"),
    ("media", 1, 0.5, "media, density grids, majorants,\nphase functions, the procedural cloud"),
    ("core", 0, 0.5, "math, rays, rng, JSON reading,\nnode grids, checks"),
]
RAY = [
    "render() resolves the settings:\nthe scene's integrator block + overrides",
    "registry: parse the block (strict)\nand construct the integrator",
    "integrator precomputes: shadow maps,\nphoton grids (mfs), in the thread arena",
    "driver, per tile and pixel: R2 position,\nRng(seed, pixel, sample)",
    "PinholeCamera::generate_ray(px, py)\n-> Ray{o, d}",
    "Integrator::Li(ray, rng): march or\ntrack through SceneContext's media",
    "Film::add_sample(x, y, L)\n(non-finite dropped, counted)",
    "Film::resolve() -> Image; header:\nresolved block, scene as rendered",
]


def box(ax, x, y, w, h, title, body, colour):
    ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.02", fc=colour, ec="#333",
                                lw=1.0))
    ax.text(x, y + h * 0.22, title, ha="center", va="center", fontsize=10, weight="bold")
    ax.text(x, y - h * 0.15, body, ha="center", va="center", fontsize=7.2)


def main():
    out = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "check_layers.py"), "--graph"],
                         capture_output=True, text=True).stdout
    edges = set()
    for line in out.splitlines():
        if " -> " in line:
            a, rest = line.split(" -> ")
            edges.add((a.strip(), rest.split()[0]))
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 7.5), gridspec_kw={"width_ratios": [1.15, 1]})
    pos = {}
    for name, row, col, body in LAYERS:
        x, y = 0.2 + col * 0.6, 0.06 + row * 0.135
        pos[name] = (x, y)
        box(ax, x, y, 0.5 if name not in ("io", "render") else 0.42, 0.105, name if name != "apps" else "apps/nimbus",
            body, "#dbe9f6" if name not in ("io", "render") else "#e8f3e0")
    # The public API beside everything.
    box(ax, 0.98, 0.40, 0.28, 0.3, "include/nimbus",
        "the public API:\nscene, render, image,\ncompare, error;\nself-contained\n(src/ is private)", "#f6ecd8")
    for (a, b) in sorted(edges):
        if a in pos and b in pos:
            (x0, y0), (x1, y1) = pos[a], pos[b]
            ax.annotate("", xy=(x1, y1 + 0.055), xytext=(x0, y0 - 0.055),
                        arrowprops=dict(arrowstyle="->", color="#777", lw=0.7, alpha=0.7,
                                        connectionstyle="arc3,rad=0.12"))
    ax.set_xlim(-0.12, 1.15)
    ax.set_ylim(-0.02, 0.97)
    ax.axis("off")
    ax.set_title("Layers: an arrow is 'includes' (measured); each folder includes only folders below it",
                 fontsize=9.5)
    for i, text in enumerate(RAY):
        y = 0.92 - i * 0.118
        box(ax2, 0.5, y, 0.86, 0.09, f"{i + 1}", text, "#f3e3e8" if i in (4, 5, 6) else "#eeeeee")
        if i + 1 < len(RAY):
            ax2.annotate("", xy=(0.5, y - 0.073), xytext=(0.5, y - 0.046), arrowprops=dict(arrowstyle="->"))
    ax2.set_xlim(0, 1)
    ax2.set_ylim(0.0, 0.98)
    ax2.axis("off")
    ax2.set_title("The life of one render and one camera ray", fontsize=9.5)
    fig.tight_layout()
    path = os.path.join(ROOT, "docs", "images", "architecture.png")
    fig.savefig(path, dpi=110)
    print(path)


if __name__ == "__main__":
    main()
