#!/usr/bin/env python3
"""Validation of `mfs` and the `octave` baseline against the path-traced reference.

Renders small scenes (validation/scenes/*.json and the Disney cloud at low resolution) with pathtrace
(reference, cached in validation/refs/, git-ignored), single, mfs (each option) and octave; writes the
table in docs/validation/render.md (between the markers) and side-by-side PNGs.

    validation/mfs_validation.py [--ref-spp 4096] [--only SCENE] [--fast]
Heavy: run with `nice`. Needs build/bin/nimbus.
"""
import argparse, json, os, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NIMBUS = os.path.join(ROOT, "build", "bin", "nimbus")
SCENES = os.path.join(ROOT, "validation", "scenes")
REFS = os.path.join(ROOT, "validation", "refs")
DOCS = os.path.join(ROOT, "docs", "validation")
TMP = os.path.join(ROOT, "validation", "refs", "tmp")

# (label, integrator block, spp)
CONFIGS = [
    ("single", {"type": "single"}, 4),
    ("octave", {"type": "octave"}, 4),
    ("mfs", {"type": "mfs"}, 4),
    ("mfs beer_lambert", {"type": "mfs", "light_path": "beer_lambert"}, 4),
    ("mfs gaussian", {"type": "mfs", "propagator": "gaussian"}, 4),
    ("mfs f=0.5", {"type": "mfs", "peak_fraction": 0.5}, 4),
    ("mfs f=0.93", {"type": "mfs", "peak_fraction": 0.93}, 4),
]


def scenes():
    out = []
    for f in sorted(os.listdir(SCENES)):
        if f.endswith(".json"):
            out.append((f[:-5], json.load(open(os.path.join(SCENES, f))), SCENES))
    cloud = json.load(open(os.path.join(ROOT, "scenes", "disney_cloud.json")))
    cloud["camera"]["width"], cloud["camera"]["height"] = 64, 48
    out.append(("disney_cloud_64", cloud, os.path.join(ROOT, "scenes")))
    return out


def render(scene, base_dir, block, spp, out, extra=()):
    s = dict(scene)
    s["integrator"] = dict(block, spp=spp, seed=1)
    path = os.path.join(base_dir, ".mfs_validation_tmp.json")  # relative VDB paths resolve from base_dir
    json.dump(s, open(path, "w"))
    t0 = time.time()
    subprocess.run(["nice", NIMBUS, "render", path, "-o", out, "--quiet", *extra], check=True)
    dt = time.time() - t0
    os.remove(path)
    return dt


def compare(a, b):
    r = subprocess.run([NIMBUS, "compare", a, b, "--bin", "4", "--min-ref", "0.05", "--json"],
                       check=True, capture_output=True, text=True)
    j = json.loads(r.stdout)
    return j["mean_luminance_a"] / j["mean_luminance_b"] - 1.0, j["rel_rmse"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--only")
    args = ap.parse_args()
    os.makedirs(TMP, exist_ok=True)
    rows = []
    for name, scene, base in scenes():
        if args.only and args.only != name:
            continue
        ref = os.path.join(REFS, f"{name}_pt{args.ref_spp}.exr")
        if not os.path.exists(ref):
            t = render(scene, base, {"type": "pathtrace"}, args.ref_spp, ref)
            print(f"{name}: reference {args.ref_spp} spp in {t:.1f}s", flush=True)
        render(scene, base, {"type": "pathtrace"}, 256, os.path.join(DOCS, f"mfs_{name}_pathtrace.png"), ("--exposure", "2"))
        for label, block, spp in CONFIGS:
            out = os.path.join(TMP, f"{name}_{label.replace(' ', '_')}.exr")
            t = render(scene, base, block, spp, out)
            mean, rrmse = compare(out, ref)
            rows.append((name, label, mean, rrmse, t))
            print(f"{name:20s} {label:20s} mean {mean:+.3f} rrmse {rrmse:.3f} time {t:.2f}s", flush=True)
            if label in ("single", "octave", "mfs"):
                render(scene, base, block, spp, os.path.join(DOCS, f"mfs_{name}_{label}.png"), ("--exposure", "2"))
        # Equal-time path tracing: as many spp as the mfs render took.
        mfs_t = [r[4] for r in rows if r[0] == name and r[1] == "mfs"][0]
        pt_probe = render(scene, base, {"type": "pathtrace"}, 16, os.path.join(TMP, "probe.exr"))
        spp = max(1, int(16 * mfs_t / max(pt_probe, 1e-3)))
        out = os.path.join(TMP, f"{name}_pt_equal.exr")
        t = render(scene, base, {"type": "pathtrace"}, spp, out)
        mean, rrmse = compare(out, ref)
        rows.append((name, f"pathtrace {spp} spp", mean, rrmse, t))
        print(f"{name:20s} pathtrace {spp:5d} spp  mean {mean:+.3f} rrmse {rrmse:.3f} time {t:.2f}s", flush=True)
    table = ["| scene | integrator | mean error | rel RMSE (4x4 bins) | time [s] |", "|---|---|---|---|---|"]
    for name, label, mean, rrmse, t in rows:
        table.append(f"| {name} | {label} | {mean:+.1%} | {rrmse:.1%} | {t:.2f} |")
    text = "\n".join(table)
    print(text)
    open(os.path.join(REFS, "table.md"), "w").write(text + "\n")


if __name__ == "__main__":
    main()
