#!/usr/bin/env python3
"""Close-ups of posed bodies over the points round them, to see what a rest or a seat the
detector found actually is (a pillow or an arm, a desk edge or an armrest).

Reads a cloud (PLY, detector frame: metres, z up, floor at z = 0) and the JSON of
`afford detect CLOUD --json OUT.json` for it, and draws one row per detection that affords
ID (every detection without --id): on the left the points within --radius metres of the
pelvis seen from above, coloured by height, with the body's joints (legs, trunk, arms) in
red and each elbow's height written beside it; on the right the same points seen from in
front of the body (x: to the body's left, z up), coloured by how far they lie ahead of
the pelvis (blue behind, red in front), with the joints in black. The title of a row gives
the detection's affordances, local scores (Eq. 3-4), position and heading.

Needs numpy and matplotlib (`pip install numpy matplotlib`); not used by the tests.

usage: tools/closeup.py CLOUD.ply DETECT.json OUT.png [--id armrest] [--radius 1.3]
e.g.   afford detect beds/views/bed_00_v03.ply --affordances sitting --json d.json -q
       tools/closeup.py beds/views/bed_00_v03.ply d.json bed_00_v03.png --id armrest
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cloud_views import read_ply, take_option  # noqa: E402

# Joint chains drawn as lines (names of agents/human.toml's joints).
CHAINS = [
    ["pelvis", "hip_l", "knee_l", "ankle_l"],
    ["pelvis", "hip_r", "knee_r", "ankle_r"],
    ["pelvis", "neck"],
    ["shoulder_l", "neck", "shoulder_r"],
    ["shoulder_l", "elbow_l", "wrist_l"],
    ["shoulder_r", "elbow_r", "wrist_r"],
]


def main(argv):
    args = list(argv)
    wanted = take_option(args, "--id", None, str)
    radius = take_option(args, "--radius", 1.3, float)
    if len(args) != 3:
        sys.exit(__doc__)
    cloud, result, out = args
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    points = read_ply(cloud)
    files = json.load(open(result))["files"]
    detections = [d for f in files for d in f["detections"]
                  if wanted is None or wanted in d["affordances"]]
    if not detections:
        sys.exit(f"{result}: no detection affords {wanted or 'anything'}")
    fig, axes = plt.subplots(len(detections), 2, figsize=(12, 5.5 * len(detections)),
                             squeeze=False)
    for row, det in zip(axes, detections):
        joints = {k: np.array(v) for k, v in det["joints"].items()}
        pelvis = joints["pelvis"]
        near = points[np.linalg.norm(points[:, :2] - pelvis[:2], axis=1) < radius]
        top, front = row
        s = top.scatter(near[:, 0], near[:, 1], c=near[:, 2], s=1, cmap="viridis")
        fig.colorbar(s, ax=top, label="z (m)")
        for chain in CHAINS:
            xyz = np.array([joints[j] for j in chain if j in joints])
            top.plot(xyz[:, 0], xyz[:, 1], "r-", lw=2)
        for side in "lr":
            e = joints.get("elbow_" + side)
            if e is not None:
                top.plot(e[0], e[1], "ko")
                top.text(e[0], e[1], f" {side} z {e[2]:.2f}")
        top.set_aspect("equal")
        scores = ", ".join(f"{k} {v:.3f}" for k, v in det["local_scores"].items())
        top.set_title(f"#{det['detection']} {', '.join(det['affordances'])}; local {scores}; "
                      f"at {np.round(pelvis, 2).tolist()}, yaw {det['yaw_deg']:.1f}",
                      fontsize=7)
        yaw = np.radians(det["yaw_deg"])
        ahead = np.array([np.cos(yaw), np.sin(yaw)])
        left = np.array([-ahead[1], ahead[0]])
        rel = near[:, :2] - pelvis[:2]
        s = front.scatter(rel @ left, near[:, 2], c=rel @ ahead, s=1, cmap="coolwarm")
        fig.colorbar(s, ax=front, label="ahead of the pelvis (m)")
        for chain in CHAINS:
            xyz = np.array([joints[j] for j in chain if j in joints])
            front.plot((xyz[:, :2] - pelvis[:2]) @ left, xyz[:, 2], "k-", lw=2)
        front.set_aspect("equal")
        front.set_title("seen from in front: x to the body's left (m), z up", fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=70)
    print(f"{len(detections)} detection(s) drawn in {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
