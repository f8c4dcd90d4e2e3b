#!/usr/bin/python3
"""Large volumes: time and memory of `mfs` and `pathtrace` against voxel count and image size (issue 12).

Builds the Disney cloud at 1/16 upsampled N times per axis (`nimbus convert --upsample N`: the same
trilinear density field on N^3 times the voxels, so the image stays the same and only the cost changes;
N = 4 is 64x the voxels, the 1/4 cloud's resolution) into a scratch directory, renders
scenes/disney_cloud.json (sun + sky) on each with `mfs` and `pathtrace` at several image sizes, and
records for each render the CPU time (user + sys), wall time and peak RSS from /usr/bin/time. One
thread (--threads 1), so CPU time is the work itself; `nice -n 10`.

Set-up is measured as docs/benchmarks.md's set-up section does: a 4 x 3, 1-spp render is the scene load
(`pathtrace`) or the load plus the set-up (`mfs`: shadow maps, photon grids); the per-pixel cost of a
render is its CPU time less that of the 4 x 3 render with the same integrator and volume. The images are
checked: each integrator's render of the upsampled cloud against the same render of the original
(`nimbus compare --bin 4 --min-ref 0.05`), beside two seeds on the original (the noise floor).

    bench/volume_scaling.py                      # ~40 min on 2 loaded cores (9 min of CPU)
    bench/volume_scaling.py --factors 1,2 --sizes 64x48 --big none --spp-mfs 1 --spp-pt 1   # a smoke run

Writes bench/results/volume_scaling.json and docs/images/volume_scaling.png (paths: --json, --plot).
"""
import argparse, datetime, json, os, platform, re, shutil, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def parse_size(s):
    m = re.fullmatch(r"(\d+)x(\d+)", s)
    if not m:
        sys.exit(f"volume_scaling.py: bad image size {s!r} (want WIDTHxHEIGHT)")
    return int(m.group(1)), int(m.group(2))


def timed(cmd):
    """Runs cmd under /usr/bin/time and nice; returns (cpu s, wall s, peak RSS MB, stdout)."""
    full = ["/usr/bin/time", "-f", "@@TIME %e %U %S %M", "nice", "-n", "10"] + cmd
    p = subprocess.run(full, capture_output=True, text=True)
    line = [l for l in p.stderr.splitlines() if l.startswith("@@TIME")]
    if p.returncode != 0 or not line:
        sys.exit(f"volume_scaling.py: failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr[-2000:]}")
    wall, user, sys_, rss_kb = line[-1].split()[1:]
    return float(user) + float(sys_), float(wall), float(rss_kb) / 1024.0, p.stdout


def grid_info(nimbus, path):
    out = subprocess.run([nimbus, "info", path], capture_output=True, text=True, check=True).stdout
    voxels = int(re.search(r"active voxels\s+(\d+)", out).group(1))
    tiles = int(re.search(r"active tiles\s+(\d+)", out).group(1))
    return voxels, tiles


def compare(nimbus, a, b):
    out = subprocess.run([nimbus, "compare", "--json", "--bin", "4", "--min-ref", "0.05", a, b],
                         capture_output=True, text=True, check=True).stdout
    m = json.loads(out)
    return {"mean_rel_error": m["mean_luminance_a"] / m["mean_luminance_b"] - 1.0, "rel_rmse": m["rel_rmse"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nimbus", default=os.path.join(ROOT, "build", "bin", "nimbus"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "scenes", "disney_cloud.json"))
    ap.add_argument("--volume", default=os.path.join(ROOT, "data", "volumes", "wdas_cloud_sixteenth.vdb"))
    ap.add_argument("--factors", default="1,2,3,4", help="upsampling factors per axis")
    ap.add_argument("--sizes", default="160x120,320x240,640x480", help="image sizes for both integrators")
    ap.add_argument("--big", default="1920x1080", help="an extra size for mfs only ('none': skip)")
    ap.add_argument("--spp-mfs", type=int, default=4)
    ap.add_argument("--spp-pt", type=int, default=4)
    ap.add_argument("--spp-big", type=int, default=1, help="mfs spp at the --big size")
    ap.add_argument("--check-size", default="320x240", help="the size whose images are compared")
    ap.add_argument("--work", default=None, help="scratch directory (default: a new one under $TMPDIR)")
    ap.add_argument("--keep", action="store_true", help="keep the scratch directory")
    ap.add_argument("--replot", action="store_true",
                    help="only rewrite the plot (and derived numbers) from the existing --json")
    ap.add_argument("--json", default=os.path.join(ROOT, "bench", "results", "volume_scaling.json"))
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "images", "volume_scaling.png"))
    args = ap.parse_args()
    if args.replot:
        with open(args.json) as f:
            result = json.load(f)
        result["derived"] = derive(result)
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
        plot(result, args.plot)
        return
    factors = [int(f) for f in args.factors.split(",")]
    if factors[0] != 1:
        sys.exit("volume_scaling.py: --factors must start with 1 (the original cloud: the ratios' base)")
    sizes = [parse_size(s) for s in args.sizes.split(",")]
    big = None if args.big == "none" else parse_size(args.big)
    check = parse_size(args.check_size)
    for f in (args.nimbus, args.scene, args.volume):
        if not os.path.exists(f):
            sys.exit(f"volume_scaling.py: {f}: no such file")
    work = args.work or tempfile.mkdtemp(prefix="nimbus_volume_scaling_")
    os.makedirs(work, exist_ok=True)
    print(f"scratch: {work}", flush=True)

    # 1. The volumes.
    volumes = []
    for n in factors:
        path = os.path.join(work, f"cloud_x{n}.nvdb")
        cpu, wall, rss, _ = timed([args.nimbus, "convert", args.volume, path, "--upsample", str(n)])
        voxels, tiles = grid_info(args.nimbus, path)
        volumes.append({"factor": n, "file": path, "active_voxels": voxels, "tiles": tiles,
                        "file_mb": os.path.getsize(path) / 2**20, "convert_cpu_s": cpu, "convert_rss_mb": rss})
        print(f"x{n}: {voxels} active voxels, {tiles} tiles, {volumes[-1]['file_mb']:.1f} MB file, "
              f"convert {cpu:.1f} s CPU, {rss:.0f} MB", flush=True)

    # 2. The renders: each configuration for every volume in turn, so the load drifts over all alike.
    def render(n, integrator, w, h, spp, seed=1, tag=""):
        out = os.path.join(work, f"{integrator}_x{n}_{w}x{h}_{spp}spp{tag}.exr")
        cmd = [args.nimbus, "render", args.scene, "--quiet", "--threads", "1", "--integrator", integrator,
               "--spp", str(spp), "--seed", str(seed), "--res", f"{w}x{h}",
               "--set", f"media.0.shape.file={os.path.join(work, f'cloud_x{n}.nvdb')}", "-o", out]
        cpu, wall, rss, _ = timed(cmd)
        runs.append({"factor": n, "integrator": integrator, "width": w, "height": h, "spp": spp, "seed": seed,
                     "cpu_s": cpu, "wall_s": wall, "rss_mb": rss})
        if integrator == "mfs":  # the resolution "auto" chose (it sets the photon grids' memory)
            header = subprocess.run([args.nimbus, "info", out], capture_output=True, text=True).stdout
            m = re.search(r'"scatter_grid_resolution":(\d+)', header)
            runs[-1]["scatter_grid_resolution"] = int(m.group(1)) if m else None
        with open(os.path.join(work, "runs.json"), "w") as f:  # kept as it goes (--work DIR --keep)
            json.dump({"volumes": volumes, "runs": runs}, f, indent=1)
        print(f"  {integrator:9s} x{n} {w}x{h} {spp} spp seed {seed}: {cpu:7.2f} s CPU {wall:7.2f} s wall "
              f"{rss:6.0f} MB", flush=True)
        return out

    runs = []
    configs = [("pathtrace", 4, 3, 1), ("mfs", 4, 3, 1)]
    configs += [(i, w, h, args.spp_mfs if i == "mfs" else args.spp_pt) for (w, h) in sizes
                for i in ("mfs", "pathtrace")]
    if big:
        configs.append(("mfs", big[0], big[1], args.spp_big))
    images = {}
    for (integrator, w, h, spp) in configs:
        for n in factors:
            images[(integrator, n, w, h)] = render(n, integrator, w, h, spp)

    # 3. Like with like: each upsampled cloud's image against the original's, beside the noise floor.
    checks = []
    cw, ch = check
    for integrator in ("mfs", "pathtrace"):
        spp = args.spp_mfs if integrator == "mfs" else args.spp_pt
        if (integrator, 1, cw, ch) not in images:
            continue
        ref = images[(integrator, 1, cw, ch)]
        other_seed = render(1, integrator, cw, ch, spp, seed=2, tag="_seed2")
        checks.append(dict(integrator=integrator, factor=1, against="x1, seed 2", width=cw, height=ch,
                           **compare(args.nimbus, other_seed, ref)))
        for n in factors[1:]:
            checks.append(dict(integrator=integrator, factor=n, against="x1", width=cw, height=ch,
                               **compare(args.nimbus, images[(integrator, n, cw, ch)], ref)))
    for c in checks:
        print(f"  {c['integrator']:9s} x{c['factor']} vs {c['against']}: mean {100 * c['mean_rel_error']:+.2f} %, "
              f"binned rel RMSE {100 * c['rel_rmse']:.2f} %", flush=True)

    result = {
        "what": "bench/volume_scaling.py: the 1/16 Disney cloud upsampled N x per axis, scenes/disney_cloud.json",
        "date": datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC"),
        "machine": f"{platform.node()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end",
        "threads": 1, "spp_mfs": args.spp_mfs, "spp_pathtrace": args.spp_pt,
        "volumes": [{k: v for k, v in vol.items() if k != "file"} for vol in volumes],
        "runs": runs, "image_checks": checks}
    result["derived"] = derive(result)
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, "w") as f:
        json.dump(result, f, indent=1)
    print(f"wrote {args.json}")
    plot(result, args.plot)
    print(f"wrote {args.plot}")
    if not args.keep and not args.work:
        shutil.rmtree(work)


def derive(r):
    """Set-up and per-sample costs from the runs: the 4 x 3 renders are the fixed costs."""
    fixed = {(x["integrator"], x["factor"]): x["cpu_s"] for x in r["runs"] if x["width"] == 4}
    voxels = {v["factor"]: v["active_voxels"] for v in r["volumes"]}
    fixed_costs = [{"factor": n, "active_voxels": voxels[n], "load_cpu_s": fixed[("pathtrace", n)],
                    "mfs_setup_cpu_s": fixed[("mfs", n)] - fixed[("pathtrace", n)]} for n in sorted(voxels)]
    per_sample = [{"factor": x["factor"], "integrator": x["integrator"], "width": x["width"],
                   "height": x["height"], "spp": x["spp"],
                   "ns_per_sample": 1e9 * (x["cpu_s"] - fixed[(x["integrator"], x["factor"])]) /
                   (x["width"] * x["height"] * x["spp"])}
                  for x in r["runs"] if x["width"] != 4 and x["seed"] == 1]
    return {"fixed": fixed_costs, "per_sample": per_sample}


def plot(r, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    vox = {v["factor"]: v["active_voxels"] / 1e6 for v in r["volumes"]}
    runs = [x for x in r["runs"] if x["seed"] == 1]
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    styles = {"mfs": "-", "pathtrace": "--"}
    sizes = sorted({(x["width"], x["height"]) for x in runs}, key=lambda s: s[0] * s[1])
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for integrator in ("mfs", "pathtrace"):
        for i, (w, h) in enumerate(sizes):
            rs = sorted((x for x in runs if x["integrator"] == integrator and (x["width"], x["height"]) == (w, h)),
                        key=lambda x: x["factor"])
            if not rs:
                continue
            label = f"{integrator} {w}x{h}" if w > 4 else f"{integrator} 4x3 (fixed cost)"
            xs = [vox[x["factor"]] for x in rs]
            ax[0].plot(xs, [x["cpu_s"] for x in rs], styles[integrator], marker="o", color=colors[i], label=label)
            ax[1].plot(xs, [x["rss_mb"] for x in rs], styles[integrator], marker="o", color=colors[i], label=label)
    ax[0].set(xscale="log", yscale="log", xlabel="active voxels (millions)", ylabel="CPU time, s (1 thread)",
              title="time against voxel count")
    ax[1].set(xscale="log", xlabel="active voxels (millions)", ylabel="peak RSS, MB",
              title="memory against voxel count")
    # Per-sample cost against pixel count, one line per volume.
    for n in sorted(vox):
        for integrator in ("mfs", "pathtrace"):
            pts = sorted((d["width"] * d["height"], d["ns_per_sample"]) for d in r["derived"]["per_sample"]
                         if d["factor"] == n and d["integrator"] == integrator)
            if pts:
                ax[2].plot([p[0] for p in pts], [p[1] / 1e3 for p in pts], styles[integrator], marker="o",
                           color=colors[sorted(vox).index(n)], label=f"{integrator}, {vox[n]:.1f} M voxels")
    ax[2].set(xscale="log", yscale="log", xlabel="pixels", ylabel="CPU per sample, us (set-up excluded)",
              title="per-sample cost against image size")
    for a in ax:
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle("Disney cloud 1/16 upsampled 1-4x per axis (same field, 1-61x the voxels): "
                 f"mfs {r['spp_mfs']} spp, pathtrace {r['spp_pathtrace']} spp, 1 thread")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
