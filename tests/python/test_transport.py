"""nimbus.beam and nimbus.slab: the arrays hold what `nimbus beam` and `nimbus slab --csv` write."""
import csv
import io
import os
import tempfile
import unittest

import numpy as np

from nimbus_test_support import cli
import nimbus


class Beam(unittest.TestCase):
    def test_beam_matches_the_cli_csv(self):
        theta = [0.0, 0.05, 0.1, 0.3, 1.0, 3.14159]
        radii = [0.0, 0.1, 0.5, 2.0]
        r = nimbus.beam("hg:0.9", albedo=0.95, depths=[0.5, 2.0], photons=4000, models=["mc", "mfs", "gsa"],
                        theta_edges=theta, r_edges=radii, seed=3)
        self.assertEqual(r["models"], ["mc", "mfs", "gsa"])
        self.assertEqual(r["depths"].tolist(), [0.5, 2.0])
        self.assertEqual(r["theta_edges"].tolist(), theta)
        for m in ("mc", "mfs", "gsa"):
            self.assertEqual(r[m]["angular"].shape, (2, 5))
            self.assertEqual(r[m]["radial"].shape, (2, 3))
            self.assertEqual(r[m]["unscattered"].shape, (2,))
        # Unscattered flux: exp(-c z) with c = b / albedo (b = 1).
        self.assertTrue(np.allclose(r["mfs"]["unscattered"], np.exp(-np.array([0.5, 2.0]) / 0.95), rtol=1e-12))
        self.assertTrue(np.all(r["mc"]["angular_stderr"] >= 0))
        out = cli("beam", "--phase", "hg:0.9", "--albedo", "0.95", "--depths", "0.5,2", "--photons", "4000",
                  "--models", "mc,mfs,gsa", "--theta-edges", ",".join(map(str, theta)),
                  "--r-edges", ",".join(map(str, radii)), "--seed", "3").stdout
        rows = list(csv.DictReader(io.StringIO(out)))
        self.assertEqual(len(rows), 3 * 2 * (5 + 3 + 1))
        seen = {}
        for row in rows:
            m, q, d = row["model"], row["quantity"], [0.5, 2.0].index(float(row["depth"]))
            k = seen.get((m, q, d), 0)
            seen[(m, q, d)] = k + 1
            value = r[m][q][d] if q == "unscattered" else r[m][q][d, k]
            err = r[m][q + "_stderr"][d] if q == "unscattered" else r[m][q + "_stderr"][d, k]
            self.assertTrue(np.isclose(value, float(row["value"]), rtol=1e-8, atol=0), (m, q, d, k))
            self.assertTrue(np.isclose(err, float(row["stderr"]), rtol=1e-8, atol=0), (m, q, d, k))

    def test_bad_arguments(self):
        with self.assertRaises(nimbus.Error):
            nimbus.beam("hg:1.5", albedo=0.9, depths=[1.0], photons=100)
        with self.assertRaises(nimbus.Error):
            nimbus.beam("hg:0.9", albedo=0.0, depths=[1.0], photons=100)
        with self.assertRaises(nimbus.Error):
            nimbus.beam("hg:0.9", albedo=0.9, depths=[2.0, 1.0], photons=100)
        with self.assertRaises(nimbus.Error):
            nimbus.beam("hg:0.9", albedo=0.9, depths=[1.0], photons=100, models=["nope"])


class Slab(unittest.TestCase):
    def test_slab_matches_the_cli(self):
        r = nimbus.slab(mu_s=10.0, mu_a=0.5, thickness=0.2, g=0.8, n=1.37, photons=5000, seed=2,
                        angle_bins=6, r_bins=5)
        self.assertEqual(r["reflect_angular"].shape, (6,))
        self.assertEqual(r["transmit_radial"].shape, (5,))
        self.assertEqual(r["theta_edges"].shape, (7,))
        self.assertAlmostEqual(r["specular"], ((1.37 - 1) / (1.37 + 1)) ** 2, places=12)
        total = r["specular"] + r["diffuse_reflectance"] + r["transmittance"] + r["absorbed"]
        self.assertAlmostEqual(total, 1.0, delta=1e-3)  # roulette keeps energy only on average
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "slab.csv")
            out = cli("slab", "--mu-s", "10", "--mu-a", "0.5", "--thickness", "0.2", "--g", "0.8", "--n", "1.37",
                      "--photons", "5000", "--seed", "2", "--angle-bins", "6", "--r-bins", "5", "--csv", path).stdout
            with open(path) as f:
                rows = list(csv.DictReader(f))
        for line in out.split("\n"):
            if line:
                name, value, err = line.split()
                self.assertTrue(np.isclose(r[name], float(value), rtol=1e-7, atol=1e-12), name)
        self.assertEqual(len(rows), 2 * (6 + 5))
        counts = {}
        for row in rows:
            key = f"{row['side']}_{row['quantity']}"
            k = counts.get(key, 0)
            counts[key] = k + 1
            edges = r["theta_edges"] if row["quantity"] == "angular" else r["r_edges"]
            self.assertTrue(np.isclose(edges[k], float(row["lo"]), rtol=1e-8, atol=1e-12))
            self.assertTrue(np.isclose(r[key][k], float(row["value"]), rtol=1e-8, atol=1e-12), (key, k))
            self.assertTrue(np.isclose(r[key + "_stderr"][k], float(row["stderr"]), rtol=1e-8, atol=1e-12))

    def test_any_phase_function(self):
        r = nimbus.slab(mu_s=5.0, mu_a=0.0, thickness=0.5, phase="dhg:0.9,-0.3,0.9", photons=2000)
        self.assertAlmostEqual(r["absorbed"], 0.0, places=12)
        with self.assertRaises(nimbus.Error):
            nimbus.slab(mu_s=5.0, mu_a=0.0, thickness=0.5, g=0.5, phase="iso", photons=2000)
        with self.assertRaises(nimbus.Error):
            nimbus.slab(mu_s=-1.0, mu_a=0.0, thickness=0.5, photons=2000)


if __name__ == "__main__":
    unittest.main()
