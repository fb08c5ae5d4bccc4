#!/usr/bin/env python3
"""Converts Crytek Sponza, as stored in the Godot 3 project TheOnlyJoey/godot-sponza, into a scene that
sensorlight loads: scenes/big/sponza/{sponza.obj, sponza.mtl, sponza.toml} and the colour textures and
cut-out masks it uses, copied into scenes/big/sponza/textures/ (scenes/big/ is ignored by git).

Run from the repository root:

    python3 scripts/sponza.py [--mirror PATH]

PATH is either a plain clone (`git clone https://github.com/TheOnlyJoey/godot-sponza scenes/big/godot-sponza`,
the default PATH; read from its work tree) or a bare mirror of the repository (read with `git cat-file`).

What it reads:
- models/sponza.scn: a compressed Godot 3 binary resource (a PackedScene) holding one MeshInstance, its
  ArrayMesh (25 surfaces, compressed vertex arrays) and the 25 SpatialMaterials the surfaces use. The
  MeshInstance's transform (scale 0.125 and a turn from z-up to y-up) is applied, so the output is in
  the Godot project's units, y up, the atrium's floor at y = 0: the building is 23.2 x 9.7 x 14.3
  units, the ground-floor arcade 2.6 units high (smaller than metres: the real atrium is ~30 m long).
- scenes/sponza.scn: the project's main scene, for the transform of the node that instances the model
  (identity), its camera (the eye and the direction it looks in) and its DirectionalLight (the sun).
- sponza/textures/*.tga: each material's albedo texture, and a cut-out mask where the repository has one
  beside it (`<name>_mask.tga`, or `_diff` replaced by `_mask`): the chains, the leaves and the plants.

What it writes: one OBJ group per surface (the surface's name), its material (albedo colour as `Kd`,
albedo texture as `map_Kd`, mask as `map_d`), triangles counter-clockwise seen from the front (Godot's are
clockwise, so each is reversed), `vt` with v running up the image (Godot's runs down). A texture the
repository lacks (three curtain textures are absent from the mirror) is left out: that material renders
with its albedo colour alone (said). The scene hides three materials (transparent with albedo alpha 0:
the plants, the leaves and Material__47); they are restored as Crytek's Sponza has them, from the
importer's sponza/<name>.material (opaque; the plants and leaves cut out by their masks, Material__47 grey
0.588 in sRGB, Kd 0.305). The output is the same on every run.

Python 3 standard library plus `zstandard` (pip install zstandard).
"""
import argparse
import math
import os
import struct
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "scenes", "big", "sponza")
DEFAULT_MIRROR = os.path.join("scenes", "big", "godot-sponza")
REPO_URL = "https://github.com/TheOnlyJoey/godot-sponza"
MODEL = "models/sponza.scn"
MAIN_SCENE = "scenes/sponza.scn"

# The scene file's choices that the Godot project does not make.
IMAGE_SIZE = (512, 512)
VFOV_DEG = 60.0
SUN_IRRADIANCE = 4.0
SKY = (0.3, 0.35, 0.45)  # 0.5 x (0.6, 0.7, 0.9): a moderate blue sky


# ----------------------------------------------------------------------------------------------------
# Reading the repository


class Repo:
    """Files of the godot-sponza repository: from a bare mirror (git cat-file) or a clone's work tree."""

    def __init__(self, path):
        self.path = path
        self.bare = not os.path.exists(os.path.join(path, ".git")) and os.path.isdir(
            os.path.join(path, "objects"))

    def read(self, name):
        """The file's bytes, or None where the repository does not have it."""
        if not self.bare:
            full = os.path.join(self.path, name)
            if not os.path.isfile(full):
                return None
            with open(full, "rb") as f:
                return f.read()
        done = subprocess.run(["git", "-C", self.path, "cat-file", "-p", "HEAD:" + name],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        return done.stdout if done.returncode == 0 else None


def open_repo(path):
    if path is None:
        path = DEFAULT_MIRROR
        if not os.path.isdir(path):
            sys.exit(f"sponza.py: no clone at {DEFAULT_MIRROR}. This script needs the repository "
                     f"TheOnlyJoey/godot-sponza: git clone {REPO_URL} {DEFAULT_MIRROR}\n"
                     f"(or pass --mirror PATH for a clone elsewhere)")
    if not os.path.isdir(path):
        sys.exit(f"sponza.py: {path} is not a directory (a clone of {REPO_URL} or a bare mirror of it)")
    repo = Repo(path)
    if repo.read(MODEL) is None:
        sys.exit(f"sponza.py: {path} has no {MODEL}: is it TheOnlyJoey/godot-sponza? ({REPO_URL})")
    return repo


# ----------------------------------------------------------------------------------------------------
# Godot 3 binary resources


def decompress_rscc(data):
    """The contents of a compressed resource (core/io/file_access_compressed.cpp, open_after_magic):
    'RSCC', u32 mode, u32 block size, u32 total size, (total / block size + 1) u32 compressed block
    sizes, then the blocks, each compressed on its own. Modes (core/io/compression.h): 0 FastLZ,
    1 Deflate, 2 Zstd, 3 Gzip. The result starts where 'RSRC' would be followed by the header."""
    mode, block_size, total = struct.unpack_from("<III", data, 4)
    count = total // block_size + 1
    sizes = struct.unpack_from(f"<{count}I", data, 16)
    offset = 16 + 4 * count
    out = bytearray()
    if mode == 2:
        try:
            import zstandard
        except ImportError:
            sys.exit("sponza.py: needs the zstandard module to read Godot's compressed scenes: "
                     "pip install zstandard")
        decompressor = zstandard.ZstdDecompressor()
        unpack = lambda block, size: decompressor.decompress(block, max_output_size=size)
    elif mode in (1, 3):
        import zlib
        unpack = lambda block, size: zlib.decompress(block, 15 if mode == 1 else 31)
    else:
        sys.exit(f"sponza.py: compression mode {mode} (FastLZ) is not supported")
    for i, size in enumerate(sizes):
        expected = block_size if i < count - 1 else total % block_size
        if expected:
            out += unpack(data[offset:offset + size], block_size)
        offset += size
    if len(out) != total:
        sys.exit(f"sponza.py: decompressed {len(out)} bytes, the header says {total}")
    return bytes(out)


class Ref:
    """A Variant OBJECT: an internal resource ('local://N') or an external one (index into the list)."""

    def __init__(self, external, index):
        self.external, self.index = external, index


class Reader:
    """Godot 3's ResourceInteractiveLoaderBinary (core/io/resource_format_binary.cpp), little-endian,
    32-bit reals, format versions 1-3."""

    def __init__(self, data):
        self.data, self.pos = data, 0

    def take(self, fmt):
        values = struct.unpack_from("<" + fmt, self.data, self.pos)
        self.pos += struct.calcsize("<" + fmt)
        return values

    def u32(self):
        return self.take("I")[0]

    def bytes(self, n):
        self.pos += n
        return self.data[self.pos - n:self.pos]

    def ustring(self):
        """get_unicode_string: u32 length (with the trailing NUL), UTF-8 bytes, no padding."""
        return self.bytes(self.u32()).rstrip(b"\0").decode("utf-8")

    def string_ref(self):
        """_get_string: an index into the string table, or (top bit set) a string given in place."""
        n = self.u32()
        if n & 0x80000000:
            return self.bytes(n & 0x7FFFFFFF).rstrip(b"\0").decode("utf-8")
        return self.strings[n]

    # parse_variant's type ids (VARIANT_* in resource_format_binary.cpp) with the number of 32-bit
    # reals that follow for the fixed-size maths types.
    REALS = {10: 2, 11: 4, 12: 3, 13: 4, 14: 4, 15: 6, 16: 9, 17: 12, 18: 6, 20: 4}  # Vector2 .. Color
    POOLS = {32: "i", 33: "f", 35: "fff", 36: "ffff", 37: "ff"}  # Int, Real, Vector3/Color/Vector2 arrays

    def variant(self):
        kind = self.u32()
        if kind == 1:  # NIL
            return None
        if kind == 2:  # BOOL
            return bool(self.u32())
        if kind == 3:  # INT
            return self.take("i")[0]
        if kind == 40:  # INT64
            return self.take("q")[0]
        if kind == 4:  # REAL
            return self.take("f")[0]
        if kind == 41:  # DOUBLE
            return self.take("d")[0]
        if kind == 5:  # STRING
            return self.ustring()
        if kind in self.REALS:  # Transform: basis rows 0-2 then origin; AABB: position then size
            return self.take(f"{self.REALS[kind]}f")
        if kind == 22:  # NODE_PATH: u16 names, u16 subnames (top bit: absolute), string refs
            names, subnames = self.take("HH")
            subnames &= 0x7FFF
            if self.format < 3:  # FORMAT_VERSION_NO_NODEPATH_PROPERTY: a property name followed
                subnames += 1
            return [self.string_ref() for _ in range(names + subnames)]
        if kind == 23:  # RID
            return self.u32()
        if kind == 24:  # OBJECT: 0 empty, 1 external by type and path, 2 internal, 3 external by index
            how = self.u32()
            if how == 0:
                return None
            if how == 1:
                return (self.ustring(), self.ustring())
            if how in (2, 3):
                return Ref(how == 3, self.u32())
            raise ValueError(f"object reference kind {how} at {self.pos}")
        if kind == 26:  # DICTIONARY: u32 count (top bit: shared), then key, value pairs
            count = self.u32() & 0x7FFFFFFF
            pairs = [(self.variant(), self.variant()) for _ in range(count)]
            return {key if isinstance(key, (str, int, float, bool)) else repr(key): value
                    for key, value in pairs}
        if kind == 30:  # ARRAY
            return [self.variant() for _ in range(self.u32() & 0x7FFFFFFF)]
        if kind == 31:  # RAW_ARRAY (PoolByteArray), padded to 4 bytes
            n = self.u32()
            raw = self.bytes(n)
            self.pos += (4 - n % 4) % 4
            return raw
        if kind in self.POOLS:
            n = self.u32()
            fmt = self.POOLS[kind]
            return self.take(f"{n * len(fmt)}{fmt[0]}")
        if kind == 34:  # STRING_ARRAY
            return [self.ustring() for _ in range(self.u32())]
        raise ValueError(f"Variant type {kind} at {self.pos}: not a Godot 3 binary resource?")


def parse_resource(data):
    """A binary resource: {'type', 'external': [(type, path)], 'internal': {path: (type, props)}, 'main'}.
    Header (ResourceInteractiveLoaderBinary::open): 'RSRC' (absent inside an RSCC stream), u32 big-endian,
    u32 64-bit reals, u32 major, u32 minor, u32 format, type string, u64 import metadata offset,
    14 reserved u32, string table, external resources (type, path), internal resources (path, u64 offset
    from the start of the stream). At each offset (poll): type string, u32 property count, then
    (string ref name, Variant value) pairs. The last internal resource is the main one."""
    if data[:4] == b"RSCC":
        data = decompress_rscc(data)
        r = Reader(data)
    elif data[:4] == b"RSRC":
        r = Reader(data)
        r.pos = 4
    else:
        raise ValueError("not a Godot binary resource (no RSRC/RSCC magic)")
    big_endian, real64, _major, _minor, r.format = r.take("5I")
    if big_endian or real64:
        sys.exit("sponza.py: big-endian or 64-bit-real resources are not supported")
    kind = r.ustring()
    r.pos += 8 + 14 * 4
    r.strings = [r.ustring() for _ in range(r.u32())]
    external = [(r.ustring(), r.ustring()) for _ in range(r.u32())]
    offsets = [(r.ustring(), r.take("Q")[0]) for _ in range(r.u32())]
    internal = {}
    for path, offset in offsets:
        r.pos = offset
        res_type = r.ustring()
        props = {}
        for _ in range(r.u32()):
            name = r.string_ref()
            props[name] = r.variant()
        internal[path] = (res_type, props)
    return {"type": kind, "external": external, "internal": internal, "main": offsets[-1][0]}


def internal_resource(res, ref):
    """The (type, props) an internal Ref names: its path is 'local://<index>' (save: get_subindex)."""
    return res["internal"][f"local://{ref.index}"]


# ----------------------------------------------------------------------------------------------------
# Transforms: Godot's Transform is a 3x3 basis (rows) and an origin; x' = basis x + origin.

IDENTITY = ((1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0))


def to_transform(value):
    return (tuple(value[:9]), tuple(value[9:12])) if value is not None else IDENTITY


def mat_vec(basis, v):
    return tuple(basis[3 * i] * v[0] + basis[3 * i + 1] * v[1] + basis[3 * i + 2] * v[2] for i in range(3))


def compose(a, b):
    """a after b (Godot's a * b: the child b's transform in the parent a's space)."""
    (ba, oa), (bb, ob) = a, b
    basis = tuple(sum(ba[3 * i + k] * bb[3 * k + j] for k in range(3)) for i in range(3) for j in range(3))
    origin = tuple(x + y for x, y in zip(mat_vec(ba, ob), oa))
    return basis, origin


def apply(t, p):
    return tuple(x + y for x, y in zip(mat_vec(t[0], p), t[1]))


def column(t, j):
    return tuple(t[0][3 * i + j] for i in range(3))


def normalize(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v) if n > 0 else v


# ----------------------------------------------------------------------------------------------------
# The node tree of a PackedScene


NAME_INDEX_BITS = 18          # scene/resources/packed_scene.h
FLAG_ID_IS_PATH = 1 << 30
NO_PARENT_SAVED = 0x7FFFFFFF
TYPE_INSTANCED = 0x7FFFFFFF
FLAG_MASK = (1 << 24) - 1


def scene_nodes(res):
    """The nodes of the main PackedScene, from its '_bundled' dictionary (SceneState::set_bundled_scene,
    scene/resources/packed_scene.cpp): 'nodes' is a PoolIntArray of, per node, parent, owner, type,
    name (low 18 bits), instance, property count, (name, value) index pairs into 'names' and 'variants',
    group count, groups. Each node gets its global transform (parents come first)."""
    _, props = res["internal"][res["main"]]
    bundled = props["_bundled"]
    names, variants, ints = bundled["names"], bundled["variants"], bundled["nodes"]
    nodes, i = [], 0
    for _ in range(bundled["node_count"]):
        parent, _owner, kind, name, instance, count = ints[i:i + 6]
        i += 6
        properties = {names[ints[i + 2 * k]]: variants[ints[i + 2 * k + 1]] for k in range(count)}
        i += 2 * count
        i += 1 + ints[i]  # groups
        if parent >= 0 and parent != NO_PARENT_SAVED and parent & FLAG_ID_IS_PATH:
            sys.exit("sponza.py: a node whose parent is given by path (an edited instance) is not supported")
        local = to_transform(properties.get("transform"))
        root = parent < 0 or parent == NO_PARENT_SAVED
        node = {
            "name": names[name & ((1 << NAME_INDEX_BITS) - 1)],
            "type": None if kind == TYPE_INSTANCED else names[kind],
            "instance": variants[instance & FLAG_MASK] if instance >= 0 else None,
            "props": properties,
            "global": local if root else compose(nodes[parent & FLAG_MASK]["global"], local),
        }
        nodes.append(node)
    return nodes


# ----------------------------------------------------------------------------------------------------
# ArrayMesh surfaces (servers/visual_server.h ArrayFormat; servers/visual_server.cpp _surface_set_data
# writes and _get_array_from_surface reads them)

ARRAY_VERTEX, ARRAY_NORMAL, ARRAY_TANGENT, ARRAY_COLOR, ARRAY_TEX_UV, ARRAY_TEX_UV2, ARRAY_BONES, \
    ARRAY_WEIGHTS, ARRAY_INDEX = range(9)
ARRAY_COMPRESS_BASE = ARRAY_INDEX + 1
ARRAY_FLAG_USE_2D_VERTICES = 1 << (ARRAY_INDEX + ARRAY_COMPRESS_BASE + 1)
ARRAY_FLAG_USE_16_BIT_BONES = 1 << (ARRAY_INDEX + ARRAY_COMPRESS_BASE + 2)
PRIMITIVE_TRIANGLES = 4


def compressed(fmt, array):
    return bool(fmt & (1 << (array + ARRAY_COMPRESS_BASE)))


def element_size(fmt, array):
    """Bytes of one vertex's element of an array, as _get_array_from_surface computes them: each array
    present follows the previous one in the interleaved vertex, no padding but the vertex's own."""
    if array == ARRAY_VERTEX:
        n = 2 if fmt & ARRAY_FLAG_USE_2D_VERTICES else 3
        size = n * (2 if compressed(fmt, array) else 4)  # half floats when ARRAY_COMPRESS_VERTEX
        return 8 if size == 6 else size  # compressed 3D: 4 halves (x, y, z, 1)
    if array == ARRAY_NORMAL:
        return 4 if compressed(fmt, array) else 12  # 4 signed bytes (x, y, z, 0) x 127
    if array in (ARRAY_TANGENT, ARRAY_COLOR):
        return 4 if compressed(fmt, array) else 16
    if array in (ARRAY_TEX_UV, ARRAY_TEX_UV2):
        return 4 if compressed(fmt, array) else 8  # 2 half floats when compressed
    if array == ARRAY_BONES:
        return 8 if fmt & ARRAY_FLAG_USE_16_BIT_BONES else 4
    if array == ARRAY_WEIGHTS:
        return 8 if compressed(fmt, array) else 16
    raise ValueError(array)


def decode_surface(surface):
    """Positions, normals (or None), UVs (or None) and triangles (index triples) of one surface."""
    fmt, count = surface["format"], surface["vertex_count"]
    if surface["primitive"] != PRIMITIVE_TRIANGLES:
        sys.exit(f"sponza.py: surface '{surface.get('name')}' is primitive {surface['primitive']}, "
                 "not triangles")
    if fmt & ARRAY_FLAG_USE_2D_VERTICES:
        sys.exit(f"sponza.py: surface '{surface.get('name')}' has 2D vertices")
    offsets, stride = {}, 0
    for array in range(ARRAY_INDEX):
        if fmt & (1 << array):
            offsets[array] = stride
            stride += element_size(fmt, array)
    data = surface["array_data"]
    if len(data) != stride * count:
        sys.exit(f"sponza.py: surface '{surface.get('name')}': {len(data)} bytes of vertices, "
                 f"expected {count} x {stride}")

    def column_of(array, fmt_char, n):
        """The first n values of one array's element in every vertex (the rest of the vertex skipped)."""
        after = stride - offsets[array] - struct.calcsize("<" + fmt_char * n)
        layout = "<" + "x" * offsets[array] + fmt_char * n + "x" * after
        return list(struct.iter_unpack(layout, data))

    positions = column_of(ARRAY_VERTEX, "e" if compressed(fmt, ARRAY_VERTEX) else "f", 3)
    normals = None
    if ARRAY_NORMAL in offsets:
        if compressed(fmt, ARRAY_NORMAL):
            normals = [(x / 127.0, y / 127.0, z / 127.0) for x, y, z in column_of(ARRAY_NORMAL, "b", 3)]
        else:
            normals = column_of(ARRAY_NORMAL, "f", 3)
    uvs = None
    if ARRAY_TEX_UV in offsets:
        uvs = column_of(ARRAY_TEX_UV, "e" if compressed(fmt, ARRAY_TEX_UV) else "f", 2)
    if fmt & (1 << ARRAY_INDEX):
        # 16-bit indices below 65536 vertices, else 32-bit (_get_array_from_surface)
        wide = count >= (1 << 16)
        indices = struct.unpack_from(f"<{surface['index_count']}{'I' if wide else 'H'}",
                                     surface["array_index_data"])
    else:
        indices = range(count)
    triangles = [tuple(indices[i:i + 3]) for i in range(0, len(indices) - 2, 3)]
    return positions, normals, uvs, triangles


# ----------------------------------------------------------------------------------------------------
# Materials (scene/resources/material.cpp SpatialMaterial; properties equal to their defaults are not
# saved, so a missing albedo_color is white and a missing uv1_scale is 1)


def srgb_to_linear(c):
    """SpatialMaterial's albedo is a hint_color uniform: sRGB, made linear before shading."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def texture_path(res, ref):
    """The repository path of an external texture (res://sponza/...), or None."""
    if not isinstance(ref, Ref) or not ref.external:
        return None
    _, path = res["external"][ref.index]
    return path[len("res://"):] if path.startswith("res://") else path


def mask_for(repo, albedo):
    """The cut-out mask the repository keeps beside an albedo texture: X_mask.tga or, for X_diff.tga,
    X_mask.tga (chain_texture, sponza_thorn_diff, vase_plant). None where there is none."""
    stem, ext = os.path.splitext(albedo)
    candidates = [stem + "_mask" + ext]
    if stem.endswith("_diff"):
        candidates.append(stem[:-len("_diff")] + "_mask" + ext)
    for path in candidates:
        if repo.read(path) is not None:
            return path
    return None


def describe_material(repo, res, name, props):
    """What the MTL says of one material: name, Kd, albedo texture and mask (repository paths or None),
    the UV scale and offset, and notes for the report."""
    color = props.get("albedo_color") or (1.0, 1.0, 1.0, 1.0)
    albedo = texture_path(res, props.get("albedo_texture"))
    notes = []
    if albedo is not None and repo.read(albedo) is None:
        notes.append(f"its albedo texture {os.path.basename(albedo)} is not in the repository: "
                     "albedo colour alone")
        albedo = None
    mask = mask_for(repo, albedo) if albedo else None
    transparent = props.get("flags_transparent") or props.get("params_use_alpha_scissor")
    if transparent and not mask:
        notes.append("transparent in Godot (albedo alpha %g) but has no mask: rendered opaque" % color[3])
    scale = props.get("uv1_scale") or (1.0, 1.0, 1.0)
    offset = props.get("uv1_offset") or (0.0, 0.0, 0.0)
    return {
        "name": name,
        "kd": tuple(srgb_to_linear(c) for c in color[:3]),
        "albedo": albedo,
        "mask": mask,
        "uv": (scale[0], scale[1], offset[0], offset[1]),
        "notes": notes,
    }


def hidden(props):
    """A material the project's scene hides: transparent with albedo alpha 0 (Godot's ALPHA is albedo
    alpha x texture alpha, so nothing of it is drawn). The plants, the leaves and Material__47 are."""
    color = props.get("albedo_color") or (1.0, 1.0, 1.0, 1.0)
    return bool(props.get("flags_transparent")) and color[3] == 0.0


def material(repo, model, name, props):
    """The material as the MTL gives it. One that the scene hides is restored as Crytek's Sponza has it:
    from the importer's copy of the Collada material, sponza/<name>.material (opaque; the plants and
    leaves then take their cut-out masks, Material__47 its grey)."""
    if hidden(props):
        data = repo.read(f"sponza/{name}.material")
        if data is not None:
            source = parse_resource(data)
            described = describe_material(repo, source, name, source["internal"][source["main"]][1])
            described["notes"].insert(0, f"hidden in {MODEL} (transparent, albedo alpha 0): "
                                         f"restored from sponza/{name}.material")
            return described
    return describe_material(repo, model, name, props)


# ----------------------------------------------------------------------------------------------------
# Gathering the model


def gather(repo):
    """The surfaces (with world transforms) and materials of the Sponza model, and the main scene's
    camera and sun: {'surfaces': [...], 'materials': [...], 'camera': transform, 'sun': transform}."""
    model = parse_resource(repo.read(MODEL))
    main = parse_resource(repo.read(MAIN_SCENE))
    main_nodes = scene_nodes(main)
    placed = IDENTITY
    for node in main_nodes:
        inst = node["instance"]
        if isinstance(inst, Ref) and inst.external and main["external"][inst.index][1] == "res://" + MODEL:
            placed = node["global"]
    camera = next((n["global"] for n in main_nodes if n["type"] == "Camera"), None)
    sun = next((n["global"] for n in main_nodes if n["type"] == "DirectionalLight"), None)

    surfaces, materials, by_ref = [], [], {}
    for node in scene_nodes(model):
        if node["type"] != "MeshInstance" or not isinstance(node["props"].get("mesh"), Ref):
            continue
        world = compose(placed, node["global"])
        _, mesh = internal_resource(model, node["props"]["mesh"])
        keys = sorted((k for k in mesh if k.startswith("surfaces/")), key=lambda k: int(k.split("/")[1]))
        for key in keys:
            surface = mesh[key]
            index = int(key.split("/")[1])
            # MeshInstance material_override, then material/<i>, then the surface's own
            ref = (node["props"].get("material_override") or node["props"].get(f"material/{index}")
                   or surface.get("material"))
            ident = (ref.external, ref.index) if isinstance(ref, Ref) else None
            if ident not in by_ref:
                props = internal_resource(model, ref)[1] if isinstance(ref, Ref) and not ref.external else {}
                name = props.get("resource_name") or surface.get("name") or f"material_{len(materials)}"
                by_ref[ident] = len(materials)
                materials.append(material(repo, model, name, props))
            surfaces.append({"name": surface.get("name") or key, "world": world,
                             "data": decode_surface(surface), "material": by_ref[ident]})
    names = [m["name"] for m in materials]
    if len(set(names)) != len(names):
        sys.exit(f"sponza.py: two materials share a name: {names}")
    return {"surfaces": surfaces, "materials": materials, "camera": camera, "sun": sun}


# ----------------------------------------------------------------------------------------------------
# Writing


def fmt(x, digits):
    s = f"{x:.{digits}f}"
    return "0" if s.strip("-0.") == "" else s.rstrip("0").rstrip(".")


def write_obj(path, model):
    """One group per surface; v, vt, vn per Godot vertex; faces reversed (Godot's front faces are
    clockwise, sensorlight's counter-clockwise); v = 1 - v (Godot's UV origin is the image's top left,
    OBJ's its bottom left). Returns (triangles, vertices, bounds)."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    triangles = vertices = 0
    with open(path, "w", newline="\n") as f:
        f.write("# Crytek Sponza, converted from TheOnlyJoey/godot-sponza (models/sponza.scn) by "
                "scripts/sponza.py.\n# Units: the Godot scene's (the building is 23 units long); y up; "
                "faces counter-clockwise seen from the front.\nmtllib sponza.mtl\n")
        base = 1
        for surface in model["surfaces"]:
            positions, normals, uvs, tris = surface["data"]
            material = model["materials"][surface["material"]]
            world = surface["world"]
            su, sv, ou, ov = material["uv"]
            lines = [f"\ng {surface['name']}\nusemtl {material['name']}"]
            for p in positions:
                q = apply(world, p)
                for i in range(3):
                    lo[i], hi[i] = min(lo[i], q[i]), max(hi[i], q[i])
                lines.append(f"v {fmt(q[0], 5)} {fmt(q[1], 5)} {fmt(q[2], 5)}")
            if uvs:
                lines.extend(f"vt {fmt(u * su + ou, 5)} {fmt(1.0 - (v * sv + ov), 5)}" for u, v in uvs)
            if normals:
                # the basis is a rotation times a uniform scale here, so normals turn with it
                for n in normals:
                    m = normalize(mat_vec(world[0], n))
                    lines.append(f"vn {fmt(m[0], 4)} {fmt(m[1], 4)} {fmt(m[2], 4)}")
            for a, b, c in tris:
                corner = [str(base + k) for k in (a, c, b)]  # reversed winding
                if uvs and normals:
                    corner = [f"{k}/{k}/{k}" for k in corner]
                elif normals:
                    corner = [f"{k}//{k}" for k in corner]
                elif uvs:
                    corner = [f"{k}/{k}" for k in corner]
                lines.append("f " + " ".join(corner))
            f.write("\n".join(lines) + "\n")
            base += len(positions)
            vertices += len(positions)
            triangles += len(tris)
    return triangles, vertices, (lo, hi)


def write_mtl(path, materials):
    with open(path, "w", newline="\n") as f:
        f.write("# Materials of Crytek Sponza from TheOnlyJoey/godot-sponza, by scripts/sponza.py:\n"
                "# Kd the Godot albedo colour (linear), map_Kd its albedo texture, map_d a cut-out mask.\n")
        for m in materials:
            f.write(f"\nnewmtl {m['name']}\nKd {' '.join(fmt(c, 4) for c in m['kd'])}\n")
            if m["albedo"]:
                f.write(f"map_Kd textures/{os.path.basename(m['albedo'])}\n")
            if m["mask"]:
                f.write(f"map_d textures/{os.path.basename(m['mask'])}\n")


def copy_textures(repo, materials, folder):
    os.makedirs(folder, exist_ok=True)
    paths = sorted({p for m in materials for p in (m["albedo"], m["mask"]) if p})
    for path in paths:
        with open(os.path.join(folder, os.path.basename(path)), "wb") as f:
            f.write(repo.read(path))
    return paths


def camera_and_sun(model):
    """The main scene's camera (eye, and target 1 m along its -z) and its DirectionalLight's direction
    towards the sun (its +z: a Godot light shines along its -z)."""
    cam = model["camera"]
    eye = cam[1]
    forward = normalize(tuple(-x for x in column(cam, 2)))
    target = tuple(e + d for e, d in zip(eye, forward))
    sun = normalize(column(model["sun"], 2)) if model["sun"] else (0.1, 1.0, 0.2)
    return eye, target, sun


def write_toml(path, model, triangles):
    eye, target, sun = camera_and_sun(model)
    vec = lambda v, d=4: "[" + ", ".join(fmt(x, d) for x in v) + "]"
    with open(path, "w", newline="\n") as f:
        f.write(f"""# Generated by scripts/sponza.py: Crytek Sponza ({triangles} triangles) from the Godot 3
# project TheOnlyJoey/godot-sponza, in its units (the building is 23 units long, the floor at y = 0).
# Camera: the project's (scenes/sponza.scn), on the atrium's floor looking along its length; sun: the
# project's DirectionalLight, steeply through the open roof; a moderate blue sky.
mesh = "sponza.obj"

[camera]
eye = {vec(eye)}
target = {vec(target)}
up = [0, 1, 0]
vfov_deg = {fmt(VFOV_DEG, 2)}

[image]
width = {IMAGE_SIZE[0]}
height = {IMAGE_SIZE[1]}

[sun]
direction = {vec(sun)}
irradiance = {fmt(SUN_IRRADIANCE, 3)}

[render]
background = {vec(SKY, 3)}
""")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mirror", metavar="PATH",
                        help=f"a bare mirror or a clone of {REPO_URL} (default: {DEFAULT_MIRROR})")
    args = parser.parse_args()
    repo = open_repo(args.mirror)
    model = gather(repo)
    os.makedirs(OUT, exist_ok=True)
    triangles, vertices, (lo, hi) = write_obj(os.path.join(OUT, "sponza.obj"), model)
    write_mtl(os.path.join(OUT, "sponza.mtl"), model["materials"])
    textures = copy_textures(repo, model["materials"], os.path.join(OUT, "textures"))
    write_toml(os.path.join(OUT, "sponza.toml"), model, triangles)

    mats = model["materials"]
    print(f"{len(model['surfaces'])} surfaces, {triangles} triangles, {vertices} vertices")
    print(f"{len(mats)} materials, {sum(1 for m in mats if m['albedo'])} with a colour texture, "
          f"{sum(1 for m in mats if m['mask'])} with a cut-out mask; {len(textures)} textures copied")
    print("bounds: " + " .. ".join("(" + ", ".join(f"{x:.2f}" for x in b) + ")" for b in (lo, hi)))
    for m in mats:
        for note in m["notes"]:
            print(f"note: material '{m['name']}': {note}")
    print(f"wrote {os.path.relpath(OUT, ROOT)}/sponza.obj, sponza.mtl, sponza.toml, textures/")


if __name__ == "__main__":
    main()
