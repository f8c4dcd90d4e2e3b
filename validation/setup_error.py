#!/usr/bin/env python3
"""The image error that the `mfs` set-up's choices buy (issue 12: set-up time against error).

Renders a few scenes of validation/mfs_validation.py's suite with `mfs` (4 spp, several seeds) and
prints each render's whole-image mean error and binned rel RMSE against the path-traced reference
(`nimbus compare --bin 4 --min-ref 0.05`, as docs/validation/render.md), and the set-up time the CLI
reports. Integrator options come from --set (JSON values), so the error of e.g. fewer photons is

    nice validation/setup_error.py --set photons=65536 --label p64k

References are rendered once (pathtrace, the suite's spp, capped at --ref-spp) into --refs.
"""
import argparse, json, os, statistics, subprocess, sys, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mfs_validation as mv  # noqa: E402

SCENES = ["disney_cloud", "disney_cloud_thin", "sphere_r10_a0.99_hg0.85_side", "sphere_r10_a0.99_hg0.85_front",
          "box_r5_a0.999_hg0.9_side_rgb", "sphere_r2_a0.99_hg0.85_side"]


def render(nimbus, scene, base_dir, block, spp, out, seed):
    s = dict(scene)
    s["integrator"] = dict(block, spp=spp, seed=seed)
    path = os.path.join(base_dir, f".mfs_validation_{os.getpid()}.json")
    json.dump(s, open(path, "w"))
    t0 = time.time()
    try:
        subprocess.run([nimbus, "render", path, "-o", out, "--quiet"], check=True)
    finally:
        os.remove(path)
    return time.time() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--nimbus", default=mv.NIMBUS)
    ap.add_argument("--refs", default=mv.REFS)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--set", action="append", default=[], help="integrator option KEY=JSON")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--label", default="mfs")
    ap.add_argument("--only", help="comma-separated scene names")
    ap.add_argument("--json", help="append the results to this JSON-lines file")
    args = ap.parse_args()
    block = {"type": "mfs"}
    for kv in args.set:
        k, v = kv.split("=", 1)
        block[k] = json.loads(v)
    os.makedirs(os.path.join(args.refs, "tmp"), exist_ok=True)
    suite = mv.suite()
    names = args.only.split(",") if args.only else SCENES
    for name in names:
        scene, base, ref_spp = suite[name]
        ref_spp = min(ref_spp, args.ref_spp)
        ref = os.path.join(args.refs, f"{name}_pt{ref_spp}.exr")
        if not os.path.exists(ref):
            t = render(args.nimbus, scene, base, {"type": "pathtrace"}, ref_spp, ref, 1)
            print(f"{name}: reference {ref_spp} spp in {t:.1f}s", flush=True)
        means, rmses, times = [], [], []
        for seed in range(1, args.seeds + 1):
            out = os.path.join(args.refs, "tmp", f"{name}_{args.label}_{seed}.exr")
            times.append(render(args.nimbus, scene, base, block, 4, out, seed))
            r = subprocess.run([args.nimbus, "compare", out, ref, "--bin", "4", "--min-ref", "0.05", "--json"],
                               check=True, capture_output=True, text=True)
            j = json.loads(r.stdout)
            means.append(j["mean_luminance_a"] / j["mean_luminance_b"] - 1.0)
            rmses.append(j["rel_rmse"])
        row = {"scene": name, "label": args.label, "set": args.set, "mean_error": means, "rel_rmse": rmses,
               "time_s": times}
        print(f"{name:32s} {args.label:12s} mean {' '.join(f'{m:+.4f}' for m in means)}  "
              f"rrmse {' '.join(f'{r:.4f}' for r in rmses)} (avg {statistics.mean(rmses):.4f})  "
              f"time {statistics.median(times):.2f}s", flush=True)
        if args.json:
            with open(args.json, "a") as f:
                f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
