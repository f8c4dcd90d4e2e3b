"""The examples in examples/ run (at small sizes) and write their plots."""
import os
import subprocess
import sys
import tempfile
import unittest

from nimbus_test_support import SOURCE_DIR


def run_example(name, *args):
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, os.path.join(SOURCE_DIR, "examples", name), *args], env=env,
                       capture_output=True, text=True, timeout=240)
    if r.returncode != 0:
        raise AssertionError(f"{name} exited {r.returncode}:\n{r.stdout}\n{r.stderr}")
    return r.stdout


class Examples(unittest.TestCase):
    def test_albedo_sweep(self):
        with tempfile.TemporaryDirectory() as d:
            out = run_example("albedo_sweep.py", "--out", d, "--size", "16", "--spp", "2",
                              "--albedos", "0.3,0.9,0.99", "--integrators", "single,pathtrace")  # mfs: seconds of set-up each
            self.assertTrue(os.path.getsize(os.path.join(d, "albedo_sweep.png")) > 0)
        means = [float(line.split()[-1]) for line in out.splitlines() if line.startswith("albedo")]
        self.assertEqual(len(means), 3)
        self.assertEqual(means, sorted(means))  # brighter as less is absorbed

    def test_disney_cloud(self):
        with tempfile.TemporaryDirectory() as d:
            out = run_example("disney_cloud.py", "--out", d, "--size", "32", "--spp", "4", "--mfs-spp", "1",
                              "--mfs-photons", "8192", "--mfs-grid", "16")
            self.assertTrue(os.path.getsize(os.path.join(d, "disney_cloud.png")) > 0)
        self.assertIn("relative RMSE", out)


if __name__ == "__main__":
    unittest.main()
