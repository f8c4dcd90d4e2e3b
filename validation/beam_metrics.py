"""Read `nimbus beam` CSV output and compute the comparison metrics of docs/validation/beam.md.

on-axis radiance: mean plane-integrated radiance over the cone theta < cone (solid-angle weighted);
HWHM: the polar angle where the radiance (bin centres, linear interpolation) first falls to half the
on-axis value.  Standard errors for Monte Carlo from its per-bin errors (bins are independent).
"""
import collections
import csv
import math


def load(path):
    """{(model, depth, quantity): list of (lo, hi, value, stderr)} sorted by lo."""
    d = collections.defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            d[(r["model"], float(r["depth"]), r["quantity"])].append(
                tuple(float(r[k]) for k in ("lo", "hi", "value", "stderr")))
    for v in d.values():
        v.sort()
    return d


def solid_angle(lo, hi):
    return 2.0 * math.pi * (math.cos(lo) - math.cos(hi))


def on_axis(bins, cone):
    """Mean radiance over theta < cone (bins entirely inside), with its standard error."""
    num = den = var = 0.0
    for lo, hi, v, e in bins:
        if hi <= cone + 1e-12:
            w = solid_angle(lo, hi)
            num += v * w
            var += (e * w) ** 2
            den += w
    if den == 0.0:
        raise ValueError(f"no bin inside the cone {cone}")
    return num / den, math.sqrt(var) / den


def hwhm(bins, peak):
    """First angle where the profile falls to peak/2 (linear between bin centres)."""
    prev_c, prev_v = 0.0, peak
    for lo, hi, v, e in bins:
        c = 0.5 * (lo + hi)
        if v < 0.5 * peak:
            if prev_v == v:
                return c
            return prev_c + (prev_v - 0.5 * peak) * (c - prev_c) / (prev_v - v)
        prev_c, prev_v = c, v
    return float("nan")


def merge_edges(mc_bins, rel=0.03, max_angle=math.pi / 2):
    """Edges of merged Monte Carlo bins, from 0 outward, each with relative standard error < rel."""
    edges = [mc_bins[0][0]]
    num = var = 0.0
    for lo, hi, v, e in mc_bins:
        if hi > max_angle + 1e-12:
            break
        w = solid_angle(lo, hi)
        num += v * w
        var += (e * w) ** 2
        if num > 0.0 and math.sqrt(var) < rel * num:
            edges.append(hi)
            num = var = 0.0
    return edges


def rebin(bins, edges):
    """Mean radiance over each [edges[i], edges[i+1]] (edges must be bin edges), with errors."""
    out = []
    j = 0
    for a, b in zip(edges[:-1], edges[1:]):
        num = var = den = 0.0
        while j < len(bins) and bins[j][1] <= b + 1e-12:
            lo, hi, v, e = bins[j]
            if lo >= a - 1e-12:
                w = solid_angle(lo, hi)
                num += v * w
                var += (e * w) ** 2
                den += w
            j += 1
        out.append((a, b, num / den, math.sqrt(var) / den))
    return out


def cone_for(bins, peak, fraction=0.3):
    """A small cone: `fraction` of the half-width, at least the first bin."""
    w = hwhm(bins, peak)
    edges = [hi for lo, hi, v, e in bins]
    target = max(fraction * w, edges[0]) if math.isfinite(w) else edges[0]
    return max([e for e in edges if e <= target] or [edges[0]])


def metrics(d, model, depth, cone, edges=None):
    bins = d[(model, depth, "angular")]
    if edges is not None:
        bins = rebin(bins, edges)
    L0, e0 = on_axis(bins, cone)
    return L0, e0, hwhm(bins, L0)


def hwhm_stderr(d, depth, cone, samples=200, seed=1):
    """Bootstrap-like spread of the MC half-width: perturb bins by their standard errors."""
    import random
    rng = random.Random(seed)
    bins = d[("mc", depth, "angular")]
    vals = []
    for _ in range(samples):
        pert = [(lo, hi, v + rng.gauss(0.0, e), e) for lo, hi, v, e in bins]
        L0, _ = on_axis(pert, cone)
        vals.append(hwhm(pert, L0))
    m = sum(vals) / len(vals)
    return math.sqrt(sum((x - m) ** 2 for x in vals) / (len(vals) - 1))
