#!/usr/bin/env python3
"""Rewrites a labelled set of clouds with one perturbation, for robustness probes: the
set's labels.csv and its clouds (PLY or PCD, detector frame) in, DST/labels.csv and one
binary little-endian PLY (float x y z) per row out, the `file` column renamed to it. The
other columns are kept, so `afford eval DST/labels.csv` scores the perturbed set.

Kinds and AMOUNT:
  noise SIGMA     Gaussian noise of SIGMA metres on every coordinate
  strays F        F times the point count again, strewn uniformly over the cloud's box
  clumps F        the same number of points in clumps of ten (sigma 1 cm round a
                  uniform centre): floating fragments, speckle
  tilt DEG        the cloud turned DEG degrees about x through its centroid
  keep F          a random fraction F of the points kept
  voxel EDGE      one point per EDGE-metre voxel, the centroid (PCL's VoxelGrid)
  none 0          the clouds rewritten unchanged (float32 PLY, as the others)

One random stream (seed --seed, default 7) runs over the rows in order: the same set,
kind, amount and seed write the same files. The robustness probe of docs/results.md
(2026-11-26) was made this way on the wide seed 2. Needs numpy.

usage: tools/perturb.py SRC/labels.csv DST KIND AMOUNT [--seed 7]
"""
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cloud_views import read_ply, take_option  # noqa: E402
from pcd_preview import read_pcd  # noqa: E402


def read_cloud(path):
    if path.lower().endswith(".pcd"):
        cols, _, _ = read_pcd(path)
        p = np.stack([np.asarray(cols[c], np.float64) for c in "xyz"], 1)
        return p[np.isfinite(p).all(1)]
    return read_ply(path)


def perturb(p, kind, amt, rng):
    if kind == "noise":
        return p + rng.normal(0, amt, p.shape)
    if kind == "strays":
        n = int(len(p) * amt)
        lo, hi = p.min(0), p.max(0)
        return np.vstack([p, lo + rng.random((n, 3)) * (hi - lo)])
    if kind == "clumps":
        n = int(len(p) * amt / 10)
        lo, hi = p.min(0), p.max(0)
        c = lo + rng.random((n, 3)) * (hi - lo)
        return np.vstack([p] + [c + rng.normal(0, 0.01, (n, 3)) for _ in range(10)])
    if kind == "tilt":
        a = np.radians(amt)
        c = p.mean(0)
        r = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        return (p - c) @ r.T + c
    if kind == "keep":
        return p[rng.random(len(p)) < amt]
    if kind == "voxel":
        k = np.floor(p / amt).astype(np.int64)
        _, inv = np.unique(k, axis=0, return_inverse=True)
        inv = inv.ravel()
        n = inv.max() + 1
        s = np.zeros((n, 3))
        np.add.at(s, inv, p)
        return s / np.bincount(inv, minlength=n)[:, None]
    if kind == "none":
        return p
    sys.exit(f"unknown kind {kind!r}\n\n{__doc__}")


def write_ply(path, p):
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(p)}\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n").encode()
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(head)
        f.write(p.astype("<f4").tobytes())
    os.replace(tmp, path)


def main():
    args = sys.argv[1:]
    seed = take_option(args, "--seed", 7, int)
    if len(args) != 4:
        sys.exit(__doc__)
    labels, dst, kind, amt = args[0], args[1], args[2], float(args[3])
    src = os.path.dirname(os.path.abspath(labels))
    os.makedirs(dst, exist_ok=True)
    with open(labels, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{labels}: no rows")
    rng = np.random.default_rng(seed)
    out = []
    for r in rows:
        p = perturb(read_cloud(os.path.join(src, r["file"])), kind, amt, rng)
        name = os.path.splitext(r["file"])[0] + ".ply"
        write_ply(os.path.join(dst, name), p)
        out.append(dict(r, file=name))
    with open(os.path.join(dst, "labels.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(out)
    print(f"{len(out)} clouds written to {dst} ({kind} {amt:g}, seed {seed})")


if __name__ == "__main__":
    main()
