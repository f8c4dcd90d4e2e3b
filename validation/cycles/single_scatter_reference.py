"""Deterministic single-scattering reference for one homogeneous sphere or box (numpy only).

For max_events = 1 scenes with directional and point lights this integrates, per pixel,

    L = sum over lights  int_{t0}^{t1} sigma_s T(cam, x) p(cos) E_light T(x, light) dt

with Gauss-Legendre quadrature along the ray (T analytic: exp(-sigma_t * chord)) and n x n
stratified positions inside each pixel (the one-pixel box filter), plus the environment seen
through the medium. It shares no code with nimbus or Cycles and so adjudicates between them.

    /usr/bin/python3 validation/cycles/single_scatter_reference.py SCENE.json OUT.npy [--sub 8] [--nodes 64]
"""
import argparse
import json
import math

import numpy as np


def rgb(v):
    return np.array([float(v)] * 3 if isinstance(v, (int, float)) else [float(x) for x in v])


def hg(cos, g):
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * cos) ** 1.5)


def phase_eval(phase, cos):
    kind = phase.get("type", "isotropic")
    if kind == "isotropic":
        return np.full_like(cos, 1.0 / (4.0 * math.pi))
    if kind == "hg":
        return hg(cos, phase["g"])
    if kind == "double_hg":
        return phase["w"] * hg(cos, phase["g1"]) + (1.0 - phase["w"]) * hg(cos, phase["g2"])
    raise ValueError(f"phase {kind} not supported")


def intersect(shape, o, d):
    """Entry/exit distances (t0, t1) of rays o + t d (arrays (..., 3)); t1 <= t0 means a miss."""
    if shape["type"] == "sphere":
        c = np.array(shape.get("center", [0, 0, 0]), float)
        oc = o - c
        b = np.sum(oc * d, -1)
        disc = b * b - (np.sum(oc * oc, -1) - shape["radius"] ** 2)
        s = np.sqrt(np.maximum(disc, 0.0))
        t0, t1 = -b - s, -b + s
        miss = disc <= 0.0
    elif shape["type"] == "box":
        lo, hi = np.array(shape["min"], float), np.array(shape["max"], float)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / d
            ta, tb = (lo - o) * inv, (hi - o) * inv
        t0 = np.nanmax(np.minimum(ta, tb), -1)
        t1 = np.nanmin(np.maximum(ta, tb), -1)
        miss = t1 <= t0
    else:
        raise ValueError(f"shape {shape['type']} not supported")
    t0 = np.maximum(t0, 0.0)
    t1 = np.where(miss, t0, np.maximum(t1, t0))
    return t0, t1


def render(scene, sub=8, nodes=64):
    cam = scene["camera"]
    (medium,) = scene["media"]
    sigma_s, sigma_a = rgb(medium["sigma_s"]), rgb(medium.get("sigma_a", 0.0))
    sigma_t = sigma_s + sigma_a
    phase = medium.get("phase", {"type": "isotropic"})
    W, H = cam["width"], cam["height"]
    pos = np.array(cam["position"], float)
    fwd = np.array(cam["look_at"], float) - pos
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.array(cam.get("up", [0, 0, 1]), float))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    tan_half = math.tan(math.radians(cam["fov_y_deg"]) / 2)
    xs, gw = np.polynomial.legendre.leggauss(nodes)
    env = np.zeros(3)
    for light in scene["lights"]:
        if light["type"] == "environment":
            env = rgb(light["radiance"])
    img = np.zeros((H, W, 3))
    j = (np.arange(sub) + 0.5) / sub
    for y in range(H):
        px = (np.arange(W)[:, None, None] + j[None, None, :]) * np.ones((1, sub, 1))
        py = (y + j[None, :, None]) * np.ones((W, 1, sub))
        sx = (2 * px / W - 1) * tan_half * W / H
        sy = (1 - 2 * py / H) * tan_half
        d = fwd + sx[..., None] * right + sy[..., None] * up
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        o = np.broadcast_to(pos, d.shape)
        t0, t1 = intersect(medium["shape"], o, d)
        # Quadrature nodes along [t0, t1]: shape (..., nodes).
        half = 0.5 * (t1 - t0)
        t = 0.5 * (t0 + t1)[..., None] + half[..., None] * xs
        x = o[..., None, :] + t[..., None] * d[..., None, :]
        L = np.zeros(d.shape[:-1] + (3,))
        for light in scene["lights"]:
            if light["type"] == "directional":
                wi = -np.array(light["direction"], float)
                wi = np.broadcast_to(wi / np.linalg.norm(wi), x.shape)
                E = rgb(light["irradiance"])
                if light.get("angular_diameter_deg", 0.0) != 0.0:
                    raise ValueError("only angular_diameter_deg = 0 here")
                dist2 = None
            elif light["type"] == "point":
                v = np.array(light["position"], float) - x
                dist2 = np.sum(v * v, -1)
                wi = v / np.sqrt(dist2)[..., None]
                E = rgb(light["intensity"])
            else:
                continue
            a0, a1 = intersect(medium["shape"], x, wi)
            if dist2 is not None:
                a1 = np.minimum(a1, np.sqrt(dist2))
            chord = np.maximum(a1 - a0, 0.0)
            f = phase_eval(phase, np.sum(wi * d[..., None, :], -1))
            geo = 1.0 if dist2 is None else 1.0 / dist2
            for c in range(3):
                integrand = (sigma_s[c] * np.exp(-sigma_t[c] * (t - t0[..., None])) * f * E[c] * geo
                             * np.exp(-sigma_t[c] * chord))
                L[..., c] += half * np.sum(integrand * gw, -1)
        # The environment seen through the medium (single scattering of it is not included).
        L += env * np.exp(-sigma_t * (t1 - t0)[..., None])
        img[y] = L.mean(axis=(1, 2))
    if np.any(env > 0) and np.any(sigma_s > 0):
        raise ValueError("environment in-scattering is not part of this reference")
    return img.astype(np.float32)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("scene")
    p.add_argument("output")
    p.add_argument("--sub", type=int, default=8, help="n x n positions per pixel")
    p.add_argument("--nodes", type=int, default=64, help="Gauss-Legendre nodes per ray")
    a = p.parse_args()
    with open(a.scene) as f:
        scene = json.load(f)
    if scene.get("integrator", {}).get("max_events", 0) != 1:
        raise SystemExit("single_scatter_reference.py: the scene must have max_events = 1")
    np.save(a.output, render(scene, a.sub, a.nodes))


if __name__ == "__main__":
    main()
