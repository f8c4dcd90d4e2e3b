#!/usr/bin/python3
"""`pathtrace` against Tungsten (Benedikt Bitterli's renderer) on the homogeneous HG spheres of
bench/bench_pathtrace_efficiency.cpp: image means (the translation's check) and efficiency side by side.

Writes each scene twice, as a nimbus scene and as a Tungsten scene (Tungsten's own JSON format, written
here; nothing of Tungsten's is in this repository: README.md says how to build it), renders both K times
with independent seeds on one thread, alternating the two renderers, and prints per scene:
  mean            the image mean (pixels and channels) of the K renders together, with its standard error
  var/sample      the per-pixel sample variance across the K images times spp, averaged over pixels and
                  channels (background included), with a delete-one-seed jackknife standard error
  ns/sample       the render process's CPU time (user + sys, from the kernel's accounting of the child)
                  over its samples: the median over the K runs, and the same with the start-up (the median
                  CPU time of 1-spp renders) taken off
  efficiency      1 / (var/sample x ns/sample), and the ratio nimbus / Tungsten
and how well the two images agree in 8 x 8 pixel bins (z: differences in standard errors).

Usage:  /usr/bin/python3 validation/tungsten/side_by_side.py --tungsten /work/tungsten-src/build/tungsten
            [--nimbus build/bin/nimbus] [--spp 256] [-K 12] [--scenes front,side,back] [--keep DIR]
            [--tungsten-sobol] [--json FILE]
"""
import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from exr_reader import read_exr  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# name: (optical radius, albedo, HG g, the way the light travels) as in bench_pathtrace_efficiency.cpp
SCENES = {
    "front": ("sphere_r2_a0.99_hg0.85_front", 2.0, 0.99, 0.85, [0.2, 1, -0.25]),
    "side": ("sphere_r10_a0.99_hg0.85_side", 10.0, 0.99, 0.85, [1, 0, 0]),
    "back": ("sphere_r10_a0.99_hg0.85_back", 10.0, 0.99, 0.85, [0.2, -1, 0.25]),
}
RES, FOV_DEG, CAMERA = 48, 35.0, [0, -4, 0]
CAP_DEG = 0.5  # half-angle of Tungsten's light cap (it has no delta directional light)
MAX_BOUNCES = 1000000  # Tungsten's bounce limits (integrator and medium); nimbus has none by default


def nimbus_scene(tau, albedo, g, light):
    return {"camera": {"position": CAMERA, "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": FOV_DEG,
                       "width": RES, "height": RES},
            "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1},
                       "sigma_s": albedo * tau, "sigma_a": (1 - albedo) * tau,
                       "phase": {"type": "hg", "g": g}}],
            "lights": [{"type": "directional", "direction": light, "irradiance": 1.0}],
            "integrator": {"type": "pathtrace"}}


def cap_radiance(irradiance, cap_deg):
    """Radiance of a uniform cap of half-angle cap_deg giving `irradiance` on a surface facing it:
    E = L pi sin^2(theta) = L pi (1 - cos^2 theta), with cos theta as Tungsten computes it (float32), so
    that its light-sampling estimate L x 2 pi (1 - cos) (cos theta ~ 1 over the cap) carries no rounding."""
    c = float(np.cos(np.float32(np.deg2rad(np.float32(cap_deg)))))
    return irradiance / (math.pi * (1 - c * c))


def tungsten_scene(tau, albedo, g, light, sobol=False):
    """The same scene in Tungsten's format: the medium fills a unit sphere with an index-matched
    ("forward") boundary; the light is an infinite_sphere_cap of CAP_DEG around the direction it comes
    from (its +y axis, set by the transform's `up`). min_bounces 1 hides the cap from camera rays that
    miss the sphere (nimbus's directional light is not seen by the camera); no camera ray through the
    sphere points into the cap in these three scenes. sobol: Tungsten's default sampler (a Sobol sequence
    per pixel) instead of independent random numbers."""
    n = math.sqrt(sum(c * c for c in light))
    towards = [-c / n for c in light]
    return {
        "media": [{"name": "medium", "type": "homogeneous", "sigma_s": albedo * tau,
                   "sigma_a": (1 - albedo) * tau, "phase_function": {"type": "henyey_greenstein", "g": g},
                   "max_bounces": MAX_BOUNCES}],
        "bsdfs": [{"name": "boundary", "type": "forward", "albedo": 1}],
        "primitives": [
            {"name": "sphere", "type": "sphere", "int_medium": "medium", "bsdf": "boundary"},
            {"name": "sun", "type": "infinite_sphere_cap", "cap_angle": CAP_DEG, "sample": True,
             "transform": {"up": towards}, "emission": cap_radiance(1.0, CAP_DEG)}],
        "camera": {"type": "pinhole", "fov": FOV_DEG, "resolution": [RES, RES], "tonemap": "linear",
                   "reconstruction_filter": "box",
                   "transform": {"position": CAMERA, "look_at": [0, 0, 0], "up": [0, 0, 1]}},
        "integrator": {"type": "path_tracer", "min_bounces": 1, "max_bounces": MAX_BOUNCES,
                       "enable_light_sampling": True, "enable_volume_light_sampling": True,
                       "enable_consistency_checks": False, "enable_two_sided_shading": True},
        "renderer": {"output_file": "tungsten.png", "overwrite_output_files": True,
                     "adaptive_sampling": False, "enable_resume_render": False,
                     "stratified_sampler": sobol, "scene_bvh": True, "spp": 16, "spp_step": 16,
                     "checkpoint_interval": "0", "timeout": "0"},
    }


def read_pfm(path):
    """H x W x 3 float32, row 0 at the top, of a little-endian colour PFM (Tungsten writes bottom-up)."""
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF", "not a colour PFM"
        w, h = map(int, f.readline().split())
        assert float(f.readline()) < 0, "big-endian PFM"
        img = np.frombuffer(f.read(), "<f4").reshape(h, w, 3)
    return img[::-1].astype(np.float64)


def read_exr_rgb(path):
    """H x W x 3 float64 (R, G, B) of a nimbus EXR (validation/exr_reader.py)."""
    channels, _ = read_exr(path)
    return np.stack([channels[c] for c in "RGB"], axis=-1).astype(np.float64)


def run_cpu(cmd):
    """Run cmd; return the CPU seconds (user + sys) the child used."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def render_nimbus(nimbus, scene_path, out_dir, spp, seed):
    out = os.path.join(out_dir, f"nimbus_{seed}_{spp}.exr")
    cpu = run_cpu([nimbus, "render", scene_path, "-o", out, "--spp", str(spp), "--seed", str(seed),
                   "--threads", "1", "--quiet"])
    return read_exr_rgb(out), cpu


def render_tungsten(tungsten, scene_path, out_dir, spp, seed):
    out = os.path.join(out_dir, f"tungsten_{seed}_{spp}.pfm")
    cpu = run_cpu([tungsten, "-t", "1", "--seed", str(seed), "--spp", str(spp), "-d", out_dir,
                   "-o", os.path.join(out_dir, "tungsten.png"), "-e", out, scene_path])
    return read_pfm(out), cpu


def stats(images, cpus, startup, spp):
    """Mean, per-sample variance (with a jackknife standard error over seeds) and ns per sample."""
    stack = np.stack(images)  # K x H x W x 3
    K = len(images)
    pixels = stack.shape[1] * stack.shape[2]

    def var_per_sample(s):
        return float(np.mean(np.var(s, axis=0, ddof=1)) * spp)

    v = var_per_sample(stack)
    jack = [var_per_sample(np.delete(stack, k, axis=0)) for k in range(K)]
    v_se = math.sqrt((K - 1) / K * sum((j - statistics.fmean(jack)) ** 2 for j in jack))
    mean = float(stack.mean())
    mean_se = float(np.sqrt(np.var(stack.mean(axis=(1, 2, 3)), ddof=1) / K))
    cpu = statistics.median(cpus)
    return {"mean": mean, "mean_se": mean_se, "var": v, "var_se": v_se,
            "ns": cpu * 1e9 / (spp * pixels), "ns_net": (cpu - startup) * 1e9 / (spp * pixels),
            "ns_min": min(cpus) * 1e9 / (spp * pixels), "ns_max": max(cpus) * 1e9 / (spp * pixels),
            "startup_s": startup}


def binned_agreement(a, b, k=8):
    """The two renderers' K images averaged over k x k pixel bins: the rms and the largest |z| of their
    difference over the lit bins (mean above 5 % of the brightest), z in standard errors of the
    difference from the spread of the K images."""
    def bins(images):
        x = np.stack(images).mean(-1)
        return x.reshape(len(images), x.shape[1] // k, k, x.shape[2] // k, k).mean((2, 4))
    ba, bb = bins(a), bins(b)
    lit = ba.mean(0) > 0.05 * ba.mean(0).max()
    se = np.sqrt(ba.var(0, ddof=1) / len(ba) + bb.var(0, ddof=1) / len(bb))
    z = (ba.mean(0) - bb.mean(0))[lit] / se[lit]
    return float(np.sqrt(np.mean(z * z))), float(np.abs(z).max()), int(lit.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tungsten", required=True, help="the built tungsten binary")
    ap.add_argument("--nimbus", default=os.path.join(ROOT, "build", "bin", "nimbus"))
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("-K", type=int, default=12, help="independent seeds per renderer and scene")
    ap.add_argument("--startup-runs", type=int, default=3, help="1-spp renders to time the start-up")
    ap.add_argument("--scenes", default="front,side,back")
    ap.add_argument("--tungsten-sobol", action="store_true",
                    help="Tungsten with its default Sobol sampler (else independent random numbers, as nimbus)")
    ap.add_argument("--keep", help="write scenes and images here instead of a temporary folder")
    ap.add_argument("--json", help="also write the results here")
    args = ap.parse_args()

    work = args.keep or tempfile.mkdtemp(prefix="nimbus_tungsten_")
    os.makedirs(work, exist_ok=True)
    results = {}
    for key in args.scenes.split(","):
        name, tau, albedo, g, light = SCENES[key]
        d = os.path.join(work, key)
        os.makedirs(d, exist_ok=True)
        nscene, tscene = os.path.join(d, "nimbus.json"), os.path.join(d, "tungsten.json")
        json.dump(nimbus_scene(tau, albedo, g, light), open(nscene, "w"), indent=1)
        json.dump(tungsten_scene(tau, albedo, g, light, args.tungsten_sobol), open(tscene, "w"), indent=1)
        runners = {"nimbus": lambda spp, seed: render_nimbus(args.nimbus, nscene, d, spp, seed),
                   "tungsten": lambda spp, seed: render_tungsten(args.tungsten, tscene, d, spp, seed)}
        startup = {r: [] for r in runners}
        for i in range(args.startup_runs):
            for r in (("nimbus", "tungsten") if i % 2 == 0 else ("tungsten", "nimbus")):
                startup[r].append(runners[r](1, 90000 + i)[1])
        images, cpus = {r: [] for r in runners}, {r: [] for r in runners}
        for k in range(args.K):  # alternate the two renderers, and which goes first
            for r in (("nimbus", "tungsten") if k % 2 == 0 else ("tungsten", "nimbus")):
                img, cpu = runners[r](args.spp, 1000 + k)
                images[r].append(img)
                cpus[r].append(cpu)
        res = {r: stats(images[r], cpus[r], statistics.median(startup[r]), args.spp) for r in runners}
        for r in runners:
            res[r]["eff"] = 1e9 / (res[r]["var"] * res[r]["ns"])
            res[r]["eff_net"] = 1e9 / (res[r]["var"] * res[r]["ns_net"])
        res["bins_rms_z"], res["bins_max_z"], res["bins_lit"] = binned_agreement(images["nimbus"],
                                                                                  images["tungsten"])
        results[name] = res
        n, t = res["nimbus"], res["tungsten"]
        diff = (n["mean"] - t["mean"]) / math.hypot(n["mean_se"], t["mean_se"])
        print(f"{name}  (spp {args.spp}, K {args.K})")
        for r in runners:
            x = res[r]
            print(f"  {r:9s} mean {x['mean']:.5f} +- {x['mean_se']:.5f}  var/sample {x['var']:.4e} +- "
                  f"{x['var_se']:.1e}  ns/sample {x['ns']:.0f} [{x['ns_min']:.0f}, {x['ns_max']:.0f}] "
                  f"(start-up {x['startup_s']:.3f} s, net {x['ns_net']:.0f})  efficiency {x['eff']:.4e}")
        print(f"  means differ by {diff:+.2f} standard errors; 8 x 8 bins: rms z {res['bins_rms_z']:.2f}, max |z| "
              f"{res['bins_max_z']:.2f} over {res['bins_lit']} lit bins")
        print(f"  nimbus / Tungsten: variance "
              f"{n['var'] / t['var']:.3f}, time {n['ns'] / t['ns']:.3f} (net {n['ns_net'] / t['ns_net']:.3f}), "
              f"efficiency {n['eff'] / t['eff']:.2f} (net {n['eff_net'] / t['eff_net']:.2f})", flush=True)
    if args.json:
        json.dump(results, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
