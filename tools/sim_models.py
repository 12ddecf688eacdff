#!/usr/bin/env python3
"""Rebuilds the simulation-model evaluation set listed in data/models/simmodels.csv.

Each row of simmodels.csv is one furniture mesh from a public robot-simulation repository
(`source_repo`, `source_path`, pinned `commit`) with its object-level labels
(docs/conventions.md). The script converts every mesh to the PLY that
`afford synth --models` reads (binary little endian, float x y z, triangles; metres, z up,
the lowest point at z = 0, the bounding box centred in x and y) and writes
OUT_DIR/meshes/<name>.ply and OUT_DIR/labels.csv (the label columns only, CRLF).

Formats: Collada .dae (<triangles>, <polylist>, <polygons>, <trifans>, <tristrips>; the
<library_visual_scenes> node transforms; <unit meter>; <up_axis> turned to z up unless the
row's `ignore_up_axis` is 1) and binary or ASCII .stl (no unit: taken as metres). The row's
`scale` multiplies the result (the model.sdf <scale>, 1 for every model now).

Usage:
    python3 tools/sim_models.py SRC_DIR OUT_DIR
    python3 tools/sim_models.py --git-dir-root MIRRORS OUT_DIR

SRC_DIR holds plain clones named <owner>+<name>, each checked out at the commit pinned in
simmodels.csv (the script stops if a clone is missing or its HEAD differs):

    mkdir SRC_DIR && cd SRC_DIR
    git clone https://github.com/aws-robotics/aws-robomaker-small-house-world aws-robotics+aws-robomaker-small-house-world
    git -C aws-robotics+aws-robomaker-small-house-world checkout dd44be6205b2e6577bf641300dacc1699cb2ca81
    git clone https://github.com/aws-robotics/aws-robomaker-bookstore-world aws-robotics+aws-robomaker-bookstore-world
    git -C aws-robotics+aws-robomaker-bookstore-world checkout ed542eb41809d5c5f1c67f32d4ba24e0e90886b3
    git clone https://github.com/ipa320/cob_simulation ipa320+cob_simulation
    git -C ipa320+cob_simulation checkout 907144342c0351c9427ddd960ef4dfe013847113
    git clone https://github.com/WPI-RAIL/rail_collada_models WPI-RAIL+rail_collada_models
    git -C WPI-RAIL+rail_collada_models checkout 573185318fbc539e2454cd03a828f20f9a9599ee

With --git-dir-root DIR the files are read as `git --git-dir=G show COMMIT:PATH` from bare
mirrors, G = DIR/<owner>+<name>/repo (or .../repo/.git, DIR/<owner>+<name>.git,
DIR/<owner>+<name>); there only the pinned commit must be present, HEAD may differ.

Python 3 standard library and numpy only.
"""
import argparse
import csv
import math
import os
import re
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_MODELS = os.path.join(REPO, "data", "models", "simmodels.csv")

# The header of the labels.csv that `afford synth --models` and `afford eval` read.
LABEL_COLUMNS = ["file", "class", "sitting", "backrest", "armrest", "headrest", "lying",
                 "width_m", "depth_m", "height_m", "source_repo", "source_path", "doubtful"]

# A written size may differ from the csv's by rounding only.
SIZE_TOLERANCE_M = 0.0015


class SourceError(Exception):
    """A problem with the sources, reported as one line without a traceback."""


# ---------------------------------------------------------------- reading the sources

def run_git(args):
    try:
        res = subprocess.run(["git"] + args, capture_output=True)
    except OSError as e:
        raise SourceError("cannot run git: %s" % e)
    if res.returncode != 0:
        msg = res.stderr.decode("utf-8", "replace").strip().splitlines()
        raise SourceError("git %s: %s" % (" ".join(args), msg[0] if msg else "failed"))
    return res.stdout


def clone_hint(repo, commit, where):
    return ("git clone https://github.com/%s %s && git -C %s checkout %s"
            % (repo, where, where, commit))


def work_tree_reader(src_dir, repo, commit):
    """Reads files of a clone at SRC_DIR/<owner>+<name>, after checking its HEAD."""
    where = os.path.join(src_dir, repo.replace("/", "+"))
    if not os.path.isdir(where):
        raise SourceError("no clone of %s at %s (%s)" % (repo, where, clone_hint(repo, commit, where)))
    head = run_git(["-C", where, "rev-parse", "HEAD"]).decode().strip()
    if head != commit:
        raise SourceError("%s is at %s, simmodels.csv pins %s (git -C %s checkout %s)"
                          % (where, head, commit, where, commit))

    def read(path):
        try:
            with open(os.path.join(where, path), "rb") as fh:
                return fh.read()
        except OSError as e:
            raise SourceError("%s: %s" % (repo, e))
    return read


def find_git_dir(root, repo):
    """The mirror's git directory: the layouts a bare snapshot or clone can have."""
    base = os.path.join(root, repo.replace("/", "+"))
    for cand in (os.path.join(base, "repo"), os.path.join(base, "repo", ".git"),
                 base + ".git", os.path.join(base, ".git"), base):
        if os.path.isfile(os.path.join(cand, "HEAD")) and os.path.isdir(os.path.join(cand, "objects")):
            return cand
    raise SourceError("no git mirror of %s under %s" % (repo, base))


def mirror_reader(root, repo, commit):
    """Reads files at the pinned commit of a bare mirror, whatever its HEAD."""
    git_dir = find_git_dir(root, repo)
    try:
        run_git(["--git-dir=" + git_dir, "cat-file", "-e", commit + "^{commit}"])
    except SourceError:
        raise SourceError("mirror %s lacks the pinned commit %s" % (git_dir, commit))

    def read(path):
        return run_git(["--git-dir=" + git_dir, "show", "%s:%s" % (commit, path)])
    return read


def open_sources(rows, src_dir, git_dir_root):
    """One reader per source repository, all checked before anything is converted."""
    readers = {}
    for row in rows:
        repo, commit = row["source_repo"], row["commit"]
        if repo in readers:
            continue
        if git_dir_root:
            readers[repo] = mirror_reader(git_dir_root, repo, commit)
        else:
            readers[repo] = work_tree_reader(src_dir, repo, commit)
    return readers


# ---------------------------------------------------------------- Collada

def floats(text):
    return np.array([float(t) for t in (text or "").split()], dtype=np.float64)


def ints(text):
    return np.array([int(t) for t in (text or "").split()], dtype=np.int64)


def strip_ns(root):
    # the COLLADA namespace differs between versions; tags are compared without it
    for el in root.iter():
        if isinstance(el.tag, str) and "}" in el.tag:
            el.tag = el.tag.split("}", 1)[1]
    return root


def rot_matrix(axis, deg):
    a = np.asarray(axis, dtype=np.float64)
    n = np.linalg.norm(a)
    if n == 0:
        return np.eye(4)
    x, y, z = a / n
    t = math.radians(deg)
    c, s, C = math.cos(t), math.sin(t), 1 - math.cos(t)
    m = np.eye(4)
    m[:3, :3] = [[x * x * C + c, x * y * C - z * s, x * z * C + y * s],
                 [y * x * C + z * s, y * y * C + c, y * z * C - x * s],
                 [z * x * C - y * s, z * y * C + x * s, z * z * C + c]]
    return m


def node_local(node):
    """The node's transform elements composed in document order (COLLADA post-multiplies)."""
    m = np.eye(4)
    for ch in node:
        if ch.tag == "matrix":
            m = m @ floats(ch.text).reshape(4, 4)
        elif ch.tag == "translate":
            t = np.eye(4)
            t[:3, 3] = floats(ch.text)[:3]
            m = m @ t
        elif ch.tag == "rotate":
            v = floats(ch.text)
            m = m @ rot_matrix(v[:3], v[3])
        elif ch.tag == "scale":
            s = np.eye(4)
            s[0, 0], s[1, 1], s[2, 2] = floats(ch.text)[:3]
            m = m @ s
        elif ch.tag in ("lookat", "skew"):
            raise SourceError("unsupported COLLADA transform <%s>" % ch.tag)
    return m


def fan(poly):
    return [(poly[0], poly[k], poly[k + 1]) for k in range(1, len(poly) - 1)]


def strip(s):
    # every other triangle of a strip is flipped to keep one winding
    return [(s[k], s[k + 1], s[k + 2]) if k % 2 == 0 else (s[k + 1], s[k], s[k + 2])
            for k in range(len(s) - 2)]


def primitive_triangles(prim, vidx):
    """Triangle index arrays of one primitive element; vidx maps a <p> to vertex indices."""
    if prim.tag == "triangles":
        return [vidx(p).reshape(-1, 3) for p in prim.findall("p")]
    out = []
    if prim.tag == "polylist":
        idx = vidx(prim.find("p"))
        start = 0
        for n in ints(prim.find("vcount").text):
            out += fan(idx[start:start + n])
            start += n
    elif prim.tag == "polygons":
        ps = prim.findall("p") + [ph.find("p") for ph in prim.findall("ph")]
        for p in ps:
            out += fan(vidx(p))
    elif prim.tag == "trifans":
        for p in prim.findall("p"):
            out += fan(vidx(p))
    elif prim.tag == "tristrips":
        for p in prim.findall("p"):
            out += strip(vidx(p))
    return [np.array(out, dtype=np.int64)] if out else []


class Dae:
    PRIMITIVES = ("triangles", "polylist", "polygons", "trifans", "tristrips")

    def __init__(self, data):
        self.root = strip_ns(ET.fromstring(data))
        # ids are looked up per element type: exporters reuse one id for a visual_scene and its node
        self.ids = {}
        for el in self.root.iter():
            if el.get("id") is not None:
                self.ids.setdefault((el.tag, el.get("id")), el)
        unit = self.root.find("asset/unit")
        self.unit = float(unit.get("meter")) if unit is not None and unit.get("meter") else 1.0
        up = self.root.find("asset/up_axis")
        self.up = up.text.strip() if up is not None and up.text else "Y_UP"

    def ref(self, url, tag):
        return self.ids[(tag, url.lstrip("#"))]

    def source_array(self, src_el):
        data = floats(src_el.find("float_array").text)
        acc = src_el.find("technique_common/accessor")
        stride = int(acc.get("stride", 3)) if acc is not None else 3
        offset = int(acc.get("offset", 0)) if acc is not None else 0
        count = int(acc.get("count")) if acc is not None else len(data) // stride
        return data[offset:offset + count * stride].reshape(count, stride)[:, :3]

    def geometry(self, geom):
        """(vertices Nx3, triangles Mx3) of a <geometry> in its own frame."""
        mesh = geom.find("mesh")
        if mesh is None:
            return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
        pos = None
        for inp in mesh.find("vertices").findall("input"):
            if inp.get("semantic") == "POSITION":
                pos = self.source_array(self.ref(inp.get("source"), "source"))
        tris = []
        for prim in mesh:
            if prim.tag in self.PRIMITIVES and prim.findall("input"):
                tris += primitive_triangles(prim, vertex_index_reader(prim))
        t = np.concatenate(tris) if tris else np.zeros((0, 3), dtype=np.int64)
        return pos, t

    def scene_meshes(self):
        """Vertices and triangles of all geometry instances, in the file's units and axes."""
        inst = self.root.find("scene/instance_visual_scene")
        if inst is not None:
            scene = self.ref(inst.get("url"), "visual_scene")
        else:
            scene = self.root.find("library_visual_scenes/visual_scene")
        verts, faces = [], []
        for node in scene.findall("node"):
            self.walk(node, np.eye(4), verts, faces)
        return np.concatenate(verts), np.concatenate(faces)

    def walk(self, node, parent, verts, faces):
        m = parent @ node_local(node)
        for ig in node.findall("instance_geometry"):
            pos, tri = self.geometry(self.ref(ig.get("url"), "geometry"))
            if len(tri) == 0:
                continue
            h = np.c_[pos, np.ones(len(pos))] @ m.T
            faces.append(tri + sum(len(v) for v in verts))
            verts.append(h[:, :3])
        for inode in node.findall("instance_node"):
            self.walk(self.ref(inode.get("url"), "node"), m, verts, faces)
        for child in node.findall("node"):
            self.walk(child, m, verts, faces)

    def to_metres_zup(self, v, ignore_up_axis):
        v = v * self.unit
        if ignore_up_axis:
            return v
        if self.up == "Y_UP":      # +90 degrees about x: y -> z, z -> -y
            v = np.c_[v[:, 0], -v[:, 2], v[:, 1]]
        elif self.up == "X_UP":    # x -> z
            v = np.c_[-v[:, 2], v[:, 1], v[:, 0]]
        return v


def vertex_index_reader(prim):
    """A function mapping a <p> of this primitive to its VERTEX indices (offset and stride)."""
    inputs = prim.findall("input")
    stride = max(int(i.get("offset", 0)) for i in inputs) + 1
    voff = [int(i.get("offset", 0)) for i in inputs if i.get("semantic") == "VERTEX"]
    if not voff:
        raise SourceError("no VERTEX input in <%s>" % prim.tag)
    return lambda p_el: ints(p_el.text).reshape(-1, stride)[:, voff[-1]]


def read_dae(data, ignore_up_axis):
    dae = Dae(data)
    v, f = dae.scene_meshes()
    return dae.to_metres_zup(v, ignore_up_axis), f


# ---------------------------------------------------------------- STL

def read_stl(data):
    """Binary STL if the size matches its triangle count, else ASCII; vertices welded."""
    if len(data) >= 84:
        n = struct.unpack("<I", data[80:84])[0]
        if 84 + 50 * n == len(data):
            rec = np.frombuffer(data[84:], count=n,
                                dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
            v = rec["v"].reshape(-1, 3).astype(np.float64)
            return weld(v, np.arange(len(v)).reshape(-1, 3))
    txt = data.decode("ascii", "replace")
    v = np.array([[float(x) for x in m.groups()] for m in
                  re.finditer(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", txt)], dtype=np.float64)
    return weld(v, np.arange(len(v)).reshape(-1, 3))


def weld(v, f):
    """Merges identical vertices: STL repeats them for every triangle."""
    _, inv = np.unique(np.round(v, 6), axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    out = np.zeros((inv.max() + 1, 3))
    out[inv] = v
    return out, inv[f]


# ---------------------------------------------------------------- PLY output

def normalise(v, f):
    """Drops degenerate triangles and unused vertices; centres x, y; lowest point to z = 0."""
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    used = np.unique(f)
    remap = -np.ones(len(v), dtype=np.int64)
    remap[used] = np.arange(len(used))
    v, f = v[used], remap[f]
    lo, hi = v.min(0), v.max(0)
    return v - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]]), f


def write_ply(path, v, f):
    v = np.ascontiguousarray(v, dtype="<f4")
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
              % (len(v), len(f))).encode()
    rec = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    rec["n"] = 3
    rec["i"] = f
    with open(path, "wb") as fh:
        fh.write(header)
        fh.write(v.tobytes())
        fh.write(rec.tobytes())


# ---------------------------------------------------------------- the set

def convert_row(row, read):
    """The normalised mesh of one simmodels.csv row."""
    path = row["source_path"]
    data = read(path)
    ext = path.lower().rsplit(".", 1)[-1]
    if ext == "dae":
        v, f = read_dae(data, row["ignore_up_axis"] == "1")
    elif ext == "stl":
        v, f = read_stl(data)
    else:
        raise SourceError("%s: unsupported mesh format .%s" % (path, ext))
    return normalise(v * float(row["scale"]), f)


def size_mismatch(row, v):
    """A note if the mesh's size is not the csv's: the source or the converter changed."""
    size = v.max(0) - v.min(0)
    want = [float(row[k]) for k in ("width_m", "depth_m", "height_m")]
    if np.all(np.abs(size - want) <= SIZE_TOLERANCE_M):
        return None
    return "%s: size %.3f x %.3f x %.3f m, simmodels.csv says %s x %s x %s" % (
        row["file"], size[0], size[1], size[2], row["width_m"], row["depth_m"], row["height_m"])


def build(rows, readers, out_dir):
    """Writes the meshes and labels.csv; returns the size mismatches."""
    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    problems = []
    for row in rows:
        v, f = convert_row(row, readers[row["source_repo"]])
        write_ply(os.path.join(out_dir, row["file"]), v, f)
        problems += [p for p in [size_mismatch(row, v)] if p]
        print("%-40s %6d vertices %6d triangles" % (row["file"], len(v), len(f)))
    # csv's default line end is CRLF, as in the labels files the set was made from
    with open(os.path.join(out_dir, "labels.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(LABEL_COLUMNS)
        for row in rows:
            w.writerow([row[k] for k in LABEL_COLUMNS])
    return problems


def read_models(path):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    need = LABEL_COLUMNS + ["commit", "ignore_up_axis", "scale"]
    missing = [k for k in need if rows and k not in rows[0]]
    if missing:
        raise SourceError("%s lacks the columns %s" % (path, ", ".join(missing)))
    for row in rows:
        # the mesh name is taken from `file`; it must stay inside OUT_DIR/meshes
        if not re.fullmatch(r"meshes/[A-Za-z0-9_.-]+\.ply", row["file"]):
            raise SourceError("%s: bad file name %r" % (path, row["file"]))
    return rows


def parse_args():
    ap = argparse.ArgumentParser(
        description="Rebuild the simulation-model set of data/models/simmodels.csv: "
                    "OUT_DIR/meshes/*.ply and OUT_DIR/labels.csv.",
        usage="%(prog)s [-h] [--models CSV] (SRC_DIR | --git-dir-root DIR) OUT_DIR")
    ap.add_argument("dirs", nargs="+", metavar="DIR",
                    help="SRC_DIR (clones named <owner>+<name>) and OUT_DIR; only OUT_DIR "
                         "with --git-dir-root")
    ap.add_argument("--git-dir-root", metavar="DIR",
                    help="read from bare mirrors DIR/<owner>+<name>/repo at the pinned commits")
    ap.add_argument("--models", default=DEFAULT_MODELS,
                    help="the recipe and labels (default: data/models/simmodels.csv)")
    a = ap.parse_args()
    want = 1 if a.git_dir_root else 2
    if len(a.dirs) != want:
        ap.error("give SRC_DIR OUT_DIR, or --git-dir-root DIR OUT_DIR")
    a.src_dir = None if a.git_dir_root else a.dirs[0]
    a.out_dir = a.dirs[-1]
    return a


def main():
    a = parse_args()
    try:
        rows = read_models(a.models)
        readers = open_sources(rows, a.src_dir, a.git_dir_root)
        problems = build(rows, readers, a.out_dir)
    except SourceError as e:
        print("sim_models.py: error: %s" % e, file=sys.stderr)
        return 1
    for p in problems:
        print("sim_models.py: size differs: %s" % p, file=sys.stderr)
    print("%d models written to %s" % (len(rows), a.out_dir))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
