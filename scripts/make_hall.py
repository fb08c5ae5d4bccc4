#!/usr/bin/env python3
"""Writes a closed hall, the large interior of docs/BENCHMARKS.md ("A real interior"): a room 20 × 8 × 10 m
(metres, y up) with two rows of six fluted columns, a row of seven fine spheres on pedestals between them,
a red and a green end wall, lit only by three ceiling panels; the camera stands inside. Most of its
triangles are detail far finer than a sensor's texel (the flutes, the spheres), as in real interiors.

  python3 scripts/make_hall.py [TRIANGLES ...]       (default 550000; run from anywhere)

writes scenes/big/hall-<TRIANGLES>/{hall.obj, hall.mtl, hall.toml} (ignored by git). The count is a
target: columns and spheres are tessellated to about it. Deterministic: the same count writes the same
bytes. `tests/interior.rs` builds the same hall in Rust at a small count (`tests/common/hall.rs`).
"""
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "scenes", "big")

# The hall's inside: x in [-10, 10], y in [0, 8], z in [-5, 5].
HALL = (10.0, 8.0, 5.0)
COLUMN_X = [-7.5, -4.5, -1.5, 1.5, 4.5, 7.5]
COLUMN_Z = [-3.0, 3.0]
COLUMN_RADIUS, FLUTE_DEPTH, FLUTES, FLUTE_SEGMENTS = 0.35, 0.05, 24, 6
SHAFT = (0.3, 7.3)  # between the base and the capital
SPHERE_X = [-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0]
SPHERE_RADIUS, PEDESTAL = 0.45, 0.9
# The full-size hall's tessellation: 64 rings per shaft, spheres of 108 stacks.
RINGS, STACKS = 64, 108
FULL = 12 * FLUTES * FLUTE_SEGMENTS * RINGS * 2 + 7 * 2 * (2 * STACKS) * (STACKS - 1)

MTL = """# Materials of the hall (scripts/make_hall.py): Kd albedo, Ke emitted radiance (linear RGB).
newmtl stone
Kd 0.6 0.55 0.48
newmtl plaster
Kd 0.72 0.7 0.64
newmtl red
Kd 0.65 0.12 0.1
newmtl green
Kd 0.15 0.5 0.2
newmtl ceiling
Kd 0.75 0.75 0.75
newmtl marble
Kd 0.8 0.78 0.74
newmtl bronze
Kd 0.55 0.38 0.22
newmtl panel
Kd 0.8 0.8 0.8
Ke 12 11.5 10.5
"""


class Obj:
    def __init__(self):
        self.lines = []
        self.vertices = 0
        self.triangles = 0

    def group(self, name, material):
        self.lines.append(f"g {name}\nusemtl {material}")

    def vertex(self, p):
        self.lines.append("v %.6f %.6f %.6f" % p)
        self.vertices += 1
        return self.vertices

    def face(self, *corners):
        self.lines.append("f " + " ".join(str(c) for c in corners))
        self.triangles += len(corners) - 2

    def quad(self, a, b, c, d):
        """A quad counter-clockwise seen from its front."""
        self.face(*(self.vertex(p) for p in (a, b, c, d)))

    def box(self, lo, hi):
        """A closed box, faces outwards."""
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        v = [self.vertex((x, y, z)) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
        at = lambda i, j, k: v[4 * i + 2 * j + k]
        for a, b, c, d in [
            ((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)),  # -x
            ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)),  # +x
            ((0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)),  # -y
            ((0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)),  # +y
            ((0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)),  # -z
            ((0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)),  # +z
        ]:
            self.face(at(*a), at(*b), at(*c), at(*d))


def shell(obj):
    """Floor, ceiling and walls, fronts inwards, each wall in 2 m squares (so no face is huge)."""
    x, y, z = HALL
    obj.group("floor", "stone")
    for i in range(10):
        for k in range(5):
            x0, z0 = -x + 2 * i, -z + 2 * k
            obj.quad((x0, 0, z0), (x0, 0, z0 + 2), (x0 + 2, 0, z0 + 2), (x0 + 2, 0, z0))
    obj.group("ceiling", "ceiling")
    for i in range(10):
        for k in range(5):
            x0, z0 = -x + 2 * i, -z + 2 * k
            obj.quad((x0, y, z0), (x0 + 2, y, z0), (x0 + 2, y, z0 + 2), (x0, y, z0 + 2))
    obj.group("side_walls", "plaster")
    for i in range(10):
        for j in range(4):
            x0, y0 = -x + 2 * i, 2 * j
            obj.quad((x0, y0, -z), (x0 + 2, y0, -z), (x0 + 2, y0 + 2, -z), (x0, y0 + 2, -z))
            obj.quad((x0, y0, z), (x0, y0 + 2, z), (x0 + 2, y0 + 2, z), (x0 + 2, y0, z))
    for name, material, wx, sign in [("west_wall", "red", -x, 1), ("east_wall", "green", x, -1)]:
        obj.group(name, material)
        for k in range(5):
            for j in range(4):
                z0, y0 = -z + 2 * k, 2 * j
                corners = [(wx, y0, z0), (wx, y0, z0 + 2), (wx, y0 + 2, z0 + 2), (wx, y0 + 2, z0)]
                obj.quad(*(corners if sign > 0 else corners[::-1]))
    obj.group("panels", "panel")
    for cx in (-6.0, 0.0, 6.0):
        h = y - 0.02
        obj.quad((cx - 1.0, h, -0.6), (cx + 1.0, h, -0.6), (cx + 1.0, h, 0.6), (cx - 1.0, h, 0.6))


def column(obj, cx, cz, rings):
    """A fluted shaft (FLUTES concave flutes of FLUTE_SEGMENTS facets, `rings` rows) between a square base
    and a capital."""
    obj.box((cx - 0.5, 0.0, cz - 0.5), (cx + 0.5, SHAFT[0], cz + 0.5))
    obj.box((cx - 0.5, SHAFT[1], cz - 0.5), (cx + 0.5, HALL[1], cz + 0.5))
    around = FLUTES * FLUTE_SEGMENTS
    profile = []
    for s in range(around):
        t = (s % FLUTE_SEGMENTS) / FLUTE_SEGMENTS
        r = COLUMN_RADIUS - FLUTE_DEPTH * math.sin(math.pi * t)
        phi = 2.0 * math.pi * s / around
        profile.append((r * math.cos(phi), r * math.sin(phi)))
    first = obj.vertices + 1
    for j in range(rings + 1):
        h = SHAFT[0] + (SHAFT[1] - SHAFT[0]) * j / rings
        for px, pz in profile:
            obj.vertex((cx + px, h, cz + pz))
    at = lambda j, s: first + j * around + s % around
    for j in range(rings):
        for s in range(around):
            # Outwards: phi turns x -> z, so (s, j), (s, j + 1), (s + 1, j + 1) is counter-clockwise outside.
            a, b, c, d = at(j, s), at(j, s + 1), at(j + 1, s + 1), at(j + 1, s)
            obj.face(a, d, c)
            obj.face(a, c, b)


def sphere(obj, cx, cy, cz, stacks):
    slices = 2 * stacks
    north = obj.vertex((cx, cy + SPHERE_RADIUS, cz))
    for i in range(1, stacks):
        theta = math.pi * i / stacks
        y, r = SPHERE_RADIUS * math.cos(theta), SPHERE_RADIUS * math.sin(theta)
        for j in range(slices):
            phi = 2.0 * math.pi * j / slices
            obj.vertex((cx + r * math.cos(phi), cy + y, cz + r * math.sin(phi)))
    south = obj.vertex((cx, cy - SPHERE_RADIUS, cz))
    ring = lambda i, j: north + 1 + (i - 1) * slices + j % slices
    for j in range(slices):
        obj.face(north, ring(1, j + 1), ring(1, j))
    for i in range(1, stacks - 1):
        for j in range(slices):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            obj.face(a, b, c)
            obj.face(a, c, d)
    for j in range(slices):
        obj.face(south, ring(stacks - 1, j), ring(stacks - 1, j + 1))


def write(triangles):
    scale = triangles / FULL
    rings = max(2, round(RINGS * scale))
    stacks = max(4, round(STACKS * math.sqrt(scale)))
    obj = Obj()
    shell(obj)
    for i, cx in enumerate(COLUMN_X):
        for k, cz in enumerate(COLUMN_Z):
            obj.group(f"column_{i}_{k}", "marble")
            column(obj, cx, cz, rings)
    for i, cx in enumerate(SPHERE_X):
        obj.group(f"pedestal_{i}", "stone")
        obj.box((cx - 0.3, 0.0, -0.3), (cx + 0.3, PEDESTAL, 0.3))
        obj.group(f"sphere_{i}", "bronze")
        sphere(obj, cx, PEDESTAL + SPHERE_RADIUS, 0.0, stacks)
    name = f"hall-{triangles}"
    out = os.path.join(OUT, name)
    os.makedirs(out, exist_ok=True)
    header = (
        f"# A closed hall (scripts/make_hall.py {triangles}): {obj.triangles} triangles, {rings} rings per "
        f"column, spheres of {stacks} stacks.\nmtllib hall.mtl\n"
    )
    with open(os.path.join(out, "hall.obj"), "w") as f:
        f.write(header + "\n".join(obj.lines) + "\n")
    with open(os.path.join(out, "hall.mtl"), "w") as f:
        f.write(MTL)
    with open(os.path.join(out, "hall.toml"), "w") as f:
        f.write(
            f"# Generated by scripts/make_hall.py: a closed hall of {obj.triangles} triangles, camera inside.\n"
            'mesh = "hall.obj"\n\n[camera]\neye = [-9.0, 1.7, 0.8]\ntarget = [4.0, 2.6, -0.4]\nup = [0, 1, 0]\n'
            "vfov_deg = 60\n\n[image]\nwidth = 128\nheight = 96\n"
        )
    print(f"{out}/hall.toml: {obj.triangles} triangles")


def main():
    for n in [int(a) for a in sys.argv[1:]] or [550000]:
        write(n)


if __name__ == "__main__":
    main()
