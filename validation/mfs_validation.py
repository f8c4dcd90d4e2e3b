#!/usr/bin/env python3
"""Validation of `mfs` (each option), `single` and the `octave` baseline against the path tracer.

The suite (issue 4): homogeneous spheres and a box of optical radius 1 to 50, albedo 0.9 to 0.9999,
HG g 0.7 to 0.95 and a double HG, light from the side, the front (behind the camera) and the back,
chromatic coefficients, and the Disney cloud at two densities. For each scene:
  - a converged pathtrace reference (cached in validation/refs/, git-ignored) and a second, independent
    half-spp render whose difference estimates the reference's own noise;
  - every deterministic configuration: whole-image mean error (luminance), relative RMSE over 4x4 bins
    with reference >= 5 % of the mean (`nimbus compare --bin 4 --min-ref 0.05`), wall time;
  - pathtrace at 4, 16, 64 spp (error against time), from which the time path tracing needs to reach
    the rel RMSE of `mfs` is read off (rel RMSE ~ c / sqrt(spp)): the equal-error speed-up.
Writes docs/validation/render_results.json, the tables in docs/validation/render.md (between markers),
render_suite.png (reference | mfs | octave | single | mfs error) and render_error_time.png.

    nice validation/mfs_validation.py [--only NAME] [--scale 1.0]
Needs build/bin/nimbus, /usr/bin/python3 with numpy + matplotlib. ~1 h on 2 cores (references).
"""
import argparse, json, math, os, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NIMBUS = os.path.join(ROOT, "build", "bin", "nimbus")
REFS = os.path.join(ROOT, "validation", "refs")
DOCS = os.path.join(ROOT, "docs", "validation")
TMP = os.path.join(REFS, "tmp")
IMG = os.path.join(DOCS, "render")

CONFIGS = [  # (label, integrator block, spp)
    ("mfs", {"type": "mfs"}, 4),
    ("mfs K=1", {"type": "mfs", "large_angle_scatters": 1}, 4),
    ("mfs K=2", {"type": "mfs", "large_angle_scatters": 2}, 4),
    ("mfs K=3", {"type": "mfs", "large_angle_scatters": 3}, 4),
    ("mfs similarity photons", {"type": "mfs", "photon_transport": "similarity"}, 4),
    ("mfs light side", {"type": "mfs", "forward_side": "light"}, 4),
    ("mfs L1 grid", {"type": "mfs", "scatter_grid_bands": 2}, 4),
    ("mfs straight beam", {"type": "mfs", "beam_photons": 0}, 4),
    ("mfs collimated beam", {"type": "mfs", "light_blur": False}, 4),
    ("mfs filtered lookups", {"type": "mfs", "filtered_lookups": True}, 4),
    ("mfs path lengthening", {"type": "mfs", "path_lengthening": True}, 4),
    ("mfs beer_lambert", {"type": "mfs", "light_path": "beer_lambert"}, 4),
    ("mfs gaussian", {"type": "mfs", "propagator": "gaussian"}, 4),
    ("mfs f=0", {"type": "mfs", "peak_fraction": 0.0}, 4),
    ("octave", {"type": "octave"}, 4),
    ("single", {"type": "single"}, 4),
]
PT_SPP = [4, 16, 64]

SIDE, FRONT, BACK = [1, 0, 0], [0.2, 1, -0.25], [0.2, -1, 0.25]


def homogeneous(shape, tau, albedo, phase, light, res=48, chroma=None, ref_spp=2048):
    """Unit sphere / box (half-size 1) of optical radius tau seen from 4 units."""
    ss = albedo * tau
    sa = (1 - albedo) * tau
    if chroma:
        ss = [ss * c for c in chroma]
    geo = ({"type": "sphere", "center": [0, 0, 0], "radius": 1} if shape == "sphere"
           else {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]})
    return ({"camera": {"position": [0, -4, 0] if shape == "sphere" else [-2.2, -4, 1.6], "look_at": [0, 0, 0],
                        "up": [0, 0, 1], "fov_y_deg": 35 if shape == "sphere" else 45, "width": res, "height": res},
             "media": [{"shape": geo, "sigma_s": ss, "sigma_a": sa, "phase": phase}],
             "lights": [{"type": "directional", "direction": light, "irradiance": 1.0}]},
            ROOT, ref_spp)


def hg(g):
    return {"type": "hg", "g": g}


def cloud(sigma_s):
    s = json.load(open(os.path.join(ROOT, "scenes", "disney_cloud.json")))
    s["camera"]["width"], s["camera"]["height"] = 64, 48
    s["media"][0]["sigma_s"] = sigma_s
    return s, os.path.join(ROOT, "scenes"), 2048


def suite():
    return {
        "sphere_r1_a0.9_hg0.7_side": homogeneous("sphere", 1, 0.9, hg(0.7), SIDE),
        "sphere_r2_a0.99_hg0.85_side": homogeneous("sphere", 2, 0.99, hg(0.85), SIDE),
        "sphere_r2_a0.99_hg0.85_front": homogeneous("sphere", 2, 0.99, hg(0.85), FRONT),
        "sphere_r10_a0.99_hg0.85_side": homogeneous("sphere", 10, 0.99, hg(0.85), SIDE),
        "sphere_r10_a0.99_hg0.85_front": homogeneous("sphere", 10, 0.99, hg(0.85), FRONT),
        "sphere_r10_a0.99_hg0.85_back": homogeneous("sphere", 10, 0.99, hg(0.85), BACK, ref_spp=8192),
        "sphere_r10_a0.999_dhg_side": homogeneous("sphere", 10, 0.999,
                                                  {"type": "double_hg", "g1": 0.9, "g2": -0.4, "w": 0.85}, SIDE),
        "box_r5_a0.999_hg0.9_side_rgb": homogeneous("box", 5, 0.999, hg(0.9), SIDE, chroma=[0.8, 1.0, 1.25]),
        "sphere_r20_a0.9999_hg0.95_back": homogeneous("sphere", 20, 0.9999, hg(0.95), BACK, res=32, ref_spp=16384),
        "sphere_r50_a0.9999_hg0.85_side": homogeneous("sphere", 50, 0.9999, hg(0.85), SIDE, res=32, ref_spp=512),
        "disney_cloud": cloud(0.2),
        "disney_cloud_thin": cloud(0.05),
    }


def render(scene, base_dir, block, spp, out, seed=1):
    s = dict(scene)
    s["integrator"] = dict(block, spp=spp, seed=seed)
    path = os.path.join(base_dir, f".mfs_validation_{os.getpid()}.json")  # relative paths resolve from base_dir
    json.dump(s, open(path, "w"))
    t0 = time.time()
    try:
        subprocess.run([NIMBUS, "render", path, "-o", out, "--quiet"], check=True)
    finally:
        os.remove(path)
    return time.time() - t0


def compare(a, b):
    r = subprocess.run([NIMBUS, "compare", a, b, "--bin", "4", "--min-ref", "0.05", "--json"],
                       check=True, capture_output=True, text=True)
    j = json.loads(r.stdout)
    return j["mean_luminance_a"] / j["mean_luminance_b"] - 1.0, j["rel_rmse"], j["mean_luminance_b"]


def png(exr, out, exposure, heat_ref=None):
    if heat_ref:
        subprocess.run([NIMBUS, "compare", exr, heat_ref, "--heatmap", out, "--heatmap-range", "0.5"], check=True,
                       capture_output=True)
    else:
        subprocess.run([NIMBUS, "convert", exr, out, "--exposure", f"{exposure:.3f}"], check=True)


def pathtrace_fit(runs, noise):
    """Path tracing's rel RMSE against the reference ~ sqrt(c2 / spp + noise^2), its time ~ t0 + k spp,
    fitted through the first and last of `runs` (increasing spp). Returns (c2, k, t0)."""
    last, first = runs[-1], runs[0]
    c2 = max(last["rel_rmse"] ** 2 - noise ** 2, 1e-12) * last["spp"]
    k = max((last["time_s"] - first["time_s"]) / (last["spp"] - first["spp"]), 1e-9)
    t0 = max(first["time_s"] - k * first["spp"], 0.0)
    return c2, k, t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--only")
    ap.add_argument("--orders", action="store_true", help="only the order-by-order comparison")
    ap.add_argument("--tables", action="store_true", help="only rewrite tables and plots from the results")
    ap.add_argument("--size-study", action="store_true", help="only the 160x120 equal-error study")
    args = ap.parse_args()
    if args.size_study:
        os.makedirs(TMP, exist_ok=True)
        return size_study()
    if args.orders:
        os.makedirs(TMP, exist_ok=True)
        return orders()
    os.makedirs(TMP, exist_ok=True)
    os.makedirs(IMG, exist_ok=True)
    results_path = os.path.join(DOCS, "render_results.json")
    results = json.load(open(results_path)) if os.path.exists(results_path) else {}
    if args.tables:
        size_table()
        write_table(results)
        return plots(results)
    for name, (scene, base, ref_spp) in suite().items():
        if args.only and args.only not in name:
            continue
        ref = os.path.join(REFS, f"{name}_pt{ref_spp}.exr")
        half = os.path.join(REFS, f"{name}_pt{ref_spp // 2}_seed2.exr")
        if not os.path.exists(ref):
            t = render(scene, base, {"type": "pathtrace"}, ref_spp, ref)
            print(f"{name}: reference {ref_spp} spp in {t:.1f}s", flush=True)
        if not os.path.exists(half):
            render(scene, base, {"type": "pathtrace"}, ref_spp // 2, half, seed=2)
        _, half_rrmse, ref_mean = compare(half, ref)
        noise = half_rrmse / math.sqrt(3.0)  # var(half - full) = 3 var(full)
        exposure = math.log2(0.3 / max(ref_mean, 1e-12))
        r = {"reference_spp": ref_spp, "reference_noise_rel_rmse": noise, "configs": {}, "pathtrace": []}
        png(ref, os.path.join(IMG, f"{name}_reference.png"), exposure)
        for label, block, spp in CONFIGS:
            out = os.path.join(TMP, f"{name}_{label.replace(' ', '_').replace('=', '')}.exr")
            t = render(scene, base, block, spp, out)
            mean, rrmse, _ = compare(out, ref)
            r["configs"][label] = {"mean_error": mean, "rel_rmse": rrmse, "time_s": t}
            print(f"{name:34s} {label:18s} mean {mean:+.3f} rrmse {rrmse:.3f} time {t:.2f}s", flush=True)
            if label in ("mfs", "octave", "single"):
                png(out, os.path.join(IMG, f"{name}_{label}.png"), exposure)
            if label == "mfs":
                png(out, os.path.join(IMG, f"{name}_mfs_error.png"), 0, heat_ref=ref)
        for spp in PT_SPP:
            out = os.path.join(TMP, f"{name}_pt{spp}.exr")
            t = render(scene, base, {"type": "pathtrace"}, spp, out, seed=3)
            mean, rrmse, _ = compare(out, ref)
            r["pathtrace"].append({"spp": spp, "mean_error": mean, "rel_rmse": rrmse, "time_s": t})
            print(f"{name:34s} pathtrace {spp:4d} spp  mean {mean:+.3f} rrmse {rrmse:.3f} time {t:.2f}s", flush=True)
        c2, k, t0 = pathtrace_fit(r["pathtrace"], noise)
        for label, c in r["configs"].items():
            target2 = c["rel_rmse"] ** 2 - noise ** 2
            if target2 <= 0:
                c["pathtrace_equal_error_time_s"] = None
                continue
            spp_needed = c2 / target2
            c["pathtrace_equal_error_spp"] = spp_needed
            c["pathtrace_equal_error_time_s"] = t0 + k * spp_needed
            c["speedup"] = c["pathtrace_equal_error_time_s"] / c["time_s"]
        results[name] = r
        json.dump(results, open(results_path, "w"), indent=1, sort_keys=True)
    write_table(results)
    plots(results)


ORDER_SCENES = ["sphere_r2_a0.99_hg0.85_side", "sphere_r10_a0.99_hg0.85_side", "sphere_r10_a0.99_hg0.85_front",
                "sphere_r10_a0.99_hg0.85_back", "sphere_r20_a0.9999_hg0.95_back", "disney_cloud"]


def write_between_markers(name, text):
    """Replaces what lies between <!-- name --> and <!-- /name --> in docs/validation/render.md."""
    doc = os.path.join(DOCS, "render.md")
    if not os.path.exists(doc):
        return
    d = open(doc).read()
    a, b = d.find(f"<!-- {name} -->"), d.find(f"<!-- /{name} -->")
    if a >= 0 and b > a:
        open(doc, "w").write(d[:a] + f"<!-- {name} -->\n" + text + "\n" + d[b:])


def orders():
    """mfs with K wide scatters against the path tracer limited to K wide scatters (the same split)."""
    path = os.path.join(DOCS, "render_orders.json")
    out = json.load(open(path)) if os.path.exists(path) else {}
    all_scenes = suite()
    for name in ORDER_SCENES:
        scene, base, ref_spp = all_scenes[name]
        out[name] = {}
        for K in (0, 1, 2, 3):
            ref = os.path.join(REFS, f"{name}_wide{K}_pt{ref_spp // 2}.exr")
            if not os.path.exists(ref):
                render(scene, base, {"type": "pathtrace", "max_wide_scatters": K}, ref_spp // 2, ref)
            res = {}
            # (forward_side "light" counts paths by their last scatter of any kind, not comparable per K.)
            for label, block in (("mfs", {"type": "mfs"}),):
                img = os.path.join(TMP, f"{name}_K{K}_{label.replace(' ', '_')}.exr")
                render(scene, base, dict(block, large_angle_scatters=K), 4, img)
                mean, rrmse, _ = compare(img, ref)
                res[label] = {"mean_error": mean, "rel_rmse": rrmse}
                print(f"{name:34s} K={K} {label:12s} mean {mean:+.3f} rrmse {rrmse:.3f}", flush=True)
            out[name][str(K)] = res
        json.dump(out, open(path, "w"), indent=1, sort_keys=True)
    lines = ["| scene | K = 0 | K = 1 | K = 2 | K = 3 |", "|---|---|---|---|---|"]
    for name, byk in out.items():
        lines.append(f"| {name} | " + " | ".join(
            f"{byk[str(K)]['mfs']['mean_error']:+.1%} / {byk[str(K)]['mfs']['rel_rmse']:.1%}" if str(K) in byk else "-"
            for K in range(4)) + " |")
    text = "\n".join(lines)
    print(text)
    write_between_markers("orders", text)


def size_study():
    """Equal-error speed-up on the Disney cloud at a production-like size (fixed costs amortised)."""
    scene, base, _ = cloud(0.2)
    scene = json.loads(json.dumps(scene))
    scene["camera"]["width"], scene["camera"]["height"] = 160, 120
    ref = os.path.join(REFS, "disney_cloud_160_pt1024.exr")
    half = os.path.join(REFS, "disney_cloud_160_pt512_seed2.exr")
    if not os.path.exists(ref):
        render(scene, base, {"type": "pathtrace"}, 1024, ref)
    if not os.path.exists(half):
        render(scene, base, {"type": "pathtrace"}, 512, half, seed=2)
    noise = compare(half, ref)[1] / math.sqrt(3.0)
    rows = {"reference_noise_rel_rmse": noise, "pathtrace": [], "configs": {}}
    for spp in (4, 16, 64):
        out = os.path.join(TMP, f"size_pt{spp}.exr")
        t = render(scene, base, {"type": "pathtrace"}, spp, out, seed=3)
        m, e, _ = compare(out, ref)
        rows["pathtrace"].append({"spp": spp, "time_s": t, "mean_error": m, "rel_rmse": e})
    c2, k, _ = pathtrace_fit(rows["pathtrace"], noise)
    for label, block, spp in (("mfs 4 spp", {"type": "mfs"}, 4), ("mfs 1 spp", {"type": "mfs"}, 1),
                              ("single 4 spp", {"type": "single", "transmittance": "shadow_map"}, 4),
                              ("octave 4 spp", {"type": "octave"}, 4)):
        out = os.path.join(TMP, f"size_{label.replace(' ', '_')}.exr")
        t = render(scene, base, block, spp, out)
        m, e, _ = compare(out, ref)
        need = c2 / max(e ** 2 - noise ** 2, 1e-12)
        rows["configs"][label] = {"time_s": t, "mean_error": m, "rel_rmse": e, "pathtrace_spp": need,
                                  "pathtrace_time_s": k * need, "speedup": k * need / t}
        print(f"160x120 {label:14s} mean {m:+.3f} rrmse {e:.3f} time {t:.1f}s  pathtrace needs {need:.0f} spp "
              f"= {k * need:.0f}s: {k * need / t:.1f}x", flush=True)
    json.dump(rows, open(os.path.join(DOCS, "render_size_study.json"), "w"), indent=1)
    size_table()


def size_table():
    """The size study's table, between the markers <!-- size --> in docs/validation/render.md."""
    path = os.path.join(DOCS, "render_size_study.json")
    if not os.path.exists(path):
        return
    rows = json.load(open(path))
    pt = rows["pathtrace"]
    lines = [f"Reference pathtrace 1024 spp (its own noise {rows['reference_noise_rel_rmse']:.1%} rel RMSE); path "
             "tracing at " + ", ".join(str(p["spp"]) for p in pt[:-1]) + f" and {pt[-1]['spp']} spp took " +
             ", ".join(f"{p['time_s']:.1f} s ({p['rel_rmse']:.0%})" for p in pt) + ".", "",
             "| integrator | time [s] | mean error | rel RMSE | pathtrace spp for the same rel RMSE | its time [s] "
             "| speed-up |", "|---|---|---|---|---|---|---|"]
    for label, c in rows["configs"].items():
        lines.append(f"| {label} | {c['time_s']:.1f} | {c['mean_error']:+.1%} | {c['rel_rmse']:.1%} | "
                     f"{c['pathtrace_spp']:.0f} | {c['pathtrace_time_s']:.1f} | {c['speedup']:.1f}x |")
    write_between_markers("size", "\n".join(lines))


def write_table(results):
    lines = ["| scene | ref noise | mfs | octave |" +
             " mfs time [s] | pathtrace equal-error time [s] | speed-up |", "|---|---|---|---|---|---|---|"]
    for name in suite():
        if name not in results:
            continue
        r = results[name]
        m, o = r["configs"]["mfs"], r["configs"]["octave"]
        eq = m.get("pathtrace_equal_error_time_s")
        lines.append(f"| {name} | {r['reference_noise_rel_rmse']:.1%} | {m['mean_error']:+.1%} / {m['rel_rmse']:.1%} | "
                     f"{o['mean_error']:+.1%} / {o['rel_rmse']:.1%} | {m['time_s']:.2f} | " +
                     ("- | - |" if eq is None else f"{eq:.1f} | {m['speedup']:.1f}x |"))
    lines += ["", "All configurations (mean error / rel RMSE):", "",
              "| scene | " + " | ".join(l for l, _, _ in CONFIGS) + " |", "|---" * (len(CONFIGS) + 1) + "|"]
    for name in suite():
        if name not in results:
            continue
        cs = results[name]["configs"]
        lines.append(f"| {name} | " + " | ".join(
            f"{cs[l]['mean_error']:+.0%} / {cs[l]['rel_rmse']:.0%}" if l in cs else "-" for l, _, _ in CONFIGS) + " |")
    text = "\n".join(lines)
    print(text)
    write_between_markers("table", text)


def plots(results):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.image as mpimg
    names = [n for n in suite() if n in results]
    cols = ["reference", "mfs", "octave", "single", "mfs_error"]
    fig, axes = plt.subplots(len(names), len(cols), figsize=(2.0 * len(cols), 2.0 * len(names)), squeeze=False)
    for i, n in enumerate(names):
        for j, c in enumerate(cols):
            ax = axes[i][j]
            ax.axis("off")
            p = os.path.join(IMG, f"{n}_{c}.png")
            if os.path.exists(p):
                ax.imshow(mpimg.imread(p), interpolation="nearest")
            if i == 0:
                ax.set_title(c.replace("_", " "), fontsize=9)
        axes[i][0].text(-0.05, 0.5, n.replace("_", "\n", 1), transform=axes[i][0].transAxes, ha="right",
                        va="center", fontsize=6)
    fig.tight_layout()
    fig.savefig(os.path.join(DOCS, "render_suite.png"), dpi=90)
    plt.close(fig)

    cols = 4
    rows = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), squeeze=False)
    for k, n in enumerate(names):
        ax = axes[k // cols][k % cols]
        r = results[n]
        pt = r["pathtrace"]
        ax.loglog([p["time_s"] for p in pt], [p["rel_rmse"] for p in pt], "k-o", label="pathtrace", ms=3)
        for label, mk in (("mfs", "o"), ("mfs K=1", "s"), ("octave", "^"), ("single", "v")):
            c = r["configs"][label]
            ax.loglog([c["time_s"]], [c["rel_rmse"]], mk, label=label)
        ax.axhline(r["reference_noise_rel_rmse"], color="gray", lw=0.5, ls="--")
        ax.set_title(n, fontsize=8)
        ax.set_xlabel("time [s]", fontsize=7)
        ax.set_ylabel("rel RMSE", fontsize=7)
        ax.tick_params(labelsize=6)
        if k == 0:
            ax.legend(fontsize=6)
    for k in range(len(names), rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.tight_layout()
    fig.savefig(os.path.join(DOCS, "render_error_time.png"), dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    main()
