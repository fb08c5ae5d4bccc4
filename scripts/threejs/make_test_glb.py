#!/usr/bin/env python3
"""The three.js harness's self-test: a small glb in `sensorlight bake`'s conventions, shot with shoot.sh and
checked pixel by pixel against what it must show. Only the Python standard library (zlib included).

    make_test_glb.py selftest [--width W] [--height H] [--exposure E] [--exr float|half-zip] [--keep DIR]
    make_test_glb.py write DIR [--exr float|half-zip]
    make_test_glb.py check DIR SHOT.png [--width W] [--height H] [--exposure E]

`selftest` writes the scene into a temporary directory (or DIR with --keep), runs shoot.sh on it and checks the
shot; its exit status is shoot.sh's when that fails (3: no Chromium/three.js, so skip), else 0 when every
check passes and 1 when one does not. `write` only writes DIR/test.glb and DIR/test.lightmap.exr; `check`
checks a shot of them.

The scene, seen from straight above by the glb's one camera (world -Z at the top of the picture, +X right):
  - a floor quad (y = 0, x and z in [-1, 1]), base colour (0.8, 0.6, 0.4), its TEXCOORD_1 spanning texels
    rows 0..7 of the 8×10 lightmap: u = (x + 1) / 2, v = 0.8 (z + 1) / 2, so the texel at uv (0, 0) (EXR row 0,
    column 0, a bright blue marker) lies at the picture's top-left corner, red grows to the right and green
    downwards;
  - a box (x, z in [0.2, 0.7], y in [0, 0.4]) with a 2×2 nearest-filtered baseColorTexture on its top
    (TEXCOORD_0) and a base colour factor; its TEXCOORD_1 is constant, the centre of texel (2, 8) on the top and
    of texel (5, 9) on the sides, so they show those texels' values exactly;
  - an emitting quad, "lamp" (x in [-0.45, -0.1], z in [0.3, 0.65], y = 0.6, facing the camera) with
    emissiveFactor (1, 0.5, 0.25), KHR_materials_emissive_strength 0.5 and, as `sensorlight bake` writes
    emitters, a lightmap too (TEXCOORD_1 the centre of texel (6, 9)): it shows emission + base colour × L;
  - a second emitting quad, "lamp2" (x in [-0.9, -0.7], z in [-0.3, -0.1], y = 0.3), with emissiveFactor
    (0.25, 0.5, 1), strength 0.8, and no lightmap: it shows its emission alone.
The lightmap is stored as an uncompressed scan-line RGB float EXR (`--exr float`, the default) or a
ZIP-compressed RGBA half one (`--exr half-zip`); both are written here by hand.

Each pixel the check uses is one whose centre and four points ±0.45 px around it see the same surface (found
by casting rays through the glb's camera), and its expected colour is computed from the surface's definition:
bilinear lightmap filtering (texel centres at (i + 0.5) / width, clamped at the edges) × base colour ×
exposure, clamped and sRGB-encoded. Every such pixel must match within 2/255.
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))

# The lightmap: LM_W × LM_H texels, row 0 at the top (uv v = 0).
LM_W, LM_H = 8, 10
FLOOR_ROWS = 8  # the floor's TEXCOORD_1 spans rows 0..7
BOX_TOP_TEXEL = (2, 8)  # (column, row)
BOX_SIDE_TEXEL = (5, 9)
LAMP_TEXEL = (6, 9)


def lightmap_value(col, row):
    """The linear (r, g, b) = E/π stored at a texel."""
    if (col, row) == (0, 0):
        return (0.15, 0.2, 1.6)  # the orientation marker
    if (col, row) == BOX_TOP_TEXEL:
        return (0.9, 0.7, 0.5)
    if (col, row) == BOX_SIDE_TEXEL:
        return (0.35, 0.45, 0.55)
    if (col, row) == LAMP_TEXEL:
        return (0.2, 0.4, 0.6)
    return (0.1 + 0.13 * col, 0.1 + 0.11 * row, 0.15 + 0.05 * ((col + 2 * row) % 7))


FLOOR_COLOR = (0.8, 0.6, 0.4)
BOX_FACTOR = (0.9, 0.95, 1.0)
# The box top's 2×2 sRGB texture, row 0 at the top (uv v = 0): distinct quadrants to check its orientation.
BOX_TEXTURE = [[(255, 64, 64), (64, 255, 64)], [(64, 64, 255), (255, 255, 128)]]
EMISSION = (1.0, 0.5, 0.25)
EMISSIVE_STRENGTH = 0.5
LAMP_COLOR = (0.5, 0.5, 0.5)
EMISSION2 = (0.25, 0.5, 1.0)
EMISSIVE_STRENGTH2 = 0.8

FLOOR = (-1.0, 1.0)  # x and z range
BOX = ((0.2, 0.7), (0.0, 0.4), (0.2, 0.7))  # x, y, z ranges
EMITTER = ((-0.45, -0.1), 0.6, (0.3, 0.65))  # x range, y, z range
EMITTER2 = ((-0.9, -0.7), 0.3, (-0.3, -0.1))

CAMERA_HEIGHT = 2.0
CAMERA_YFOV = 2 * math.atan(0.62)
CAMERA_ZNEAR = 0.05


# ---------------------------------------------------------------------------------------------------- files


def half_bits(value):
    return struct.unpack("<H", struct.pack("<e", value))[0]


def write_exr(path, width, height, pixel, kind):
    """A single-part scan-line EXR. kind "float": R, G, B as 32-bit floats, uncompressed. kind "half-zip":
    R, G, B, A as halfs, ZIP (16-line blocks). pixel(col, row) gives (r, g, b) with row 0 the top."""
    half = kind == "half-zip"
    names = ["A", "B", "G", "R"] if half else ["B", "G", "R"]  # channels are stored in alphabetical order
    pixel_type, size = (1, 2) if half else (2, 4)

    def attribute(name, type_name, value):
        return name.encode() + b"\0" + type_name.encode() + b"\0" + struct.pack("<i", len(value)) + value

    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", pixel_type, 0, 1, 1) for n in names) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = b"".join(
        [
            struct.pack("<I", 20000630) + struct.pack("<I", 2),  # magic, version 2, single-part scan lines
            attribute("channels", "chlist", chlist),
            attribute("compression", "compression", bytes([3 if half else 0])),
            attribute("dataWindow", "box2i", box),
            attribute("displayWindow", "box2i", box),
            attribute("lineOrder", "lineOrder", bytes([0])),
            attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
            attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
            attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
            b"\0",
        ]
    )

    def line(row):
        out = bytearray()
        for name in names:
            for col in range(width):
                v = 1.0 if name == "A" else pixel(col, row)["RGB".index(name)]
                out += struct.pack("<H", half_bits(v)) if half else struct.pack("<f", v)
        return bytes(out)

    def zip_block(raw):
        # OpenEXR's ZIP: bytes split into the even- and odd-indexed halves, then delta-coded, then zlib.
        t = bytearray(raw[0::2] + raw[1::2])
        for i in range(len(t) - 1, 0, -1):
            t[i] = (t[i] - t[i - 1] + 128) & 0xFF
        packed = zlib.compress(bytes(t), 9)
        return packed if len(packed) < len(raw) else raw

    lines_per_block = 16 if half else 1
    chunks = []
    for y0 in range(0, height, lines_per_block):
        raw = b"".join(line(r) for r in range(y0, min(height, y0 + lines_per_block)))
        data = zip_block(raw) if half else raw
        chunks.append(struct.pack("<ii", y0, len(data)) + data)
    offset = len(header) + 8 * len(chunks)
    table = b""
    for c in chunks:
        table += struct.pack("<Q", offset)
        offset += len(c)
    with open(path, "wb") as f:
        f.write(header + table + b"".join(chunks))


def png_bytes(rows):
    """An 8-bit RGB PNG of rows of (r, g, b)."""

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    height, width = len(rows), len(rows[0])
    raw = b"".join(b"\0" + bytes(c for px in row for c in px) for row in rows)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b"")
    )


def quad(corners, normal, uv0, uv1):
    """Two triangles of a planar quad, wound counter-clockwise seen from the side `normal` points to."""
    a, b, c, _ = corners
    e1 = [b[i] - a[i] for i in range(3)]
    e2 = [c[i] - a[i] for i in range(3)]
    cross = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    order = [0, 1, 2, 0, 2, 3] if sum(cross[i] * normal[i] for i in range(3)) > 0 else [0, 2, 1, 0, 3, 2]
    return corners, [normal] * 4, uv0, uv1, order


def floor_uv1(x, z):
    return ((x - FLOOR[0]) / (FLOOR[1] - FLOOR[0]), FLOOR_ROWS / LM_H * (z - FLOOR[0]) / (FLOOR[1] - FLOOR[0]))


def texel_centre(texel):
    return ((texel[0] + 0.5) / LM_W, (texel[1] + 0.5) / LM_H)


def meshes():
    """(name, material index, [quads]) of the scene."""
    lo, hi = FLOOR
    floor_corners = [(lo, 0.0, lo), (hi, 0.0, lo), (hi, 0.0, hi), (lo, 0.0, hi)]
    floor = quad(floor_corners, (0, 1, 0), None, [floor_uv1(x, z) for x, _, z in floor_corners])

    (x0, x1), (y0, y1), (z0, z1) = BOX
    top_corners = [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)]
    box = [
        quad(
            top_corners,
            (0, 1, 0),
            [((x - x0) / (x1 - x0), (z - z0) / (z1 - z0)) for x, _, z in top_corners],
            [texel_centre(BOX_TOP_TEXEL)] * 4,
        )
    ]
    sides = [
        ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (-1, 0, 0)),
        ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (1, 0, 0)),
        ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, -1)),
        ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1)),
    ]
    for corners, n in sides:
        box.append(quad(corners, n, [(0.25, 0.25)] * 4, [texel_centre(BOX_SIDE_TEXEL)] * 4))

    (ex0, ex1), ey, (ez0, ez1) = EMITTER
    emitter = quad(
        [(ex0, ey, ez0), (ex1, ey, ez0), (ex1, ey, ez1), (ex0, ey, ez1)], (0, 1, 0), None, [texel_centre(LAMP_TEXEL)] * 4
    )
    (ex0, ex1), ey, (ez0, ez1) = EMITTER2
    emitter2 = quad([(ex0, ey, ez0), (ex1, ey, ez0), (ex1, ey, ez1), (ex0, ey, ez1)], (0, 1, 0), None, None)
    return [("floor", 0, [floor]), ("box", 1, box), ("lamp", 2, [emitter]), ("lamp2", 3, [emitter2])]


def write_glb(path, lightmap_uri):
    binary = bytearray()
    views, accessors = [], []

    def add_view(data, target=None):
        while len(binary) % 4:
            binary.append(0)
        view = {"buffer": 0, "byteOffset": len(binary), "byteLength": len(data)}
        if target:
            view["target"] = target
        binary.extend(data)
        views.append(view)
        return len(views) - 1

    def add_accessor(values, kind, component=5126):
        if component == 5126:
            data = b"".join(struct.pack("<%df" % len(v), *v) for v in values)
        else:
            data = struct.pack("<%dI" % len(values), *values)
        accessor = {
            "bufferView": add_view(data, 34963 if component == 5125 else 34962),
            "componentType": component,
            "count": len(values),
            "type": kind,
        }
        if kind == "VEC3":
            accessor["min"] = [min(v[i] for v in values) for i in range(3)]
            accessor["max"] = [max(v[i] for v in values) for i in range(3)]
        accessors.append(accessor)
        return len(accessors) - 1

    gltf_meshes, nodes = [], []
    for name, material, quads in meshes():
        positions, normals, uv0, uv1, indices = [], [], [], [], []
        for corners, ns, q0, q1, order in quads:
            base = len(positions)
            positions += corners
            normals += ns
            if q0:
                uv0 += q0
            if q1:
                uv1 += q1
            indices += [base + i for i in order]
        attributes = {"POSITION": add_accessor(positions, "VEC3"), "NORMAL": add_accessor(normals, "VEC3")}
        if uv0:
            attributes["TEXCOORD_0"] = add_accessor(uv0, "VEC2")
        if uv1:
            attributes["TEXCOORD_1"] = add_accessor(uv1, "VEC2")
        primitive = {"attributes": attributes, "indices": add_accessor(indices, "SCALAR", 5125), "material": material}
        gltf_meshes.append({"name": name, "primitives": [primitive]})
        nodes.append({"name": name, "mesh": len(gltf_meshes) - 1})

    image_view = add_view(png_bytes(BOX_TEXTURE))
    s = math.sqrt(0.5)
    nodes.append(
        {
            "name": "camera",
            "camera": 0,
            "translation": [0.0, CAMERA_HEIGHT, 0.0],
            "rotation": [-s, 0.0, 0.0, s],  # -90° about x: looking down -y, the picture's top towards -z
        }
    )

    def lightmap():
        return {"uri": lightmap_uri, "texCoord": 1, "page": 0, "encoding": "linear", "quantity": "irradiance/pi"}

    document = {
        "asset": {"version": "2.0", "generator": "sensorlight scripts/threejs/make_test_glb.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gltf_meshes,
        "cameras": [
            {
                "type": "perspective",
                "perspective": {"yfov": CAMERA_YFOV, "aspectRatio": 4 / 3, "znear": CAMERA_ZNEAR},
            }
        ],
        "materials": [
            {
                "name": "floor",
                "pbrMetallicRoughness": {"baseColorFactor": [*FLOOR_COLOR, 1.0], "metallicFactor": 0.0},
                "extras": {"lightmap": lightmap()},
            },
            {
                "name": "box",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [*BOX_FACTOR, 1.0],
                    "baseColorTexture": {"index": 0, "texCoord": 0},
                    "metallicFactor": 0.0,
                },
                "extras": {"lightmap": lightmap()},
            },
            {
                "name": "lamp",
                "pbrMetallicRoughness": {"baseColorFactor": [*LAMP_COLOR, 1.0], "metallicFactor": 0.0},
                "emissiveFactor": list(EMISSION),
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": EMISSIVE_STRENGTH}},
                "extras": {"lightmap": lightmap()},
            },
            {
                "name": "lamp2",
                "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0},
                "emissiveFactor": list(EMISSION2),
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": EMISSIVE_STRENGTH2}},
            },
        ],
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071}],
        "images": [{"bufferView": image_view, "mimeType": "image/png"}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(binary)}],
    }
    while len(binary) % 4:
        binary.append(0)
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    with open(path, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary)))
        f.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        f.write(struct.pack("<II", len(binary), 0x004E4942) + bytes(binary))


def write_scene(directory, exr_kind):
    os.makedirs(directory, exist_ok=True)
    write_exr(os.path.join(directory, "test.lightmap.exr"), LM_W, LM_H, lightmap_value, exr_kind)
    write_glb(os.path.join(directory, "test.glb"), "test.lightmap.exr")


# ---------------------------------------------------------------------------------------------------- check


def read_png(path):
    """(width, height, rows of (r, g, b)) of an 8-bit RGB or RGBA PNG."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and color in (2, 6) and interlace == 0, f"{path}: unsupported PNG kind"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    channels = 4 if color == 6 else 3
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        start = y * (stride + 1)
        kind, line = raw[start], bytearray(raw[start + 1 : start + 1 + stride])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 0xFF
            elif kind == 2:
                line[i] = (line[i] + b) & 0xFF
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 0xFF
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 0xFF
        rows.append([tuple(line[x * channels : x * channels + 3]) for x in range(width)])
        previous = line
    return width, height, rows


def srgb_encode(v):
    v = min(max(v, 0.0), 1.0)
    return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055


def srgb_decode(c):
    c /= 255
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def bilinear(u, v):
    """The lightmap at (u, v) with bilinear filtering, texel centres at (i + 0.5) / size, clamped at edges."""
    fx, fy = u * LM_W - 0.5, v * LM_H - 0.5
    x0, y0 = math.floor(fx), math.floor(fy)
    ax, ay = fx - x0, fy - y0

    def texel(c, r):
        return lightmap_value(min(max(c, 0), LM_W - 1), min(max(r, 0), LM_H - 1))

    out = []
    for k in range(3):
        top = texel(x0, y0)[k] * (1 - ax) + texel(x0 + 1, y0)[k] * ax
        bottom = texel(x0, y0 + 1)[k] * (1 - ax) + texel(x0 + 1, y0 + 1)[k] * ax
        out.append(top * (1 - ay) + bottom * ay)
    return out


def hit(px, py, width, height):
    """(surface, point) the ray through picture point (px, py) (pixels from the top-left) meets first."""
    t = math.tan(CAMERA_YFOV / 2)
    nx, ny = px / width * 2 - 1, 1 - py / height * 2
    d = (nx * t * width / height, -1.0, -ny * t)  # the camera looks down -y with -z up
    o = (0.0, CAMERA_HEIGHT, 0.0)
    best = (math.inf, None, None)

    def plane_y(y, xr, zr, name):
        nonlocal best
        s = (o[1] - y) / -d[1] if d[1] else math.inf
        p = (o[0] + s * d[0], y, o[2] + s * d[2])
        if 0 < s < best[0] and xr[0] <= p[0] <= xr[1] and zr[0] <= p[2] <= zr[1]:
            best = (s, name, p)

    plane_y(0.0, FLOOR, FLOOR, "floor")
    plane_y(EMITTER[1], EMITTER[0], EMITTER[2], "lamp")
    plane_y(EMITTER2[1], EMITTER2[0], EMITTER2[2], "lamp2")
    # The box: the slab test gives where the ray enters it and through which face.
    (bx, by, bz) = BOX
    s_in, face = -math.inf, None
    s_out = math.inf
    for axis, (lo, hi) in enumerate((bx, by, bz)):
        if d[axis] == 0:
            if not lo <= o[axis] <= hi:
                s_in = math.inf
            continue
        a, b = (lo - o[axis]) / d[axis], (hi - o[axis]) / d[axis]
        if a > b:
            a, b = b, a
        if a > s_in:
            s_in, face = a, axis
        s_out = min(s_out, b)
    if s_in <= s_out and 0 < s_in < best[0]:
        p = tuple(o[i] + s_in * d[i] for i in range(3))
        best = (s_in, "box-top" if face == 1 else "box-side", p)
    return best[1], best[2]


def expected(surface, p, exposure):
    """The linear colour the surface shows at p, before exposure."""
    if surface == "floor":
        u, v = floor_uv1(p[0], p[2])
        return [c * l for c, l in zip(FLOOR_COLOR, bilinear(u, v))]
    if surface == "box-top":
        (x0, x1), _, (z0, z1) = BOX
        u, v = (p[0] - x0) / (x1 - x0), (p[2] - z0) / (z1 - z0)
        texel = BOX_TEXTURE[min(int(v * 2), 1)][min(int(u * 2), 1)]
        return [f * srgb_decode(t) * l for f, t, l in zip(BOX_FACTOR, texel, lightmap_value(*BOX_TOP_TEXEL))]
    if surface == "box-side":
        texel = BOX_TEXTURE[0][0]
        return [f * srgb_decode(t) * l for f, t, l in zip(BOX_FACTOR, texel, lightmap_value(*BOX_SIDE_TEXEL))]
    if surface == "lamp":
        return [e * EMISSIVE_STRENGTH + c * l for e, c, l in zip(EMISSION, LAMP_COLOR, lightmap_value(*LAMP_TEXEL))]
    if surface == "lamp2":
        return [e * EMISSIVE_STRENGTH2 for e in EMISSION2]
    return [0.0, 0.0, 0.0]


def near_texture_edge(p, margin):
    """Whether p on the box's top is within margin (in uv) of a boundary between its texture's texels."""
    (x0, x1), _, (z0, z1) = BOX
    u, v = (p[0] - x0) / (x1 - x0), (p[2] - z0) / (z1 - z0)
    return abs(u - 0.5) < margin or abs(v - 0.5) < margin


def check(png, width, height, exposure):
    """Compares the shot with the scene's definition; prints the findings and returns whether they pass."""
    w, h, rows = read_png(png)
    if (w, h) != (width, height):
        print(f"check: the shot is {w}×{h}, not {width}×{height}")
        return False
    tolerance = 2
    worst = {}
    counts = {}
    bad = []
    for y in range(height):
        for x in range(width):
            cx, cy = x + 0.5, y + 0.5
            surface, p = hit(cx, cy, width, height)
            if any(hit(cx + dx, cy + dy, width, height)[0] != surface for dx, dy in ((-0.45, -0.45), (0.45, -0.45), (-0.45, 0.45), (0.45, 0.45))):
                continue
            if surface == "box-top" and near_texture_edge(p, 2 / width):
                continue
            want = [round(255 * srgb_encode(exposure * c)) for c in expected(surface, p, exposure)]
            got = rows[y][x]
            err = max(abs(a - b) for a, b in zip(want, got))
            key = surface or "background"
            counts[key] = counts.get(key, 0) + 1
            if err > worst.get(key, (-1,))[0]:
                worst[key] = (err, x, y, tuple(want), tuple(got))
            if err > tolerance:
                bad.append((key, x, y, tuple(want), tuple(got)))
    for key in sorted(counts):
        err, x, y, want, got = worst[key]
        print(f"check: {key:10s} {counts[key]:6d} pixels, largest error {err}/255 at ({x}, {y}): expected {want}, got {got}")

    # Spot checks, in the words of the conventions: the lightmap texel at uv (0, 0) (EXR row 0, column 0, the
    # blue marker) shows at the floor's top-left in the picture; the texels at the other corners where they
    # belong; the midpoint between two texel centres is their average (bilinear filtering).
    t = math.tan(CAMERA_YFOV / 2)

    def pixel_of(xw, zw):
        nx = xw / (CAMERA_HEIGHT * t * width / height)
        ny = -zw / (CAMERA_HEIGHT * t)
        return int((nx + 1) / 2 * width), int((1 - ny) / 2 * height)

    def floor_point(u, v):
        return (FLOOR[0] + u * (FLOOR[1] - FLOOR[0]), FLOOR[0] + v * LM_H / FLOOR_ROWS * (FLOOR[1] - FLOOR[0]))

    spots = [
        ("texel (0, 0), the marker (uv (0, 0) corner)", texel_centre((0, 0))),
        ("texel (7, 0) (u = 1, v = 0 corner)", texel_centre((7, 0))),
        ("texel (0, 7) (u = 0, v = 1 corner)", texel_centre((0, 7))),
        ("between texels (3, 4) and (4, 4)", (4 / LM_W, 4.5 / LM_H)),
    ]
    for label, (u, v) in spots:
        xw, zw = floor_point(u, v)
        px, py = pixel_of(xw, zw)
        surface, p = hit(px + 0.5, py + 0.5, width, height)
        want = [round(255 * srgb_encode(exposure * c)) for c in expected(surface, p, exposure)]
        print(f"check: {label}: pixel ({px}, {py}) on {surface}, expected {tuple(want)}, got {rows[py][px]}")

    if bad:
        print(f"check: FAILED: {len(bad)} pixels off by more than {tolerance}/255, e.g.")
        for key, x, y, want, got in bad[:8]:
            print(f"check:   {key} at ({x}, {y}): expected {want}, got {got}")
        return False
    if set(counts) != {"floor", "box-top", "box-side", "lamp", "lamp2", "background"}:
        print(f"check: FAILED: not every surface was checked ({sorted(counts)})")
        return False
    print(f"check: passed: every checked pixel within {tolerance}/255")
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    selftest = sub.add_parser("selftest")
    write = sub.add_parser("write")
    write.add_argument("dir")
    checker = sub.add_parser("check")
    checker.add_argument("dir")
    checker.add_argument("png")
    for p in (selftest, write):
        p.add_argument("--exr", choices=["float", "half-zip"], default="float")
    for p in (selftest, checker):
        p.add_argument("--width", type=int, default=320)
        p.add_argument("--height", type=int, default=240)
        p.add_argument("--exposure", type=float, default=0.75)
    selftest.add_argument("--keep", metavar="DIR", help="write the scene and the shot into DIR and keep them")
    args = parser.parse_args()

    if args.command == "write":
        write_scene(args.dir, args.exr)
        return 0
    if args.command == "check":
        return 0 if check(args.png, args.width, args.height, args.exposure) else 1

    with tempfile.TemporaryDirectory(prefix="sensorlight-threejs-selftest.") as tmp:
        directory = args.keep or tmp
        write_scene(directory, args.exr)
        shot = os.path.join(directory, "shot.png")
        command = [os.path.join(HERE, "shoot.sh"), os.path.join(directory, "test.glb"), shot,
                   "--width", str(args.width), "--height", str(args.height), "--exposure", str(args.exposure), "--verbose"]
        status = subprocess.run(command).returncode
        if status != 0:
            print(f"selftest: shoot.sh exited with status {status}", file=sys.stderr)
            return status
        return 0 if check(shot, args.width, args.height, args.exposure) else 1


if __name__ == "__main__":
    sys.exit(main())
