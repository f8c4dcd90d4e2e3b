#!/usr/bin/env python3
"""The Disney cloud's dark silhouette away from the sun, order by order (issue 12;
docs/validation/render.md, "The cloud's dark silhouette (2026-12-03)").

Sun only (scenes/disney_cloud.json without its sky), 128 x 128, a crop of the dark lower-left edge
(pixels 16,64 to 64,128: 6 x 8 bins of 8 x 8 pixels). Renders into --out (files already there are kept):
  ptF_s{1,2}   pathtrace, all orders, 256 spp each;  ptF_s{3,4}  the same, 1024 spp each
  ptK{K}_s{1,2} pathtrace max_wide_scatters K (K = 0..3), 512 spp each
  mfK{K}       mfs large_angle_scatters K (0..3, all), 4 spp, 4 Mi scatter-grid photons (16x)
  mfK{K}_{tag} the same with one more option (--variant TAG=FIELD=JSON, repeatable; K from --variant-k)
and prints, per 8 x 8 bin: mfs against pathtrace for all orders (reference: the four full-order renders,
2560 spp) and, per K, (mfs K - pathtrace K) over the full-order reference's light (how much of each bin's
deficit each order holds). Bins with under 5 % of the mean bin of the crop's reference are left out (0).

    nice validation/cloud_edge.py --out /tmp/edge [--variant pf05=peak_fraction=0.5]
"""
import argparse, copy, json, os, subprocess, sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import exr_reader  # noqa: E402

REGION = "16,64,64,128"
X0, Y0, X1, Y1 = 16, 64, 64, 128


def lum(path):
    c, _ = exr_reader.read_exr(path)
    return 0.2126 * c["R"] + 0.7152 * c["G"] + 0.0722 * c["B"]


def bins(x, k=8):
    return x.reshape(x.shape[0] // k, k, x.shape[1] // k, k).mean(axis=(1, 3))


def sun_scene(out):
    s = json.load(open(os.path.join(HERE, "..", "scenes", "disney_cloud.json")))
    s["lights"] = [l for l in s["lights"] if l["type"] != "environment"]
    s["camera"]["width"] = s["camera"]["height"] = 128
    shape = s["media"][0]["shape"]
    shape["file"] = os.path.normpath(os.path.join(HERE, "..", "scenes", shape["file"]))
    path = os.path.join(out, "cloud_sun.json")
    json.dump(s, open(path, "w"))
    return path


def render(nimbus, scene, out, name, integrator, spp, seed, sets):
    path = os.path.join(out, name + ".exr")
    if os.path.exists(path):
        return path
    cmd = [nimbus, "render", scene, "--integrator", integrator, "--spp", str(spp), "--seed", str(seed),
           "--region", REGION, "-o", path, "-q"]
    for k, v in sets.items():
        cmd += ["--set", f"integrator.{k}={json.dumps(v)}"]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    return path


def show(title, x, mask):
    print(title)
    print(np.round(np.where(mask, 100 * x, 0)).astype(int))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--nimbus", default=os.path.join(HERE, "..", "build", "bin", "nimbus"))
    ap.add_argument("--variant", action="append", default=[], help="TAG=FIELD=JSON: one more mfs render")
    ap.add_argument("--variant-k", default="all", choices=["0", "1", "2", "3", "all"],
                    help="large_angle_scatters of the variants (compared with pathtrace at the same K)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    scene = sun_scene(a.out)
    n = a.nimbus
    full = [(render(n, scene, a.out, f"ptF_s{s}", "pathtrace", spp, s, {}), spp)
            for s, spp in ((1, 256), (2, 256), (3, 1024), (4, 1024))]
    R = sum(w * lum(p) for p, w in full) / sum(w for _, w in full)
    R8 = bins(R)
    mask = R8 >= 0.05 * R8.mean()
    photons = {"photons": 4 << 20}
    mf_all = render(n, scene, a.out, "mfKall", "mfs", 4, 1, dict(photons, large_angle_scatters="all"))
    A8 = bins(lum(mf_all))
    print(f"all orders: mfs against pathtrace ({sum(w for _, w in full)} spp), crop mean "
          f"{100 * (A8[mask].sum() / R8[mask].sum() - 1):+.1f} %")
    show("per bin, %", (A8 - R8) / R8, mask)
    ptK = {"all": R8}
    for K in range(4):
        pts = [lum(render(n, scene, a.out, f"ptK{K}_s{s}", "pathtrace", 512, s, {"max_wide_scatters": K}))
               for s in (1, 2)]
        P8 = ptK[str(K)] = bins(0.5 * (pts[0] + pts[1]))
        M8 = bins(lum(render(n, scene, a.out, f"mfK{K}", "mfs", 4, 1, dict(photons, large_angle_scatters=K))))
        print(f"K <= {K}: pathtrace's share of the light {100 * P8[mask].sum() / R8[mask].sum():.1f} %, "
              f"mfs - pathtrace {100 * (M8[mask].sum() / P8[mask].sum() - 1):+.1f} % of its own light, "
              f"{100 * (M8[mask].sum() - P8[mask].sum()) / R8[mask].sum():+.2f} % of all the light")
        show(f"K <= {K}: (mfs - pathtrace) / all orders' light per bin, %", (M8 - P8) / R8, mask)
    for v in a.variant:
        tag, field, value = v.split("=", 2)
        sets = dict(photons, large_angle_scatters=a.variant_k if a.variant_k == "all" else int(a.variant_k))
        sets[field] = json.loads(value)
        V8 = bins(lum(render(n, scene, a.out, f"mfK{a.variant_k}_{tag}", "mfs", 4, 1, sets)))
        P8 = ptK[a.variant_k]
        print(f"{tag} (K <= {a.variant_k}): crop {100 * (V8[mask].sum() - P8[mask].sum()) / R8[mask].sum():+.2f} % "
              "of all the light")
        show(f"{tag}: (mfs - pathtrace) / all orders' light per bin, %", (V8 - P8) / R8, mask)

if __name__ == "__main__":
    main()
