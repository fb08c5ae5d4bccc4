#!/usr/bin/env python3
"""Writes scenes/room/room.obj and room.mtl: a furnished living room for the metrics (paper §IV uses
indoor scenes). Closed room 6 x 3 x 5 m (y up), four area lights of different shapes, furniture, a
16-sided pillar and a low-poly sphere. Every face is wound counter-clockwise seen from its front (into
the room for the shell, outwards for objects, and towards the room for the lights).

Run from the project root: python3 scripts/make_room.py
"""
import math

out = []


def sub(a, b): return [a[i] - b[i] for i in range(3)]
def add(a, b): return [a[i] + b[i] for i in range(3)]
def scale(a, s): return [x * s for x in a]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def mean(ps): return [sum(p[i] for p in ps) / len(ps) for i in range(3)]


def face(pts, facing):
    """One polygon, reordered so that its normal points along `facing`."""
    n = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))
    if dot(n, facing) < 0:
        pts = pts[::-1]
    for p in pts:
        out.append("v %.4f %.4f %.4f" % tuple(p))
    k = len(pts)
    out.append("f " + " ".join(str(-(k - i)) for i in range(k)))


def group(name, material):
    out.append(f"\ng {name}\nusemtl {material}")


def box(name, material, lo, hi):
    """An axis-aligned box, faces outwards (the bottom face too: a box may stand on legs)."""
    group(name, material)
    c = mean([lo, hi])
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    quads = [
        [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0]],
        [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
        [[x0, y0, z0], [x0, y1, z0], [x0, y1, z1], [x0, y0, z1]],
        [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]],
        [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
        [[x0, y1, z0], [x1, y1, z0], [x1, y1, z1], [x0, y1, z1]],
    ]
    for q in quads:
        face(q, sub(mean(q), c))


def ngon(center, radius, normal_axis, sides, facing, start=0.0):
    """Regular polygon in the plane perpendicular to a coordinate axis."""
    pts = []
    for k in range(sides):
        a = start + 2 * math.pi * k / sides
        u, v = radius * math.cos(a), radius * math.sin(a)
        if normal_axis == 1:
            pts.append([center[0] + u, center[1], center[2] + v])
        elif normal_axis == 2:
            pts.append([center[0] + u, center[1] + v, center[2]])
        else:
            pts.append([center[0], center[1] + u, center[2] + v])
    face(pts, facing)


# The shell: x in [-3, 3], y in [0, 3], z in [-2.5, 2.5]; normals point into the room.
inside = [0.0, 1.5, 0.0]
for name, material, quad in [
    ("floor", "wood", [[-3, 0, -2.5], [3, 0, -2.5], [3, 0, 2.5], [-3, 0, 2.5]]),
    ("ceiling", "ceiling", [[-3, 3, -2.5], [3, 3, -2.5], [3, 3, 2.5], [-3, 3, 2.5]]),
    ("back_wall", "plaster", [[-3, 0, -2.5], [3, 0, -2.5], [3, 3, -2.5], [-3, 3, -2.5]]),
    ("front_wall", "plaster", [[-3, 0, 2.5], [3, 0, 2.5], [3, 3, 2.5], [-3, 3, 2.5]]),
    ("left_wall", "terracotta", [[-3, 0, -2.5], [-3, 3, -2.5], [-3, 3, 2.5], [-3, 0, 2.5]]),
    ("right_wall", "sage", [[3, 0, -2.5], [3, 3, -2.5], [3, 3, 2.5], [3, 0, 2.5]]),
]:
    group(name, material)
    face(quad, sub(inside, mean(quad)))

# Lights, each just inside its wall or ceiling, facing the room.
group("ceiling_panel", "panel_light")          # rectangle
face([[-1.6, 2.99, -1.2], [-0.4, 2.99, -1.2], [-0.4, 2.99, -0.6], [-1.6, 2.99, -0.6]], [0, -1, 0])
group("round_light", "warm_light")             # disc
ngon([1.5, 2.99, 0.8], 0.35, 1, 20, [0, -1, 0])
group("strip_light", "cool_light")             # long thin strip on the back wall
face([[-1.0, 2.2, -2.49], [1.0, 2.2, -2.49], [1.0, 2.28, -2.49], [-1.0, 2.28, -2.49]], [0, 0, 1])
group("triangle_lamp", "amber_light")          # triangle on the left wall
face([[-2.99, 1.2, 0.8], [-2.99, 1.2, 1.6], [-2.99, 1.9, 1.2]], [1, 0, 0])

# Furniture.
box("table_top", "walnut", [-0.9, 0.72, -0.5], [0.5, 0.78, 0.3])
for i, (x, z) in enumerate([(-0.85, -0.45), (0.45, -0.45), (-0.85, 0.25), (0.45, 0.25)]):
    box(f"table_leg_{i}", "walnut", [x - 0.03, 0.0, z - 0.03], [x + 0.03, 0.72, z + 0.03])
for i, x in enumerate([-0.6, 0.2]):
    box(f"chair_seat_{i}", "linen", [x - 0.22, 0.44, 0.45], [x + 0.22, 0.49, 0.89])
    box(f"chair_back_{i}", "linen", [x - 0.22, 0.49, 0.84], [x + 0.22, 0.95, 0.89])
    for j, (dx, dz) in enumerate([(-0.19, 0.48), (0.19, 0.48), (-0.19, 0.86), (0.19, 0.86)]):
        box(f"chair_leg_{i}_{j}", "linen", [x + dx - 0.02, 0.0, dz - 0.02], [x + dx + 0.02, 0.44, dz + 0.02])
box("sofa_base", "blue_fabric", [1.2, 0.0, -2.3], [2.9, 0.42, -1.5])
box("sofa_back", "blue_fabric", [1.2, 0.42, -2.3], [2.9, 0.9, -2.05])
box("sofa_arm", "blue_fabric", [2.7, 0.42, -2.05], [2.9, 0.62, -1.5])
box("shelf", "birch", [-2.95, 0.0, -2.4], [-2.55, 1.9, -1.2])
for i, (y, colour) in enumerate([(0.45, "red_books"), (0.95, "green_books"), (1.45, "red_books")]):
    box(f"books_{i}", colour, [-2.54, y, -2.3], [-2.4, y + 0.3, -1.4])

# A 16-sided pillar (one surface: 22.5° between faces, under the 30° crease angle) and a sphere.
group("pillar", "plaster")
sides, r, c = 16, 0.18, (2.2, 0.6)
for k in range(sides):
    a0, a1 = 2 * math.pi * k / sides, 2 * math.pi * (k + 1) / sides
    p0 = [c[0] + r * math.cos(a0), 0.0, c[1] + r * math.sin(a0)]
    p1 = [c[0] + r * math.cos(a1), 0.0, c[1] + r * math.sin(a1)]
    q = [p0, p1, [p1[0], 3.0, p1[2]], [p0[0], 3.0, p0[2]]]
    face(q, sub(mean(q), [c[0], mean(q)[1], c[1]]))
group("sphere", "copper")
centre, radius, rings, segments = [-0.2, 0.98, -0.1], 0.2, 8, 14
for i in range(rings):
    t0, t1 = math.pi * i / rings, math.pi * (i + 1) / rings
    for j in range(segments):
        f0, f1 = 2 * math.pi * j / segments, 2 * math.pi * (j + 1) / segments
        pt = lambda t, f: add(centre, scale([math.sin(t) * math.cos(f), math.cos(t), math.sin(t) * math.sin(f)], radius))
        poly = [pt(t0, f0), pt(t0, f1), pt(t1, f1), pt(t1, f0)]
        if i == 0:
            poly = [poly[0], poly[2], poly[3]]
        elif i == rings - 1:
            poly = [poly[0], poly[1], poly[2]]
        face(poly, sub(mean(poly), centre))

header = """# A living room for sensorlight's metrics, generated by scripts/make_room.py (edit that, not this).
# 6 x 3 x 5 m, y up. Four area lights of different shapes: a rectangular ceiling panel, a round
# ceiling light, a strip on the back wall and a triangular lamp on the left wall.
mtllib room.mtl"""
open("scenes/room/room.obj", "w").write(header + "\n" + "\n".join(out) + "\n")
