"""nimbus.render from dicts and files against the CLI, bit for bit; errors with their JSON path; progress
and interruption."""
import json
import os
import signal
import tempfile
import threading
import time
import unittest

import numpy as np

from nimbus_test_support import cli, small_scene, write_json
import nimbus


class RenderMatchesCli(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def cli_render(self, doc, *args):
        scene = os.path.join(self.dir, "scene.json")
        out = os.path.join(self.dir, "out.exr")
        write_json(scene, doc)
        cli("render", scene, "-o", out, "-q", *args)
        return nimbus.read_exr(out)

    def test_dict_render_equals_cli_bit_for_bit(self):
        for integrator in ("pathtrace", "single"):  # (mfs: the same driver, seconds of set-up)
            with self.subTest(integrator=integrator):
                doc = small_scene(integrator)
                exr = self.cli_render(doc)
                r = nimbus.render(nimbus.scene_from_dict(doc))
                self.assertEqual(r["rgba"].dtype, np.float32)
                self.assertEqual(r["rgba"].shape, (16, 24, 4))
                self.assertTrue(np.array_equal(r["rgba"], exr["rgba"]), integrator)
                self.assertGreater(float(r["rgba"][..., :3].mean()), 0.0)
                self.assertEqual((r["integrator"], r["spp"], r["width"], r["height"]), (integrator, 4, 24, 16))
                self.assertEqual(r["settings"]["type"], integrator)
                self.assertEqual(json.loads(exr["metadata"]["nimbus/integrator_settings"]), r["settings"])

    def test_options_match_cli_options(self):
        doc = small_scene("pathtrace", spp=2)
        exr = self.cli_render(doc, "--spp", "3", "--seed", "11", "--threads", "2")
        r = nimbus.render(doc, spp=3, seed=11, threads=1)  # a dict is accepted as it is
        self.assertTrue(np.array_equal(r["rgba"], exr["rgba"]))
        self.assertEqual((r["spp"], r["seed"]), (3, 11))

    def test_file_with_overrides_equals_cli_set(self):
        scene = os.path.join(self.dir, "scene.json")
        write_json(scene, small_scene())
        out = os.path.join(self.dir, "set.exr")
        cli("render", scene, "-o", out, "-q", "--set", "camera.width=20", "--set", "media.0.sigma_s=2.5")
        s = nimbus.load_scene(scene, overrides={"camera.width": 20, "media.0.sigma_s": 2.5})
        self.assertEqual((s.width, s.height, s.file), (20, 16, scene))
        self.assertEqual(s.document["media"][0]["sigma_s"], 2.5)
        self.assertTrue(np.array_equal(nimbus.render(s)["rgba"], nimbus.read_exr(out)["rgba"]))
        s2 = nimbus.load_scene(scene, overrides=["camera.width=20", "media.0.sigma_s=2.5"])
        self.assertTrue(np.array_equal(nimbus.render(s2)["rgba"], nimbus.read_exr(out)["rgba"]))

    def test_layers(self):
        r = nimbus.render(small_scene(spp=2), layers=["depth", "direct", "samples"])
        self.assertEqual(set(r["layers"]), {"depth", "direct", "samples"})
        self.assertEqual(r["layers"]["depth"].shape, (16, 24))
        self.assertEqual(r["layers"]["direct"].shape, (16, 24, 3))
        self.assertTrue(np.all(r["layers"]["samples"] == 2))
        centre = r["layers"]["depth"][8, 12]
        self.assertTrue(3.0 < centre < 5.0, centre)  # the sphere's near side lies 3 from the camera

    def test_adaptive_noise_equals_cli(self):
        doc = small_scene("pathtrace")
        exr = self.cli_render(doc, "--noise", "0.2", "--spp", "256")
        r = nimbus.render(doc, noise=0.2, spp=256, layers=["samples"])
        self.assertTrue(np.array_equal(r["rgba"], exr["rgba"]))
        self.assertLessEqual(r["noise_estimate"], 0.2)
        self.assertGreater(r["noise_estimate"], 0.0)
        n = r["layers"]["samples"]
        self.assertEqual(float(n.max()), float(r["spp"]))
        self.assertGreaterEqual(float(n.min()), 8.0)
        self.assertAlmostEqual(r["spp_mean"], float(n.mean()), places=4)

    def test_write_image_round_trip(self):
        r = nimbus.render(small_scene(spp=1))
        path = os.path.join(self.dir, "w.exr")
        nimbus.write_image(path, r["rgba"])
        self.assertTrue(np.array_equal(nimbus.read_exr(path)["rgba"], r["rgba"]))


class Errors(unittest.TestCase):
    def test_dict_errors_carry_the_json_path(self):
        doc = small_scene()
        doc["media"][0]["sigma_s"] = -1
        with self.assertRaises(nimbus.SceneError) as e:
            nimbus.scene_from_dict(doc)
        self.assertIn("/media/0/sigma_s", str(e.exception))
        self.assertIsInstance(e.exception, ValueError)

    def test_dict_and_file_give_the_same_message(self):
        doc = small_scene()
        doc["camera"]["widht"] = 3
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "bad.json")
            write_json(path, doc)
            with self.assertRaises(nimbus.SceneError) as from_file:
                nimbus.load_scene(path)
            r = cli("render", path, "-o", os.path.join(d, "x.exr"), check=False)
            self.assertEqual(r.returncode, 2)
            self.assertFalse(os.path.exists(os.path.join(d, "x.exr")))
        with self.assertRaises(nimbus.SceneError) as from_dict:
            nimbus.scene_from_dict(doc)
        self.assertIn("/camera/widht", str(from_dict.exception))
        self.assertEqual(str(from_file.exception).replace(path, "(dict)"), str(from_dict.exception))
        self.assertIn(str(from_file.exception), r.stderr)

    def test_values_without_json_form(self):
        doc = small_scene()
        doc["lights"][0]["irradiance"] = object()
        with self.assertRaises(nimbus.SceneError) as e:
            nimbus.scene_from_dict(doc)
        self.assertIn("/lights/0/irradiance", str(e.exception))

    def test_numpy_values_are_numbers(self):
        doc = small_scene()
        doc["media"][0]["sigma_s"] = np.float32(4.0)
        doc["camera"]["position"] = np.array([0, -4, 0.3])
        doc["camera"]["width"] = np.int64(24)
        self.assertEqual(nimbus.scene_from_dict(doc).width, 24)

    def test_bad_overrides(self):
        with self.assertRaises(nimbus.SceneError) as e:
            nimbus.scene_from_dict(small_scene(), overrides={"camera.width": "wide"})
        self.assertIn("/camera/width", str(e.exception))
        with self.assertRaises(nimbus.SceneError) as e:
            nimbus.scene_from_dict(small_scene(), overrides={"media.3.sigma_s": 1})
        self.assertIn("media.3.sigma_s", str(e.exception))

    def test_missing_file_and_bad_options(self):
        with self.assertRaises(nimbus.SceneError) as e:
            nimbus.load_scene("/nonexistent/scene.json")
        self.assertIn("/nonexistent/scene.json", str(e.exception))
        with self.assertRaises(nimbus.Error):
            nimbus.render(small_scene(), layers=["nope"])
        with self.assertRaises(nimbus.Error):
            nimbus.render(small_scene(), integrator="nope")
        with self.assertRaises(nimbus.Error):
            nimbus.render(small_scene(), spp=0)

    def test_relative_paths_resolve_against_base_dir(self):
        doc = small_scene()
        doc["media"][0]["shape"] = {"type": "vdb", "file": "tiny.vdb"}
        with self.assertRaises(nimbus.SceneError) as e:
            nimbus.scene_from_dict(doc, base_dir="/nonexistent")
        self.assertIn("/media/0/shape/file", str(e.exception))
        self.assertIn("/nonexistent/tiny.vdb", str(e.exception))
        from nimbus_test_support import SOURCE_DIR
        s = nimbus.scene_from_dict(doc, base_dir=os.path.join(SOURCE_DIR, "fuzz", "data"))
        self.assertEqual(s.media, 1)


class ProgressAndInterrupt(unittest.TestCase):
    def test_progress_is_called(self):
        calls = []
        nimbus.render(small_scene(spp=8), progress=lambda done, total: calls.append((done, total)))
        self.assertGreater(len(calls), 0)
        done, total = calls[-1]
        self.assertEqual(done, total)
        self.assertEqual(total, 24 * 16 * 8)
        self.assertEqual(calls, sorted(calls))

    def test_an_exception_in_the_callback_stops_the_render(self):
        class Stop(Exception):
            pass

        def progress(done, total):
            raise Stop()

        start = time.monotonic()
        with self.assertRaises(Stop):
            nimbus.render(small_scene(spp=1 << 20, width=64, height=64), progress=progress)
        self.assertLess(time.monotonic() - start, 20.0)

    def test_ctrl_c_raises_keyboard_interrupt(self):
        timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
        start = time.monotonic()
        timer.start()
        try:
            with self.assertRaises(KeyboardInterrupt):
                nimbus.render(small_scene(spp=1 << 20, width=64, height=64))
        finally:
            timer.cancel()
        self.assertLess(time.monotonic() - start, 20.0)
        # The module still works afterwards.
        self.assertEqual(nimbus.render(small_scene(spp=1))["spp"], 1)

    def test_the_gil_is_released(self):
        """Python threads run while a render runs (with the GIL held they would wait for it)."""
        done = threading.Event()
        result = {}

        def work():
            result["r"] = nimbus.render(small_scene(spp=1 << 20, width=32, height=32), time_limit=1.0)
            done.set()

        t = threading.Thread(target=work)
        t.start()
        ticks = 0
        while not done.is_set():
            ticks += 1
            time.sleep(0.01)
        t.join()
        self.assertGreater(ticks, 20)
        self.assertTrue(result["r"]["time_limited"])

    def test_time_limit(self):
        r = nimbus.render(small_scene(spp=1 << 20, width=32, height=32), time_limit=0.5)
        self.assertTrue(r["time_limited"])
        self.assertLess(r["spp"], 1 << 20)
        self.assertGreaterEqual(r["spp"], 1)


class TransientRender(unittest.TestCase):
    def test_time_bins_sum_to_the_image(self):
        doc = small_scene("pathtrace", spp=4)
        doc["film"] = {"time_bins": [3.0, 9.0, 6]}
        r = nimbus.render(doc, threads=2)
        plain = nimbus.render(small_scene("pathtrace", spp=4), threads=2)
        self.assertTrue(np.array_equal(r["rgba"], plain["rgba"]))  # the steady image is unchanged
        t = r["time_bins"]
        self.assertEqual(t["bins"].shape, (6, 16, 24, 3))
        self.assertEqual((t["under"].shape, t["over"].shape), ((16, 24, 3), (16, 24, 3)))
        self.assertTrue(np.allclose(t["edges"], np.linspace(3.0, 9.0, 7)))
        total = t["bins"].astype(np.float64).sum(axis=0) + t["under"] + t["over"]
        rgb = r["rgba"][..., :3].astype(np.float64)
        self.assertTrue(np.allclose(total, rgb, rtol=1e-5, atol=1e-7), float(np.abs(total - rgb).max()))
        self.assertGreater(float(t["bins"].sum()), 0.1 * float(rgb.sum()))  # the bins hold the light
        again = nimbus.render(doc, threads=1)["time_bins"]
        self.assertTrue(np.array_equal(again["bins"], t["bins"]))
        self.assertNotIn("time_bins", plain)


if __name__ == "__main__":
    unittest.main()
