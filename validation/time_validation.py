#!/usr/bin/python3
"""Plots for docs/validation/time.md: time-resolved photon Monte Carlo against closed forms.

Runs the built `nimbus` (default build/bin/nimbus, or $NIMBUS):
  1. `nimbus slab --time-edges`: diffuse reflectance R(t) of a thick isotropic slab (mu_s = 1, 40 mfp,
     matched boundary) against the diffusion solution (Patterson, Chance & Wilson 1989, extrapolated
     boundary, integrated over the surface), written into docs/images/time_slab_diffusion.png;
  2. `nimbus beam --time-edges`: the delay n(s - z) of scattered light crossing planes at b z = 0.25, 1, 3
     for a Gaussian forward peak (theta2 = 0.002), Monte Carlo against the corrected MFS kernel's delay
     density (docs/images/time_beam_delay.png), and prints the mean and variance rows;
  3. the generalised propagator's (gsa) delay for HG 0.9 / 0.95, double HG and the cloud Mie table at
     b z = 0.25, 1: MC against its moment-matched gamma law (docs/images/time_gsa_delay.png).
Usage:  /usr/bin/python3 validation/time_validation.py [--photons N] [--beam-only | --gsa-only]
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


def diffusion_rate(t, mu_sp=1.0, mu_a=0.0, n=1.0, A=1.0):
    """time_resolved.h: diffusion_reflectance_rate (same formula, written again here)."""
    D = 1.0 / (3.0 * (mu_a + mu_sp))
    v = 1.0 / n
    z0 = 1.0 / mu_sp
    zp = z0 + 4.0 * A * D
    s = 4.0 * D * v * t
    return 0.5 / math.sqrt(math.pi * s) / t * math.exp(-mu_a * v * t) * (
        z0 * math.exp(-z0 * z0 / s) + zp * math.exp(-zp * zp / s))


def slab(photons):
    edges = ",".join("%.6g" % (0.5 * 400.0 ** (i / 40.0)) for i in range(41))
    out = subprocess.run([NIMBUS, "slab", "--mu-s", "1", "--mu-a", "0", "--g", "0", "--thickness", "40",
                          "--photons", str(photons), "--time-edges", edges], check=True, capture_output=True,
                         text=True).stdout
    lines = out.splitlines()
    rows = list(csv.DictReader(io.StringIO("\n".join(l for l in lines if "," in l))))
    t, r, e, m = [], [], [], []
    for row in rows:
        lo, hi = float(row["tlo"]), float(row["thi"])
        if not math.isfinite(hi) or lo < 0.5:
            continue
        w = hi - lo
        t.append(math.sqrt(lo * hi))
        r.append(float(row["reflectance"]) / w)
        e.append(float(row["reflectance_stderr"]) / w)
        m.append(sum(diffusion_rate(lo + w * (k + 0.5) / 200) for k in range(200)) / 200)
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].errorbar(t, r, yerr=e, fmt="k.", label="photon MC")
    ax[0].plot(t, m, "tab:blue", label="diffusion (PCW 1989, extrapolated boundary)")
    ax[0].set_xscale("log")
    ax[0].set_yscale("log")
    ax[0].set_xlabel("time t [mean free paths]")
    ax[0].set_ylabel("R(t) per unit time")
    ax[0].legend()
    ax[1].errorbar(t, [a / b for a, b in zip(r, m)], yerr=[a / b for a, b in zip(e, m)], fmt="k.")
    ax[1].axhline(1.0, color="tab:blue")
    ax[1].set_xscale("log")
    ax[1].set_ylim(0.5, 1.5)
    ax[1].set_xlabel("time t [mean free paths]")
    ax[1].set_ylabel("MC / diffusion")
    fig.suptitle("Isotropic slab, 40 mfp, n = 1: time-resolved diffuse reflectance")
    fig.tight_layout()
    fig.savefig(os.path.join(IMAGES, "time_slab_diffusion.png"), dpi=90)
    print("slab: t, MC/diffusion")
    for a, b, c, d in zip(t, r, e, m):
        print("  %8.2f  %.3f +- %.3f" % (a, b / d, c / d))


def beam(photons):
    edges = "0," + ",".join("%.6g" % (1e-6 * 10 ** (i / 12.0)) for i in range(61))  # 1e-6 .. 0.1
    out = subprocess.run([NIMBUS, "beam", "--phase", "gauss:0.002", "--albedo", "1", "--depths", "0.25,1,3",
                          "--geometry", "slab:3.5", "--models", "mc,mfs,mc_fwd", "--photons", str(photons),
                          "--theta-edges", "0,3.14159", "--r-edges", "0,100", "--time-edges", edges],
                         check=True, capture_output=True, text=True).stdout
    rows = list(csv.DictReader(io.StringIO(out)))
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    for k, z in enumerate([0.25, 1.0, 3.0]):
        for model, style in (("mc", "k."), ("mfs", "tab:blue")):
            sel = [r for r in rows if r["model"] == model and abs(float(r["depth"]) - z) < 1e-9]
            d = [r for r in sel if r["quantity"] == "delay" and math.isfinite(float(r["hi"]))]
            d = [r for r in d if float(r["lo"]) > 0.0]
            x = [math.sqrt(float(r["lo"]) * float(r["hi"])) for r in d]
            y = [float(r["value"]) / math.log(float(r["hi"]) / float(r["lo"])) for r in d]
            if model == "mc":
                ax[k].set_ylim(max(y) * 1e-4, max(y) * 3)
                ax[k].errorbar(x, y, yerr=[float(r["stderr"]) / math.log(float(r["hi"]) / float(r["lo"])) for r in d],
                               fmt=style, label="photon MC")
            else:
                ax[k].plot(x, y, style, label="corrected MFS kernel")
        for model in ("mc", "mc_fwd", "mfs"):
            sel = [r for r in rows if r["model"] == model and abs(float(r["depth"]) - z) < 1e-9]
            mean = [r for r in sel if r["quantity"] == "delay_mean"][0]
            var = [r for r in sel if r["quantity"] == "delay_variance"][0]
            print("beam z=%g %s: mean %s +- %s, variance %s +- %s" % (z, model, mean["value"], mean["stderr"],
                                                                     var["value"], var["stderr"]))
        ax[k].set_xscale("log")
        ax[k].set_yscale("log")
        ax[k].set_title("b z = %g" % z)
        ax[k].set_xlabel("delay s - z [mean free paths]")
        ax[k].set_ylabel("scattered light per unit ln(delay)")
        ax[k].legend()
    fig.suptitle("Gaussian peak theta2 = 0.002, albedo 1: delay of the scattered light crossing each plane")
    fig.tight_layout()
    fig.savefig(os.path.join(IMAGES, "time_beam_delay.png"), dpi=90)


def gsa(photons):
    """The generalised propagator's delay (moment-matched gamma law) against photon MC at b z = 0.25, 1."""
    edges = "0," + ",".join("%.6g" % (1e-5 * 10 ** (i / 10.0)) for i in range(61))  # 1e-5 .. 10
    phases = ["hg:0.9", "hg:0.95", "dhg:0.95,-0.3,0.9", "mie:cloud_mie_550nm"]
    fig, ax = plt.subplots(2, len(phases), figsize=(4 * len(phases), 7))
    for j, phase in enumerate(phases):
        out = subprocess.run([NIMBUS, "beam", "--phase", phase, "--albedo", "1", "--depths", "0.25,1",
                              "--geometry", "slab:1.5", "--models", "mc,gsa,mc_fwd", "--photons", str(photons),
                              "--theta-edges", "0,3.14159", "--r-edges", "0,100", "--time-edges", edges],
                             check=True, capture_output=True, text=True).stdout
        rows = list(csv.DictReader(io.StringIO(out)))
        for k, z in enumerate([0.25, 1.0]):
            a = ax[k][j]
            for model, style, label in (("mc", "k.", "photon MC (all light)"),
                                        ("mc_fwd", "g.", "photon MC (never backward)"),
                                        ("gsa", "tab:orange", "gsa: gamma law, exact moments")):
                sel = [r for r in rows if r["model"] == model and abs(float(r["depth"]) - z) < 1e-9]
                d = [r for r in sel if r["quantity"] == "delay" and math.isfinite(float(r["hi"]))
                     and float(r["lo"]) > 0.0]
                x = [math.sqrt(float(r["lo"]) * float(r["hi"])) for r in d]
                y = [float(r["value"]) / math.log(float(r["hi"]) / float(r["lo"])) for r in d]
                if model.startswith("mc"):
                    if model == "mc":
                        a.set_ylim(max(y) * 1e-3, max(y) * 3)
                    a.errorbar(x, y, yerr=[float(r["stderr"]) / math.log(float(r["hi"]) / float(r["lo"]))
                                           for r in d], fmt=style, label=label)
                else:
                    a.plot(x, y, style, label=label)
            for model in ("mc", "mc_fwd", "gsa"):
                sel = [r for r in rows if r["model"] == model and abs(float(r["depth"]) - z) < 1e-9]
                mean = [r for r in sel if r["quantity"] == "delay_mean"][0]
                var = [r for r in sel if r["quantity"] == "delay_variance"][0]
                print("gsa %s z=%g %s: mean %s +- %s, variance %s +- %s" % (
                    phase, z, model, mean["value"], mean["stderr"], var["value"], var["stderr"]))
            a.set_xscale("log")
            a.set_yscale("log")
            a.set_title("%s, b z = %g" % (phase, z))
            a.set_xlabel("delay s - z [mean free paths]")
            a.set_ylabel("scattered light per unit ln(delay)")
            a.legend(fontsize=7)
    fig.suptitle("Albedo 1: delay of the scattered light crossing each plane, MC against the gsa gamma law")
    fig.tight_layout()
    fig.savefig(os.path.join(IMAGES, "time_gsa_delay.png"), dpi=80)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--photons", type=int, default=400000)
    ap.add_argument("--beam-only", action="store_true")
    ap.add_argument("--gsa-only", action="store_true")
    args = ap.parse_args()
    if args.gsa_only:
        gsa(args.photons)
        return
    if not args.beam_only:
        slab(args.photons)
    beam(args.photons)
    gsa(args.photons)


if __name__ == "__main__":
    main()
