#!/usr/bin/env python3
"""Cuts clouds with vertical planes through the body the detector placed, as an image edge
would cut a bed or a seat, to measure what a detector loses (or wrongly gains) when part of
the furniture is out of view.

Reads the JSON results of `afford detect FILES --out-dir DIR` (one per cloud; PLY clouds
only) and, for each cloud with a detection of HIERARCHY, takes its best-scoring one and
writes these cuts of the cloud (every point on the far side of the plane dropped, floor
included) under OUT, with OUT/labels.csv giving each cut the labels `--label` names:

- lying (the body's axis from the pelvis to the ankles): `side` and `side0` keep 0.25 m and
  0.10 m beside the axis (a bed cut lengthwise); `feet0` and `feet30` keep the head end up
  to the pelvis and 0.30 m past it; `head20` keeps the foot end from 0.20 m above the pelvis;
- sitting (the body's heading, from the back to the front of the seat): `back10` keeps from
  0.10 m behind the pelvis on (the back out of view); `front10` and `front20` keep up to
  0.10 m and 0.20 m in front of it (the seat's front out of view).

Labels are per object (docs/conventions.md): a bed cut by the image edge is still a bed.

usage: tools/cut_views.py DETECTIONS_DIR OUT --hierarchy lying|sitting --label NAME=0|1 ...
e.g.   afford detect beds/views/*.ply --affordances lying --out-dir det -q
       tools/cut_views.py det cut --hierarchy lying --label lying=1
       afford eval cut/labels.csv --affordances lying
"""
import glob
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cloud_views import read_ply  # noqa: E402


def cuts(hierarchy, d, xy):
    """The cuts of points `xy` (N x 2) for detection `d`: (tag, mask of the points kept)."""
    pelvis = np.array(d["position"][:2])
    if hierarchy == "lying":
        j = d["joints"]
        feet = (np.array(j["ankle_l"][:2]) + np.array(j["ankle_r"][:2])) / 2.0
        axis = (feet - pelvis) / np.linalg.norm(feet - pelvis)
        s = (xy - pelvis) @ axis
        t = (xy - pelvis) @ np.array([-axis[1], axis[0]])
        return [("side", t < 0.25), ("side0", t < 0.10), ("feet0", s < 0.0),
                ("feet30", s < 0.30), ("head20", s > -0.20)]
    yaw = np.radians(d["yaw_deg"])
    s = (xy - pelvis) @ np.array([np.cos(yaw), np.sin(yaw)])
    return [("back10", s > -0.10), ("front10", s < 0.10), ("front20", s < 0.20)]


def write_ply(path, p):
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(p)}\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n").encode()
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(head + p.astype("<f4").tobytes())
    os.replace(tmp, path)


def main():
    args = sys.argv[1:]
    labels = []
    hierarchy = None
    rest = []
    while args:
        a = args.pop(0)
        if a == "--hierarchy" and args:
            hierarchy = args.pop(0)
        elif a == "--label" and args:
            name, _, value = args.pop(0).partition("=")
            labels.append((name, value))
        else:
            rest.append(a)
    if len(rest) != 2 or hierarchy not in ("lying", "sitting") or not labels:
        sys.exit(__doc__)
    det, out = rest
    os.makedirs(out, exist_ok=True)
    rows = []
    for path in sorted(glob.glob(os.path.join(det, "*.json"))):
        for f in json.load(open(path))["files"]:
            found = [d for d in f["detections"] if d["hierarchy"] == hierarchy]
            if not found or not f["file"].endswith(".ply"):
                continue
            best = max(found, key=lambda d: d["score"])
            p = read_ply(f["file"])
            name = os.path.splitext(os.path.basename(f["file"]))[0]
            for tag, keep in cuts(hierarchy, best, p[:, :2]):
                if keep.any():
                    write_ply(os.path.join(out, f"{name}_{tag}.ply"), p[keep])
                    rows.append(f"{name}_{tag}.ply")
    with open(os.path.join(out, "labels.csv"), "w") as g:
        g.write("file," + ",".join(n for n, _ in labels) + "\n")
        for r in rows:
            g.write(r + "," + ",".join(v for _, v in labels) + "\n")
    print(f"{len(rows)} cut clouds and {os.path.join(out, 'labels.csv')}")


if __name__ == "__main__":
    main()
