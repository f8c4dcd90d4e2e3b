#!/usr/bin/python3
"""Tables and plot for docs/validation/lidar.md: `nimbus lidar`, photon Monte Carlo against the fused
small-angle model (mfs) and the single-scatter lidar equation (single).

Runs the built `nimbus` (default build/bin/nimbus, or $NIMBUS) on ocean-like and cloud-like slabs (lengths
in scattering mean free paths, b = 1), prints per case and range bin: MC +- stderr, mfs, single,
mfs / MC - 1, single / MC - 1 and MC / single (the multiple-to-single ratio), and the whole return;
plots docs/images/lidar_returns.png.
Usage:  /usr/bin/python3 validation/lidar_validation.py [--photons N] [--cases a,b]
"""
import argparse
import csv
import io
import math
import os
import subprocess

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NIMBUS = os.environ.get("NIMBUS", os.path.join(ROOT, "build", "bin", "nimbus"))
IMAGES = os.path.join(ROOT, "docs", "images")

# name: (phase, albedo, distance, thickness, fov, receiver radius, bins)
CASES = {
    "ocean_hg0.9_a0.9_fov5mrad": ("hg:0.9", 0.9, 2.0, 8.0, 0.005, 0.01, 16),
    "ocean_hg0.9_a0.9_fov50mrad": ("hg:0.9", 0.9, 2.0, 8.0, 0.05, 0.01, 16),
    "cloud_hg0.85_a0.99_fov1mrad": ("hg:0.85", 0.99, 50.0, 8.0, 0.001, 0.01, 16),
    "cloud_hg0.85_a0.99_fov10mrad": ("hg:0.85", 0.99, 50.0, 8.0, 0.01, 0.01, 16),
    "cloud_hg0.95_a0.99_fov10mrad": ("hg:0.95", 0.99, 50.0, 8.0, 0.01, 0.01, 16),
    "ocean_dhg_a0.95_fov20mrad": ("dhg:0.95,-0.5,0.95", 0.95, 2.0, 8.0, 0.02, 0.01, 16),
    "mie_a0.99_fov10mrad": ("mie:cloud_mie_550nm", 0.99, 50.0, 8.0, 0.01, 0.01, 16),
}


def run_case(name, photons):
    phase, albedo, dist, D, fov, r, nb = CASES[name]
    edges = f"{2 * dist}:{2 * (dist + D)}:{nb}"
    cmd = [NIMBUS, "lidar", "--mu-s", "1", "--albedo", str(albedo), "--phase", phase, "--thickness", str(D),
           "--distance", str(dist), "--fov", str(fov), "--receiver-radius", str(r), "--time-edges", edges,
           "--photons", str(photons)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    rows = {}
    for row in csv.DictReader(io.StringIO(out)):
        rows.setdefault(row["model"], []).append(row)
    return rows


def report(name, rows):
    phase, albedo, dist, D, fov, r, nb = CASES[name]
    print(f"\n### {name}: {phase}, albedo {albedo}, distance {dist}, D {D}, fov {fov} rad, r_rx {r}")
    print("| depth (mfp) | MC | +- | mfs | single | mfs/MC-1 | single/MC-1 | MC/single |")
    print("|---|---|---|---|---|---|---|---|")
    mc = [x for x in rows["mc"] if math.isfinite(float(x["thi"])) and float(x["tlo"]) >= 2 * dist - 1e-9]
    mfs = [x for x in rows["mfs"] if math.isfinite(float(x["thi"])) and float(x["tlo"]) >= 2 * dist - 1e-9]
    out = []
    for m, f, s in zip(mc, mfs, rows["single"]):
        v, e, fv, sv = float(m["value"]), float(m["stderr"]), float(f["value"]), float(s["value"])
        if not (v > 0 and sv > 0):
            continue
        z = 0.5 * (float(m["tlo"]) + float(m["thi"])) / 2 - dist
        print(f"| {z:.2f} | {v:.4g} | {e / v * 100:.1f} % | {fv:.4g} | {sv:.4g} | {fv / v - 1:+.3f} | "
              f"{sv / v - 1:+.3f} | {v / sv:.3f} |")
        out.append((z, v, e, fv, sv))
    tot = lambda k: sum(float(x["value"]) for x in rows[k])  # noqa: E731
    print(f"whole return: MC {tot('mc'):.4g}, mfs {tot('mfs'):.4g}, single {sum(float(x['value']) for x in rows['single']):.4g}")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--photons", type=int, default=1000000)
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args()
    names = args.cases.split(",")
    results = {n: report(n, run_case(n, args.photons)) for n in names}
    cols = min(4, len(names))
    rows_n = (len(names) + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, 3.4 * rows_n), squeeze=False)
    for ax, n in zip(axes.flat, names):
        z = [x[0] for x in results[n]]
        ax.errorbar(z, [x[1] for x in results[n]], yerr=[2 * x[2] for x in results[n]], fmt="o", ms=3,
                    label="photon MC")
        ax.plot(z, [x[3] for x in results[n]], "-", label="mfs (fused)")
        ax.plot(z, [x[4] for x in results[n]], "--", label="single scatter")
        ax.set_yscale("log")
        ax.set_title(n, fontsize=8)
        ax.set_xlabel("depth of the return z = t/2 - d [mfp]", fontsize=8)
        ax.set_ylabel("received per bin [1/mfp^2 per photon]", fontsize=8)
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    fig.tight_layout()
    os.makedirs(IMAGES, exist_ok=True)
    fig.savefig(os.path.join(IMAGES, "lidar_returns.png"), dpi=110)


if __name__ == "__main__":
    main()
