#!/usr/bin/env python3
"""`mfs`'s error-vs-time frontier and equal-error speed-up on the Cycles-comparison scenes
(validation/cycles/scenes/, which the suite of mfs_validation.py does not hold: thin media, surfaces,
point, spot and area lights), sized to WIDTH pixels wide: docs/validation/render.md, "Beyond the suite".
References (pathtrace, 2048 spp in two halves) are cached in validation/refs/ as other_NAME_WIDTH_pt2048*.
Prints one table row per scene and writes the frontiers to --out.

    nice validation/beyond_suite.py --scenes a_sphere_iso_sun,g_cloud_over_ground --width 128
"""
import argparse, json, math, os, sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mfs_validation as mv  # noqa: E402

SCENES = os.path.join(HERE, "cycles", "scenes")
DEFAULT = ("a_sphere_iso_sun,b_sphere_hg_env,c_box_chromatic_back,e_sphere_point,g_cloud_over_ground,"
           "h_sphere_in_medium,j_mesh,k_spot_medium,l_sphere_light,m_rect_light")


def row(name, r):
    m = mv.best_mfs(r)
    noise = r["reference_noise_rel_rmse"]
    e = math.sqrt(max(m["rel_rmse"] ** 2 - noise ** 2, 0.0))
    eq = m["equal_error"]
    spp = r["fit"]["c2"] / max(m["rel_rmse"] ** 2 - noise ** 2, 1e-12)
    return (f"| `{name}` | {noise * 100:.1f}% | {m['spp']} | {m['mean_error'] * 100:+.1f}% / {e * 100:.1f}% | "
            f"{m['cpu_s']:.2f} | {spp:.0f} | {eq['uniform_cpu_s']:.2f} | {eq['adaptive_cpu_s']:.2f} | "
            f"**{m.get('speedup_cpu_s', float('nan')):.2f}x** |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default=DEFAULT, help="comma-separated names in validation/cycles/scenes/")
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--out", default=os.path.join(mv.REFS, "beyond_suite.json"))
    a = ap.parse_args()
    results = {}
    for name in a.scenes.split(","):
        scene = json.load(open(os.path.join(SCENES, name + ".json")))
        if name == "l_sphere_light":  # the light's own pixels are exact everywhere: leave them out
            for light in scene["lights"]:
                light["visible"] = False
        c = scene["camera"]
        sized = mv.sized(scene, a.width, round(c["height"] * a.width / c["width"]))
        results[name] = mv.frontier(f"other_{name}_{a.width}", sized, SCENES, 2048, mfs_spp=[1, 4, 16],
                                    octave_spp=[])
        print(row(name, results[name]), flush=True)
        json.dump(results, open(a.out, "w"), indent=1)


if __name__ == "__main__":
    main()
