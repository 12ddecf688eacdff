#!/usr/bin/env python3
"""Three orthographic views of a PLY/PCD cloud in the detector's frame, for labelling by eye.

Top (looking down, x right, y up), front (looking along +y, x right, z up) and side
(looking along -x, y right... i.e. along x, y to the right, z up); each pixel shows the
nearest point, shaded by its depth along the view (near light, far dark) and tinted by
height (z). Scale is the same in all views and printed in the file name's sidecar line on
stdout. Reads binary little-endian / ascii PLY with float or double x y z (other vertex
properties skipped), with numpy only.

usage: tools/cloud_views.py IN.ply OUT.png [--px 0.01]
"""
import struct
import sys
import zlib

import numpy as np

PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4",
             "uint": "u4", "float": "f4", "double": "f8", "int8": "i1", "uint8": "u1",
             "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4",
             "float32": "f4", "float64": "f8"}


def read_ply(path):
    raw = open(path, "rb").read()
    end = raw.index(b"end_header") + len(b"end_header")
    end = raw.index(b"\n", end) + 1
    lines = raw[:end].decode("ascii", "replace").splitlines()
    fmt, n, props, in_vertex = None, 0, [], False
    for ln in lines:
        t = ln.split()
        if not t:
            continue
        if t[0] == "format":
            fmt = t[1]
        elif t[0] == "element":
            in_vertex = t[1] == "vertex"
            if in_vertex:
                n = int(t[2])
        elif t[0] == "property" and in_vertex:
            props.append((t[-1], PLY_TYPES[t[1]]))
    if fmt == "ascii":
        arr = np.loadtxt(raw[end:].decode().splitlines()[:n], ndmin=2)
        idx = [p[0] for p in props]
        return np.stack([arr[:, idx.index(c)] for c in "xyz"], 1)
    dt = np.dtype([(nm, ("<" if fmt == "binary_little_endian" else ">") + t) for nm, t in props])
    arr = np.frombuffer(raw[end:end + dt.itemsize * n], dt)
    return np.stack([arr[c].astype(np.float64) for c in "xyz"], 1)


def view(p, a, b, d, px, near_high):
    """Project onto axes a (right), b (up); keep the nearest along d."""
    lo = p.min(0)
    u = ((p[:, a] - lo[a]) / px).astype(int)
    v = ((p[:, b] - lo[b]) / px).astype(int)
    w, h = u.max() + 1, v.max() + 1
    depth = p[:, d] if near_high else -p[:, d]
    order = np.argsort(depth)  # far first, near overwrites
    img = np.zeros((h, w, 3), np.uint8)
    dn = (depth - depth.min()) / max(np.ptp(depth), 1e-6)
    zn = (p[:, 2] - p[:, 2].min()) / max(np.ptp(p[:, 2]), 1e-6)
    shade = 0.35 + 0.65 * dn
    col = np.stack([0.25 + 0.75 * zn, 0.55 + 0.2 * (1 - zn), 1 - 0.8 * zn], 1)
    rgb = (col * shade[:, None] * 255).astype(np.uint8)
    img[h - 1 - v[order], u[order]] = rgb[order]
    return img


def write_png(path, img):
    h, w, _ = img.shape
    rows = b"".join(b"\x00" + img[y].tobytes() for y in range(h))
    def chunk(t, d):
        c = struct.pack(">I", len(d)) + t + d
        return c + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows, 6)) + chunk(b"IEND", b"")
    open(path, "wb").write(png)


def take_option(args, name, default, kind):
    """Removes `name VALUE` from the argument list `args` and returns VALUE as `kind`."""
    if name not in args:
        return default
    i = args.index(name)
    value = kind(args[i + 1])
    del args[i:i + 2]
    return value


def main():
    args = sys.argv[1:]
    px = take_option(args, "--px", 0.01, float)
    p = read_ply(args[0])
    p = p[np.isfinite(p).all(1)]
    lo, hi = np.percentile(p, 0.5, 0), np.percentile(p, 99.5, 0)
    p = p[((p >= lo - 0.05) & (p <= hi + 0.05)).all(1)]
    ext = np.ptp(p, 0)
    px = max(px, ext.max() / 700)
    top = view(p, 0, 1, 2, px, True)
    front = view(p, 0, 2, 1, px, False)
    side = view(p, 1, 2, 0, px, True)
    gap = 12
    h = max(top.shape[0], front.shape[0], side.shape[0])
    pad = lambda im: np.concatenate([im, np.full((h - im.shape[0], im.shape[1], 3), 255, np.uint8)], 0)
    sep = np.full((h, gap, 3), 255, np.uint8)
    write_png(args[1], np.concatenate([pad(top), sep, pad(front), sep, pad(side)], 1))
    print(f"{args[1]}: top | front (along +y) | side (along -x); {px*100:.1f} cm/px; "
          f"extent x {ext[0]:.2f} y {ext[1]:.2f} z {ext[2]:.2f} m; z from {p[:,2].min():.2f}")


if __name__ == "__main__":
    main()
