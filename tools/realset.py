#!/usr/bin/env python3
"""Rebuilds the real-scan development set described by data/real/realset.csv.

Each row of the CSV is one labelled cloud (labels in the shape `afford eval` reads, scene
level, docs/conventions.md) with its provenance (`source_repo`, `source_path`, `commit`,
`licence`) and how it is made:

- kind `pcd` / `ply`: the file is fetched and run through
  `afford convert RAW OUT.ply [--camera] --floor auto [--transform PITCH]`, where `pitch_deg`
  (the camera's approximate downward pitch, degrees) pre-rotates a camera frame about its x
  axis so that the floor finder, which searches within 25 degrees of up, sees the floor;
  `frame` is `camera` for a depth-camera frame (x right, y down, z forward), or the axis
  that is about up (`--up`): `y` for PCL's OpenNI frames, whose `VIEWPOINT 0 0 0 0 1 0 0`
  (180 degrees about x, applied by the reader) turns the camera frame to y up, z backward;
- kind `depth`: a 16-bit depth PNG, back-projected with `depth_to_ply` (an example of this
  crate) using `intrinsics` (fx,fy,cx,cy) and `depth_scale` (units per metre), then
  converted as above;
- kind `crop`: the points of the already built cloud `crop_of` inside `crop_box`
  (xmin xmax ymin ymax, detector frame, metres), e.g. one chair cut from a scene.

Sources come from raw.githubusercontent.com at the pinned commit, or, with --mirror DIR,
from local bare clones DIR/<owner>+<name>/repo (as `git show COMMIT:PATH`). Nothing is
written into the repository: everything goes under OUT.

usage: tools/realset.py OUT [--mirror DIR] [--afford BIN] [--depth-to-ply BIN]
       (build the two binaries first: cargo build --release --examples)
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def fetch(row, mirror, dest):
    repo, commit = row["source_repo"], row["commit"]
    for path in row["source_path"].split(" | ")[:1]:
        if mirror:
            git = os.path.join(mirror, repo.replace("/", "+"), "repo")
            data = subprocess.run(["git", "-C", git, "show", f"{commit}:{path}"],
                                  check=True, capture_output=True).stdout
        else:
            url = f"https://raw.githubusercontent.com/{repo}/{commit}/{path}"
            with urllib.request.urlopen(url) as r:
                data = r.read()
        with open(dest, "wb") as f:
            f.write(data)


def pitch_matrix(deg):
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    m = [1, 0, 0, 0, 0, c, s, 0, 0, -s, c, 0, 0, 0, 0, 1]
    return " ".join(f"{v:.6f}" for v in m)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--labels", default=os.path.join(REPO, "data", "real", "realset.csv"))
    ap.add_argument("--mirror")
    ap.add_argument("--afford", default=os.path.join(REPO, "target", "release", "afford"))
    ap.add_argument("--depth-to-ply", default=os.path.join(
        REPO, "target", "release", "examples", "depth_to_ply"))
    ap.add_argument("--only", help="build only this file name")
    a = ap.parse_args()
    raw_dir = os.path.join(a.out, "raw")
    os.makedirs(raw_dir, exist_ok=True)
    rows = list(csv.DictReader(open(a.labels, newline="")))
    failed = 0
    for row in rows:
        name = row["file"]
        if a.only and name != a.only:
            continue
        out = os.path.join(a.out, name)
        kind = row["kind"]
        try:
            if kind == "crop":
                src = os.path.join(a.out, row["crop_of"])
                subprocess.run([sys.executable, os.path.join(HERE, "cloud_crop.py"), src, out,
                                *row["crop_box"].split()], check=True)
                continue
            ext = os.path.splitext(row["source_path"].split(" | ")[0])[1]
            raw = os.path.join(raw_dir, os.path.splitext(name)[0] + ext)
            if not os.path.exists(raw):
                fetch(row, a.mirror, raw)
            src = raw
            if kind == "depth":
                src = raw + ".camera.ply"
                subprocess.run([a.depth_to_ply, raw, src, "--intrinsics", row["intrinsics"],
                                "--scale", row["depth_scale"]], check=True)
            cmd = [a.afford, "convert", src, out, "--floor", "auto"]
            if row["frame"] == "camera":
                cmd.append("--camera")
            else:
                cmd.append(f"--up={row['frame']}")
            if row["pitch_deg"] and float(row["pitch_deg"]) != 0:
                cmd += ["--transform", pitch_matrix(float(row["pitch_deg"]))]
            subprocess.run(cmd, check=True)
        except (subprocess.CalledProcessError, OSError) as e:
            print(f"error: {name}: {e}", file=sys.stderr)
            failed += 1
    shutil.copy(a.labels, os.path.join(a.out, "labels.csv"))
    print(f"{len(rows)} rows, {failed} failed; labels in {os.path.join(a.out, 'labels.csv')}")
    sys.exit(2 if failed else 0)


if __name__ == "__main__":
    main()
