#!/usr/bin/env python3
"""The picture of docs/compositing.md: a transparent-film render's alpha, and the render composited over a
background plate (a dusk gradient with a hill line), in linear light.

    build/bin/nimbus render scene.json -o cloud.exr          # a scene with "film": {"transparent": true}
    build/bin/nimbus convert --alpha cloud.exr cloud.png     # RGBA PNG, straight colour
    /usr/bin/python3 scripts/alpha_composite.py cloud.png out.png
"""
import sys

import matplotlib.image as mi
import numpy as np


def linear(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb(c):
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def main(src, dst):
    a = mi.imread(src)
    if a.ndim != 3 or a.shape[2] != 4:
        raise SystemExit(f"{src}: not an RGBA PNG (convert with --alpha)")
    h, w = a.shape[:2]
    y = np.linspace(0.0, 1.0, h)[:, None, None]
    plate = (1 - y) * np.array([0.20, 0.28, 0.55]) + y * np.array([0.85, 0.45, 0.25])
    x = np.linspace(0.0, 1.0, w)[None, :]
    hill = 0.82 - 0.06 * np.sin(6 * x) - 0.03 * np.sin(17 * x + 1)
    plate = np.broadcast_to(np.where(y > hill[..., None], np.array([0.05, 0.06, 0.05]), plate), (h, w, 3))
    colour, alpha = linear(a[..., :3]), a[..., 3:4]
    over = colour * alpha + plate * (1 - alpha)  # straight colour: C A + B (1 - A)
    mi.imsave(dst, np.concatenate([srgb(np.repeat(alpha, 3, axis=2)), srgb(over)], axis=1))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    main(sys.argv[1], sys.argv[2])
