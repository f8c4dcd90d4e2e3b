"""Convert EXR files to (h, w, 3) float32 .npy arrays, row 0 = top (run inside Blender).

    blender -b --factory-startup --python validation/cycles/exr_to_npy.py -- A.exr A.npy [B.exr B.npy ...]

/usr/bin/python3 has no OpenEXR module; Blender's image loader reads the float buffer unchanged.
"""
import sys

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:]
if len(argv) % 2:
    raise SystemExit("exr_to_npy.py: expected pairs IN.exr OUT.npy")
for src, dst in zip(argv[0::2], argv[1::2]):
    img = bpy.data.images.load(src, check_existing=False)
    w, h = img.size
    buf = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    bpy.data.images.remove(img)
    np.save(dst, buf.reshape(h, w, 4)[::-1, :, :3].copy())
    print(f"exr_to_npy: {src} -> {dst} ({w}x{h})")
