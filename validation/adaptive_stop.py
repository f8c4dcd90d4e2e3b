#!/usr/bin/env python3
"""Adaptive sampling's whole-image mean (render --noise): does the stop darken the image? (issue 12)

Renders scenes adaptively with `pathtrace` at each noise target over many seeds, with two nimbus builds
alternating seed by seed (A B A B, one thread each, CPU time), and compares each render with a uniform
reference (16384 spp; the cloud's 8192) (validation/refs/, made as mfs_validation.py makes them: two merged sample ranges whose
difference gives the reference's own noise). Per build and target: the whole-image mean error averaged
over seeds with its standard error (the spread over seeds / sqrt(seeds)), the binned rel RMSE (4 x 4
bins, --min-ref 0.05; RMS over seeds, the reference's noise removed in quadrature), mean CPU seconds and
spp, and err^2 x CPU (the cost to reach a given error, for errors falling as 1/sqrt(time)). A uniform
render at a fixed spp over the same seeds shows the spread of an unbiased render.

  python3 validation/adaptive_stop.py --old /tmp/old/nimbus --new build/bin/nimbus --seeds 24 \\
      --targets 0.2,0.1,0.05 --scenes sphere,cloud --json out.json
"""
import argparse, json, math, os, resource, statistics, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mfs_validation as mv  # noqa: E402  (scenes and references)


def scenes():
    sphere = mv.homogeneous("sphere", 2, 0.99, mv.hg(0.85), mv.SIDE, res=64)
    cloud_scene, base, _ = mv.cloud(0.2)
    cloud_scene = mv.sized(cloud_scene, 48, 36)
    return {"sphere": ("sphere_r2_a0.99_hg0.85_side_64", sphere[0], sphere[1], 16384),
            "cloud": ("disney_cloud_48x36", cloud_scene, base, 8192)}


def render(binary, scene, base, seed, extra, out):
    s = dict(scene)
    s["integrator"] = {"type": "pathtrace", "seed": seed}
    path = os.path.join(base, f".adaptive_stop_{os.getpid()}.json")
    json.dump(s, open(path, "w"))
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        p = subprocess.run([binary, "render", path, "-o", out, "--threads", "1", *extra], check=True,
                           capture_output=True, text=True)
    finally:
        os.remove(path)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    spp = None
    for word in p.stderr.split("adaptive:")[-1].split()[:1]:
        try:
            spp = float(word)
        except ValueError:
            pass
    return r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime, spp


def summary(rows, ref_noise):
    n = len(rows)
    means = [r["mean_err"] for r in rows]
    sd = statistics.stdev(means) if n > 1 else float("nan")
    rms = math.sqrt(max(0.0, sum(r["rel_rmse"] ** 2 for r in rows) / n - ref_noise ** 2))
    cpu = sum(r["cpu"] for r in rows) / n
    spp = [r["spp"] for r in rows if r["spp"] is not None]
    return {"seeds": n, "mean_err": sum(means) / n, "se": sd / math.sqrt(n), "sd": sd, "rel_rmse": rms,
            "cpu": cpu, "spp": sum(spp) / len(spp) if spp else None, "err2_cpu": rms * rms * cpu}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True, help="nimbus binary A")
    ap.add_argument("--new", required=True, help="nimbus binary B")
    ap.add_argument("--seeds", default="24", help="seeds per target: one number, or one per target (24,16,8)")
    ap.add_argument("--targets", default="0.2,0.1,0.05")
    ap.add_argument("--scenes", default="sphere,cloud")
    ap.add_argument("--uniform-spp", type=int, default=16, help="the uniform render (0: none)")
    ap.add_argument("--json", default=None, help="write every render's numbers here")
    args = ap.parse_args()
    targets = [float(t) for t in args.targets.split(",")]
    seeds = [int(s) for s in args.seeds.split(",")]
    seeds = seeds * len(targets) if len(seeds) == 1 else seeds
    all_scenes = scenes()
    results = {}
    tmp = tempfile.mkdtemp(prefix="adaptive_stop_")
    for name in args.scenes.split(","):
        tag, scene, base, ref_spp = all_scenes[name]
        ref, ref_noise = mv.reference(tag, scene, base, ref_spp)
        print(f"{name}: reference {ref} (its noise {100 * ref_noise:.2f} %)", flush=True)
        runs = [(f"noise {t}", ["--noise", str(t)], n) for t, n in zip(targets, seeds)]
        if args.uniform_spp:
            runs.append((f"uniform {args.uniform_spp}", ["--spp", str(args.uniform_spp)], max(seeds)))
        for label, extra, n_seeds in runs:
            rows = {"old": [], "new": []}
            for seed in range(1, n_seeds + 1):
                for which, binary in (("old", args.old), ("new", args.new)):
                    out = os.path.join(tmp, f"{which}.exr")
                    cpu, spp = render(binary, scene, base, seed, extra, out)
                    m, r, _ = mv.compare(out, ref)
                    rows[which].append({"seed": seed, "mean_err": m, "rel_rmse": r, "cpu": cpu, "spp": spp})
            for which in ("old", "new"):
                s = summary(rows[which], ref_noise)
                results[f"{name} {label} {which}"] = {"summary": s, "runs": rows[which]}
                print(f"{name:7s} {label:12s} {which}: mean error {100 * s['mean_err']:+.2f} % "
                      f"+- {100 * s['se']:.2f} (sd {100 * s['sd']:.1f}, {s['seeds']} seeds), rel RMSE "
                      f"{100 * s['rel_rmse']:.2f} %, CPU {s['cpu']:.2f} s, spp {s['spp']}, "
                      f"err^2 x CPU {1e4 * s['err2_cpu']:.2f}", flush=True)
            if args.json:
                json.dump(results, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
