#!/usr/bin/env python3
"""Camera-view preview of an organised PCD (for labelling real scans by eye).

Writes OUT.png: the RGB channel when the cloud has one (rgb/rgba field), beside a
shaded depth image (near light, far dark, NaN black), both in the camera's pixel grid.
Reads ascii, binary and binary_compressed PCD (LZF), with numpy only.

usage: tools/pcd_preview.py IN.pcd OUT.png
"""
import os
import struct
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cloud_views import write_png  # noqa: E402


def lzf_decompress(data, out_len):
    """Plain LZF decoder (the scheme PCD binary_compressed uses)."""
    out = bytearray(out_len)
    i = o = 0
    n = len(data)
    while i < n:
        ctrl = data[i]
        i += 1
        if ctrl < 32:
            ln = ctrl + 1
            out[o:o + ln] = data[i:i + ln]
            i += ln
            o += ln
        else:
            ln = ctrl >> 5
            ref = o - ((ctrl & 0x1F) << 8) - 1
            if ln == 7:
                ln += data[i]
                i += 1
            ref -= data[i]
            i += 1
            ln += 2
            for k in range(ln):
                out[o + k] = out[ref + k]
            o += ln
    return bytes(out)


def read_pcd(path):
    raw = open(path, "rb").read()
    header = {}
    pos = 0
    while True:
        end = raw.index(b"\n", pos)
        line = raw[pos:end].decode("ascii", "replace").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        header[key.upper()] = vals
        if key.upper() == "DATA":
            break
    fields = header["FIELDS"]
    sizes = [int(s) for s in header["SIZE"]]
    types = header["TYPE"]
    counts = [int(c) for c in header.get("COUNT", ["1"] * len(fields))]
    w, h = int(header["WIDTH"][0]), int(header["HEIGHT"][0])
    n = w * h
    kind = {"F": "f", "U": "u", "I": "i"}
    dtypes = [np.dtype(f"<{kind[t]}{s}") for t, s in zip(types, sizes)]
    mode = header["DATA"][0]
    cols = {}
    if mode == "ascii":
        arr = np.loadtxt(raw[pos:].decode().splitlines(), ndmin=2)
        c = 0
        for f, cnt, dt in zip(fields, counts, dtypes):
            cols[f] = arr[:, c].astype(np.float64)
            c += cnt
    elif mode == "binary":
        rec = np.dtype([(f"{f}_{k}", dt, (cnt,)) for k, (f, cnt, dt) in enumerate(zip(fields, counts, dtypes))])
        arr = np.frombuffer(raw[pos:pos + rec.itemsize * n], rec)
        for k, f in enumerate(fields):
            cols[f] = arr[f"{f}_{k}"][:, 0]
    else:
        comp, dec = struct.unpack("<II", raw[pos:pos + 8])
        body = lzf_decompress(raw[pos + 8:pos + 8 + comp], dec)
        off = 0
        for f, cnt, dt, s in zip(fields, counts, dtypes, sizes):
            cols[f] = np.frombuffer(body[off:off + n * cnt * s], dt).reshape(n, cnt)[:, 0]
            off += n * cnt * s
    return cols, w, h


def main():
    cols, w, h = read_pcd(sys.argv[1])
    if h == 1:
        sys.exit(f"{sys.argv[1]}: not organised (height 1); no camera view")
    z = cols["z"].astype(np.float64).reshape(h, w)
    ok = np.isfinite(z) & (z > 0)
    lo, hi = (np.percentile(z[ok], [2, 98]) if ok.any() else (0, 1))
    g = np.clip(1 - (z - lo) / max(hi - lo, 1e-6), 0, 1) * 215 + 40
    depth = np.where(ok, g, 0).astype(np.uint8)
    depth = np.stack([depth] * 3, -1)
    panels = [depth]
    key = "rgb" if "rgb" in cols else ("rgba" if "rgba" in cols else None)
    if key:
        v = cols[key]
        u = (v.view(np.uint32) if v.dtype.kind == "f" else v.astype(np.uint32)).reshape(h, w)
        rgb = np.stack([(u >> 16) & 255, (u >> 8) & 255, u & 255], -1).astype(np.uint8)
        panels.insert(0, rgb)
    write_png(sys.argv[2], np.concatenate(panels, 1))


if __name__ == "__main__":
    main()
