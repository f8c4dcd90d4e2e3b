#!/usr/bin/env python3
"""Refactoring guard: renders a fixed set of small scenes with every integrator and option, and compares
each image pixel for pixel with the same renders by another build.

    validation/regress.py render DIR [--nimbus build/bin/nimbus]   # renders the set into DIR
    validation/regress.py compare BASE NEW                          # exit 1 unless every image matches

A refactor that claims "images unchanged" renders the set with the build before it and after it and
compares: `nimbus compare --bin 1` must report equal RGB means and zero binned
(1 x 1) relative and maximum errors for each image (per-pixel luminance: only a change that keeps every
pixel's luminance and the image's channel means would slip through). Scenes: the validation suite's
homogeneous spheres and box (validation/mfs_validation.py) at 20 x 20, the Disney cloud at 32 x 24, a
point light and the demo. About two minutes on 2 cores.
"""
import argparse, json, os, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "validation"))
import mfs_validation as mv  # noqa: E402

BLOCKS = {  # name: (integrator block, spp)
    "pt": ({"type": "pathtrace"}, 2),
    "pt_k1": ({"type": "pathtrace", "max_wide_scatters": 1}, 2),
    "single": ({"type": "single"}, 2),
    "single_map": ({"type": "single", "transmittance": "shadow_map", "shadow_map_resolution": 24}, 2),
    "octave": ({"type": "octave"}, 2),
    "mfs": ({"type": "mfs"}, 2),
    "mfs_k1": ({"type": "mfs", "large_angle_scatters": 1}, 1),
    "mfs_k0": ({"type": "mfs", "large_angle_scatters": 0}, 1),
    "mfs_light": ({"type": "mfs", "forward_side": "light"}, 1),
    "mfs_opts": ({"type": "mfs", "photon_transport": "similarity", "scatter_grid_bands": 2, "beam_photons": 0,
                  "path_lengthening": True, "filtered_lookups": True, "peak_fraction": 0.5}, 1),
    "mfs_bl": ({"type": "mfs", "light_path": "beer_lambert", "propagator": "gaussian", "light_blur": False}, 1),
}


def scenes():
    out = {}
    for name in ["sphere_r1_a0.9_hg0.7_side", "sphere_r10_a0.99_hg0.85_back", "sphere_r10_a0.999_dhg_side",
                 "box_r5_a0.999_hg0.9_side_rgb"]:
        s, base, _ = mv.suite()[name]
        s = json.loads(json.dumps(s))
        s["camera"]["width"] = s["camera"]["height"] = 20
        out[name] = (s, base)
    s, base, _ = mv.cloud(0.2)
    s["camera"]["width"], s["camera"]["height"] = 32, 24
    out["cloud"] = (s, base)
    s, base, _ = mv.homogeneous("sphere", 3, 0.95, mv.hg(0.8), mv.SIDE, res=20)
    s["lights"] = [{"type": "point", "position": [2, -2, 1], "intensity": [4, 3, 2]},
                   {"type": "environment", "radiance": 0.1}]
    out["point_env"] = (s, base)
    return out


def render(args):
    os.makedirs(args.dir, exist_ok=True)
    for sname, (scene, base) in scenes().items():
        for bname, (block, spp) in BLOCKS.items():
            s = dict(scene, integrator=dict(block, spp=spp, seed=7))
            path = os.path.join(base, f".regress_{os.getpid()}.json")
            with open(path, "w") as f:
                json.dump(s, f)
            try:
                subprocess.run([args.nimbus, "render", path, "-o", os.path.join(args.dir, f"{sname}.{bname}.exr"),
                                "--quiet", "--threads", "2"], check=True)
            finally:
                os.remove(path)
    subprocess.run([args.nimbus, "render", "-o", os.path.join(args.dir, "demo.exr"), "--quiet", "--spp", "2"],
                   check=True, env=dict(os.environ))
    subprocess.run([args.nimbus, "render", "-o", os.path.join(args.dir, "demo_mfs.exr"), "--quiet", "--spp", "1",
                    "--integrator", "mfs"], check=True)


def compare(args):
    bad = 0
    names = sorted(n for n in os.listdir(args.base) if n.endswith(".exr"))
    for n in names:
        r = subprocess.run([args.nimbus, "compare", os.path.join(args.new, n), os.path.join(args.base, n),
                            "--bin", "1", "--json"], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{n}: compare failed: {r.stderr.strip()}")
            bad += 1
            continue
        j = json.loads(r.stdout)
        same = (j["mean_a"] == j["mean_b"] and j["rel_rmse"] == 0 and j["max_abs_rel_error"] == 0)
        if not same:
            bad += 1
        print(f"{n}: {'same' if same else 'DIFFERENT'} mean_rel_error {j['mean_rel_error']:+.3e} rel_rmse {j['rel_rmse']:.3e}")
    print(f"{len(names) - bad} passed, {bad} failed")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("dir")
    r.add_argument("--nimbus", default=os.path.join(ROOT, "build", "bin", "nimbus"))
    c = sub.add_parser("compare")
    c.add_argument("base")
    c.add_argument("new")
    c.add_argument("--nimbus", default=os.path.join(ROOT, "build", "bin", "nimbus"))
    args = ap.parse_args()
    if args.cmd == "render":
        render(args)
        return 0
    return compare(args)


if __name__ == "__main__":
    sys.exit(main())
