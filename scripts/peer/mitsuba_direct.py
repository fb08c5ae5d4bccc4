#!/usr/bin/env python3
"""Render a sensorlight scene with Mitsuba 3's `direct` or `path` integrator: an independent peer.

With `--epsilon 0` (or `--bounces 0`), sensorlight computes exactly direct illumination from one-sided
Lambertian area lights onto two-sided Lambertian surfaces: pixel = Le + Kd·R, R = (1/π) ∫ Ke cosθ dω over
the emitters visible from the point. Mitsuba's `direct` integrator (emitter and BSDF sampling, combined by
MIS) estimates the same quantity with an unrelated code base, so it serves as a peer reference.

With global illumination (`--bounces N|auto`), R integrates the light every surface really reflects,
L = Le + Kd·R, recursively. `--integrator path` renders that with Mitsuba's `path` integrator (emitter and
BSDF sampling by MIS at every vertex, Russian roulette from depth `--rr-depth`, default Mitsuba's 5, which
is unbiased): `--max-depth D` with D = N + 2 for sensorlight's N indirect bounces (depth 1: the emitters
seen; 2: their direct light; each further depth one bounce), `--max-depth -1` (the default) for
`--bounces auto`.

Usage (Mitsuba lives in a venv outside the repository):

    python3 -m venv /work/venv-mitsuba && /work/venv-mitsuba/bin/pip install mitsuba numpy
    /work/venv-mitsuba/bin/python scripts/peer/mitsuba_direct.py scenes/cornell/cornell.toml \\
        -o cornell-mitsuba.exr --spp 4096
    /work/venv-mitsuba/bin/python scripts/peer/mitsuba_direct.py scenes/cornell/cornell.toml \\
        -o cornell-path.exr --integrator path --max-depth 10 --spp 1024     # ↔ reference --bounces 8

The default variant, `llvm_ad_rgb`, JIT-compiles through the system's libLLVM and needs LLVM ≥ 16
(Dr.Jit emits `llvm.maximum`, which LLVM 14 and 15 cannot lower on x86: the process aborts with "LLVM
ERROR: Cannot select: … fmaximum"). On Debian 12: `apt-get install libllvm19` (Dr.Jit then finds it; or
point `DRJIT_LIBLLVM_PATH` at it). `--variant scalar_rgb` needs no LLVM; on 2 cores it was about 5× slower
(Cornell box, 256×256, 256 spp: 3.9 s against 0.8 s).

How each convention is matched
------------------------------
* Scene file: the TOML is read with `tomllib`; `mesh` is resolved against the TOML's directory, `[image]`
  width/height are used unless `--width`/`--height` override them (as `sensorlight render` does).
* Geometry: the OBJ is parsed here (not by Mitsuba's OBJ loader, to control winding and grouping):
  `v` (first three values), `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` and negative (relative) indices,
  polygons fan-triangulated from their first vertex (as `tobj`, sensorlight's loader, does); texture
  coordinates `vt` (u, v) become (u, 1 − v), the image's row 0 at the top, as sensorlight and Mitsuba read
  them; zero-area triangles dropped. One Mitsuba mesh per material, its front the
  counter-clockwise one, as in sensorlight. Shading normals as sensorlight's: a face's `vn`, normalised
  and turned to its front's side, are the mesh's vertex normals (the mesh is a triangle soup, so a corner
  is a vertex); a face without them takes its flat geometric normal normalize((v1 − v0) × (v2 − v0)) at
  its corners; a material with no `vn` at all is built with `face_normals`. (sensorlight shades a whole
  OBJ group flat where only some of its faces give `vn`, and warns; this script, which does not read
  groups, only those faces.)
* Materials: every `mtllib` is read (beside the OBJ as written, else by file name beside the OBJ);
  `Kd` is the albedo (0.8 grey when a material has no `Kd`, is undefined, or no `usemtl` was given,
  sensorlight's default) and `Ke` the emitted radiance (0 when absent). Every surface gets a `twosided`
  `diffuse` BSDF of reflectance Kd (other surfaces reflect on both sides); emitters keep that BSDF too,
  so their own reflected light adds to Le, as sensorlight's Le + Kd·R does.
* Textures: `map_Kd` (beside its MTL) is read as sRGB, turned linear, multiplied by Kd and given to the
  `diffuse` BSDF as a `raw` bilinear `bitmap` that repeats: Mitsuba point-samples it at each sample, as
  sensorlight's oracle does at level 0 (the box filter then averages it over the pixel). `map_d`
  (cut-outs) is refused: Mitsuba's `direct` and `path` integrators test shadow rays against every
  surface, a `mask` BSDF's holes included (tried: the light through a card's holes never reaches the
  floor), so there is no peer for a cut-out's shadow here.
* Sun and sky: a scene's `[sun]` becomes the same disc sensorlight draws (`src/scene/sun.rs`: a 32-gon of
  the round disc's area, 10⁴ diagonals of the mesh's bounds away, radiance E / (A / (D² + A/π))), an
  `area` emitter; `[render] background` a `constant` emitter; a `[sky]` map an `envmap` emitter of the
  same radiance. Mitsuba reads a map's columns as sensorlight does (texel centres, u wrapping) but its
  rows from pole to pole (row j at v = j/(H−1)) where sensorlight's are texel centres (v = (j+½)/H):
  the script hands Mitsuba the map resampled to 2H + 1 rows at v = j/2H, on which Mitsuba's linear
  interpolation is sensorlight's exactly (every kink of sensorlight's bilinear function is a row).
* Emitters: a material with any Ke component > 0 gets an `area` emitter of radiance Ke (linear RGB); with
  a `map_Ke`, Ke (1 when the material gives none) times that texture, read as `map_Kd` is.
  Mitsuba's area emitter is one-sided: it emits only towards the side its geometric normal points to,
  i.e. the counter-clockwise front, sensorlight's convention.
* Colour: the `*_rgb` variants render linear RGB with no spectral upsampling, so Kd and Ke are used as
  given. Mitsuba refuses a reflectance above 1, which sensorlight accepts: such a scene is an error here.
* Camera: `perspective` with `to_world = look_at(eye, target, up)`, `fov` = the scene's `vfov_deg`
  and `fov_axis = 'y'` (the *vertical* full angle, as sensorlight's `vfov_deg`), so for any aspect
  ratio the image plane spans the same ±tan(vfov/2)·aspect horizontally. Mitsuba's look_at orients the
  image like sensorlight (right = forward × up, row 0 at the top). Near and far clip planes are set from
  the scene's bounding box so nothing in the scene is clipped.
* Film: `hdrfilm`, RGB, float32, written as a linear OpenEXR with channels R, G, B (what
  `sensorlight compare` reads). `--pixel-sampling box` (the default) renders with the `box`
  reconstruction filter (radius ½ pixel): each pixel is the plain average of samples spread uniformly
  over its area. `--pixel-sampling centre` instead shoots every sample through the pixel centre
  (i + ½, j + ½), exactly where sensorlight's G-buffer samples; it needs an `llvm_*` variant.
* Sampling: `--spp` samples per pixel with the `independent` sampler seeded by `--seed`; the direct
  integrator takes `--emitter-samples` emitter and `--bsdf-samples` BSDF samples (default 1 each) per
  camera sample and combines them by MIS; the path integrator one of each per vertex. For a dark scene lit in a few pixels (door-ajar),
  `--pixel-mask EARLIER.exr` spends the samples on the pixels that an earlier render found lit. `--variant` picks the
  Mitsuba variant (default `llvm_ad_rgb`, the vectorised CPU backend, when available).

What cannot match
-----------------
* Silhouettes and other discontinuities inside a pixel. sensorlight point-samples pixel centres; with
  `--pixel-sampling box` Mitsuba averages over the pixel area, so pixels straddling a silhouette, and
  pixels crossed by a hard shadow edge, differ. Mask silhouettes when comparing (e.g. `compare.py`: a 3×3
  neighbourhood of differing `surface_id` from a sensorlight render with `--aovs`); shadow edges are not
  caught by that mask, which is why `--pixel-sampling centre` exists. Even with centre sampling, a ray
  that grazes an edge can be resolved differently by Mitsuba's ray tracer and sensorlight's rasteriser.
* Noise: Mitsuba is Monte Carlo; its error falls as 1/√spp. Estimate it by rendering twice with
  different `--seed` values (relative RMSE between the two ÷ √2 is the noise of one).
* Self-intersection offsets and near-plane handling differ between the two renderers; this matters only
  at contact edges (a box standing on a floor), within a pixel or so of them. With `path` it matters at
  every vertex too: sensorlight's oracle lifts each by 2e-4 of the scene's diagonal and does not see
  geometry nearer than 1e-4 of it (as its sensors), so a vertex that close to a seam loses a little light
  through it (≈ 0.05 % of a closed box's); Mitsuba offsets by its own small epsilon.
* Anything a sensorlight scene's `[render]` table sets for the algorithm (sensor kind, ε, bounces, …) is
  irrelevant here: `direct` is always ε = 0, the exact direct illumination, and `path` the bounces that
  `--max-depth` says.

The time taken (scene load, render, total) is printed on stdout, and with `--json` written to a file.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

DEFAULT_KD = 0.8


class SceneError(Exception):
    """A problem in the scene files, with the file (and line) it came from."""


@dataclass
class Material:
    name: str
    kd: tuple[float, float, float] | None = None
    ke: tuple[float, float, float] | None = None
    kd_map: Path | None = None
    ke_map: Path | None = None
    d_map: Path | None = None

    @property
    def albedo(self) -> tuple[float, float, float]:
        """Kd: as given; without one, 1 under a texture and 0.8 grey otherwise (sensorlight's)."""
        if self.kd is not None:
            return self.kd
        return (1.0, 1.0, 1.0) if self.kd_map is not None else (DEFAULT_KD,) * 3

    @property
    def emission(self) -> tuple[float, float, float]:
        """Ke: as given; without one, 1 under a `map_Ke` and 0 otherwise (sensorlight's)."""
        if self.ke is not None:
            return self.ke
        return (1.0, 1.0, 1.0) if self.ke_map is not None else (0.0, 0.0, 0.0)

    @property
    def is_emitter(self) -> bool:
        return max(self.emission) > 0.0


@dataclass
class Mesh:
    """Triangles grouped by material name (None = no usemtl / undefined: default grey)."""

    materials: dict[str, Material] = field(default_factory=dict)
    triangles: dict[str | None, list[tuple[tuple[float, ...], ...]]] = field(default_factory=dict)
    # Per triangle of `triangles`, its corners' shading normals, or None where the face gives none.
    normals: dict[str | None, list[tuple[tuple[float, ...], ...] | None]] = field(default_factory=dict)
    # Per triangle, its corners' texture coordinates (image rows down), or None where the face gives none.
    uvs: dict[str | None, list[tuple[tuple[float, float], ...] | None]] = field(default_factory=dict)
    dropped_degenerate: int = 0
    warnings: list[str] = field(default_factory=list)


def parse_floats(values: list[str], where: str) -> list[float]:
    try:
        return [float(v) for v in values]
    except ValueError as e:
        raise SceneError(f"{where}: {e}") from None


def statements(path: Path):
    """The statements of an OBJ or MTL file: (file:line, keyword, arguments), comments and blank lines left out."""
    for line_no, raw in enumerate(path.read_text().splitlines(), 1):
        words = raw.split("#", 1)[0].split()
        if words:
            yield f"{path}:{line_no}", words[0], words[1:]


def load_mtl(path: Path, materials: dict[str, Material]) -> None:
    current: Material | None = None
    for where, key, args in statements(path):
        if key == "newmtl":
            if not args:
                raise SceneError(f"{where}: 'newmtl' needs a name")
            current = Material(args[0])
            materials[current.name] = current
        elif key in ("Kd", "Ke"):
            if current is None:
                raise SceneError(f"{where}: '{key}' before any 'newmtl'")
            values = parse_floats(args, where)
            if len(values) != 3 or any(not math.isfinite(v) or v < 0 for v in values):
                raise SceneError(f"{where}: '{key}' needs 3 finite non-negative numbers")
            if key == "Kd":
                current.kd = tuple(values)
            else:
                current.ke = tuple(values)
        elif key in ("map_Kd", "map_Ke", "map_d") and current is not None and args:
            image = path.parent / args[-1]  # options before the name are not read (as sensorlight)
            if image.is_file():
                setattr(current, {"map_Kd": "kd_map", "map_Ke": "ke_map", "map_d": "d_map"}[key], image)


def find_mtl(obj_dir: Path, name: str, mesh: Mesh) -> Path | None:
    as_written = obj_dir / name
    if as_written.is_file():
        return as_written
    by_name = obj_dir / Path(name).name
    if by_name.is_file():
        mesh.warnings.append(f"mtllib '{name}' found by file name as {by_name}")
        return by_name
    mesh.warnings.append(f"material library '{name}' not found in {obj_dir}; its materials are grey")
    return None


def face_index(token: str, count: int, where: str) -> int:
    """0-based vertex index of one `f` token (`v`, `v/vt`, `v//vn`, `v/vt/vn`; negative = relative)."""
    text = token.split("/", 1)[0]
    try:
        i = int(text)
    except ValueError:
        raise SceneError(f"{where}: face vertex '{token}' is not an index") from None
    if 0 < i <= count:
        return i - 1
    if 0 < -i <= count:
        return count + i
    raise SceneError(f"{where}: vertex index {i} does not refer to one of the {count} defined so far")


def normal_index(token: str, count: int, where: str) -> int | None:
    """0-based normal index of one `f` token (`v//vn`, `v/vt/vn`), or None where it has none."""
    parts = token.split("/")
    if len(parts) < 3 or not parts[2]:
        return None
    return face_index(parts[2], count, where)


def texcoord_index(token: str, count: int, where: str) -> int | None:
    """0-based texture coordinate index of one `f` token (`v/vt`, `v/vt/vn`), or None where it has none."""
    parts = token.split("/")
    if len(parts) < 2 or not parts[1]:
        return None
    return face_index(parts[1], count, where)


def shading_normals(tri, given):
    """`given` corner normals normalised and turned to the front of `tri` (its flat normal where one is
    not a direction), as sensorlight's `surfaces::shading`."""
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = tri
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = cx - ax, cy - ay, cz - az
    face = (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
    length = sum(f * f for f in face) ** 0.5
    face = tuple(f / length for f in face)
    out = []
    for n in given:
        norm = sum(c * c for c in n) ** 0.5
        if not norm > 0.0 or norm == float("inf"):
            out.append(face)
            continue
        n = tuple(c / norm for c in n)
        out.append(tuple(-c for c in n) if sum(a * b for a, b in zip(n, face)) < 0.0 else n)
    return tuple(out)


def load_obj(path: Path) -> Mesh:
    if not path.is_file():
        raise SceneError(f"mesh {path} not found")
    mesh = Mesh()
    vertices: list[tuple[float, float, float]] = []
    vertex_normals: list[tuple[float, float, float]] = []
    texcoords: list[tuple[float, float]] = []
    material: str | None = None
    for where, key, args in statements(path):
        if key == "v":
            values = parse_floats(args, where)
            if len(values) not in (3, 4, 6):
                raise SceneError(f"{where}: 'v' takes 3 coordinates (optionally w, or r g b)")
            vertices.append(tuple(values[:3]))
        elif key == "vn":
            values = parse_floats(args, where)
            if len(values) != 3:
                raise SceneError(f"{where}: 'vn' takes 3 values")
            vertex_normals.append(tuple(values))
        elif key == "vt":
            values = parse_floats(args, where) + [0.0]
            texcoords.append((values[0], 1.0 - values[1]))
        elif key == "f":
            if len(args) < 3:
                raise SceneError(f"{where}: a face needs at least 3 vertices")
            idx = [face_index(a, len(vertices), where) for a in args]
            nidx = [normal_index(a, len(vertex_normals), where) for a in args]
            tidx = [texcoord_index(a, len(texcoords), where) for a in args]
            tris = mesh.triangles.setdefault(material, [])
            normals = mesh.normals.setdefault(material, [])
            uvs = mesh.uvs.setdefault(material, [])
            for k in range(1, len(idx) - 1):  # fan from the first vertex, as tobj triangulates
                tri = (vertices[idx[0]], vertices[idx[k]], vertices[idx[k + 1]])
                corners = (nidx[0], nidx[k], nidx[k + 1])
                if triangle_area2(tri) > 0.0:
                    tris.append(tri)
                    given = None if None in corners else tuple(vertex_normals[i] for i in corners)
                    normals.append(None if given is None else shading_normals(tri, given))
                    at = (tidx[0], tidx[k], tidx[k + 1])
                    uvs.append(None if None in at else tuple(texcoords[i] for i in at))
                else:
                    mesh.dropped_degenerate += 1
        elif key == "usemtl":
            if not args:
                raise SceneError(f"{where}: 'usemtl' needs a material name")
            material = args[0]
        elif key == "mtllib":
            for name in args:
                found = find_mtl(path.parent, name, mesh)
                if found is not None:
                    load_mtl(found, mesh.materials)
        # g, o, s, vt, l, p and the free-form statements carry nothing this renderer uses.
    undefined = sorted(m for m in mesh.triangles if m is not None and m not in mesh.materials)
    for name in undefined:
        mesh.warnings.append(f"material '{name}' is not defined in any MTL file; using grey Kd {DEFAULT_KD}")
    if not any(mesh.triangles.values()):
        raise SceneError(f"{path}: the mesh contains no triangles of non-zero area")
    return mesh


def flat_normal(tri):
    """The unit counter-clockwise front normal of `tri`."""
    return shading_normals(tri, [(0.0, 0.0, 0.0)])[0]


def triangle_area2(tri) -> float:
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = tri
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = cx - ax, cy - ay, cz - az
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    return nx * nx + ny * ny + nz * nz


@dataclass
class SceneSpec:
    path: Path
    mesh: Mesh
    eye: list[float]
    target: list[float]
    up: list[float]
    vfov_deg: float
    width: int
    height: int
    background: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # The [sun] table: direction, irradiance (RGB), angular diameter in degrees.
    sun: tuple[list[float], list[float], float] | None = None
    # The [sky] table: the map's path, strength and turn about +y in degrees.
    sky: tuple[Path, float, float] | None = None


def load_scene(path: Path, width: int | None, height: int | None) -> SceneSpec:
    try:
        doc = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneError(f"scene file {path} not found") from None
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{path}: {e}") from None
    try:
        cam = doc["camera"]
        eye, target = [float(x) for x in cam["eye"]], [float(x) for x in cam["target"]]
        up = [float(x) for x in cam.get("up", [0, 1, 0])]
        vfov = float(cam["vfov_deg"])
        image = doc["image"]
        w, h = int(width or image["width"]), int(height or image["height"])
        mesh_name = doc["mesh"]
    except KeyError as e:
        raise SceneError(f"{path}: missing key {e}") from None
    if not 0 < vfov < 180:
        raise SceneError(f"{path}: [camera] vfov_deg must lie in (0, 180), got {vfov}")
    if w < 1 or h < 1:
        raise SceneError(f"{path}: image width and height must be at least 1")
    background = [float(b) for b in doc.get("render", {}).get("background", [0, 0, 0])]
    sun = None
    if "sun" in doc:
        table = doc["sun"]
        irradiance = table.get("irradiance", math.pi)
        irradiance = [float(irradiance)] * 3 if isinstance(irradiance, (int, float)) else [float(x) for x in irradiance]
        sun = ([float(x) for x in table["direction"]], irradiance, float(table.get("angular_diameter_deg", 0.53)))
    sky = None
    if "sky" in doc:
        table = doc["sky"]
        sky = (path.parent / table["map"], float(table.get("strength", 1.0)), float(table.get("rotation_deg", 0.0)))
    mesh = load_obj(path.parent / mesh_name)
    return SceneSpec(path, mesh, eye, target, up, vfov, w, h, background, sun, sky)


def sky_envmap(path: Path, strength: float, rotation_deg: float) -> dict:
    """An `envmap` emitter whose radiance is sensorlight's sky map's (`src/scene/sky.rs`): the map's rows
    resampled to 2H + 1 rows at v = j / 2H (module docs)."""
    import mitsuba as mi
    import numpy as np

    try:
        texels = np.array(mi.Bitmap(str(path)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))
    except Exception as e:  # Mitsuba raises RuntimeError for unreadable files
        raise SceneError(f"sky map {path}: {e}") from None
    texels = texels.astype(np.float64) * strength
    h = texels.shape[0]
    v = np.arange(2 * h + 1) / (2 * h)
    y = np.clip(v * h - 0.5, 0.0, h - 1)
    y0 = np.floor(y).astype(int)
    f = (y - y0)[:, None, None]
    rows = texels[y0] * (1 - f) + texels[np.minimum(y0 + 1, h - 1)] * f
    to_world = mi.ScalarTransform4f().rotate([0, 1, 0], rotation_deg)
    return {"type": "envmap", "bitmap": mi.Bitmap(rows.astype(np.float32)), "to_world": to_world}


def sun_disc(direction, irradiance, diameter_deg, lo, hi):
    """The sun's facets and radiance, as `Sun::facets` (src/scene/sun.rs) builds them."""
    import numpy as np

    segments, distance_diagonals = 32, 1e4
    d = np.asarray(direction, dtype=np.float64)
    d /= np.linalg.norm(d)
    distance = distance_diagonals * float(np.linalg.norm(hi - lo))
    centre = (lo + hi) / 2 + d * distance
    step = 2 * math.pi / segments
    radius = distance * math.tan(math.radians(diameter_deg) / 2)
    radius *= math.sqrt(math.pi / (0.5 * segments * math.sin(step)))
    a = np.cross(d, [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(d, a)
    rim = [centre + (a * math.cos(k * step) + b * math.sin(k * step)) * radius for k in range(segments + 1)]
    triangles = [(centre, rim[k + 1], rim[k]) for k in range(segments)]
    # Counter-clockwise seen from the scene (the front faces it).
    t = triangles[0]
    if np.dot(np.cross(t[1] - t[0], t[2] - t[0]), d) > 0:
        triangles = [(c, q, p) for c, p, q in triangles]
    area = 0.5 * segments * radius * radius * math.sin(step)
    projected = area / (distance * distance + area / math.pi)
    return triangles, [e / projected for e in irradiance]


def colour_texture(path: Path, kd):
    """`path` (sRGB) as linear RGB times `kd` (an albedo or a radiance): a raw, repeating, bilinear Mitsuba
    bitmap texture."""
    import mitsuba as mi
    import numpy as np

    bitmap = mi.Bitmap(str(path)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    linear = np.array(bitmap, dtype=np.float32) * np.asarray(kd, dtype=np.float32)
    return {"type": "bitmap", "bitmap": mi.Bitmap(linear), "raw": True, "filter_type": "bilinear", "wrap_mode": "repeat"}


def choose_variant(requested: str | None, pixel_sampling: str) -> str:
    import mitsuba as mi

    available = mi.variants()
    if requested:
        if requested not in available:
            raise SceneError(f"Mitsuba variant '{requested}' is not available here (have: {', '.join(available)})")
        variant = requested
    else:
        variant = "llvm_ad_rgb" if "llvm_ad_rgb" in available else "scalar_rgb"
    if not variant.endswith("_rgb"):
        raise SceneError(f"variant '{variant}': use an RGB variant (scalar_rgb, llvm_ad_rgb) so Kd, Ke stay RGB")
    if pixel_sampling == "centre" and not variant.startswith("llvm"):
        raise SceneError("--pixel-sampling centre needs an llvm_* variant (it traces whole wavefronts)")
    return variant


def integrator_dict(kind: str, emitter_samples: int, bsdf_samples: int, max_depth: int, rr_depth: int) -> dict:
    """Mitsuba's `direct` (emitter + BSDF samples by MIS) or `path` (the same at every vertex, to max_depth)."""
    if kind == "direct":
        return {"type": "direct", "emitter_samples": emitter_samples, "bsdf_samples": bsdf_samples}
    return {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth}


def build_scene(spec: SceneSpec, spp: int, seed: int, integrator: dict):
    """The Mitsuba scene: one mesh per material, the camera, the film, the integrator."""
    import mitsuba as mi
    import numpy as np

    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    shapes = {}
    for k, (name, tris) in enumerate(sorted(spec.mesh.triangles.items(), key=lambda kv: str(kv[0]))):
        if not tris:
            continue
        material = spec.mesh.materials.get(name) if name is not None else None
        material = material or Material(name or "(default grey)")
        kd = material.albedo
        if max(kd) > 1.0:
            raise SceneError(f"material '{material.name}': Kd {kd} exceeds 1, which Mitsuba refuses")
        positions = np.asarray(tris, dtype=np.float32).reshape(-1, 3)
        lo, hi = np.minimum(lo, positions.min(0)), np.maximum(hi, positions.max(0))
        faces = np.arange(len(positions), dtype=np.uint32)
        given = spec.mesh.normals.get(name, [])
        smooth = any(n is not None for n in given)
        corner_uvs = spec.mesh.uvs.get(name, [])
        maps = (material.kd_map, material.ke_map, material.d_map)
        textured = any(m is not None for m in maps) and all(uv is not None for uv in corner_uvs)
        props = mi.Properties()
        props["face_normals"] = not smooth
        reflectance = colour_texture(material.kd_map, kd) if textured and material.kd_map else {"type": "rgb", "value": list(kd)}
        bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": reflectance}}
        if material.d_map and not material.is_emitter:
            raise SceneError(
                f"material '{material.name}': map_d (a cut-out) — Mitsuba's direct and path integrators let no "
                "shadow ray through a mask BSDF, so this peer cannot render its shadow"
            )
        props["bsdf"] = mi.load_dict(bsdf)
        if material.is_emitter:
            ke = material.emission
            radiance = colour_texture(material.ke_map, ke) if textured and material.ke_map else {"type": "rgb", "value": list(ke)}
            props["emitter"] = mi.load_dict({"type": "area", "radiance": radiance})
        shape = mi.Mesh(
            f"m{k}_{material.name}",
            vertex_count=len(positions),
            face_count=len(tris),
            has_vertex_normals=smooth,
            has_vertex_texcoords=textured,
            props=props,
        )
        params = mi.traverse(shape)
        # The parameter types differ by variant (dr.scalar.ArrayXf, mi.Float, …): build each as its own type.
        params["vertex_positions"] = type(params["vertex_positions"])(positions.ravel())
        params["faces"] = type(params["faces"])(faces)
        if smooth:
            corners = [n if n is not None else (flat_normal(t),) * 3 for t, n in zip(tris, given)]
            normals = np.asarray(corners, dtype=np.float32).reshape(-1, 3)
            params["vertex_normals"] = type(params["vertex_normals"])(normals.ravel())
        if textured:
            texcoords = np.asarray(corner_uvs, dtype=np.float32).reshape(-1, 2)
            params["vertex_texcoords"] = type(params["vertex_texcoords"])(texcoords.ravel())
        params.update()
        shapes[f"m{k}"] = shape
    if spec.sun is not None:
        facets, radiance = sun_disc(*spec.sun, lo, hi)
        positions = np.asarray(facets, dtype=np.float32).reshape(-1, 3)
        props = mi.Properties()
        props["face_normals"] = True
        props["bsdf"] = mi.load_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}})
        props["emitter"] = mi.load_dict({"type": "area", "radiance": {"type": "rgb", "value": radiance}})
        shape = mi.Mesh("sun", vertex_count=len(positions), face_count=len(facets), props=props)
        params = mi.traverse(shape)
        params["vertex_positions"] = type(params["vertex_positions"])(positions.ravel())
        params["faces"] = type(params["faces"])(np.arange(len(positions), dtype=np.uint32))
        params.update()
        shapes["sun"] = shape
    if spec.sky is not None:
        shapes["sky"] = sky_envmap(*spec.sky)
    elif any(b > 0 for b in spec.background):
        shapes["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": spec.background}}
    eye = np.asarray(spec.eye, dtype=np.float64)
    far = float(np.max(np.linalg.norm(np.stack([lo, hi]) - eye, axis=1)) * 4.0 + 1.0)
    diag = float(np.linalg.norm(hi - lo))
    scene_dict = {
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective",
            "fov": spec.vfov_deg,
            "fov_axis": "y",
            "near_clip": diag * 1e-5,
            "far_clip": far + diag,
            "to_world": mi.ScalarTransform4f().look_at(origin=spec.eye, target=spec.target, up=spec.up),
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
            "film": {
                "type": "hdrfilm",
                "width": spec.width,
                "height": spec.height,
                "pixel_format": "rgb",
                "component_format": "float32",
                "rfilter": {"type": "box"},
            },
        },
        **shapes,
    }
    return mi.load_dict(scene_dict)


def render_centres(scene, spec: SceneSpec, spp: int, seed: int, only=None):
    """Every sample through the pixel centre (as sensorlight's G-buffer), averaged: an (h, w, 3) array.

    `only`, an (h, w) bool array, restricts the work to those pixels (the others are 0)."""
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    sensor, integrator = scene.sensors()[0], scene.integrator()
    w, h = spec.width, spec.height
    chosen = np.flatnonzero(only.ravel()) if only is not None else np.arange(w * h)
    n = len(chosen)
    if n == 0:
        return np.zeros((h, w, 3), dtype=np.float32)
    chosen_dr = mi.UInt32(chosen.astype(np.uint32))
    per_pass = max(1, min(spp, (1 << 21) // n))  # samples of each pixel per wavefront, ≤ ~2M lanes
    sampler = mi.load_dict({"type": "independent"})
    total = np.zeros((n, 3), dtype=np.float64)
    done, pass_index = 0, 0
    while done < spp:
        k = min(per_pass, spp - done)
        # Sample-major lanes (lane = s·n + pixel); measured faster here than pixel-major on LLVM.
        pixel = dr.gather(mi.UInt32, chosen_dr, dr.arange(mi.UInt32, n * k) % n)
        x, y = pixel % w, pixel // w
        position = mi.Point2f((mi.Float(x) + 0.5) / w, (mi.Float(y) + 0.5) / h)
        sampler.seed(seed * 1_000_003 + pass_index, n * k)
        ray, weight = sensor.sample_ray(0.0, 0.5, position, mi.Point2f(0.5, 0.5))
        radiance, _, _ = integrator.sample(scene, sampler, ray)
        value = radiance * weight
        dr.eval(value)  # one kernel for all three channels (converting each alone would trace it thrice)
        arr = np.stack([np.asarray(value[c]) for c in range(3)], axis=1).reshape(k, n, 3)
        total += arr.sum(axis=0, dtype=np.float64)
        done += k
        pass_index += 1
    image = np.zeros((w * h, 3), dtype=np.float32)
    image[chosen] = total / spp
    return image.reshape(h, w, 3)


def emission_at_centres(scene, spec: SceneSpec):
    """Le seen through each pixel centre (0 off emitters and on their backs): an (h, w, 3) array.

    Written as the `emission.*` layer so that comparisons can leave emitter pixels out (their value is
    dominated by Le, which every renderer gets right) and subtract Le where they need Kd·R alone."""
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    sensor = scene.sensors()[0]
    w, h = spec.width, spec.height
    if dr.size_v(mi.Float) == 1:  # scalar variant: one ray at a time
        out = np.zeros((h, w, 3), dtype=np.float32)
        for y in range(h):
            for x in range(w):
                ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((x + 0.5) / w, (y + 0.5) / h), mi.Point2f(0.5, 0.5))
                si = scene.ray_intersect(ray)
                emitter = si.emitter(scene)
                if si.is_valid() and emitter is not None:
                    out[y, x] = np.array(emitter.eval(si))
        return out
    pixel = dr.arange(mi.UInt32, w * h)
    position = mi.Point2f((mi.Float(pixel % w) + 0.5) / w, (mi.Float(pixel // w) + 0.5) / h)
    ray, _ = sensor.sample_ray(0.0, 0.5, position, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    le = si.emitter(scene).eval(si, si.is_valid())
    dr.eval(le)
    return np.stack([np.asarray(le[c]) for c in range(3)], axis=1).reshape(h, w, 3).astype(np.float32)


def read_mask(path: Path, spec: SceneSpec):
    """Pixels where the EXR at `path` has R + G + B > 0, as an (h, w) bool array."""
    import mitsuba as mi
    import numpy as np

    if not path.is_file():
        raise SceneError(f"--pixel-mask {path}: no such file")
    bitmap = mi.Bitmap(str(path))
    data = np.array(bitmap)
    names = [bitmap.struct_()[i].name for i in range(data.shape[2])]
    if not all(c in names for c in "RGB"):
        raise SceneError(f"--pixel-mask {path}: no R, G, B channels")
    if data.shape[:2] != (spec.height, spec.width):
        raise SceneError(f"--pixel-mask {path} is {data.shape[1]}x{data.shape[0]}, the image {spec.width}x{spec.height}")
    return sum(data[:, :, names.index(c)] for c in "RGB") > 0


def write_exr(path: Path, image, emission) -> None:
    """R, G, B = the render; emission.R/G/B = Le at the pixel centres. Written atomically."""
    import mitsuba as mi
    import numpy as np

    channels = np.concatenate([image, emission], axis=2)
    names = ["R", "G", "B", "emission.R", "emission.G", "emission.B"]
    bitmap = mi.Bitmap(
        np.ascontiguousarray(channels, dtype=np.float32),
        pixel_format=mi.Bitmap.PixelFormat.MultiChannel,
        channel_names=names,
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.exr")
    bitmap.write(str(tmp))
    tmp.replace(path)


def describe(integrator: dict) -> str:
    if integrator["type"] == "direct":
        return "direct"
    depth = integrator["max_depth"]
    return f"path to depth {depth if depth >= 0 else '∞'} (roulette from {integrator['rr_depth']})"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    parser.add_argument("scene", type=Path, help="sensorlight scene file (TOML)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="output EXR (linear RGB)")
    parser.add_argument("--spp", type=int, default=256, help="samples per pixel (default 256)")
    parser.add_argument("--seed", type=int, default=0, help="sampler seed (default 0)")
    parser.add_argument("--width", type=int, help="image width (default: the scene's)")
    parser.add_argument("--height", type=int, help="image height (default: the scene's)")
    parser.add_argument("--variant", help="Mitsuba variant (default llvm_ad_rgb if available, else scalar_rgb)")
    parser.add_argument(
        "--pixel-sampling",
        choices=["box", "centre"],
        default="box",
        help="box: box filter over each pixel (default); centre: every sample through the pixel centre",
    )
    parser.add_argument(
        "--integrator",
        choices=["direct", "path"],
        default="direct",
        help="direct: direct light only (sensorlight --epsilon 0 / --bounces 0; the default);\n"
        "path: global illumination to --max-depth",
    )
    parser.add_argument(
        "--max-depth",
        type=int,
        help="with --integrator path: the longest path, -1 = unbounded (the default; sensorlight --bounces auto);\n"
        "N + 2 for sensorlight's --bounces N (1: emitters only, 2: direct light)",
    )
    parser.add_argument(
        "--rr-depth",
        type=int,
        default=5,
        help="with --integrator path: the depth from which Russian roulette ends paths (default 5, Mitsuba's)",
    )
    parser.add_argument(
        "--emitter-samples", type=int, help="with direct: emitter (light) samples per camera sample (default 1)"
    )
    parser.add_argument("--bsdf-samples", type=int, help="with direct: BSDF samples per camera sample (default 1)")
    parser.add_argument(
        "--pixel-mask",
        type=Path,
        help="with --pixel-sampling centre: render only the pixels where this EXR's R+G+B > 0 (e.g. an\n"
        "earlier render, to spend many samples on the few lit pixels of a dark scene); the rest are 0",
    )
    parser.add_argument("--threads", type=int, help="worker threads (default: all cores)")
    parser.add_argument("--json", type=Path, help="also write the timings and settings as JSON here")
    args = parser.parse_args(argv)
    if args.spp < 1:
        parser.error("--spp must be at least 1")
    for name in ("width", "height"):
        if getattr(args, name) is not None and getattr(args, name) < 1:
            parser.error(f"--{name} must be at least 1")
    if args.integrator == "path":
        if args.emitter_samples is not None or args.bsdf_samples is not None:
            parser.error("--emitter-samples and --bsdf-samples are the direct integrator's (path takes one of each)")
        if args.max_depth is None:
            args.max_depth = -1
        if args.max_depth == 0 or args.max_depth < -1:
            parser.error(f"--max-depth must be -1 (unbounded) or at least 1, got {args.max_depth}")
        if args.rr_depth < 1:
            parser.error(f"--rr-depth must be at least 1, got {args.rr_depth}")
    else:
        if args.max_depth is not None:
            parser.error("--max-depth needs --integrator path (direct is depth 2: direct light only)")
        args.emitter_samples = 1 if args.emitter_samples is None else args.emitter_samples
        args.bsdf_samples = 1 if args.bsdf_samples is None else args.bsdf_samples
        if args.emitter_samples < 0 or args.bsdf_samples < 0 or args.emitter_samples + args.bsdf_samples == 0:
            parser.error("--emitter-samples and --bsdf-samples must be ≥ 0, and not both 0")
    if args.pixel_mask and args.pixel_sampling != "centre":
        parser.error("--pixel-mask needs --pixel-sampling centre")
    if args.output.suffix.lower() != ".exr":
        parser.error(f"--output {args.output} must end in .exr")

    try:
        import mitsuba as mi
    except ImportError:
        print("error: mitsuba is not installed in this Python; see the usage in this script's docstring", file=sys.stderr)
        return 2
    try:
        variant = choose_variant(args.variant, args.pixel_sampling)
        mi.set_variant(variant)
        if args.threads:
            import drjit as dr

            dr.set_thread_count(args.threads)
        t0 = time.perf_counter()
        spec = load_scene(args.scene, args.width, args.height)
        for w in spec.mesh.warnings:
            print(f"warning: {w}", file=sys.stderr)
        if spec.mesh.dropped_degenerate:
            print(f"warning: dropped {spec.mesh.dropped_degenerate} degenerate triangle(s)", file=sys.stderr)
        integrator = integrator_dict(
            args.integrator, args.emitter_samples, args.bsdf_samples, args.max_depth, args.rr_depth
        )
        scene = build_scene(spec, args.spp, args.seed, integrator)
        only = read_mask(args.pixel_mask, spec) if args.pixel_mask else None
        t1 = time.perf_counter()
        if args.pixel_sampling == "centre":
            image = render_centres(scene, spec, args.spp, args.seed, only)
        else:
            import numpy as np

            image = np.asarray(mi.render(scene, spp=args.spp, seed=args.seed))
        t2 = time.perf_counter()
        write_exr(args.output, image, emission_at_centres(scene, spec))
    except SceneError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    timings = {
        "scene": str(args.scene),
        "output": str(args.output),
        "variant": variant,
        "spp": args.spp,
        "seed": args.seed,
        "pixel_sampling": args.pixel_sampling,
        "integrator": integrator,
        "pixel_mask": str(args.pixel_mask) if args.pixel_mask else None,
        "pixels_rendered": int(only.sum()) if only is not None else spec.width * spec.height,
        "width": spec.width,
        "height": spec.height,
        "triangles": sum(len(t) for t in spec.mesh.triangles.values()),
        "load_s": round(t1 - t0, 4),
        "render_s": round(t2 - t1, 4),
        "total_s": round(time.perf_counter() - t0, 4),
    }
    print(
        f"{args.output}: {spec.width}x{spec.height}, {args.spp} spp, {variant}, {describe(integrator)}, "
        f"{args.pixel_sampling} pixels: "
        f"load {timings['load_s']:.3f} s, render {timings['render_s']:.3f} s, total {timings['total_s']:.3f} s"
    )
    if args.json:
        args.json.write_text(json.dumps(timings, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
