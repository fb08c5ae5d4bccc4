//! Each piece's value as the mean of the light over its piece, where the light its sensor's point receives
//! is not (docs/DESIGN.md §10, "Piece means").
//!
//! One sensor measures a piece's light at one point. Where a bright surface stands a few centimetres from
//! part of the piece, the light over it is anything but uniform: on the door ajar the dividing wall beside
//! the latch jamb sees the door's lit face from 3 to 8 cm, its light 14× as bright 2 cm from the jamb as
//! 25 cm from it, and the piece's point, a hand's width out, read a seventh of the piece's mean. The camera's
//! floor there took 3 % too little light at 16 cells (1.5 % of it from that strip). The direct light has its
//! own answer (halving, then the mean over the spread points: [`super::entries`]); this is the rest of it.
//!
//! After the bounces, the light the solved cache sends each point (rays over the values, as the sensor maps
//! see them) is gathered at the piece's spread points and at its sensor's point, each direction of the
//! point's paired with one spread point's (so that what both see alike cancels), and the entry moves by its
//! reflectance times the difference: the sensor's measure stands, corrected by how far its point's light is
//! from the piece's mean. [`PROBE_RAYS`] first find the pieces where that difference matters; [`MEAN_RAYS`]
//! then measure it there. The moved values are not bounced again: they hold a sliver of the light, which
//! others see second hand.

use glam::Vec3;
use rayon::prelude::*;

use super::RadianceCache;
use super::entries::{SAMPLES_PER_PIECE, cosine_direction};
use crate::scene::bvh::Bvh;
use crate::scene::{Ray, Triangle};

/// Rays from each spread point of a piece that find whether its light varies over it (the sensor's point
/// casts all of theirs: [`paired_directions`]).
pub const PROBE_RAYS: usize = 16;

/// Rays from each spread point of a piece that measure its mean where it does (the sensor's point casts all
/// of theirs). Against the path tracer's mean over the same points, the door ajar's lit entries in the
/// camera's room were off by 30 % (relative RMSE) at 64, 24 % at 256, 23.5 % at 512 (25 % with no piece
/// means, 27 % before the directions were paired).
pub const MEAN_RAYS: usize = 256;

/// A piece's light varies over it where its points' mean differs from its sensor's point by more than this
/// share of the entry's R, as [`PROBE_RAYS`] see it: 12 % of the door ajar's lit entries.
pub const PIECE_VARIATION: f32 = 0.1;

/// A piece whose points' normals turn more than this from its entry's is curved: left as its point sees it.
pub const CURVED_DEG: f32 = 10.0;

/// The scene the gathers' rays meet.
pub struct Surroundings<'a> {
    pub bvh: &'a Bvh,
    /// The mesh's triangles, as `bvh` indexes them; those from `local` on (distant lights) have no entry.
    pub triangles: &'a [Triangle],
    pub local: usize,
    /// How far a point is lifted off its surface, and where its rays start (world units).
    pub offsets: (f32, f32),
    /// What a ray that leaves the scene sees, by its direction.
    pub background: &'a (dyn Fn(Vec3) -> Vec3 + Sync),
}

/// `values` (one per entry) with each of `entries` moved towards its piece's mean, and how many were moved;
/// `seen`: the values the entries' R gathered (the same, once converged).
pub fn piece_means(
    cache: &RadianceCache,
    (values, seen): (&[Vec3], &[Vec3]),
    entries: &[u32],
    around: &Surroundings<'_>,
) -> (Vec<Vec3>, usize) {
    let moves: Vec<(usize, Vec3)> = entries
        .par_iter()
        .filter_map(|&e| {
            let e = e as usize;
            let (entry, albedo) = (&cache.entries[e], cache.albedo[e]);
            let r = luminance(values[e] / albedo.max(Vec3::splat(1e-3)));
            if r <= 0.0 {
                return None;
            }
            // Each point's own side: the entry's normal is its piece's mean, which a curved piece's points do
            // not face (the rays of a sphere's rim would start into it). A piece curved more than
            // [`CURVED_DEG`] keeps its point's light: its points face different surroundings.
            let side = if entry.front { 1.0 } else { -1.0 };
            let points = cache.points[e / 2].map(|(p, n)| (p, n * side));
            if points.iter().any(|&(_, n)| n.dot(entry.normal) < CURVED_DEG.to_radians().cos()) {
                return None;
            }
            let turn = (e as f32 * 0.754_877_7).fract();
            let difference = |rays: usize| {
                let (all, own) = paired_directions(rays, turn);
                let at = |p: Vec3, d: &[Vec3]| gather(cache, seen, around, (p, entry.normal), d);
                let mean = points.iter().zip(&own).map(|(&(p, _), d)| at(p, d)).sum::<Vec3>();
                mean / SAMPLES_PER_PIECE as f32 - at(entry.point, &all)
            };
            (luminance(difference(PROBE_RAYS)).abs() > PIECE_VARIATION * r)
                .then(|| (e, (values[e] + albedo * difference(MEAN_RAYS)).max(Vec3::ZERO)))
        })
        .collect();
    let mut out = values.to_vec();
    moves.iter().for_each(|&(e, v)| out[e] = v);
    (out, moves.len())
}

/// The light arriving at `p` (normal `n`) from the cache's values and the background, cosine-weighted: R
/// less the direct light, as a sensor there would sum it, along `directions` (in the frame of `n`).
fn gather(
    cache: &RadianceCache,
    values: &[Vec3],
    around: &Surroundings<'_>,
    (p, n): (Vec3, Vec3),
    directions: &[Vec3],
) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let (lift, near) = around.offsets;
    let origin = p + n * lift;
    let sum: Vec3 = directions
        .iter()
        .map(|d| {
            let d = t * d.x + b * d.y + n * d.z;
            match around.bvh.intersect(&Ray::new(origin, d), near, f32::INFINITY) {
                Some(hit) if (hit.triangle as usize) < around.local => {
                    let tri = &around.triangles[hit.triangle as usize];
                    let q = origin + d * hit.t;
                    values[cache.lookup_from(q, origin, tri.surface, d.dot(tri.normal) < 0.0)]
                }
                Some(_) => Vec3::ZERO,
                None => (around.background)(d),
            }
        })
        .sum();
    sum / directions.len() as f32
}

/// `count` cosine-distributed directions about +z ([`cosine_direction`]), turned by `turn` of a full turn:
/// each entry its own, so that no direction is every piece's.
fn directions(count: usize, turn: f32) -> Vec<Vec3> {
    (0..count).map(|i| cosine_direction(i, count, turn)).collect()
}

/// The directions of a paired difference: `per_point` × [`SAMPLES_PER_PIECE`] for the sensor's point, and
/// for spread point k every [`SAMPLES_PER_PIECE`]-th of them from the k-th, so that each direction the point
/// casts one spread point casts too. The difference of the means is then the mean of each direction's
/// difference between two points a few centimetres apart, which a bright sliver seen by both cancels from;
/// with the same `per_point` directions at every point, the sensor's point's own few rays stood against
/// eight times as many, and its chance catch of a sliver moved its entry by a third (the door ajar's floor:
/// entries at nothing, or twice the oracle's mean, docs/ACCURACY.md).
fn paired_directions(per_point: usize, turn: f32) -> (Vec<Vec3>, [Vec<Vec3>; SAMPLES_PER_PIECE]) {
    let all = directions(per_point * SAMPLES_PER_PIECE, turn);
    let own = std::array::from_fn(|k| all.iter().skip(k).step_by(SAMPLES_PER_PIECE).copied().collect());
    (all, own)
}

/// Rec. 709 luminance, as `light::groups::luminance` (a layer above `gi`, docs/DESIGN.md §8).
fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_directions_are_cosine_distributed() {
        // E[cos θ] = 2/3 under the cosine density; E[x] = E[y] = 0.
        let d = directions(4096, 0.3);
        let mean = d.iter().sum::<Vec3>() / d.len() as f32;
        assert!((mean.z - 2.0 / 3.0).abs() < 1e-3, "{mean}");
        assert!(mean.x.abs() < 1e-2 && mean.y.abs() < 1e-2, "{mean}");
        assert!(d.iter().all(|v| (v.length() - 1.0).abs() < 1e-5 && v.z > 0.0));
    }

    #[test]
    fn each_direction_of_the_point_is_one_spread_point_s() {
        let (all, own) = paired_directions(16, 0.7);
        assert_eq!(all.len(), 16 * SAMPLES_PER_PIECE);
        let mut paired: Vec<Vec3> = own.iter().flatten().copied().collect();
        assert_eq!(paired.len(), all.len());
        let key = |v: &Vec3| (v.x.to_bits(), v.y.to_bits(), v.z.to_bits());
        let mut all = all;
        all.sort_by_key(key);
        paired.sort_by_key(key);
        assert_eq!(all, paired, "the spread points' directions are the point's, each once");
        // Each point's share covers the hemisphere as the whole does (E[cos θ] = 2/3), not one ring of it.
        for d in &own {
            let z = d.iter().map(|v| v.z).sum::<f32>() / d.len() as f32;
            assert!((z - 2.0 / 3.0).abs() < 0.05, "{z}");
        }
    }
}
