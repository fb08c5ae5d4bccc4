//! Which of the cache's entries light can reach (docs/DESIGN.md §10): only those are sensed.
//!
//! An entry is lit only if its sensor sees something lit: an emitter's front, the sky, or another entry that
//! is lit. Visibility runs both ways, so the entries light reaches are those the lights' own entries see,
//! and those these see, and so on: a walk over the transport's rows ([`Reach`]) from [`seeds`], sensing each
//! level as it is found. What it never reaches is dark at every bounce and costs nothing: the insides of
//! closed meshes (a column's, a sphere's), the outer sides of a closed room's walls, rooms no light enters.
//! The walk does not depend on the camera, so neither does the cache (a viewer's moves, a fly-through's
//! frames, a cache file share it).

use glam::Vec3;
use rayon::prelude::*;

use super::RadianceCache;
use super::entries::Entry;
use crate::scene::bvh::Bvh;
use crate::scene::{Mesh, Ray};

/// Directions in which an entry looks for the sky (a Fibonacci hemisphere about its normal), where rays
/// that leave the scene carry light.
pub const SKY_RAYS: usize = 64;

/// Where the walk starts: the front entries of emitting surfaces, and where rays that leave the scene carry
/// light (`sky`: a sky map, a background that is not black, or a distant light such as the sun), every entry
/// from which one of [`SKY_RAYS`] directions, or the direction of a distant emitter, leaves the scene
/// (meets none of its own triangles); none buried inside a closed shape. Increasing.
/// `bias`: how far above its surface a sensor sits (where the rays start).
pub fn seeds(cache: &RadianceCache, mesh: &Mesh, bvh: &Bvh, sky: bool, bias: f32) -> Vec<u32> {
    let local = mesh.local_triangles().len();
    // Directions towards the distant emitters (the sun's facets), from the scene's centre.
    let centre = mesh.bounds.center();
    let distant: Vec<Vec3> = mesh.triangles[local..]
        .iter()
        .filter(|t| mesh.material_of(t.surface).is_emitter())
        .map(|t| ((t.v[0] + t.v[1] + t.v[2]) / 3.0 - centre).normalize())
        .collect();
    let sees_sky = |e: &Entry| {
        let leaves = |d: Vec3| {
            d.dot(e.normal) > 0.0
                && bvh
                    .intersect(&Ray::new(e.point + e.normal * bias, d), 0.0, f32::MAX)
                    .is_none_or(|h| h.triangle as usize >= local)
        };
        let (t, b) = e.normal.any_orthonormal_pair();
        (0..SKY_RAYS).map(|k| hemisphere(k, SKY_RAYS)).any(|h| leaves(t * h.x + b * h.y + e.normal * h.z))
            || distant.iter().any(|&d| leaves(d))
    };
    (cache.entries.par_iter().enumerate())
        .filter(|(_, e)| (e.front && mesh.material_of(e.surface).is_emitter()) || (sky && sees_sky(e)))
        .map(|(i, _)| i as u32)
        .filter(|i| cache.buried.binary_search(i).is_err())
        .collect()
}

/// Direction `k` of `n` on a Fibonacci hemisphere about +z (even in area).
fn hemisphere(k: usize, n: usize) -> Vec3 {
    let z = 1.0 - (k as f32 + 0.5) / n as f32;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = k as f32 * std::f32::consts::PI * (3.0 - 5f32.sqrt());
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The walk: which entries are reached, level by level.
pub struct Reach {
    reached: Vec<bool>,
    /// Entries the walk never reaches: buried inside closed shapes (`RadianceCache::buried`).
    closed: Vec<bool>,
    count: usize,
}

impl Reach {
    /// Nothing reached yet among `entries`, of which `buried` (increasing) are never reached.
    pub fn new(entries: usize, buried: &[u32]) -> Self {
        let mut closed = vec![false; entries];
        buried.iter().for_each(|&i| closed[i as usize] = true);
        Self { reached: vec![false; entries], closed, count: 0 }
    }

    /// Marks `level` reached (entries not reached before: the seeds, then what [`Reach::next`] returned).
    pub fn mark(&mut self, level: &[u32]) {
        for &i in level {
            if !std::mem::replace(&mut self.reached[i as usize], true) {
                self.count += 1;
            }
        }
    }

    /// The entries not yet reached among `seen` (the values the last level's sensors saw; fallbacks, past
    /// the entries, ignored): the next level, increasing.
    pub fn next(&self, seen: impl Iterator<Item = u32>) -> Vec<u32> {
        let open = |c: u32| (c as usize) < self.reached.len() && !self.reached[c as usize] && !self.closed[c as usize];
        let mut next: Vec<u32> = seen.filter(|&c| open(c)).collect();
        next.sort_unstable();
        next.dedup();
        next
    }

    pub fn is_reached(&self, entry: usize) -> bool {
        self.reached[entry]
    }

    /// Entries reached.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The reached entries, increasing.
    pub fn reached(&self) -> Vec<u32> {
        (0..self.reached.len() as u32).filter(|&i| self.reached[i as usize]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_walk_follows_rows_to_entries_not_yet_reached() {
        let mut reach = Reach::new(5, &[]);
        reach.mark(&[0]);
        // Entry 0 sees 2 and 3 (and a fallback value, 7, past the entries); 3 sees 0 and 4.
        let rows = [vec![(2, 0.1), (3, 0.2), (7, 0.1)], vec![(0, 0.5), (4, 0.1)]];
        let columns = |rows: &[Vec<(u32, f32)>]| rows.iter().flatten().map(|&(c, _)| c).collect::<Vec<_>>();
        let level = reach.next(columns(&rows[..1]).into_iter());
        assert_eq!(level, vec![2, 3]);
        reach.mark(&level);
        assert_eq!(reach.next(columns(&rows).into_iter()), vec![4]);
        assert_eq!((reach.count(), reach.is_reached(1)), (3, false));
    }

    #[test]
    fn hemisphere_directions_are_unit_and_above() {
        for k in 0..SKY_RAYS {
            let d = hemisphere(k, SKY_RAYS);
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z > 0.0, "{d}");
        }
    }
}
