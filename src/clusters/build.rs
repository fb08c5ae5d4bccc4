//! Building the hierarchy with meshoptimizer's `clusterlod`: split a piece of the mesh into clusters,
//! partition them into groups, simplify each group with its border locked, split the result again, and
//! repeat until a level no longer simplifies. Regular (not sloppy, not permissive) simplification only, so
//! that a closed surface stays closed at every level: sloppy simplification where the regular one got
//! stuck opened the 40 000-triangle hall's walls at a distance, and its cache came out 1 % too dark.
//!
//! The pieces are the mesh's connected parts (surfaces that share an edge; emitters apart), not its
//! surfaces: a surface ends at a 30° crease, and a fluted column is two surfaces per flute, each a strip
//! whose locked border kept it at 130 triangles however far away it was seen (58 000 triangles a sensor in
//! a hall of columns). Within a part, each surface keeps its own vertices (welded within the surface): the
//! full detail is the mesh, every triangle with its own surface.
//!
//! What is simplified is a part welded across surfaces that look alike (`weld.rs`), so a column's
//! flutes fold into a plain shaft at coarser levels. Where the looks differ meshoptimizer sees a seam: it
//! may shorten it, moving both sides' vertices alike, but never opens it. A part of one cluster keeps its
//! surfaces apart (a box's faces).
//!
//! Where `clod_build` ends, its last clusters' error is measured against the full detail (it adds up each
//! level's), and simpler levels follow with their open borders kept (`Base::End`).
//!
//! A part of one cluster, which `clusterlod` leaves as it is, gets simpler levels of its own
//! (`Part::push_levels`). A part as a whole vanishes where it projects under a view's accepted error
//! (`Part::vanish_when_small`).

use glam::Vec3;
use meshopt::{ClodMesh, SimplifyOptions, VertexDataAdapter, clod_build, clod_default_config, typed_to_bytes};
use rayon::prelude::*;

use super::closed::{PartShape, hiding_boxes};
use super::weld::{Look, PartTriangle, Welded};
use super::{Cluster, ClusterMesh, ErrorBounds, join, root, slab, sphere};
use crate::scene::surfaces::{FxBuild, weld};
use crate::scene::{Aabb, Mesh, closest_on_triangle};

/// Bumped whenever the output of [`build`] changes: cached hierarchies of another version are rebuilt.
pub const BUILD_VERSION: u32 = 10;
/// Triangles per cluster at most (and vertices: meshoptimizer's default for rasterisation).
pub const MAX_TRIANGLES: usize = 128;
/// A part's levels beyond `clod_build`'s have at most this fraction of the previous level's triangles
/// (1 / ratio): by halves, a view at any distance finds a level near its accepted error.
const LEVEL_RATIO: usize = 2;
/// Pairs of (full-detail triangle, level triangle) at most whose distances measure a simpler level's error.
const MEASURED_PAIRS: usize = 1 << 24;

/// What [`Part::simpler_levels`] simplifies.
#[derive(Clone, Copy)]
enum Base<'a> {
    /// A small part's full detail (welded corners), its open borders free: a leaf simplifies too.
    FullDetail(&'a [u32]),
    /// Where `clod_build` ended (welded corners), and its error. Open borders stay: without, a column's
    /// shaft (an open tube) shrank level by level to a sheet, 10–40 % of its area gone at errors under half
    /// a texel, and the hall's cache came out 2 % darker.
    End { indices: &'a [u32], error: f32 },
}

/// Clusters of one connected part of the mesh, indices local to its own vertices.
struct Part {
    /// Its first surface: what its clusters carry as [`Cluster::surface`].
    surface: u32,
    positions: Vec<[f32; 3]>,
    /// The surface of each of its vertices.
    vertex_surface: Vec<u32>,
    indices: Vec<u32>,
    clusters: Vec<Cluster>,
}

/// The cluster hierarchy of `mesh`: each connected part of it apart (every emitting surface alone), at full
/// detail only where it is an emitter or fits one cluster.
pub fn build(mesh: &Mesh) -> ClusterMesh {
    let mut by_surface: Vec<Vec<usize>> = vec![Vec::new(); mesh.surfaces.len() + 1];
    for (i, t) in mesh.triangles.iter().enumerate() {
        by_surface[t.surface as usize].push(i);
    }
    let look: Vec<Look> = std::iter::once((usize::MAX, [0; 3]))
        .chain(mesh.surfaces.iter().zip(&mesh.texture_mean).map(|(s, m)| (s.material, m.to_array().map(f32::to_bits))))
        .collect();
    let connected = connected_parts(mesh);
    // Where each part hides its back faces from (`closed`): closed, or capped by closed parts.
    let shapes: Vec<PartShape> = connected
        .par_iter()
        .map(|surfaces| PartShape {
            triangles: surfaces
                .iter()
                .flat_map(|&s| by_surface[s as usize].iter().map(|&i| mesh.triangles[i].v))
                .collect(),
            cut: surfaces.iter().any(|&s| mesh.material_of(s).cutout.is_some()),
        })
        .collect();
    let hiding = hiding_boxes(&shapes);
    drop(shapes);
    let parts: Vec<Part> = (connected.par_iter().zip(&hiding))
        .map(|(surfaces, hiding)| {
            let triangles: Vec<PartTriangle> = surfaces
                .iter()
                .flat_map(|&s| by_surface[s as usize].iter().map(move |&i| (&mesh.triangles[i].v, s, mesh.uvs.get(i))))
                .collect();
            let emitter = mesh.material_of(surfaces[0]).is_emitter();
            let lod = match triangles.len() {
                _ if emitter => PartLod::FullOnly,
                n if n > MAX_TRIANGLES => PartLod::Hierarchy,
                _ => PartLod::Levels,
            };
            let mut part = part_clusters(&triangles, surfaces[0], lod, &look);
            if !emitter {
                part.vanish_when_small();
            }
            if let Some(b) = hiding {
                for c in &mut part.clusters {
                    (c.closed, c.part_min, c.part_max) = (1, b.min.into(), b.max.into());
                }
            }
            part
        })
        .collect();
    let mut out = ClusterMesh::default();
    for part in parts {
        let (base_vertex, base_index) = (out.positions.len() as u32, out.indices.len() as u32);
        out.vertex_surface.extend(part.vertex_surface);
        out.positions.extend(part.positions);
        out.indices.extend(part.indices.iter().map(|&v| v + base_vertex));
        out.clusters
            .extend(part.clusters.into_iter().map(|c| Cluster { first_index: c.first_index + base_index, ..c }));
    }
    out
}

/// The mesh's surfaces in connected parts: surfaces that share an edge (welded positions) are one part,
/// but an emitting surface is a part of its own. Each part's surfaces increasing, parts by their first.
fn connected_parts(mesh: &Mesh) -> Vec<Vec<u32>> {
    let surfaces = mesh.surfaces.len();
    let mut parent: Vec<u32> = (0..=surfaces as u32).collect();
    let emitter = |s: u32| mesh.material_of(s).is_emitter();
    let corners = weld(mesh.triangles.iter().map(|t| &t.v));
    let mut edges: std::collections::HashMap<(u32, u32), u32, FxBuild> = Default::default();
    for (t, c) in mesh.triangles.iter().zip(corners.chunks_exact(3)) {
        if emitter(t.surface) {
            continue;
        }
        for k in 0..3 {
            let edge = (c[k].min(c[(k + 1) % 3]), c[k].max(c[(k + 1) % 3]));
            let other = *edges.entry(edge).or_insert(t.surface);
            join(&mut parent, other, t.surface);
        }
    }
    let mut parts: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for s in 1..=surfaces as u32 {
        let r = root(&mut parent, s);
        parts.entry(r).or_default().push(s);
    }
    parts.into_values().collect()
}

/// How a part is drawn from afar.
#[derive(Clone, Copy, PartialEq, Eq)]
enum PartLod {
    /// At full detail only (an emitter: its light is sensed as it is).
    FullOnly,
    /// As one cluster at successively simpler levels (a part of at most [`MAX_TRIANGLES`] triangles).
    Levels,
    /// Through meshoptimizer's cluster hierarchy.
    Hierarchy,
}

/// The clusters of one part's `triangles`, carrying `surface`; `look` is each surface's [`Look`].
fn part_clusters(triangles: &[PartTriangle], surface: u32, lod: PartLod, look: &[Look]) -> Part {
    // Vertices welded within each surface, numbered part-wide.
    let mut ids: std::collections::HashMap<(u32, [u32; 3]), u32, FxBuild> = Default::default();
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut vertex_surface: Vec<u32> = Vec::new();
    let mut corners: Vec<u32> = Vec::with_capacity(3 * triangles.len());
    for &(v, s, _) in triangles {
        for p in v {
            let key = (s, p.to_array().map(|x| (x + 0.0).to_bits()));
            let id = *ids.entry(key).or_insert_with(|| {
                positions.push(p.to_array());
                vertex_surface.push(s);
                positions.len() as u32 - 1
            });
            corners.push(id);
        }
    }
    let mut part = Part { surface, positions, vertex_surface, indices: Vec::new(), clusters: Vec::new() };
    match lod {
        PartLod::FullOnly => {
            // Runs of the surface's triangles in file order.
            for run in corners.chunks(3 * MAX_TRIANGLES) {
                part.push(run, 0, ErrorBounds::default(), terminal());
            }
            return part;
        }
        PartLod::Levels => {
            // Each surface its own look: boxes welded across their faces simplified into smaller shapes,
            // and the hall's pedestals and column bases darkened its image by 0.4 %.
            let welded = Welded::new(triangles, &corners, &part.positions, |s| (s as usize, [0; 3]));
            part.push_levels(&corners, &welded);
            return part;
        }
        PartLod::Hierarchy => {}
    }
    let welded = Welded::new(triangles, &corners, &part.positions, |s| look[s as usize]);
    let mut full_detail = welded.full_detail(&corners);
    let config = meshopt::ClodConfig {
        simplify_permissive: false,
        simplify_fallback_sloppy: false,
        ..clod_default_config(MAX_TRIANGLES)
    };
    let bytes = typed_to_bytes(&welded.positions);
    let vertices = VertexDataAdapter::new(bytes, 12, 0).expect("positions are 12-byte vertices");
    // (group, refined group or -1, indices) per cluster; each group's simplified bounds.
    let mut groups: Vec<(u32, ErrorBounds)> = Vec::new();
    let mut clusters: Vec<(usize, i32, Vec<u32>)> = Vec::new();
    // Each group's box holds its members' triangles and the boxes of the groups they came from, which
    // come first (a group is emitted after the groups its members were simplified from).
    let positions = &welded.positions;
    clod_build(config, &ClodMesh::new(&welded.corners, &vertices), |group, emitted| {
        let id = groups.len();
        let mut footprint = Aabb::EMPTY;
        for c in emitted {
            footprint = footprint.union(Aabb::of(c.indices.iter().map(|&v| Vec3::from(positions[v as usize]))));
            if c.refined >= 0 {
                footprint = footprint.union(groups[c.refined as usize].1.aabb());
            }
        }
        groups.push((group.depth as u32, ErrorBounds::new(footprint, group.simplified.error)));
        clusters.extend(emitted.iter().map(|c| (id, c.refined, c.indices.to_vec())));
        id as i32
    });
    // Finest first, so that a surface's full-detail triangles are one run.
    clusters.sort_by_key(|&(group, refined, _)| (refined >= 0, group));
    let full = part.corners(&corners);
    tighten_end_errors(&mut groups, &clusters, |indices| {
        let level = part.corners(&welded.unweld(indices));
        (full.len() * level.len() <= MEASURED_PAIRS).then(|| hausdorff(&full, &level).max(hausdorff(&level, &full)))
    });
    // Where `clod_build` ends (one cluster, which it leaves as it is, or a group it could not simplify):
    // simpler levels of those clusters together. A column's shaft ended as a cluster of 66 triangles.
    let ends = |&&(group, _, _): &&(usize, i32, Vec<u32>)| groups[group].1.error >= f32::MAX;
    let (end, end_error, end_depth) = clusters.iter().filter(ends).fold((Vec::new(), 0.0f32, 0), |mut a, c| {
        a.0.extend_from_slice(&c.2);
        let own = if c.1 < 0 { ErrorBounds::FULL_DETAIL } else { groups[c.1 as usize].1.error };
        (a.0, a.1.max(own), a.2.max(if c.1 < 0 { 0 } else { groups[c.0].0 }))
    });
    let chain = part.simpler_levels(&welded, Base::End { indices: &end, error: end_error }, &full);
    let bounds = part.level_bounds();
    let beyond_end = bounds(chain.first());
    for (group, refined, indices) in clusters {
        let (depth, parent) = groups[group];
        let parent = if parent.error >= f32::MAX { beyond_end } else { parent };
        let own = if refined < 0 { ErrorBounds::default() } else { groups[refined as usize].1 };
        // The full detail with each triangle's own surface; coarser levels by the welded corners' vertices.
        let (depth, indices) = if refined < 0 { (0, full_detail(&indices)) } else { (depth, welded.unweld(&indices)) };
        part.push(&indices, depth, own, parent);
    }
    part.push_chain(&chain, end_depth + 1);
    part
}

/// Lowers the error of each group that `clod_build`'s last clusters came from, and only they, to the
/// distance `measured` between those clusters (welded corners) and the full detail, where it can be measured
/// and is smaller, but never below the error of the group's own members. `clod_build` adds up each level's
/// error: the hall's column shafts ended at 0.092 m, 0.053 m from their full detail.
fn tighten_end_errors(
    groups: &mut [(u32, ErrorBounds)],
    clusters: &[(usize, i32, Vec<u32>)],
    measured: impl Fn(&[u32]) -> Option<f32>,
) {
    let end: Vec<bool> = groups.iter().map(|g| g.1.error >= f32::MAX).collect();
    let ends = |group: usize| end[group];
    let sources: std::collections::BTreeSet<usize> =
        clusters.iter().filter(|c| ends(c.0) && c.1 >= 0).map(|c| c.1 as usize).collect();
    for source in sources {
        let from_source = || clusters.iter().filter(|c| c.1 == source as i32);
        if !from_source().all(|c| ends(c.0)) {
            continue;
        }
        let indices: Vec<u32> = from_source().flat_map(|c| c.2.iter().copied()).collect();
        let members = clusters.iter().filter(|c| c.0 == source);
        let floor = members.map(|c| if c.1 < 0 { 0.0 } else { groups[c.1 as usize].1.error }).fold(0.0, f32::max);
        if let Some(distance) = measured(&indices) {
            let error = &mut groups[source].1.error;
            *error = error.min(distance.max(floor));
        }
    }
}

/// The directed Hausdorff distance from `from` to `to`, sampled: the largest distance from a corner, an
/// edge's middle or the centroid of a triangle of `from` to the nearest triangle of `to`. Quadratic: small
/// parts only.
fn hausdorff(from: &[[Vec3; 3]], to: &[[Vec3; 3]]) -> f32 {
    let samples =
        from.iter().flat_map(|&[a, b, c]| [a, b, c, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0, (a + b + c) / 3.0]);
    samples
        .map(|p| to.iter().map(|&[a, b, c]| closest_on_triangle(p, a, b, c).distance(p)).fold(f32::MAX, f32::min))
        .fold(0.0, f32::max)
}

fn terminal() -> ErrorBounds {
    ErrorBounds { error: ErrorBounds::TERMINAL, ..Default::default() }
}

impl Part {
    /// What replaces the part's coarsest clusters, where nothing else does: nothing, at an error of half its
    /// box's diagonal (a shape shrunk to a point is that far from where it was). A part that projects under
    /// a view's accepted error as a whole (a vase across the atrium, a leaf, under a texel) is not drawn:
    /// the many small parts of a real model (Sponza: 41 000 triangles in parts of one cluster) would
    /// otherwise be drawn at full detail however far away.
    fn vanish_when_small(&mut self) {
        let part = Aabb::of(self.positions.iter().map(|&p| Vec3::from(p)));
        for c in self.clusters.iter_mut().filter(|c| c.parent.error == ErrorBounds::TERMINAL) {
            let error = (0.5 * part.diagonal()).max(c.own.error);
            c.parent = ErrorBounds::new(part.union(c.own.aabb()), error);
        }
    }

    /// A small part (one cluster) as a chain of levels after its full detail. Without them, a small part
    /// is drawn at full detail until it vanishes: Sponza's 656 leaves (45 triangles each) and its other
    /// parts of one cluster were a quarter of the triangles its sensors drew.
    fn push_levels(&mut self, corners: &[u32], welded: &Welded) {
        let chain = self.simpler_levels(welded, Base::FullDetail(&welded.corners), &self.corners(corners));
        let parent = self.level_bounds()(chain.first());
        self.push(corners, 0, ErrorBounds::default(), parent);
        self.push_chain(&chain, 1);
    }

    /// Levels simpler than `base` (`full`: the part's full detail), each from simplifying `base` to half
    /// the previous level's triangles and one cluster at most, until a level no longer simplifies by a
    /// quarter: each as the part's own vertices ([`Welded::unweld`]), and its error. Regular simplification,
    /// so a closed part stays closed.
    ///
    /// A level's error is the distance measured between it and the full detail, sampled both ways
    /// ([`MEASURED_PAIRS`] bounds the work, beyond which it is the end's error plus the distance to the
    /// end), or meshoptimizer's estimate from the full detail where larger (on a small ball, the mesh's
    /// vertices lay 1.4 times the estimate from the simpler level); never 0 (a level coarser than the mesh is
    /// never full detail) and never below the last or the end's. `clod_build`'s errors add up each level's:
    /// on the hall's columns they were 1.7 times the distance measured, and sums of them twice.
    fn simpler_levels(&self, welded: &Welded, base: Base, full: &[[Vec3; 3]]) -> Vec<(Vec<u32>, f32)> {
        let (indices, base_error, options) = match base {
            Base::FullDetail(indices) => (indices, ErrorBounds::FULL_DETAIL, SimplifyOptions::ErrorAbsolute),
            Base::End { indices, error } => {
                (indices, error, SimplifyOptions::ErrorAbsolute | SimplifyOptions::LockBorder)
            }
        };
        if indices.is_empty() || indices.len() / 3 > 16 * MAX_TRIANGLES {
            return Vec::new(); // the distances below are quadratic
        }
        let bytes = typed_to_bytes(&welded.positions);
        let vertices = VertexDataAdapter::new(bytes, 12, 0).expect("positions are 12-byte vertices");
        let (reference, offset) = match full.len() * MAX_TRIANGLES <= MEASURED_PAIRS {
            true => (std::borrow::Cow::Borrowed(full), 0.0),
            false => (self.corners(&welded.unweld(indices)).into(), base_error),
        };
        let mut levels: Vec<(Vec<u32>, f32)> = Vec::new();
        let (mut previous, mut previous_error) = (indices.len() / 3, base_error);
        loop {
            let target = (previous / LEVEL_RATIO).min(MAX_TRIANGLES);
            if target < 1 {
                break;
            }
            let mut estimate = 0.0;
            let simpler = meshopt::simplify(indices, &vertices, 3 * target, f32::MAX, options, Some(&mut estimate));
            let triangles = simpler.len() / 3;
            if simpler.is_empty() || triangles * 4 > previous * 3 || triangles > MAX_TRIANGLES {
                break;
            }
            let estimate = if matches!(base, Base::FullDetail(_)) { estimate } else { 0.0 };
            let simpler = welded.unweld(&simpler);
            let level = self.corners(&simpler);
            let measured = offset + hausdorff(&reference, &level).max(hausdorff(&level, &reference));
            let error = measured.max(estimate).max(previous_error).max(f32::MIN_POSITIVE);
            levels.push((simpler, error));
            (previous, previous_error) = (triangles, error);
        }
        levels
    }

    /// The bounds of a level of [`Part::simpler_levels`] (the part's box), terminal for none.
    fn level_bounds(&self) -> impl Fn(Option<&(Vec<u32>, f32)>) -> ErrorBounds + use<> {
        let part = Aabb::of(self.positions.iter().map(|&p| Vec3::from(p)));
        move |level| level.map_or_else(terminal, |&(_, error)| ErrorBounds::new(part, error))
    }

    /// The levels of [`Part::simpler_levels`] as clusters from `depth` on, each replaced by the next.
    fn push_chain(&mut self, chain: &[(Vec<u32>, f32)], depth: u32) {
        let bounds = self.level_bounds();
        for (k, (indices, _)) in chain.iter().enumerate() {
            self.push(indices, depth + k as u32, bounds(chain.get(k)), bounds(chain.get(k + 1)));
        }
    }

    /// The triangles of `indices` by their corners.
    fn corners(&self, indices: &[u32]) -> Vec<[Vec3; 3]> {
        indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from(self.positions[t[k] as usize]))).collect()
    }

    fn push(&mut self, indices: &[u32], depth: u32, own: ErrorBounds, parent: ErrorBounds) {
        let positions = &self.positions;
        let points = indices.iter().map(|&v| Vec3::from(positions[v as usize]));
        let sphere = sphere(points);
        let corners = indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from(positions[t[k] as usize])));
        self.clusters.push(Cluster {
            first_index: self.indices.len() as u32,
            index_count: indices.len() as u32,
            surface: self.surface,
            depth,
            sphere,
            slab: slab(corners, Vec3::from_slice(&sphere[..3])),
            own,
            parent,
            ..Default::default()
        });
        self.indices.extend_from_slice(indices);
    }
}
