"""A reader of the EXR files nimbus writes, for the validation scripts (/usr/bin/python3 has no OpenEXR
module): single-part scanline files with ZIP or no compression, FLOAT, HALF and UINT channels (the OpenEXR
file layout: openexr.com, 'OpenEXR File Layout')."""
import struct
import zlib

import numpy as np

PIXEL_TYPES = {0: "<u4", 1: "<f2", 2: "<f4"}  # UINT, HALF, FLOAT


def read_exr(path):
    """({channel name: H x W array of its type}, {string attribute: value}), row 0 at the top."""
    data = open(path, "rb").read()
    assert struct.unpack_from("<i", data, 0)[0] == 20000630, "not an EXR"
    pos, channels, attrs = 8, [], {}
    compression, window = None, None
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        name = data[pos:name_end].decode()
        type_end = data.index(b"\0", name_end + 1)
        kind = data[name_end + 1:type_end].decode()
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        value = data[type_end + 5:type_end + 5 + size]
        if name == "channels":
            p = 0
            while value[p] != 0:
                e = value.index(b"\0", p)
                channels.append((value[p:e].decode(), np.dtype(PIXEL_TYPES[struct.unpack_from("<i", value, e + 1)[0]])))
                p = e + 17
        elif name == "compression":
            compression = value[0]
        elif name == "dataWindow":
            window = struct.unpack("<4i", value)
        elif kind == "string":
            attrs[name] = value.decode()
        pos = type_end + 5 + size
    pos += 1
    assert compression in (0, 3), "only ZIP or no compression"
    x0, y0, x1, y1 = window
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = 16 if compression == 3 else 1
    line_bytes = sum(w * dt.itemsize for _, dt in channels)
    offsets = struct.unpack_from(f"<{(h + lines - 1) // lines}Q", data, pos)
    out = {c: np.zeros((h, w), dt) for c, dt in channels}
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        raw = data[off + 8:off + 8 + size]
        n = min(lines, y1 + 1 - y)
        if size < n * line_bytes:  # compressed (a chunk that would not shrink is stored as it is)
            t = np.frombuffer(zlib.decompress(raw), np.uint8).astype(np.int32)
            t = (np.cumsum(np.concatenate([t[:1], t[1:] - 128])) & 0xFF).astype(np.uint8)  # the predictor
            half = (len(t) + 1) // 2
            raw = np.empty_like(t)
            raw[0::2], raw[1::2] = t[:half], t[half:]  # the byte interleaving
            raw = raw.tobytes()
        p = 0
        for r in range(n):
            for c, dt in channels:  # each line holds every channel's row in turn
                out[c][y - y0 + r] = np.frombuffer(raw, dt, w, p)
                p += w * dt.itemsize
    return out, attrs
