"""Shared by the Python tests (tests/python/test_*.py, run by ctest with PYTHONPATH=build/python).

NIMBUS_CLI names the command-line program and NIMBUS_SOURCE_DIR the source tree (ctest sets both; by hand
they default to build/bin/nimbus and the repository of this file)."""
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.environ.get("NIMBUS_SOURCE_DIR", os.path.dirname(os.path.dirname(HERE)))
CLI = os.environ.get("NIMBUS_CLI", os.path.join(SOURCE_DIR, "build", "bin", "nimbus"))
if "nimbus" not in sys.modules:
    sys.path.insert(0, os.path.join(SOURCE_DIR, "build", "python"))


def small_scene(integrator="pathtrace", spp=4, width=24, height=16):
    """A sphere of HG medium under a sun and a sky: a few milliseconds to render."""
    return {
        "camera": {"position": [0, -4, 0.3], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 35,
                   "width": width, "height": height},
        "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1},
                   "sigma_s": 4.0, "sigma_a": 0.1, "phase": {"type": "hg", "g": 0.7}}],
        "lights": [{"type": "directional", "direction": [-0.5, 0.5, -0.707], "irradiance": 3.0},
                   {"type": "environment", "radiance": [0.05, 0.08, 0.15]}],
        "integrator": {"type": integrator, "spp": spp, "seed": 7},
    }


def write_json(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f)


def cli(*args, check=True):
    """Runs the nimbus CLI; returns the CompletedProcess (stdout and stderr as text)."""
    r = subprocess.run([CLI, *args], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"nimbus {' '.join(args)} exited {r.returncode}: {r.stderr}")
    return r
