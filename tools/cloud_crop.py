#!/usr/bin/env python3
"""Keeps the points of a PLY cloud inside an axis-aligned box (detector frame, metres) and
writes them as binary little-endian PLY (float x y z), e.g. to cut one chair out of a scan.
Bounds may be '-' for unbounded. Optional --stride N keeps every N-th kept point (to
subsample a committed sample below 1 MB).

usage: tools/cloud_crop.py IN.ply OUT.ply XMIN XMAX YMIN YMAX [ZMIN ZMAX] [--stride N]
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cloud_views import read_ply, take_option  # noqa: E402


def main():
    args = sys.argv[1:]
    stride = take_option(args, "--stride", 1, int)
    src, dst, *b = args
    if len(b) not in (4, 6):
        sys.exit(__doc__)
    b += ["-", "-"] * ((6 - len(b)) // 2)
    p = read_ply(src)
    keep = np.isfinite(p).all(1)
    for k in range(3):
        lo, hi = b[2 * k], b[2 * k + 1]
        if lo != "-":
            keep &= p[:, k] >= float(lo)
        if hi != "-":
            keep &= p[:, k] <= float(hi)
    q = p[keep][::stride].astype("<f4")
    if len(q) == 0:
        sys.exit(f"{src}: no point inside the box")
    head = (f"ply\nformat binary_little_endian 1.0\ncomment cropped from {os.path.basename(src)}"
            f" box {' '.join(b)}\nelement vertex {len(q)}\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n").encode()
    tmp = dst + ".tmp"
    with open(tmp, "wb") as f:
        f.write(head + q.tobytes())
    os.replace(tmp, dst)
    print(f"{dst}: {len(q)} points")


if __name__ == "__main__":
    main()
