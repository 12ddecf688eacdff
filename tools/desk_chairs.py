#!/usr/bin/env python3
"""A probe set that `afford synth` does not draw: office chairs pushed in under desks.

Writes OUT/meshes/*.ply (binary triangle meshes: metres, z up, floor at z = 0) and
OUT/labels.csv in the format of labelled furniture models (`afford synth --models`):
every sixth model is a desk alone (a negative), the others an office chair (arms in half
of them) pushed in under a desk with a front apron or a drawer, its seat front 0.05-0.25 m
under the desk top and at least 0.30 m left between its back and the desk edge (room for
the trunk), the drawer or apron 0.03-0.2 m over the seat. Labels, by docs/conventions.md:
sitting and backrest, armrest where the chair has arms. Extra columns: `gap_m` (apron or
drawer bottom over the seat top), `under` (apron or drawer), `push_m` (seat front under
the desk edge).

Usage:
    python3 tools/desk_chairs.py OUT [--seed 7] [--count 36]
    afford synth --models OUT/labels.csv --views 4 --out OUT/views
    afford eval OUT/views/labels.csv --heights 1.65,1.75,1.85
"""
import argparse, math, os, random, struct

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("out")
ap.add_argument("--seed", type=int, default=7)
ap.add_argument("--count", type=int, default=36)
args = ap.parse_args()
rng = random.Random(args.seed)
os.makedirs(os.path.join(args.out, "meshes"), exist_ok=True)
u = rng.uniform
def box(V, F, a, b, yaw=0.0, off=(0, 0)):
    (x0, y0, z0), (x1, y1, z1) = a, b
    c = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    cs, sn = math.cos(yaw), math.sin(yaw)
    c = [(off[0] + cs * x - sn * y, off[1] + sn * x + cs * y, z) for x, y, z in c]
    i = len(V); V.extend(c)
    q = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    for a_, b_, c_, d_ in q:
        F.append((i + a_, i + b_, i + c_)); F.append((i + a_, i + c_, i + d_))
def write(path, V, F):
    with open(path, 'wb') as f:
        f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\nproperty float z\nelement face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
        for v in V: f.write(struct.pack('<3f', *v))
        for t in F: f.write(struct.pack('<B3i', 3, *t))
def desk(V, F):
    top = u(0.70, 0.76); th = u(0.025, 0.04); depth = u(0.6, 0.8); length = u(1.2, 1.6)
    x0 = 0.0  # front edge at x = 0, desk towards +x
    box(V, F, (x0, -length / 2, top - th), (x0 + depth, length / 2, top))
    for lx in (x0 + 0.01, x0 + depth - 0.05):
        for ly in (-length / 2 + 0.01, length / 2 - 0.05):
            box(V, F, (lx, ly, 0), (lx + 0.04, ly + 0.04, top - th))
    kind = rng.choice(['apron', 'drawer'])
    if kind == 'apron':
        h = u(0.06, 0.12)
        box(V, F, (x0 + 0.02, -length / 2 + 0.05, top - th - h), (x0 + 0.04, length / 2 - 0.05, top - th))
        low = top - th - h
    else:
        h = u(0.10, 0.16); w = u(0.4, 0.6)
        box(V, F, (x0 + 0.01, -w / 2, top - th - h), (x0 + u(0.4, 0.5), w / 2, top - th))
        low = top - th - h
    return low, kind
def chair(V, F, low):
    while True:
        sh = u(0.42, 0.52)
        if low - sh >= 0.03: break
    sd = u(0.40, 0.48); sw = u(0.44, 0.50); st = 0.05
    # seat front under the desk by 0.05-0.25 m, trunk room (>= 0.30 m back to desk edge) kept
    push = u(0.05, min(0.25, max(0.05, sd - 0.30)))
    arms = rng.random() < 0.5
    # seat front edge at x = push (under the desk, whose front edge is x = 0)
    fx = push; bx = push - sd
    box(V, F, (bx, -sw / 2, sh - st), (fx, sw / 2, sh))
    bh = u(0.30, 0.50); tilt = math.radians(u(0, 10))
    n = 6
    for k in range(n):  # tilted back as a stack of slabs
        z0 = sh + bh * k / n; z1 = sh + bh * (k + 1) / n
        dx = -math.tan(tilt) * (z0 - sh)
        box(V, F, (bx - 0.03 + dx, -sw / 2, z0), (bx + dx, sw / 2, z1))
    for lx in (bx + 0.02, fx - 0.05):
        for ly in (-sw / 2 + 0.02, sw / 2 - 0.05):
            box(V, F, (lx, ly, 0), (lx + 0.03, ly + 0.03, sh - st))
    if arms:
        ah = u(0.20, 0.25)
        for s in (-1, 1):
            y0 = s * sw / 2 - (0.05 if s > 0 else 0)
            box(V, F, (bx, y0, sh + ah - 0.03), (bx + 0.30, y0 + 0.05, sh + ah))
            box(V, F, (bx + 0.25, y0 + 0.01, sh), (bx + 0.28, y0 + 0.04, sh + ah - 0.03))
    return sh, sd, arms, push
rows = []
for i in range(args.count):
    V, F = [], []
    low, kind = desk(V, F)
    if i % 6 == 5:
        name = f"desk_{i:02d}"; write(os.path.join(args.out, "meshes", f"{name}.ply"), V, F)
        rows.append((name, 'desk', 0, 0, 0, low, kind, 0, 0)); continue
    s_h, s_d, arms, push = chair(V, F, low)
    name = f"chair_at_desk_{i:02d}"; write(os.path.join(args.out, "meshes", f"{name}.ply"), V, F)
    rows.append((name, 'office_chair_at_desk', 1, 1, int(arms), low - s_h, kind, push, s_d))
with open(os.path.join(args.out, "labels.csv"), "w") as f:
    f.write('file,class,sitting,backrest,armrest,headrest,lying,width_m,depth_m,height_m,source_repo,source_path,doubtful,gap_m,under,push_m\n')
    for n, c, s, b, a, gap, kind, push, sd in rows:
        f.write(f"meshes/{n}.ply,{c},{s},{b},{a},0,0,1,1,1,probe,probe,,{gap:.3f},{kind},{push:.3f}\n")
print(f"{len(rows)} models in {args.out}")
