#!/usr/bin/python3
"""Regenerates docs/validation/beam.md and its plots: every propagator against photon Monte Carlo.

Runs the built `nimbus beam` (default build/bin/nimbus, or $NIMBUS) for a Gaussian peak
(theta2 = 0.01), HG 0.9 and HG 0.95 at albedo 0.9 / 0.99 / 0.999 and b z = 1, 3, 10, 30, plus the Mie
cloud table, then tabulates on-axis radiance and angular half-width (HWHM) errors per model and plots
the angular and radial profiles.  Usage:  /usr/bin/python3 validation/beam_validation.py [--photons N]
"""
import argparse
import math
import os
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import beam_metrics as bm  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, "docs", "validation")
MODELS = ["dolin", "tes87", "mfs", "gsa"]
COLORS = {"mc": "k", "mc_fwd": "0.55", "dolin": "tab:orange", "tes87": "tab:green", "mfs": "tab:blue", "gsa": "tab:red"}
DEPTHS = [1, 3, 10, 30]
ALBEDOS = [0.9, 0.99, 0.999]
PHASES = [("gauss:0.01", "Gaussian peak, theta2 = 0.01"), ("hg:0.9", "Henyey-Greenstein g = 0.9"),
          ("hg:0.95", "Henyey-Greenstein g = 0.95")]


def run_beam(exe, phase, albedo, depths, photons, out):
    cmd = [exe, "beam", "--phase", phase, "--albedo", str(albedo), "--depths", ",".join(map(str, depths)),
           "--photons", str(int(photons)), "--models", "mc,mc_fwd," + ",".join(MODELS), "--seed", "11", "-o", out]
    t0 = time.time()
    subprocess.run(cmd, check=True)
    return time.time() - t0


def analyse(d, z):
    """Metrics per model at depth z: merged MC bins, cone = 0.3 MC HWHM."""
    mcb = d[("mc", z, "angular")]
    edges = bm.merge_edges(mcb)
    mcr = bm.rebin(mcb, edges)
    cone = bm.cone_for(mcr, mcr[0][2], 0.3)
    L0, e0, w0 = bm.metrics(d, "mc", z, cone, edges)
    rows = {"mc": (L0, e0, w0)}
    for m in MODELS + ["mc_fwd"]:
        L, _, w = bm.metrics(d, m, z, cone, edges)
        rows[m] = (L, 0.0, w)
    return cone, edges, rows


def radial_r50(bins):
    """Radius holding half of the radial flux tallied (linear within the bin)."""
    tot = sum(v * math.pi * (hi * hi - lo * lo) for lo, hi, v, e in bins)
    acc = 0.0
    for lo, hi, v, e in bins:
        f = v * math.pi * (hi * hi - lo * lo)
        if acc + f >= 0.5 * tot and f > 0:
            return lo + (0.5 * tot - acc) / f * (hi - lo)
        acc += f
    return float("nan")


def fmt_pct(x):
    return "n/a" if not math.isfinite(x) else f"{100 * x:+.0f}%"


def fmt_w(w, e=None):
    if not math.isfinite(w):
        return "> pi/2"
    return f"{w:.4g}" if e is None or not math.isfinite(e) else f"{w:.4g} ± {e:.2g}"


def plot_config(d, phase, title, albedo, path):
    fig, axes = plt.subplots(2, 4, figsize=(15, 6.5))
    for j, z in enumerate(DEPTHS):
        ax = axes[0, j]
        for m in ["mc", "mc_fwd"] + MODELS:
            bins = d.get((m, float(z), "angular"))
            if not bins:
                continue
            xs = [0.5 * (lo + hi) for lo, hi, v, e in bins if hi <= math.pi / 2]
            ys = [max(v, 1e-12) for lo, hi, v, e in bins if hi <= math.pi / 2]
            ax.plot(xs, ys, color=COLORS[m], lw=2.0 if m == "mc" else 1.2, ls="--" if m == "mc_fwd" else "-", label=m)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(2e-3, 1.6)
        ax.set_ylim(bottom=max(1e-4, ax.get_ylim()[0]))
        ax.set_title(f"bz = {z}: angular")
        ax.set_xlabel("theta [rad]")
        if j == 0:
            ax.set_ylabel("plane-integrated radiance [1/sr]")
            ax.legend(fontsize=7)
        ax = axes[1, j]
        for m in ["mc"] + MODELS:
            bins = d.get((m, float(z), "radial"))
            xs = [0.5 * (lo + hi) for lo, hi, v, e in bins]
            ys = [max(v, 1e-14) for lo, hi, v, e in bins]
            ax.plot(xs, ys, color=COLORS[m], lw=2.0 if m == "mc" else 1.2, label=m)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(bottom=1e-7)
        ax.set_title(f"bz = {z}: radial")
        ax.set_xlabel("r [mean free paths]")
        if j == 0:
            ax.set_ylabel("forward flux per area")
    fig.suptitle(f"{title}, albedo {albedo}")
    fig.tight_layout()
    fig.savefig(path, dpi=60)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--photons", type=float, default=3e5)
    ap.add_argument("--exe", default=os.environ.get("NIMBUS", os.path.join(ROOT, "build", "bin", "nimbus")))
    args = ap.parse_args()
    os.makedirs(DOCS, exist_ok=True)
    tmp = os.path.join(ROOT, "build", "validation")
    os.makedirs(tmp, exist_ok=True)

    table = []  # (phase, albedo, z, cone, fwd_frac, {model: (L, e, w)}, hwhm_err, r50s)
    plots = []
    total_time = 0.0
    for phase, title in PHASES:
        for albedo in ALBEDOS:
            out = os.path.join(tmp, f"beam_{phase.replace(':', '_')}_{albedo}.csv")
            total_time += run_beam(args.exe, phase, albedo, DEPTHS, args.photons, out)
            d = bm.load(out)
            png = f"beam_{phase.replace(':', '_').replace('.', 'p')}_a{str(albedo).replace('.', 'p')}.png"
            plot_config(d, phase, title, albedo, os.path.join(DOCS, png))
            plots.append((title, albedo, png))
            for z in DEPTHS:
                cone, edges, rows = analyse(d, float(z))
                werr = bm.hwhm_stderr(d, float(z), cone, edges)
                r50 = {m: radial_r50(d[(m, float(z), "radial")]) for m in ["mc"] + MODELS}
                fwd = rows["mc_fwd"][0] / rows["mc"][0]
                table.append((phase, albedo, z, cone, fwd, rows, werr, r50))
    # Mie cloud table: one albedo, fewer photons (its tabulated sampler is slower).
    mie_out = os.path.join(tmp, "beam_mie.csv")
    total_time += run_beam(args.exe, "mie:cloud_mie_550nm", 0.99, [1, 3, 10], args.photons / 3, mie_out)
    dm = bm.load(mie_out)
    mie_rows = []
    for z in [1, 3, 10]:
        cone, edges, rows = analyse(dm, float(z))
        mie_rows.append((z, cone, rows["mc_fwd"][0] / rows["mc"][0], rows))
    write_doc(table, plots, mie_rows, args.photons, total_time)


def verdict(phase, z, fwd, rows):
    """Target check for the row: the model the target names, and whether forward light dominates."""
    L0, _, w0 = rows["mc"]
    if phase.startswith("gauss"):
        if z < 10:
            return ""
        m = rows["mfs"]
        ok = abs(m[0] / L0 - 1) <= 0.15 and abs(m[2] / w0 - 1) <= 0.10
        return "mfs meets" if ok else "mfs misses"
    if z > 10:
        return ""
    g = rows["gsa"]
    ok = abs(g[0] / L0 - 1) <= 0.10 and abs(g[2] / w0 - 1) <= 0.10
    if fwd < 0.9:
        return ("gsa meets" if ok else "gsa misses") + " (not forward-dominated)"
    return "gsa meets" if ok else "gsa misses"


def write_doc(table, plots, mie_rows, photons, total_time):
    L = []
    L.append("# Beam propagators against photon Monte Carlo")
    L.append("")
    L.append("Regenerated by `validation/beam_validation.py` (it runs `nimbus beam`; "
             f"{photons:.0e} photons per configuration, {total_time:.0f} s of runs on this machine).  "
             "Do not edit by hand.")
    L.append("")
    L.append("## What is compared")
    L.append("")
    L.append("A pencil beam enters an infinite medium at the origin along +z; lengths are scattering mean free "
             "paths (b = 1), absorption a = (1 - albedo)/albedo.  At planes of optical depth bz:")
    L.append("")
    L.append("* **angular**: plane-integrated scattered radiance per sr against polar angle (Monte Carlo: every "
             "crossing, weight / |cos theta| / bin solid angle);")
    L.append("* **radial**: scattered flux per unit area against radius, Monte Carlo counting *forward* crossings "
             "only (models: all their scattered light, which they carry forward);")
    L.append("* unscattered light apart (exp(-cz), checked exactly in the tests).")
    L.append("")
    L.append("Models (`src/transport/`):")
    L.append("")
    L.append("* `dolin`: Dolin's small-angle Gaussian (angular variance theta2 b z per component);")
    L.append("* `tes87`: the improved form of [Tes87/88] (oscillator kernel with T = theta2 b, L = ell);")
    L.append("* `mfs`: the corrected seed kernel (T = theta2 b / (1 - e^-bz), 1/cosh(z/L) loss; "
             "`mfs_kernel.h`).  For HG the Gaussian stand-in theta2 = (1 - g^2)/3 is used;")
    L.append("* `gsa`: the generalised small-angle propagator (`small_angle.h`): the exact Poisson-Legendre "
             "angular series (the HG-Poisson series for HG) and a Hankel-transformed small-angle spatial "
             "spread from the phase function's own Z(q);")
    L.append("* `mc_fwd` (diagnostic): the Monte Carlo light of photons that never travelled backward.  Its share of "
             "the on-axis radiance, **fwd**, measures whether forward light dominates.")
    L.append("")
    L.append("Metrics: Monte Carlo bins are merged outward until each has < 3% standard error; the **on-axis** "
             "radiance is the mean over a cone of 0.3 x the Monte Carlo HWHM; **HWHM** is where the profile "
             "first falls to half the on-axis value.  Errors are (model / MC - 1).  `r50`: radius holding half "
             "the tallied radial flux (the Monte Carlo's includes diffuse light, so it is only indicative when "
             "fwd is low).")
    L.append("")
    L.append("## Results")
    for phase, title in PHASES:
        L.append("")
        L.append(f"### {title}")
        L.append("")
        L.append("| albedo | bz | fwd | MC on-axis [1/sr] | MC HWHM [rad] | " +
                 " | ".join(f"{m} on / HWHM" for m in MODELS) + " | MC r50 | gsa r50 | target |")
        L.append("|---|---|---|---|---|" + "---|" * len(MODELS) + "---|---|---|")
        for (ph, albedo, z, cone, fwd, rows, werr, r50) in table:
            if ph != phase:
                continue
            L0, e0, w0 = rows["mc"]
            cells = [f"{fmt_pct(rows[m][0] / L0 - 1)} / {fmt_pct(rows[m][2] / w0 - 1)}" for m in MODELS]
            L.append(f"| {albedo} | {z} | {fwd:.2f} | {L0:.4g} ± {100 * e0 / L0:.1f}% | {fmt_w(w0, werr)} | " +
                     " | ".join(cells) + f" | {r50['mc']:.3g} | {r50['gsa']:.3g} | {verdict(phase, z, fwd, rows)} |")
    L.append("")
    L.append("### Mie cloud droplets (data/phase/cloud_mie_550nm.csv, g = 0.864), albedo 0.99")
    L.append("")
    L.append("| bz | fwd | MC on-axis [1/sr] | MC HWHM [rad] | " + " | ".join(f"{m} on / HWHM" for m in MODELS) + " |")
    L.append("|---|---|---|---|" + "---|" * len(MODELS))
    for z, cone, fwd, rows in mie_rows:
        L0, e0, w0 = rows["mc"]
        cells = [f"{fmt_pct(rows[m][0] / L0 - 1)} / {fmt_pct(rows[m][2] / w0 - 1)}" for m in MODELS]
        L.append(f"| {z} | {fwd:.2f} | {L0:.4g} ± {100 * e0 / L0:.1f}% | {fmt_w(w0)} | " + " | ".join(cells) + " |")
    L.append("")
    L.append("## Where each model fails")
    L.append("")
    L.extend(FAILURES)
    L.append("")
    L.append("## The slab Monte Carlo (`nimbus slab`)")
    L.append("")
    L.append("Checked in `tests/transport/photon_mc_*test.cpp` against independent results: the exact "
             "plane albedo 1 - H(1) sqrt(1 - albedo) of a semi-infinite isotropic medium (Chandrasekhar's "
             "H-function, computed in the test: 0.4149 at albedo 0.9, n = 1); van de Hulst's slab (mu_a = 10, "
             "mu_s = 90 /cm, g = 0.75, d = 0.02 cm, n = 1: Rd = 0.09739, Tt = 0.66096); Giovanelli's "
             "semi-infinite isotropic medium with n = 1.5 (total reflection 0.2600 with the specular 0.04); a "
             "purely absorbing slab with Fresnel faces (closed form); unscattered light exp(-cz); and the energy "
             "balance specular + Rd + Tt + absorbed = 1 (to roulette noise, ~1e-5).")
    L.append("")
    L.append("## Plots")
    L.append("")
    L.append("Top row: angular profiles (grey dashed: `mc_fwd`); bottom row: radial profiles.")
    for title, albedo, png in plots:
        L.append("")
        L.append(f"**{title}, albedo {albedo}**")
        L.append("")
        L.append(f"![{title}, albedo {albedo}]({png})")
    with open(os.path.join(DOCS, "beam.md.tmp"), "w") as f:
        f.write("\n".join(L) + "\n")
    os.replace(os.path.join(DOCS, "beam.md.tmp"), os.path.join(DOCS, "beam.md"))
    print("wrote", os.path.join(DOCS, "beam.md"))


FAILURES = [
    "* **Every Gaussian form on HG or Mie** (`dolin`, `tes87`, `mfs` with theta2 = (1 - g^2)/3): on-axis radiance "
    "low by a factor 5 to 100 and widths several times too large at bz = 1 and 3, as the notes predict (HG's "
    "forward peak is Cauchy-like; no theta2 fixes it).  Do not use them for HG or Mie media.",
    "* **`dolin` and `tes87` on the Gaussian peak**: about +28% on-axis at bz = 1 and -22% at bz = 3 (they keep "
    "the unscattered light's normalisation in their width); `tes87` equals `mfs` once bz >= 10.",
    "* **`mfs` on the Gaussian peak**: low on-axis by 12-17% at bz >= 10 and HWHM +3 to +10%.  The kernel is a single "
    "Gaussian while the true profile is a Poisson mixture of Gaussians (n scatters, variance n theta2), which "
    "is more peaked; at bz = 1, 3 it is 18-27% low.  The 15% / 10% target at bz >= 10 is met only narrowly "
    "(and missed at albedo 0.999, bz = 30, where the diffuse background fills the peak).",
    "* **`gsa`** (the recommended propagator): within a few % wherever forward light dominates (fwd >= 0.9) "
    "and the asymptotic regime has not set in, for the Gaussian peak, HG 0.9, HG 0.95 and Mie.  Two limits: "
    "(1) where the Monte Carlo's on-axis light is not forward light (fwd < 0.9: high albedo at bz >= 10, e.g. "
    "HG 0.9 at albedo 0.99/0.999, HG 0.95 at albedo 0.999), diffusely returning photons form a broad "
    "background the small-angle model has no term for; `gsa` then agrees with `mc_fwd` instead.  (2) It "
    "neglects the extra absorption (and scattering) along lengthened paths, which the MFS kernel's 1/cosh(z/L) "
    "describes: once x = z sqrt(a b theta2) approaches 1 or more (theta2 = (1 - g^2)/3 for HG) it overestimates "
    "the on-axis radiance even with fwd >= 0.9: albedo 0.9 at bz = 30 gives +14% (Gaussian peak, x = 1.0) and "
    "+53% (HG 0.95, x = 1.8).  At bz <= 10 with albedo 0.9 (x <= 0.84 for HG 0.9) it is within 8%.",
    "* **Radial profiles**: the models' radial profiles carry all scattered light forward; the Monte Carlo "
    "counts forward crossings, which include diffuse light re-crossing at large radii.  Near the axis "
    "`gsa` follows the Monte Carlo (the 1/r single-scatter core included); the Gaussian forms miss the core.",
]


if __name__ == "__main__":
    sys.exit(main())
