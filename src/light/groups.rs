//! Light groups: the scene's emitters gathered into at most [`MAX_GROUPS`] groups, each of whose
//! visibility a sensor measures on its own (docs/DESIGN.md §2). A group is one emitting surface where the
//! scene has few enough; otherwise nearby surfaces are merged (k-means on their centroids, seeded by
//! farthest points), so that the emitters of a group lie in one part of the scene and tend to be hidden or
//! seen together.
//!
//! The emitter triangles are listed group by group, so that a group is a range of [`Lights::emitters`].

use std::collections::BTreeMap;
use std::ops::Range;

use glam::Vec3;

use crate::scene::{Aabb, Mesh, SurfaceId, triangle_area};

/// Most light groups a scene is gathered into: each costs a sensor two extra map layers.
pub const MAX_GROUPS: usize = 8;

/// An emitting triangle: its vertices (counter-clockwise seen from its emitting front), radiance and group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    pub v: [Vec3; 3],
    pub ke: Vec3,
    pub group: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct LightGroup {
    /// Its triangles in [`Lights::emitters`].
    pub emitters: Range<u32>,
    /// Bounding box of its triangles: a sensor's zoom view of the group covers it.
    pub bounds: Aabb,
    /// Σ luminance(Ke)·area.
    pub power: f32,
}

/// The scene's emitters, by group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lights {
    pub emitters: Vec<Emitter>,
    pub groups: Vec<LightGroup>,
    /// Group of each emitting surface.
    pub surface_group: BTreeMap<SurfaceId, u32>,
}

/// Rec. 709 luminance of linear RGB `c`: a light's power, a point's weight, how bright a pixel is.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl Lights {
    /// Each group's unoccluded irradiance `Σ Ke·(projected solid angle)` over the hemisphere of a sensor at
    /// `origin` facing `n` (what the emitter pass computes per sensor; `glsl/group_light.glsl`, its twin).
    pub fn unoccluded(&self, origin: Vec3, n: Vec3) -> [Vec3; MAX_GROUPS] {
        use super::polygon::{Domain, Receiver, projected_solid_angle};
        let receiver =
            Receiver { origin: origin.as_dvec3(), t: glam::DVec3::ZERO, b: glam::DVec3::ZERO, n: n.as_dvec3() };
        let mut e = [Vec3::ZERO; MAX_GROUPS];
        for (group, light) in self.groups.iter().enumerate() {
            e[group] = (self.emitters[light.emitters.start as usize..light.emitters.end as usize].iter())
                .map(|em| {
                    let polygon = em.v.map(|v| v.as_dvec3());
                    em.ke * projected_solid_angle(&receiver, Domain::Hemisphere, &polygon) as f32
                })
                .sum();
        }
        e
    }

    /// The emitters of `mesh` (triangles whose material emits; an emission-textured one as its parts,
    /// [`Mesh::emitter_parts`]), gathered into groups.
    pub fn new(mesh: &Mesh) -> Self {
        // Emitting surfaces, in id order, with their triangles.
        let mut surfaces: BTreeMap<SurfaceId, Vec<usize>> = BTreeMap::new();
        for (i, t) in mesh.triangles.iter().enumerate() {
            if mesh.material_of(t.surface).is_emitter() {
                surfaces.entry(t.surface).or_default().push(i);
            }
        }
        let ids: Vec<SurfaceId> = surfaces.keys().copied().collect();
        let centroid = |id: &SurfaceId| {
            let tris = &surfaces[id];
            tris.iter().map(|&i| mesh.triangles[i].v.iter().sum::<Vec3>() / 3.0).sum::<Vec3>() / tris.len() as f32
        };
        let centroids: Vec<Vec3> = ids.iter().map(centroid).collect();
        let assignment = cluster(&centroids, MAX_GROUPS);

        let split = mesh.emitter_split();
        let mut lights = Lights::default();
        let groups = assignment.iter().copied().max().map_or(0, |g| g + 1);
        for g in 0..groups {
            let first = lights.emitters.len() as u32;
            let (mut bounds, mut power) = (Aabb::EMPTY, 0.0);
            for (_, id) in ids.iter().enumerate().filter(|(k, _)| assignment[*k] == g) {
                lights.surface_group.insert(*id, g as u32);
                for &i in &surfaces[id] {
                    for (v, ke) in mesh.emitter_parts(i, split) {
                        v.iter().for_each(|&p| bounds.grow(p));
                        power += luminance(ke) * triangle_area(&v);
                        lights.emitters.push(Emitter { v, ke, group: g as u32 });
                    }
                }
            }
            lights.groups.push(LightGroup { emitters: first..lights.emitters.len() as u32, bounds, power });
        }
        lights
    }

    pub fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }
}

/// Assigns each point to one of at most `k` clusters (numbered from 0, every number used): each point its
/// own cluster when there are few enough, else k-means seeded by farthest points. Deterministic.
fn cluster(points: &[Vec3], k: usize) -> Vec<usize> {
    if points.len() <= k {
        return (0..points.len()).collect();
    }
    // Farthest-point seeds, starting from the first point.
    let mut seeds = vec![points[0]];
    while seeds.len() < k {
        let far = points
            .iter()
            .copied()
            .max_by(|a, b| {
                let da = seeds.iter().map(|s| s.distance_squared(*a)).fold(f32::INFINITY, f32::min);
                let db = seeds.iter().map(|s| s.distance_squared(*b)).fold(f32::INFINITY, f32::min);
                da.total_cmp(&db)
            })
            .unwrap_or(points[0]);
        seeds.push(far);
    }
    let nearest = |p: Vec3, seeds: &[Vec3]| {
        (0..seeds.len()).min_by(|&a, &b| seeds[a].distance_squared(p).total_cmp(&seeds[b].distance_squared(p)))
    };
    let mut assignment = vec![0; points.len()];
    for _ in 0..16 {
        let next: Vec<usize> = points.iter().map(|&p| nearest(p, &seeds).unwrap_or(0)).collect();
        let changed = next != assignment;
        assignment = next;
        for (c, seed) in seeds.iter_mut().enumerate() {
            let members: Vec<Vec3> =
                points.iter().zip(&assignment).filter(|(_, a)| **a == c).map(|(p, _)| *p).collect();
            if !members.is_empty() {
                *seed = members.iter().sum::<Vec3>() / members.len() as f32;
            }
        }
        if !changed {
            break;
        }
    }
    // Renumber the clusters in use by first appearance.
    let mut renumber = BTreeMap::new();
    assignment
        .iter()
        .map(|&c| {
            let next = renumber.len();
            *renumber.entry(c).or_insert(next)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::{from_groups, rect};
    use crate::scene::{Camera, ImageSize, Material};

    fn scene_with_lights(centres: &[Vec3]) -> Mesh {
        let mut groups = vec![("floor", 0, rect(Vec3::ZERO, Vec3::X * 10.0, Vec3::Z * 10.0, Vec3::Y))];
        let names: Vec<String> = (0..centres.len()).map(|i| format!("lamp{i}")).collect();
        for (i, c) in centres.iter().enumerate() {
            groups.push((names[i].as_str(), 1, rect(*c, Vec3::X * 0.1, Vec3::Z * 0.1, -Vec3::Y)));
        }
        let materials = vec![
            Material::new("white", Vec3::splat(0.5), Vec3::ZERO),
            Material::new("lamp", Vec3::ZERO, Vec3::splat(10.0)),
        ];
        let camera = Camera::look_at(Vec3::new(0.0, 5.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0).unwrap();
        from_groups(groups, materials, camera, ImageSize { width: 4, height: 4 }).mesh
    }

    #[test]
    fn each_emitting_surface_is_a_group_when_there_are_few() {
        let centres = [Vec3::new(-2.0, 3.0, 0.0), Vec3::new(2.0, 3.0, 0.0)];
        let lights = Lights::new(&scene_with_lights(&centres));
        assert_eq!(lights.groups.len(), 2);
        assert_eq!(lights.emitters.len(), 4, "two triangles per lamp");
        for (g, group) in lights.groups.iter().enumerate() {
            assert_eq!(group.emitters.len(), 2);
            assert!(
                lights.emitters[group.emitters.start as usize..group.emitters.end as usize]
                    .iter()
                    .all(|e| e.group == g as u32)
            );
            assert!((group.bounds.center() - centres[g]).length() < 1e-5);
            assert!((group.power - 10.0 * 0.04).abs() < 1e-4, "luminance × area: {}", group.power);
        }
    }

    #[test]
    fn many_lamps_are_merged_into_nearby_groups() {
        // Two clusters of 10 lamps each, far apart: at most MAX_GROUPS groups, none spanning both.
        let mut centres = Vec::new();
        for i in 0..10 {
            centres.push(Vec3::new(-8.0 + 0.3 * i as f32, 3.0, 0.0));
            centres.push(Vec3::new(8.0 - 0.3 * i as f32, 3.0, 0.0));
        }
        let lights = Lights::new(&scene_with_lights(&centres));
        assert!(lights.groups.len() <= MAX_GROUPS && lights.groups.len() >= 2, "{} groups", lights.groups.len());
        assert_eq!(lights.emitters.len(), 40, "every emitter kept");
        for g in &lights.groups {
            assert!(g.bounds.max.x - g.bounds.min.x < 6.0, "a group spans both clusters: {:?}", g.bounds);
        }
        let total: f32 = lights.groups.iter().map(|g| g.power).sum();
        assert!((total - 20.0 * 0.4).abs() < 1e-3);
    }

    #[test]
    fn a_scene_without_emitters_has_no_groups() {
        assert!(Lights::new(&scene_with_lights(&[])).is_empty());
    }
}
