//! The radiance cache's grid on the CPU (docs/DESIGN.md §10): every point of every triangle finds an entry
//! of its own surface and side, entries sit on their surface, the two sides of a thin wall never share one,
//! and the build is the same on every run.

mod common;

use glam::Vec3;
use sensorlight::gi::RadianceCache;
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::{Mesh, Ray, Scene, Triangle};

/// The cache of `mesh` at `resolution` with coarser levels `lod`, no halving, the renderer's sensor offsets.
fn cache_of(mesh: &Mesh, resolution: u32, lod: &[([Vec3; 3], u32)]) -> RadianceCache {
    RadianceCache::build(mesh, resolution, lod, None, sensorlight::sensors::frame::offsets(mesh.scale()))
}

fn shipped(name: &str) -> Scene {
    Scene::load(&common::project(&format!("scenes/{name}/{name}.toml"))).unwrap()
}

/// Points spread over triangle `t`, its corners and edges included (where rounding is closest to a cell face).
fn points_on(t: &Triangle) -> impl Iterator<Item = Vec3> + '_ {
    grid_on(t, 12)
}

/// The points of a barycentric grid of `steps` intervals along each edge of `t`.
fn grid_on(t: &Triangle, steps: u32) -> impl Iterator<Item = Vec3> + '_ {
    (0..=steps).flat_map(move |i| {
        (0..=steps - i).map(move |j| {
            let (u, v) = (i as f32 / steps as f32, j as f32 / steps as f32);
            t.v[0] + (t.v[1] - t.v[0]) * u + (t.v[2] - t.v[0]) * v
        })
    })
}

#[test]
fn every_point_of_every_surface_finds_its_own_entry() {
    for name in ["cornell", "room", "door-ajar", "small-light"] {
        let scene = shipped(name);
        for resolution in [4, 16, 33] {
            let cache = cache_of(&scene.mesh, resolution, &[]);
            let mut looked = 0;
            for t in &scene.mesh.triangles {
                for p in points_on(t) {
                    for front in [false, true] {
                        let i = cache.lookup(p, t.surface, front);
                        assert!(
                            i < cache.entries.len(),
                            "{name} at {resolution}: {p} on surface {} fell back",
                            t.surface
                        );
                        let e = &cache.entries[i];
                        assert_eq!(
                            (e.surface, e.front),
                            (t.surface, front),
                            "{name}: {p} read another surface's entry"
                        );
                        // Its own cell, or a neighbour's where its piece of the cell was a sliver.
                        let far = (p - e.point).length() / cache.grid.cell;
                        assert!(far <= 2.0 * 3f32.sqrt(), "{name}: {p} reads an entry {far} cells away");
                        looked += 1;
                    }
                }
            }
            assert!(looked > 0);
        }
    }
}

/// The cache never carries light across a wall: from every point of the shipped scenes' surfaces (the
/// door-ajar rooms share their floor, ceiling and side walls under a 10 cm divider, a third of a cell at
/// resolution 16), the point its entry was sensed at can be seen, on the side looked up. Measured by area:
/// points spread evenly over the surfaces. A sliver beside an object standing in the cell (the 5 cm between
/// the room's shelf and its wall) may read that object's far side when it is below `MIN_SPLIT_AREA`: the
/// bounds below are the shares that leaves.
#[test]
fn no_entry_is_read_across_a_wall() {
    for (name, bound) in [("door-ajar", 0.001), ("cornell", 0.001), ("small-light", 0.001), ("room", 0.02)] {
        let scene = shipped(name);
        let bvh = Bvh::build(&scene.mesh.triangles);
        for resolution in [8, 16, 32] {
            let cache = cache_of(&scene.mesh, resolution, &[]);
            let lift = 1e-3 * cache.grid.cell;
            let spacing = cache.grid.cell / 8.0;
            let (mut blocked, mut total, mut first) = (0.0, 0.0, None);
            for t in &scene.mesh.triangles {
                let area = 0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length();
                let steps = ((area.sqrt() / spacing).ceil() as u32).clamp(2, 64);
                // Inside the triangle: a ray from its edge would start on the wall that meets it there.
                let centre = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
                let points: Vec<Vec3> = grid_on(t, steps).map(|p| p + (centre - p) * 0.02).collect();
                let weight = area / points.len() as f32;
                for &p in &points {
                    for front in [false, true] {
                        let n = if front { t.normal } else { -t.normal };
                        // Only points a sensor may see: not covered by something lying on them (under a box).
                        if bvh.intersect(&Ray::new(p + n * lift, n), lift, 0.25 * cache.grid.cell).is_some() {
                            continue;
                        }
                        let e = &cache.entries[cache.lookup(p, t.surface, front)];
                        let (a, b) = (p + e.normal * lift, e.point + e.normal * lift);
                        let d = b - a;
                        total += weight;
                        if d.length() > 4.0 * lift
                            && bvh.intersect(&Ray::new(a, d.normalize()), lift, d.length() - lift).is_some()
                        {
                            blocked += weight;
                            first.get_or_insert((p, e.point));
                        }
                    }
                }
            }
            assert!(
                blocked <= bound * total,
                "{name} at {resolution}: {:.2} % of the area reads an entry it cannot see, e.g. {first:?}",
                100.0 * blocked / total
            );
        }
    }
}

#[test]
fn entries_sit_on_their_surface_facing_their_side() {
    let scene = shipped("cornell");
    let cache = cache_of(&scene.mesh, 16, &[]);
    for e in &cache.entries {
        let on = scene.mesh.triangles.iter().filter(|t| t.surface == e.surface).any(|t| {
            let n = t.normal;
            let d = (e.point - t.v[0]).dot(n).abs();
            // On the plane, inside the triangle (barycentric signs).
            let inside = (0..3).all(|k| (t.v[(k + 1) % 3] - t.v[k]).cross(e.point - t.v[k]).dot(n) >= -1e-3);
            d < 1e-3 && inside && (e.normal.dot(n) - if e.front { 1.0 } else { -1.0 }).abs() < 1e-4
        });
        assert!(on, "entry at {} (surface {}, front {}) is on no triangle of its surface", e.point, e.surface, e.front);
    }
    // Both sides of every piece; the Cornell box's walls at 16 cells along its longest side.
    assert!(cache.entries.len().is_multiple_of(2));
    assert!((1000..6000).contains(&cache.entries.len()), "{} entries", cache.entries.len());
    assert_eq!(cache.lookup(Vec3::new(278.0, 0.0, 200.0), 1, true) % 2, 1, "odd entries are fronts");
}

/// A wall of zero thickness: its two sides are two entries, never one, at every resolution.
#[test]
fn the_two_sides_of_a_thin_wall_are_apart() {
    let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, surface| {
        let n = (b - a).cross(c - a).normalize();
        [Triangle { v: [a, b, c], normal: n, surface }, Triangle { v: [a, c, d], normal: n, surface }]
    };
    let mut triangles = Vec::new();
    triangles.extend(quad(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y, 1));
    let mesh = Mesh {
        bounds: sensorlight::scene::Aabb::of(triangles.iter().flat_map(|t| t.v)),
        triangles,
        shading: Vec::new(),
        surfaces: vec![sensorlight::scene::Surface { name: "wall".into(), material: 0 }],
        uvs: Vec::new(),
        lightmap_uvs: Vec::new(),
        materials: vec![sensorlight::scene::Material::new("grey", Vec3::splat(0.5), Vec3::ZERO)],
        textures: Default::default(),
        texture_mean: vec![Vec3::ONE],
    };
    for resolution in [1, 2, 7] {
        let cache = cache_of(&mesh, resolution, &[]);
        let p = Vec3::new(0.4, 0.6, 0.0);
        let (back, front) = (cache.lookup(p, 1, false), cache.lookup(p, 1, true));
        assert_ne!(back, front);
        assert_eq!(cache.entries[back].normal, -cache.entries[front].normal);
    }
}

#[test]
fn the_build_is_the_same_on_every_run() {
    let scene = shipped("room");
    let (a, b) = (cache_of(&scene.mesh, 24, &[]), cache_of(&scene.mesh, 24, &[]));
    assert_eq!(a.entries.len(), b.entries.len());
    if let Some(i) = (0..a.entries.len()).find(|&i| a.entries[i] != b.entries[i]) {
        panic!("entry {i} differs: {:?} and {:?}", a.entries[i], b.entries[i]);
    }
    assert!(a.slots == b.slots && a.splits == b.splits);
}

/// Triangles of a coarser level of detail (here: the floor lifted and shifted by a fraction of a cell) find
/// the nearest entry of their surface instead of the fallback.
#[test]
fn coarser_levels_read_their_surface_nearby() {
    let scene = shipped("cornell");
    let floor = scene.mesh.triangles.iter().find(|t| t.normal.y > 0.99 && t.v.iter().all(|v| v.y < 1.0)).unwrap();
    let grid = cache_of(&scene.mesh, 16, &[]).grid;
    let shift = Vec3::new(0.3, -0.6, 0.2) * grid.cell;
    let lod = [(floor.v.map(|v| v + shift), floor.surface)];
    let cache = cache_of(&scene.mesh, 16, &lod);
    let p = (floor.v[0] + floor.v[1] + floor.v[2]) / 3.0 + shift;
    let i = cache.lookup(p, floor.surface, true);
    assert!(i < cache.entries.len(), "a lower floor falls back");
    assert_eq!(cache.entries[i].surface, floor.surface);
}
