#!/usr/bin/env python3
"""A probe set that `afford synth` does not draw: messy beds.

Writes OUT/meshes/*.ply (binary triangle meshes: metres, z up, floor at z = 0) and
OUT/labels.csv in the format of labelled furniture models (`afford synth --models`): beds
0.9-1.8 m wide, mattress top 0.40-0.60 m, under a duvet 0.03-0.08 m thick with 2-6 smooth
lumps 0.03-0.15 m high and 0.10-0.35 m wide (a duvet thrown back, a blanket under it),
one or two pillows 0.10-0.20 m high, and at random a folded blanket at the foot, a bag on
the bed and a headboard. Labels, by docs/conventions.md: sitting and lying; no backrest,
armrest or headrest (a bed is sat on at its edge). Column `extras` says what was drawn.

Usage:
    python3 tools/messy_beds.py OUT [--seed 5] [--count 30]
    afford synth --models OUT/labels.csv --views 4 --out OUT/views
    afford eval OUT/views/labels.csv --heights 1.75
"""
import argparse, math, os, random, struct

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("out")
ap.add_argument("--seed", type=int, default=5)
ap.add_argument("--count", type=int, default=30)
args = ap.parse_args()
out, N = args.out, args.count
rng = random.Random(args.seed)
u = rng.uniform
os.makedirs(os.path.join(out, "meshes"), exist_ok=True)
def box(V, F, a, b):
    (x0, y0, z0), (x1, y1, z1) = a, b
    c = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    i = len(V); V.extend(c)
    for a_, b_, c_, d_ in [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]:
        F.append((i + a_, i + b_, i + c_)); F.append((i + a_, i + c_, i + d_))
def field(V, F, x0, x1, y0, y1, nx, ny, h):
    i = len(V)
    for j in range(ny + 1):
        for k in range(nx + 1):
            x = x0 + (x1 - x0) * k / nx; y = y0 + (y1 - y0) * j / ny
            V.append((x, y, h(x, y)))
    for j in range(ny):
        for k in range(nx):
            a = i + j * (nx + 1) + k; b = a + 1; c = a + nx + 1; d = c + 1
            F.append((a, b, d)); F.append((a, d, c))
def write(path, V, F):
    with open(path, 'wb') as f:
        f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\nproperty float z\nelement face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
        for v in V: f.write(struct.pack('<3f', *v))
        for t in F: f.write(struct.pack('<B3i', 3, *t))
rows = []
for i in range(N):
    V, F = [], []
    L = u(1.9, 2.1); W = rng.choice([0.9, 1.2, 1.4, 1.6, 1.8]); top = u(0.40, 0.60)
    hx, hy = L / 2, W / 2
    box(V, F, (-hx, -hy, 0.0), (hx, hy, top))  # frame and mattress as one block
    bumps = [(u(-hx + 0.5, hx), u(-hy, hy), u(0.03, 0.15), u(0.10, 0.35)) for _ in range(rng.randint(2, 6))]
    dt = u(0.03, 0.08)
    def duvet(x, y):
        z = top + dt
        for bx, by, a, w in bumps:
            z += a * math.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * w * w))
        return z
    field(V, F, -hx + 0.35, hx + 0.02, -hy - 0.02, hy + 0.02, 40, 30, duvet)
    # pillows
    n = 2 if W >= 1.2 else 1
    for k in range(n):
        pw = min(W / n - 0.06, u(0.5, 0.7)); yc = -hy + W * (k + 0.5) / n; ph = u(0.10, 0.20)
        box(V, F, (-hx + 0.03, yc - pw / 2, top), (-hx + 0.38, yc + pw / 2, top + ph))
    extras = []
    if rng.random() < 0.5:  # folded blanket at the foot
        bl = u(0.3, 0.5); box(V, F, (hx - bl, -hy, top + dt), (hx, hy, top + dt + u(0.05, 0.12))); extras.append('blanket')
    if rng.random() < 0.5:  # a bag or a box on the bed
        cx, cy = u(-hx + 0.6, hx - 0.3), u(-hy + 0.2, hy - 0.2)
        box(V, F, (cx - 0.15, cy - 0.1, top + dt), (cx + 0.15, cy + 0.1, top + dt + u(0.10, 0.25))); extras.append('bag')
    if rng.random() < 0.7:  # headboard
        box(V, F, (-hx - 0.05, -hy, 0.0), (-hx, hy, top + u(0.4, 0.8))); extras.append('headboard')
    name = f"bed_{i:02d}"; write(os.path.join(out, "meshes", name + ".ply"), V, F)
    rows.append((name, '+'.join(extras), W, top))
with open(os.path.join(out, "labels.csv"), "w") as f:
    f.write('file,class,sitting,backrest,armrest,headrest,lying,width_m,depth_m,height_m,source_repo,source_path,doubtful,extras\n')
    for n, ex, W, top in rows:
        f.write(f"meshes/{n}.ply,bed,1,0,0,0,1,{W},2,{top:.2f},probe,probe,,{ex}\n")
print(f"{len(rows)} models in {out}")
