#!/usr/bin/python3
"""Pictures for docs/transient.md: a light pulse sweeping through the Disney cloud.

Renders scenes/disney_cloud_pulse.json with the built `nimbus` (default build/bin/nimbus, or $NIMBUS) as a
transient render (`render --time-bins`), reads the time bins from OUT.time.exr (a small reader of
scanline ZIP EXRs of float channels, the files nimbus writes, below) and writes
  docs/images/transient_cloud.gif         the bins as an animation (each frame: one bin, fixed exposure),
  docs/images/transient_cloud_frames.png  six of them side by side, with the steady image,
  docs/images/transient_cloud_streak.png  a streak image: x against time along one image row.
Usage:  /usr/bin/python3 validation/transient_pictures.py [--spp N] [--res WxH] [--bins T0,T1,N]
"""
import argparse
import os
import subprocess
import tempfile

import numpy as np
from PIL import Image, ImageDraw

from exr_reader import read_exr

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NIMBUS = os.environ.get("NIMBUS", os.path.join(ROOT, "build", "bin", "nimbus"))
IMAGES = os.path.join(ROOT, "docs", "images")
LOG_K = 100.0  # the frames' and the streak's logarithmic display (to_png)


def srgb(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def to_png(rgb, scale, k=0.0):
    """sRGB of rgb * scale; with k > 0 a logarithmic display log(1 + k x) / log(1 + k) that shows light a
    hundred times fainter than the brightest (late, multiply scattered) beside the first arrivals."""
    x = np.maximum(rgb * scale, 0.0)
    if k > 0:
        x = np.log1p(k * x) / np.log1p(k)
    return Image.fromarray((255 * srgb(x) + 0.5).astype(np.uint8))


def layer(ch, name):
    return np.dstack([ch[f"{name}.R"], ch[f"{name}.G"], ch[f"{name}.B"]])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", default="160x90")
    ap.add_argument("--bins", default="1050,1850,32")
    ap.add_argument("--row", type=float, default=0.5, help="the streak's row, as a fraction of the height")
    args = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="nimbus_transient_")
    out = os.path.join(tmp, "pulse.exr")
    cmd = ["nice", "-n", "19", NIMBUS, "render", os.path.join(ROOT, "scenes", "disney_cloud_pulse.json"), "-o",
           out, "--spp", str(args.spp), "--res", args.res, "--time-bins", args.bins, "--threads", "2", "--quiet"]
    print(" ".join(cmd))
    subprocess.run(cmd, check=True)
    ch, attrs = read_exr(os.path.join(tmp, "pulse.time.exr"))
    t0, t1, n = (float(v) for v in attrs["nimbus/time_bins"].split(","))
    n = int(n)
    steady = np.dstack([ch["R"], ch["G"], ch["B"]])
    bins = [layer(ch, f"time{k:04d}") for k in range(n)]
    total = sum(bins) + layer(ch, "time_under") + layer(ch, "time_over")
    err = np.abs(total - steady).max() / max(steady.max(), 1e-30)
    print(f"render: {attrs.get('nimbus/render_seconds')} s; max |sum of bins - steady| / max = {err:.2e}")
    # One exposure for every frame (the 99.9th percentile of all bins maps to 1), logarithmic display.
    scale = 1.0 / max(np.percentile(np.stack(bins), 99.9), 1e-30)
    dt = (t1 - t0) / n
    frames = []
    for k, b in enumerate(bins):
        im = to_png(b, scale, LOG_K)
        ImageDraw.Draw(im).text((3, 2), f"s = {t0 + k * dt:.0f}-{t0 + (k + 1) * dt:.0f}", fill=(255, 255, 0))
        frames.append(im)
    os.makedirs(IMAGES, exist_ok=True)
    frames[0].save(os.path.join(IMAGES, "transient_cloud.gif"), save_all=True, append_images=frames[1:],
                   duration=120, loop=0)
    # Six frames and the steady image side by side.
    picks = [int(round(i * (n - 1) / 5)) for i in range(6)]
    steady_png = to_png(steady, 1.0 / max(np.percentile(steady, 99.5), 1e-30))
    ImageDraw.Draw(steady_png).text((3, 2), "steady", fill=(255, 255, 0))
    tiles = [frames[k] for k in picks] + [steady_png]
    w, h = tiles[0].size
    sheet = Image.new("RGB", (w * 4 + 6, h * 2 + 2), (40, 40, 40))
    for i, t in enumerate(tiles):
        sheet.paste(t, ((i % 4) * (w + 2), (i // 4) * (h + 2)))
    sheet.save(os.path.join(IMAGES, "transient_cloud_frames.png"))
    # Streak: the row's pixels (x, across) against time (down), each bin a band of rows.
    y = int(args.row * (steady.shape[0] - 1))
    streak = np.stack([b[y] for b in bins])  # n x W x 3
    band = max(1, 160 // n)
    streak = np.repeat(streak, band, axis=0)
    im = to_png(streak, 1.0 / max(np.percentile(streak, 99.9), 1e-30), LOG_K)
    canvas = Image.new("RGB", (im.size[0] + 60, im.size[1] + 16), (0, 0, 0))
    canvas.paste(im, (60, 0))
    d = ImageDraw.Draw(canvas)
    for k in range(0, n + 1, max(1, n // 5)):
        d.text((2, min(k * band, im.size[1] - 10)), f"s={t0 + k * dt:.0f}", fill=(255, 255, 255))
    d.text((60, im.size[1] + 3), f"x along row {y} ->", fill=(255, 255, 255))
    canvas.save(os.path.join(IMAGES, "transient_cloud_streak.png"))
    print("wrote", ", ".join(f"docs/images/transient_cloud{s}" for s in (".gif", "_frames.png", "_streak.png")))


if __name__ == "__main__":
    main()
