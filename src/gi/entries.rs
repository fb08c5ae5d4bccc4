//! From triangles to cache entries. Each triangle is clipped to every grid cell it meets; the pieces of one
//! surface in one cell form that cell's *piece* of the surface, and each side of a piece is an entry,
//! sensed at the point of the piece nearest its area-weighted centroid (on the surface, so that a sensor
//! there sees what the surface sees).
//!
//! **Splits.** A cell is coarser than a wall: the floor of two rooms runs under the wall between them, and a
//! cell across that wall would mix the lit room's floor with the dark one's. So a piece that another
//! surface's triangle cuts (its plane leaves a real share of the piece on both sides: a wall standing on the
//! floor, a box's side, a door above its clearance) is split by that plane, up to [`MAX_SPLITS`] deep, and
//! each part is an entry of its own; a fragment finds its part by the planes' signs (`glsl/cache.glsl`).
//! A wall's two sides are apart already: they are two entries of every piece.
//!
//! **Aliases.** A piece that only grazes its cell (less than [`MIN_AREA`] of a cell's face) and is not
//! split has no sensor of its own: it reads the nearest piece of its surface in a neighbouring cell, if
//! that piece's point can be seen from its own on both sides (so an alias never reaches across a wall), and
//! is sensed itself otherwise. So does every cell that only a coarser level of detail of the mesh reaches
//! (its triangles stray from the surface by up to their error). Cells are clipped with a margin of
//! [`MARGIN`] cells so that rounding at a cell's face cannot put a fragment in a cell without its key.
//!
//! Deterministic: pieces are summed in triangle order, splits chosen in triangle order.

use std::collections::HashMap;

use glam::{UVec3, Vec3, Vec4};
use rayon::prelude::*;

use super::grid::Grid;
use super::polygon::Polygon;
use crate::scene::bvh::Bvh;
use crate::scene::{Aabb, Ray, SurfaceId, Triangle, stratified_point, triangle_area};

/// Below this share of a cell's face, an unsplit piece reads a neighbour's entries.
pub const MIN_AREA: f32 = 0.05;
/// A plane splits a piece only if both sides keep at least this share of a cell's face.
pub const MIN_SPLIT_AREA: f32 = 0.01;
/// Splits per piece at most (a box's corner on the floor takes two; a thin wall's two faces two).
pub const MAX_SPLITS: u32 = 3;
/// Other surfaces' triangles examined for splits per piece (in triangle order): a bound for cells where
/// two detailed meshes meet.
const MAX_CANDIDATES: usize = 64;
/// A piece whose area-weighted normal is shorter than this share of its area is curved at the cell's scale
/// (its normals spread over more than about ±25°): no wall stands on it, it is not split.
pub const FLAT: f32 = 0.9;
/// Cells are clipped this much larger (in cells), so that every cell a fragment may round into has a key.
pub const MARGIN: f32 = 1e-3;
/// A reference to a piece's entries: the pair index, or with this bit a split node's index.
pub const SPLIT: u32 = 1 << 31;
/// Points spread over a piece, stratified by area, at which the light hints say whether its direct light is
/// uniform over it.
pub const SAMPLES_PER_PIECE: usize = 8;
/// Levels of halving a piece whose direct light is not uniform over it, at most: each halves it along its
/// two longest axes, so 2 levels leave parts a quarter of a cell wide.
pub const MAX_LIGHT_LEVELS: u32 = 2;
/// Levels of halving a piece whose points' openness differs ([`OPENNESS_VARIATION`]), at most: a contact's
/// crevice darkens within a few centimetres, and three levels leave parts an eighth of a cell wide (16 cm
/// in the hall).
pub const MAX_OPEN_LEVELS: u32 = 3;

// Every split tree fits the shader's walk: [`MAX_SPLITS`] planes of other surfaces, then two a level.
const _: () = assert!(MAX_SPLITS + 2 * MAX_LIGHT_LEVELS <= crate::gpu_types::CACHE_SPLIT_DEPTH);
const _: () = assert!(MAX_SPLITS + 2 * MAX_OPEN_LEVELS <= crate::gpu_types::CACHE_SPLIT_DEPTH);

/// A piece is halved where the share of the lights' hint points its spread points see differs by more than
/// this (`sensors::hints`): a shadow's edge or a streak of light crossing it. Any difference at all would
/// halve the pieces of every soft penumbra (2.8× the Cornell box's entries for no gain in its error); a
/// half would miss the streak through a door ajar (docs/ACCURACY.md).
pub const LIGHT_VARIATION: f32 = 0.25;

/// A piece is halved too where the lights' unoccluded irradiance at its spread points differs by more than
/// this factor (the pool of light a small lamp throws on the wall beside it): the piece's sensor reads its
/// light at one point. Measured against the path tracer (docs/ACCURACY.md, global illumination): the small
/// light (320 × 240) 1.51 % → 1.24 % (factor 2) → 0.65 % (1.5) over the whole image, own error, for 1.3×
/// and 1.55× the cache's sensors; the Cornell box 1.34 % → 1.18 %.
pub const IRRADIANCE_VARIATION: f32 = 1.5;

/// A piece is halved too where how open its spread points are differs by more than this factor: the share
/// of each one's cosine-weighted hemisphere that no surface closes within half the points' spread
/// ([`openness`]). Where a sphere rests on a pedestal, the piece of its underside around the contact was
/// read at its sensor's point, a hand's width up, twelve times as bright as the crevice that a camera
/// sensor on the pedestal beside the contact sees (the 40 000-triangle hall: 91 % of such a sensor's gather
/// was that one entry, and 20 such pixels 70 % of the whole image's squared error against the path
/// tracer); its lowest point there is about 8× less open than its highest. A floor's piece along a wall
/// opens from about a half to nearly all, under this factor: the wall is lit, and halving every such piece
/// would cost entries for little. Measured against the oracles (docs/ACCURACY.md): on that hall 2× (with
/// four levels), 3× and 6× gave the same error, in 13 % and 0.7 % more entries than 6×; the door ajar at
/// the program's defaults was 8.54 % off (bias −0.3 %) before, 8.72 % (−3.2 %) with 3×, 8.33 % (−2.3 %)
/// with 6×.
pub const OPENNESS_VARIATION: f32 = 6.0;

/// Directions a point's openness is measured along ([`openness`]): the same set at every point, so that
/// points of one piece differ by where they are, not by their rays.
const OPENNESS_RAYS: usize = 16;

/// The share of the cosine-weighted hemisphere above `p` (facing `n`, rays from `p + n·lift`) that no
/// surface closes within `reach`, in steps of 1/[`OPENNESS_RAYS`].
pub fn openness(bvh: &Bvh, (p, n): (Vec3, Vec3), lift: f32, reach: f32) -> f32 {
    let (t, b) = n.any_orthonormal_pair();
    let origin = p + n * lift;
    let open = (0..OPENNESS_RAYS)
        .filter(|&i| {
            let d = cosine_direction(i, OPENNESS_RAYS, 0.0);
            !bvh.occluded(&Ray::new(origin, t * d.x + b * d.y + n * d.z), 0.0, reach)
        })
        .count();
    open as f32 / OPENNESS_RAYS as f32
}

/// Direction `i` of `count` cosine-weighted about +z (Malley: a point of the disc by the golden angle and
/// stratified radius), the disc turned by `turn` of a full turn.
pub fn cosine_direction(i: usize, count: usize, turn: f32) -> Vec3 {
    let u = (i as f32 + 0.5) / count as f32;
    let phi = std::f32::consts::TAU * (i as f32 * 0.618_034 + turn).fract();
    let r = u.sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt())
}

/// Rays that tell whether a point is buried ([`Burial`]), cosine-weighted about its side's normal.
const BURIAL_RAYS: usize = 16;
/// A sensor's point stays where at most this share of those rays meets a triangle from behind or too near
/// (a plinth's open ring sees a quarter of them so, a point at a shaft's foot a third to a half).
const CLEAR: f32 = 0.125;

/// Where a piece's sensors may not sit: inside a closed shape that stands on it. A fluted shaft on its
/// plinth is a ring of corrugations, and corrugations split no piece ([`crate::gi::shape`]): the plinth's
/// top was one piece (halved where its openness varies), and the sensors of its parts inside the shaft saw
/// only the shaft's inner walls. The walk over what sensors see ([`crate::gi::reach`]) then reached every
/// flank's inner side: 5 200 of the 40 000-triangle hall's 18 500 cache sensors sensed the inside of its
/// columns.
///
/// A point is open on a side when fewer than half of [`BURIAL_RAYS`] rays from it meet a triangle from
/// behind (a closed shape's inside) or nearer than the sensors' near plane. On a side
/// where some of a piece's spread points are open, a part's sensor moves from a point that is not to its
/// openest spread point, and a part with no open point there is buried: not sensed (its side is seen from
/// nowhere but through a sliver its points miss, which reads it dark). Where no point of the piece is open on
/// a side (a room modelled inside out sees its walls from behind everywhere), nothing changes.
struct Burial<'a> {
    bvh: &'a Bvh,
    triangles: &'a [Triangle],
    /// The sensors' lift and near plane: a surface nearer than that is not in their maps, and what lies
    /// behind it is (a point at a shaft's foot sees into the shaft), so a ray that meets one counts as
    /// meeting a triangle from behind.
    offsets: (f32, f32),
}

/// Where one side of a part senses ([`Burial::sensor`]).
enum Sensor {
    At(Vec3),
    Buried,
}

impl Burial<'_> {
    /// The share of rays from `p` (its side's normal `n`) that meet a triangle from behind or too near.
    fn behind(&self, p: Vec3, n: Vec3) -> f32 {
        let (t, b) = n.any_orthonormal_pair();
        let (lift, near) = self.offsets;
        let origin = p + n * lift;
        let behind = (0..BURIAL_RAYS)
            .filter(|&i| {
                let d = cosine_direction(i, BURIAL_RAYS, 0.0);
                let d = t * d.x + b * d.y + n * d.z;
                self.bvh
                    .intersect(&Ray::new(origin, d), 0.0, f32::MAX)
                    .is_some_and(|h| h.t < near || self.triangles[h.triangle as usize].normal.dot(d) > 0.0)
            })
            .count();
        behind as f32 / BURIAL_RAYS as f32
    }

    /// Whether some of a piece's `spread` points (each with its front normal) are open on its back's and on
    /// its front's side (`normal`: its mean front normal).
    fn open_sides(&self, spread: &[(Vec3, Vec3)], normal: Vec3) -> [bool; 2] {
        [-normal, normal].map(|n| spread.iter().any(|&(p, m)| self.behind(p, facing(m, n)) < 0.5))
    }

    /// Whether neither `point` nor any of `spread` (with its front normal) is open on side `n`.
    fn inside(&self, point: Vec3, n: Vec3, spread: &[(Vec3, Vec3)]) -> bool {
        self.behind(point, n) >= 0.5 && spread.iter().all(|&(p, m)| self.behind(p, facing(m, n)) >= 0.5)
    }

    /// Where the sensor of a part's side `n` (its mean normal on that side) sits: at `point` where that is
    /// [`CLEAR`], else at the openest point of `spread` where that is more open, and open; none where no
    /// point is open.
    fn sensor(&self, point: Vec3, n: Vec3, spread: &[(Vec3, Vec3)], centroid: Vec3) -> Sensor {
        let own = self.behind(point, n);
        if own <= CLEAR {
            return Sensor::At(point);
        }
        // The openest point (one at the shape's foot sees into it), the nearest the centroid of those.
        let behind = spread.iter().map(|&(p, m)| (p, self.behind(p, facing(m, n))));
        let key = |&(p, b): &(Vec3, f32)| (b, p.distance_squared(centroid));
        let openest = behind.min_by(|x, y| key(x).partial_cmp(&key(y)).unwrap()).filter(|&(_, b)| b < own.min(0.5));
        match openest {
            Some((p, _)) => Sensor::At(p),
            None if own < 0.5 => Sensor::At(point),
            None => Sensor::Buried,
        }
    }
}

/// Front normal `m` turned to the side `n` faces.
fn facing(m: Vec3, n: Vec3) -> Vec3 {
    if m.dot(n) >= 0.0 { m } else { -m }
}

/// Whether the [`openness`] of `points` on one side (`side` 1: the one their front `normals` face, a curved
/// piece's own at each point; −1 the back) differs by more than [`OPENNESS_VARIATION`], each within half
/// the points' spread; a step of the measure is added to both ends, so that a closed point beside one open
/// ray does not count as a ratio without bound.
pub fn openness_varies(bvh: &Bvh, (points, normals): (&[Vec3], &[Vec3]), side: f32, lift: f32) -> bool {
    let reach = 0.5 * Aabb::of(points.iter().copied()).diagonal();
    if reach <= lift {
        return false;
    }
    let open = points.iter().zip(normals).map(|(&p, &n)| openness(bvh, (p, n * side), lift, reach));
    let (lo, hi) = open.fold((f32::MAX, 0.0f32), |(lo, hi), o| (lo.min(o), hi.max(o)));
    let step = 1.0 / OPENNESS_RAYS as f32;
    hi + step > OPENNESS_VARIATION * (lo + step)
}

/// Whether the light varies over these points of a piece (each with the front normal of the triangle it
/// lies on) whose mean front normal is this, on either side (the renderer's light hints, which points on
/// the lights each sees: [`LIGHT_VARIATION`]; the lights' unoccluded irradiance: [`IRRADIANCE_VARIATION`];
/// how open each point is: [`OPENNESS_VARIATION`]): where it does, a piece is halved.
pub type LightVaries<'a> = &'a (dyn Fn(&[Vec3], &[Vec3], Vec3) -> Variation + Sync);

/// What varies over a piece's points ([`LightVaries`]): each may halve it, to its own depth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Variation {
    /// The direct light (halved [`MAX_LIGHT_LEVELS`] deep, then its direct light spread over it).
    pub direct: bool,
    /// How open the points are (halved [`MAX_OPEN_LEVELS`] deep).
    pub openness: bool,
}

/// One side of one piece of surface: where its sensor sits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    pub point: Vec3,
    /// Unit normal of this side.
    pub normal: Vec3,
    pub surface: SurfaceId,
    /// The triangles' counter-clockwise side.
    pub front: bool,
    /// Area of the piece: its weight in averages.
    pub area: f32,
}

/// A piece cut in two by a plane: a fragment at `p` goes to `children[(plane · (p, 1) ≥ 0) as usize]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    pub plane: Vec4,
    /// References ([`SPLIT`] | node, or a pair of entries).
    pub children: [u32; 2],
}

/// The grid's pieces: each (cell, surface) key with the reference its fragments start from, the split
/// nodes, and the entries (pair `k`: entries `2k`, the back, and `2k + 1`, the front).
pub struct Pieces {
    /// Sorted by (packed cell, surface).
    pub keys: Vec<((u32, SurfaceId), u32)>,
    pub splits: Vec<Split>,
    pub entries: Vec<Entry>,
    /// Of the splits, those that halve a piece where its direct light varies.
    pub light_splits: usize,
    /// Entry pairs whose direct light is the mean over the points spread over their piece ([`Pieces::points`]):
    /// it varies over it and it can be halved no more.
    pub spread: Vec<u32>,
    /// Per entry pair, points spread over its piece (stratified by area, off its edges), with the front
    /// normals of the triangles they lie on.
    pub points: Vec<[(Vec3, Vec3); SAMPLES_PER_PIECE]>,
    /// Entries whose side of their piece lies inside a closed shape ([`Burial`]): seen from nowhere, never
    /// sensed. Increasing.
    pub buried: Vec<u32>,
}

/// The packed cell of a key's first word.
pub fn pack(c: UVec3) -> u32 {
    c.x | c.y << 10 | c.z << 20
}

fn unpack(c: u32) -> UVec3 {
    UVec3::new(c & 1023, (c >> 10) & 1023, c >> 20)
}

/// A triangle's piece of one cell.
#[derive(Clone, Copy)]
struct Clip {
    cell: u32,
    surface: SurfaceId,
    triangle: u32,
}

/// A piece's entries before they are numbered: a leaf, or a split of two (by a wall's plane, or, `lit`, a
/// halving where the direct light varies).
enum Tree {
    Leaf(Leaf),
    Split { plane: Vec4, children: Box<[Tree; 2]>, lit: bool },
}

/// What a leaf's entry pair needs.
#[derive(Clone)]
struct Leaf {
    area: f32,
    centroid: Vec3,
    /// Where its sensors sit: the back's, the front's (the point nearest the centroid, unless buried).
    point: [Vec3; 2],
    normal: Vec3,
    /// Points spread over it, with the front normals of the triangles they lie on: where its light varies,
    /// their mean stands for the piece.
    points: Box<[(Vec3, Vec3); SAMPLES_PER_PIECE]>,
    /// Whether its direct light still varies over it when it can be halved no more: the mean at `points`
    /// is its direct light.
    spread: bool,
    /// Whether its back's and its front's side lie inside a closed shape ([`Burial`]).
    buried: [bool; 2],
}

/// Every cell of `grid` within the margin of triangle `v`, with the triangle's piece of it.
fn cells_of(grid: &Grid, v: &[Vec3; 3]) -> impl Iterator<Item = (UVec3, Polygon)> {
    let margin = Vec3::splat(MARGIN * grid.cell);
    let b = Aabb::of(v.iter().copied());
    let (lo, hi) = (grid.cell_of(b.min - margin), grid.cell_of(b.max + margin));
    let (grid, v) = (*grid, *v);
    (lo.z..=hi.z).flat_map(move |z| {
        (lo.y..=hi.y).flat_map(move |y| {
            (lo.x..=hi.x).filter_map(move |x| {
                let c = UVec3::new(x, y, z);
                let polygon = Polygon::triangle(&v).in_cell(&grid, c);
                (polygon.len >= 3).then_some((c, polygon))
            })
        })
    })
}

/// Builds the pieces of the mesh's `triangles` on `grid`; `lod`: triangles of coarser levels of detail,
/// which add aliases only; `light`: where the direct light varies (pieces are halved there); `corrugated`:
/// per surface id, whether it is a corrugation of a larger shape (`gi::shape`: its pieces are neither split
/// nor halved, and its planes split no other piece); `offsets`: the sensors' lift and near plane
/// (`sensors::frame::offsets`), for where they may sit ([`Burial`]).
pub fn build(
    grid: &Grid,
    triangles: &[Triangle],
    lod: &[([Vec3; 3], SurfaceId)],
    (light, corrugated): (Option<LightVaries<'_>>, &[bool]),
    offsets: (f32, f32),
) -> Pieces {
    let mut clips: Vec<Clip> = triangles
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, tri)| {
            cells_of(grid, &tri.v).map(move |(c, _)| Clip { cell: pack(c), surface: tri.surface, triangle: t as u32 })
        })
        .collect();
    // Stable: within a key, triangle order, so that sums are the same on every run.
    clips.sort_by_key(|c| (c.cell, c.surface));
    let runs: Vec<&[Clip]> = clips.chunk_by(|a, b| (a.cell, a.surface) == (b.cell, b.surface)).collect();
    // The runs of one cell are adjacent: each run's range of them, whose other surfaces may split it.
    let mut cell_runs: Vec<(usize, usize)> = Vec::with_capacity(runs.len());
    for group in runs.chunk_by(|a, b| a[0].cell == b[0].cell) {
        let start = cell_runs.len();
        cell_runs.extend(std::iter::repeat_n((start, start + group.len()), group.len()));
    }

    let face = grid.cell * grid.cell;
    let bvh = Bvh::build(triangles);
    let burial = Burial { bvh: &bvh, triangles, offsets };
    let trees: Vec<Tree> = runs
        .par_iter()
        .enumerate()
        .map(|(i, run)| {
            let cell = unpack(run[0].cell);
            let polygons: Vec<(Polygon, Vec3)> = run
                .iter()
                .map(|c| {
                    let t = &triangles[c.triangle as usize];
                    (Polygon::triangle(&t.v).in_cell(grid, cell), t.normal)
                })
                .collect();
            let surface_normal = polygons.iter().map(|(p, n)| *n * p.area_centroid().0).sum::<Vec3>();
            let area: f32 = polygons.iter().map(|(p, _)| p.area_centroid().0).sum();
            // No wall stands on a corrugation's piece (the planes of its neighbouring facets cut it into up
            // to eight parts for no better light) or on a piece curved at the cell's scale (a sphere's);
            // both are halved where their light varies (a capital's shadow on a column's top, a sphere's
            // lit top and dark underside).
            let cell_runs = &runs[cell_runs[i].0..cell_runs[i].1];
            let candidates = if surface_normal.length() < FLAT * area || corrugated[run[0].surface as usize] {
                Vec::new()
            } else {
                split_planes(grid, triangles, cell_runs, (run[0].surface, surface_normal), corrugated)
            };
            // A corrugation's side may lie inside its closed shape; a shape whose sides are corrugations
            // stands on a piece of its cell without splitting it.
            let rule = if corrugated[run[0].surface as usize] {
                Some(Rule::Inside)
            } else {
                let enclosed =
                    (cell_runs.iter()).any(|r| r[0].surface != run[0].surface && corrugated[r[0].surface as usize]);
                enclosed.then_some(Rule::Foot([false; 2]))
            };
            let parts = Parts { min: MIN_SPLIT_AREA * face, light, burial: rule.map(|rule| (&burial, rule)) };
            split(polygons, &candidates, MAX_SPLITS, parts)
        })
        .collect();

    // Number the entries and splits; note which unsplit pieces are small enough to alias a neighbour.
    let mut pieces = Pieces {
        keys: Vec::with_capacity(runs.len()),
        splits: Vec::new(),
        entries: Vec::new(),
        light_splits: 0,
        spread: Vec::new(),
        points: Vec::new(),
        buried: Vec::new(),
    };
    let mut own: HashMap<(u32, SurfaceId), (u32, Vec3, Vec3)> = HashMap::new();
    let mut small = Vec::new();
    let mut references = vec![u32::MAX; runs.len()];
    for (i, tree) in trees.iter().enumerate() {
        let key = (runs[i][0].cell, runs[i][0].surface);
        match tree {
            Tree::Leaf(leaf) if leaf.area < MIN_AREA * face => small.push(i),
            _ => {
                references[i] = pieces.number(tree, key.1);
                if let Tree::Leaf(leaf) = tree {
                    own.insert(key, (references[i], leaf.point[1], leaf.normal));
                }
            }
        }
    }
    let clear = |from: Vec3, n: Vec3, to: Vec3, n_to: Vec3| visible(&bvh, grid, from, n, to, n_to);
    let nearest = |own: &HashMap<(u32, SurfaceId), (u32, Vec3, Vec3)>, key: (u32, SurfaceId), from: Vec3, n: Vec3| {
        let mut found: Vec<(f32, u32, Vec3, Vec3)> = neighbours(grid, unpack(key.0))
            .filter_map(|c| own.get(&(pack(c), key.1)).map(|&(r, p, m)| (p.distance_squared(from), r, p, m)))
            .collect();
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        found.into_iter().find(|&(_, _, p, m)| clear(from, n, p, m)).map(|(_, r, _, _)| r)
    };
    for &i in &small {
        let key = (runs[i][0].cell, runs[i][0].surface);
        let Tree::Leaf(leaf) = &trees[i] else { unreachable!("small pieces are unsplit") };
        references[i] = match nearest(&own, key, leaf.centroid, leaf.normal) {
            Some(r) => r,
            None => pieces.number(&trees[i], key.1),
        };
    }
    pieces.keys.extend(runs.iter().zip(&references).map(|(run, &r)| ((run[0].cell, run[0].surface), r)));

    // Cells only a coarser level reaches read the nearest piece of their surface around them.
    let known: std::collections::HashSet<(u32, SurfaceId)> = pieces.keys.iter().map(|(k, _)| *k).collect();
    let mut extra: Vec<((u32, SurfaceId), Vec3, Vec3)> = lod
        .par_iter()
        .flat_map_iter(|(v, surface)| {
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            cells_of(grid, v).map(move |(c, polygon)| ((pack(c), *surface), polygon.area_centroid().1, n))
        })
        .filter(|(k, _, _)| !known.contains(k))
        .collect();
    extra.sort_by_key(|(k, _, _)| *k);
    extra.dedup_by_key(|(k, _, _)| *k);
    for (key, from, n) in extra {
        if let Some(r) = nearest(&own, key, from, n) {
            pieces.keys.push((key, r));
        }
    }
    pieces.keys.sort_by_key(|(k, _)| *k);
    pieces
}

impl Pieces {
    /// Numbers `tree`'s entries and splits (of `surface`); returns the reference its fragments start from.
    fn number(&mut self, tree: &Tree, surface: SurfaceId) -> u32 {
        match tree {
            Tree::Leaf(l) => {
                let pair = (self.entries.len() / 2) as u32;
                let ([back, front], area) = (l.point, l.area);
                self.entries.push(Entry { point: back, normal: -l.normal, surface, front: false, area });
                self.entries.push(Entry { point: front, normal: l.normal, surface, front: true, area });
                self.points.push(*l.points);
                if l.spread {
                    self.spread.push(pair);
                }
                self.buried.extend((0..2).filter(|&side| l.buried[side]).map(|side| 2 * pair + side as u32));
                pair
            }
            Tree::Split { plane, children, lit } => {
                let node = self.splits.len();
                self.light_splits += *lit as usize;
                self.splits.push(Split { plane: *plane, children: [0; 2] });
                let children = [self.number(&children[0], surface), self.number(&children[1], surface)];
                self.splits[node].children = children;
                SPLIT | node as u32
            }
        }
    }
}

/// Planes of other surfaces' triangles in this cell (`cell`: its runs) that may split `surface`'s piece,
/// whose area-weighted normal is `normal`: not parallel to it, not of a corrugation, each once.
fn split_planes(
    grid: &Grid,
    triangles: &[Triangle],
    cell: &[&[Clip]],
    (surface, normal): (SurfaceId, Vec3),
    corrugated: &[bool],
) -> Vec<Vec4> {
    let n = normal.normalize_or_zero();
    let mut planes: Vec<Vec4> = Vec::new();
    let others = (cell.iter())
        .filter(|run| run[0].surface != surface && !corrugated[run[0].surface as usize])
        .flat_map(|run| run.iter());
    for clip in others.take(MAX_CANDIDATES) {
        let t = &triangles[clip.triangle as usize];
        if t.normal.dot(n).abs() > 0.999 {
            continue; // parallel: it cannot cut the piece (a shelf above the floor)
        }
        let plane = t.normal.extend(-t.normal.dot(t.v[0]));
        let same = |q: &Vec4| q.truncate().dot(plane.truncate()) > 0.9999 && (q.w - plane.w).abs() < 1e-4 * grid.cell;
        if !planes.iter().any(same) {
            planes.push(plane);
        }
    }
    planes
}

/// `polygons` (each with its triangle's normal) split by the first of `planes` that leaves at least `min`
/// of area on both sides, then each side by the rest, `depth` levels at most; each part then [`lit`].
fn split(polygons: Vec<(Polygon, Vec3)>, planes: &[Vec4], depth: u32, parts: Parts<'_>) -> Tree {
    if depth > 0 {
        for (k, plane) in planes.iter().enumerate() {
            let mut sides: [Vec<(Polygon, Vec3)>; 2] = [Vec::new(), Vec::new()];
            for (p, n) in &polygons {
                for (side, part) in p.split(*plane).into_iter().enumerate() {
                    if part.len >= 3 {
                        sides[side].push((part, *n));
                    }
                }
            }
            let area = |s: &[(Polygon, Vec3)]| s.iter().map(|(p, _)| p.area_centroid().0).sum::<f32>();
            if area(&sides[0]) >= parts.min && area(&sides[1]) >= parts.min {
                let rest = &planes[k + 1..];
                let [below, above] = sides;
                let children = [split(below, rest, depth - 1, parts), split(above, rest, depth - 1, parts)];
                return Tree::Split { plane: *plane, children: Box::new(children), lit: false };
            }
        }
    }
    lit(polygons, parts, 0)
}

/// How a piece is cut into the parts that hold entries, besides the planes that split it.
#[derive(Clone, Copy)]
struct Parts<'a> {
    /// The least area a part keeps.
    min: f32,
    /// Where the direct light varies: parts are halved there.
    light: Option<LightVaries<'a>>,
    /// Where a closed shape may stand on the piece: its sensors keep out of it, on the sides (back, front)
    /// where some of the piece is open.
    burial: Option<(&'a Burial<'a>, Rule)>,
}

/// How [`Burial`] keeps a piece's sensors out of closed shapes.
#[derive(Clone, Copy)]
enum Rule {
    /// A corrugation: a side of it is buried where none of its points is open (a column's inside, whose
    /// rays near its ends meet the plinth's top and the capital's bottom from their fronts).
    Inside,
    /// A piece a shape may stand on: its sensors move to open points on the sides (back, front) where some
    /// of the piece is open ([`Burial::sensor`]).
    Foot([bool; 2]),
}

/// A leaf's area, centroid, sensor points (its point nearest the centroid, unless `burial` finds it buried
/// on that side) and area-weighted normal.
fn leaf(
    polygons: &[(Polygon, Vec3)],
    points: Box<[(Vec3, Vec3); SAMPLES_PER_PIECE]>,
    burial: Option<(&Burial<'_>, Rule)>,
) -> Leaf {
    let (mut area, mut weighted, mut normal) = (0.0, Vec3::ZERO, Vec3::ZERO);
    for (p, n) in polygons {
        let (a, c) = p.area_centroid();
        area += a;
        weighted += c * a;
        normal += *n * a.max(f32::MIN_POSITIVE);
    }
    let centroid = if area > 0.0 {
        weighted / area
    } else {
        polygons.iter().map(|(p, _)| p.area_centroid().1).sum::<Vec3>() / polygons.len() as f32
    };
    let point = polygons
        .iter()
        .map(|(p, _)| p.closest(centroid))
        .min_by(|a, b| a.distance_squared(centroid).total_cmp(&b.distance_squared(centroid)))
        .unwrap_or(centroid);
    let normal = normal.try_normalize().unwrap_or(polygons[0].1);
    let sides = [-normal, normal].map(|n| match burial {
        Some((burial, Rule::Foot(open))) if open[(n == normal) as usize] => {
            burial.sensor(point, n, &points[..], centroid)
        }
        Some((burial, Rule::Inside)) if burial.inside(point, n, &points[..]) => Sensor::Buried,
        _ => Sensor::At(point),
    });
    let buried = sides.each_ref().map(|s| matches!(s, Sensor::Buried));
    let point = sides.map(|s| match s {
        Sensor::At(p) => p,
        Sensor::Buried => point,
    });
    Leaf { area, centroid, point, normal, points, spread: false, buried }
}

/// A leaf, halved along its two longest axes (the second where it is at least half the first) where `light`
/// says its light varies over it, while that variation's levels ([`Variation`]) go deeper than `depth`, the
/// halvings made so far.
fn lit(polygons: Vec<(Polygon, Vec3)>, mut parts: Parts<'_>, depth: u32) -> Tree {
    let (points, normals) = spread(&polygons);
    let spread_points: Box<[(Vec3, Vec3); SAMPLES_PER_PIECE]> =
        Box::new(std::array::from_fn(|k| (points[k], normals[k])));
    if let (0, Some((burial, Rule::Foot(_)))) = (depth, parts.burial) {
        // The whole piece: the sides on which some of it is open, that its parts keep their sensors to.
        let normal = normals.iter().sum::<Vec3>().try_normalize().unwrap_or(normals[0]);
        parts.burial = Some((burial, Rule::Foot(burial.open_sides(&spread_points[..], normal))));
    }
    let mut whole = leaf(&polygons, spread_points, parts.burial);
    let Some(varies) = parts.light else { return Tree::Leaf(whole) };
    let variation = varies(&points, &normals, whole.normal);
    let halved = (variation.direct && depth < MAX_LIGHT_LEVELS) || (variation.openness && depth < MAX_OPEN_LEVELS);
    if !halved || whole.area < 4.0 * parts.min {
        whole.spread = variation.direct;
        return Tree::Leaf(whole);
    }
    let b = Aabb::of(polygons.iter().flat_map(|(p, _)| p.v[..p.len].iter().copied()));
    let extent = b.max - b.min;
    let mut axes = [0, 1, 2];
    axes.sort_by(|&a, &c| extent[c].total_cmp(&extent[a]));
    // The second axis only where it is at least half as long as the first: a strip (a column's flute) is
    // halved along its length, not across its few centimetres.
    let planes: Vec<Vec4> = axes[..2]
        .iter()
        .filter(|&&a| extent[a] > 0.0 && extent[a] >= 0.5 * extent[axes[0]])
        .map(|&a| {
            let mut plane = Vec4::ZERO;
            plane[a] = 1.0;
            plane.w = -b.center()[a];
            plane
        })
        .collect();
    halve(polygons, &planes, parts, depth)
}

/// `polygons` split by each of `planes` in turn, then each part [`lit`] one level down.
fn halve(polygons: Vec<(Polygon, Vec3)>, planes: &[Vec4], parts: Parts<'_>, depth: u32) -> Tree {
    let Some((plane, rest)) = planes.split_first() else { return lit(polygons, parts, depth + 1) };
    let mut sides: [Vec<(Polygon, Vec3)>; 2] = [Vec::new(), Vec::new()];
    for (p, n) in &polygons {
        for (side, part) in p.split(*plane).into_iter().enumerate() {
            if part.len >= 3 {
                sides[side].push((part, *n));
            }
        }
    }
    if sides.iter().any(|s| s.is_empty()) {
        return halve(polygons, rest, parts, depth);
    }
    let [below, above] = sides;
    let children = [halve(below, rest, parts, depth), halve(above, rest, parts, depth)];
    Tree::Split { plane: *plane, children: Box::new(children), lit: true }
}

/// [`SAMPLES_PER_PIECE`] points over `polygons`, stratified by area over their fan triangles
/// (`scene::stratified_point`, as the lights' hint points), each moved a twentieth of the way to its
/// triangle's centre: never on the piece's edge, where a wall that split it stands (a sensor there would see
/// both sides); and the front normal of the polygon each lies on. Deterministic.
fn spread(polygons: &[(Polygon, Vec3)]) -> ([Vec3; SAMPLES_PER_PIECE], [Vec3; SAMPLES_PER_PIECE]) {
    let fans: Vec<([Vec3; 3], Vec3)> = polygons
        .iter()
        .flat_map(|(p, n)| (1..p.len.saturating_sub(1)).map(move |i| ([p.v[0], p.v[i], p.v[i + 1]], *n)))
        .collect();
    let areas: Vec<f32> = fans.iter().map(|(t, _)| triangle_area(t)).collect();
    let total: f32 = areas.iter().sum();
    let fallback = (polygons[0].0.v[0], polygons[0].1);
    let spread: [(Vec3, Vec3); SAMPLES_PER_PIECE] = std::array::from_fn(|k| {
        if total <= 0.0 || fans.is_empty() {
            return fallback;
        }
        let (i, u, v) = stratified_point(&areas, total, k, SAMPLES_PER_PIECE);
        let (t, n) = &fans[i];
        let p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
        (p.lerp((t[0] + t[1] + t[2]) / 3.0, 0.05), *n)
    });
    (spread.map(|(p, _)| p), spread.map(|(_, n)| n))
}

/// Whether `to` (on a surface of normal `n_to`) can be seen from `from` (normal `n`) on both sides: the
/// segments between the points lifted a little along their normals, and along their opposites.
fn visible(bvh: &Bvh, grid: &Grid, from: Vec3, n: Vec3, to: Vec3, n_to: Vec3) -> bool {
    let lift = 1e-3 * grid.cell;
    [1.0, -1.0].iter().all(|&side| {
        let (a, b) = (from + n * (side * lift), to + n_to * (side * lift));
        let d = b - a;
        let length = d.length();
        length <= lift || !bvh.occluded(&Ray::new(a, d / length), 0.0, length * (1.0 - 1e-4))
    })
}

/// The 3³ cells around `c` (itself included) inside the grid.
fn neighbours(grid: &Grid, c: UVec3) -> impl Iterator<Item = UVec3> {
    let dims = grid.dims.as_ivec3();
    let c = c.as_ivec3();
    (-1..=1).flat_map(move |z| {
        (-1..=1).flat_map(move |y| {
            (-1..=1).filter_map(move |x| {
                let n = c + glam::IVec3::new(x, y, z);
                (n.cmpge(glam::IVec3::ZERO).all() && n.cmplt(dims).all()).then(|| n.as_uvec3())
            })
        })
    })
}
