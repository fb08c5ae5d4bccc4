//! The cluster hierarchy (docs/DESIGN.md §9), on the CPU: error bounds grow up the hierarchy, the finest
//! level is the mesh exactly, any selection of a closed sphere is watertight, surfaces and emitters are
//! kept, and the cache returns what was built.

mod common;

use std::collections::HashMap;

use common::meshes::scene;
use glam::Vec3;
use sensorlight::clusters::{self, Cluster, ClusterMesh, CullTree, cache, selected, tree};
use sensorlight::scene::{Aabb, SurfaceId};

/// A triangle by its corners' bits, rotated so that the smallest corner comes first (orientation kept).
fn key(t: [[u32; 3]; 3]) -> [[u32; 3]; 3] {
    let first = (0..3).min_by_key(|&k| t[k]).unwrap();
    [t[first], t[(first + 1) % 3], t[(first + 2) % 3]]
}

fn bits(p: [f32; 3]) -> [u32; 3] {
    p.map(|x| (x + 0.0).to_bits())
}

fn triangles(c: &ClusterMesh, clusters: impl Iterator<Item = Cluster>) -> Vec<[[u32; 3]; 3]> {
    let mut out: Vec<_> = clusters
        .flat_map(|k| c.triangles_of(&k).map(|t| key(t.map(|v| bits(c.positions[v as usize])))).collect::<Vec<_>>())
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn error_bounds_grow_up_the_hierarchy() {
    let c = clusters::build(&scene());
    let mut levels = 0;
    for k in &c.clusters {
        levels = levels.max(k.depth);
        assert!(k.own.error <= k.parent.error, "{k:?}");
        if k.parent.error < f32::MAX && k.own.error > 0.0 {
            // The parent's box holds its child's, so its projected error is at least as large from anywhere.
            assert!(k.parent.aabb().contains(&k.own.aabb()), "{k:?}");
        }
        if k.parent.error < f32::MAX {
            // And it holds the cluster's own triangles.
            let points = c.triangles_of(k).flatten().map(|v| Vec3::from(c.positions[v as usize]));
            assert!(k.parent.aabb().contains(&Aabb::of(points)), "{k:?}");
        }
    }
    assert!(levels >= 3, "a 16k-triangle sphere simplifies over several levels, found {levels}");
    // From anywhere, at any threshold: the parent's projected error is never below the child's.
    for eye in [Vec3::new(0.0, 0.0, 1.2), Vec3::new(5.0, 1.0, -3.0), Vec3::new(0.3, -1.4, 0.2)] {
        for k in &c.clusters {
            let (own, parent) =
                (clusters::projected_error(&k.own, eye, 1e-3), clusters::projected_error(&k.parent, eye, 1e-3));
            assert!(own <= parent, "{eye} {k:?}");
        }
    }
}

#[test]
fn the_finest_level_is_the_mesh_each_triangle_once() {
    let mesh = scene();
    let c = clusters::build(&mesh);
    let mut input: Vec<_> = mesh.triangles.iter().map(|t| key(t.v.map(|p| bits(p.to_array())))).collect();
    input.sort_unstable();
    let finest = triangles(&c, c.clusters.iter().copied().filter(Cluster::is_full_detail));
    assert_eq!(finest.len(), mesh.triangles.len());
    assert!(finest == input, "the full-detail clusters hold exactly the mesh's triangles");
    assert!(c.clusters.iter().all(|k| k.triangles() as usize <= clusters::MAX_TRIANGLES && k.triangles() > 0));
}

#[test]
fn surfaces_are_kept_apart_and_emitters_never_simplified() {
    let mesh = scene();
    let c = clusters::build(&mesh);
    for k in &c.clusters {
        assert!(c.triangles_of(k).flatten().all(|v| c.vertex_surface[v as usize] == k.surface), "{k:?}");
    }
    let surfaces: std::collections::BTreeSet<SurfaceId> = c.clusters.iter().map(|k| k.surface).collect();
    assert_eq!(surfaces.into_iter().collect::<Vec<_>>(), [1, 2, 3]);
    let lamp = mesh.surfaces.iter().position(|s| mesh.materials[s.material].is_emitter()).unwrap() as u32 + 1;
    for k in c.clusters.iter().filter(|k| k.surface == lamp) {
        assert!(k.is_full_detail() && k.parent.error == f32::MAX, "an emitter cluster is simplified: {k:?}");
    }
    // The others are simplified: they have coarser versions.
    assert!(c.clusters.iter().any(|k| k.surface != lamp && !k.is_full_detail()));
}

/// Every directed edge of the selected triangles has exactly one twin the other way: no crack, no overlap.
fn assert_watertight(c: &ClusterMesh, chosen: &[Cluster], what: &str) {
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for k in chosen {
        for t in c.triangles_of(k) {
            for e in 0..3 {
                *edges.entry((t[e], t[(e + 1) % 3])).or_default() += 1;
            }
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "{what}: edge {a}–{b} used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "{what}: edge {a}–{b} has no twin (a crack)");
    }
}

#[test]
fn any_selection_of_a_closed_sphere_is_watertight_and_coarser_far_away() {
    let c = clusters::build(&scene());
    let ball: Vec<Cluster> = c.clusters.iter().copied().filter(|k| k.surface == 1).collect();
    let full = ball.iter().filter(|k| k.is_full_detail()).map(|k| k.triangles()).sum::<u32>();
    let mut coarsest = full;
    for eye in [Vec3::new(0.0, 0.0, 1.05), Vec3::new(0.0, 2.0, 2.0), Vec3::new(8.0, 0.0, 0.0), Vec3::splat(40.0)] {
        for tau in [1e-4, 1e-3, 1.0 / 64.0, 0.1, 1.0, 100.0] {
            let chosen: Vec<Cluster> = ball.iter().copied().filter(|k| selected(k, eye, 1e-4, tau)).collect();
            assert_watertight(&c, &chosen, &format!("eye {eye}, τ {tau}"));
            coarsest = coarsest.min(chosen.iter().map(|k| k.triangles()).sum());
        }
    }
    assert!(coarsest * 20 < full, "far away the sphere is coarse: {coarsest} of {full} triangles");
    // At a threshold of 0, the full detail exactly.
    let chosen: Vec<Cluster> = ball.iter().copied().filter(|k| selected(k, Vec3::splat(9.0), 1e-4, 0.0)).collect();
    assert!(chosen.iter().all(Cluster::is_full_detail) && chosen.iter().map(|k| k.triangles()).sum::<u32>() == full);
}

#[test]
fn no_selection_takes_more_clusters_than_the_bound() {
    let c = clusters::build(&scene());
    let bound = clusters::max_selected(&c);
    let full = c.clusters.iter().filter(|k| k.is_full_detail()).count();
    assert!(full <= bound && bound < c.clusters.len(), "{full} ≤ bound {bound} < {} clusters", c.clusters.len());
    let mut most = 0;
    for eye in [Vec3::new(0.0, 0.0, 1.05), Vec3::new(0.0, -1.4, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::splat(40.0)] {
        for tau in [0.0, 1e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 1.0, 100.0] {
            let n = c.clusters.iter().filter(|k| selected(k, eye, 1e-4, tau)).count();
            assert!(n <= bound, "eye {eye}, τ {tau}: {n} clusters selected, bound {bound}");
            most = most.max(n);
        }
    }
    assert_eq!(most, full, "the finest level is the largest selection here");
}

/// A cluster's sphere and slab bound how far its triangles reach along any direction (what the culling
/// pass tests against a sensor's tangent plane), and on a smooth surface the slab is much tighter than the
/// sphere alone along the surface's normal.
#[test]
fn a_clusters_reach_bounds_its_triangles_and_is_tight_along_its_normal() {
    let c = clusters::build(&scene());
    let dirs: Vec<Vec3> = (0..64)
        .map(|i| {
            let (z, phi) = (1.0 - 2.0 * (i as f32 + 0.5) / 64.0, i as f32 * 2.399_963);
            let r = (1.0 - z * z).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    let (mut slab_sum, mut sphere_sum) = (0.0f32, 0.0f32);
    for k in &c.clusters {
        let points: Vec<Vec3> = c.triangles_of(k).flatten().map(|v| Vec3::from(c.positions[v as usize])).collect();
        let axis = Vec3::from_slice(&k.slab[..3]);
        for &dir in dirs.iter().chain([axis, -axis].iter()) {
            let most = points.iter().map(|p| dir.dot(*p)).fold(f32::MIN, f32::max);
            let reach = clusters::reach(k.sphere, k.slab, dir);
            assert!(most <= reach, "{k:?} along {dir}: a corner at {most}, reach {reach}");
        }
        let centre = Vec3::from_slice(&k.sphere[..3]);
        slab_sum += clusters::reach(k.sphere, k.slab, axis) - axis.dot(centre);
        sphere_sum += k.sphere[3];
    }
    assert!(
        slab_sum * 4.0 < sphere_sum,
        "along their normals clusters reach {slab_sum} in all, their spheres {sphere_sum}"
    );
}

/// The bounding tree's walk selects exactly what testing every cluster selects, from near and far, at
/// every threshold, testing a few clusters per cluster it selects; every cluster is in exactly one leaf.
#[test]
fn the_tree_walk_selects_what_testing_every_cluster_selects() {
    let mesh = scene();
    let c = clusters::build(&mesh);
    let tree = CullTree::build(&c, |s| mesh.material_of(s).is_emitter());
    let mut items = tree.items.clone();
    items.sort_unstable();
    assert_eq!(items, (0..c.clusters.len() as u32).collect::<Vec<_>>(), "each cluster in one leaf");
    assert_eq!(tree.per_depth.iter().sum::<u32>() as usize, tree.nodes.len());
    assert!(tree.depth() <= 8, "a shallow tree: depth {}", tree.depth());
    for (i, n) in tree.nodes.iter().enumerate() {
        let count = n.count as usize;
        assert!(if n.leaf { count <= tree::LEAF } else { count >= 1 }, "node {i}: {n:?}");
    }
    let near = 1e-4;
    let (mut tested, mut taken, mut all) = (0usize, 0usize, 0usize);
    for eye in [Vec3::new(0.0, 0.0, 1.001), Vec3::new(0.0, -1.4, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::splat(40.0)] {
        for tau in [0.0, 1e-4, 1e-3, 1.0 / 128.0, 3e-2, 0.1, 1.0, 100.0] {
            let count = std::cell::Cell::new(0usize);
            let mut walked = tree.select(
                |n| n.may_select(eye, near, tau),
                |k| {
                    count.set(count.get() + 1);
                    selected(&c.clusters[k as usize], eye, near, tau)
                },
            );
            walked.sort_unstable();
            let every: Vec<u32> =
                (0..c.clusters.len() as u32).filter(|&k| selected(&c.clusters[k as usize], eye, near, tau)).collect();
            assert_eq!(walked, every, "eye {eye}, τ {tau}");
            tested += count.get();
            taken += every.len();
            all += c.clusters.len();
        }
    }
    // The walk's work follows what it selects (here about 2×), not the hierarchy's size.
    assert!(
        tested <= 3 * taken && tested * 2 < all,
        "the walk tested {tested} clusters to select {taken}; testing each would test {all}"
    );
}

#[test]
fn the_cache_returns_what_was_built_and_rebuilds_what_it_cannot_trust() {
    let mesh = scene();
    let dir = std::env::temp_dir().join(format!("sensorlight-clusters-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (built, note) = cache::load_or_build(&mesh, Some(&dir));
    assert!(note.is_none(), "{note:?}");
    let file = cache::path(&dir, &mesh);
    assert!(file.is_file());
    let (read, _) = cache::load_or_build(&mesh, Some(&dir));
    assert!(read == built);
    let bytes = std::fs::read(&file).unwrap();
    let key = cache::mesh_key(&mesh);
    assert!(cache::decode(&bytes, key).is_some());
    assert!(cache::decode(&bytes, key ^ 1).is_none(), "another mesh's file");
    assert!(cache::decode(&bytes[..bytes.len() - 1], key).is_none(), "a truncated file");
    // A damaged file is rebuilt and replaced.
    std::fs::write(&file, &bytes[..100]).unwrap();
    let (again, _) = cache::load_or_build(&mesh, Some(&dir));
    assert!(again == built && std::fs::read(&file).unwrap() == bytes);
    // A moved vertex is another mesh.
    let mut moved = mesh.clone();
    moved.triangles[0].v[0].x += 1e-3;
    assert_ne!(cache::mesh_key(&moved), key);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A fluted column is two surfaces per flute, each a strip that, simplified alone with its border locked,
/// never went below its 2 × rings triangles. Simplified as one connected part, welded across its flanks
/// (one material): the full detail keeps every triangle's surface; a coarser triangle's corners are of one
/// material, and on a column its first corner's flank (which it is shaded and cached as) faces as it does;
/// the coarsest level is a small share of the full detail and under two triangles a flank (seams kept each
/// flank at two or more: 576 for these 288); any selection far away stays watertight (by positions: each
/// surface keeps its own vertices along the seams).
#[test]
fn a_shape_of_many_surfaces_is_simplified_as_one() {
    let scene = common::hall::hall(16, 8, (32, 24));
    let mesh = &scene.mesh;
    let c = clusters::build(mesh);
    // Each surface's normal at each of its corners, area-weighted.
    let mut normals: HashMap<([u32; 3], SurfaceId), Vec3> = HashMap::new();
    for t in &mesh.triangles {
        let n = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]);
        for p in t.v {
            *normals.entry((bits(p.to_array()), t.surface)).or_default() += n;
        }
    }
    for k in &c.clusters {
        for t in c.triangles_of(k) {
            let s = t.map(|v| c.vertex_surface[v as usize]);
            if k.is_full_detail() {
                assert!(s.iter().all(|&x| x == s[0]), "a full-detail triangle across surfaces in {k:?}");
                continue;
            }
            let material = s.map(|x| mesh.surfaces[x as usize - 1].material);
            assert!(material.iter().all(|&m| m == material[0]), "a triangle across materials in {k:?}");
            let p = t.map(|v| Vec3::from(c.positions[v as usize]));
            let facet = (p[1] - p[0]).cross(p[2] - p[0]);
            let first = normals[&(bits(c.positions[t[0] as usize]), s[0])];
            let flanks = mesh.surfaces[s[0] as usize - 1].name.starts_with("columns/");
            assert!(!flanks || first.dot(facet) > 0.0, "a facet of {k:?} shaded as a flank facing away from it");
        }
    }
    let column = |k: &&Cluster| mesh.surfaces[k.surface as usize - 1].name.starts_with("columns/");
    let full: u32 = c.clusters.iter().filter(column).filter(|k| k.is_full_detail()).map(|k| k.triangles()).sum();
    // The coarsest level: what a view far away selects.
    let far = Vec3::new(0.0, 3.0, 60.0);
    let coarsest: u32 =
        c.clusters.iter().filter(column).filter(|k| selected(k, far, 1e-3, 0.02)).map(|k| k.triangles()).sum();
    let surfaces = mesh.surfaces.iter().filter(|s| s.name.starts_with("columns/")).count() as u32;
    assert_eq!(full, 6 * 2 * 144 * 16);
    assert!(coarsest * 10 <= full, "the columns' coarsest level has {coarsest} of {full} triangles");
    assert!(coarsest < 2 * surfaces, "{coarsest} triangles for {surfaces} flanks: the flutes did not fold");
    // Far away, by positions: every edge of the selected columns has its twin.
    let eye = Vec3::new(0.0, 3.0, 60.0);
    let chosen: Vec<Cluster> =
        c.clusters.iter().filter(column).copied().filter(|k| selected(k, eye, 1e-3, 0.02)).collect();
    let edges = edges_by_position(&c, &chosen);
    // The shafts are open tubes: only their top and bottom rims may have no twin.
    let inside = |p: [u32; 3]| {
        let y = f32::from_bits(p[1]);
        y > 0.31 && y < 5.29
    };
    let open: Vec<_> = edges.keys().filter(|(a, b)| !edges.contains_key(&(*b, *a))).collect();
    assert!(!open.is_empty(), "the rims are open");
    assert!(open.iter().all(|(a, b)| !(inside(*a) || inside(*b))), "a crack between two flanks");
}

/// How often each directed edge of the selected triangles occurs, by its corners' positions (surfaces keep
/// their own vertices, so ids differ across a seam).
fn edges_by_position(c: &ClusterMesh, chosen: &[Cluster]) -> HashMap<([u32; 3], [u32; 3]), i32> {
    let mut edges = HashMap::new();
    for k in chosen {
        for t in c.triangles_of(k) {
            for e in 0..3 {
                let (a, b) = (bits(c.positions[t[e] as usize]), bits(c.positions[t[(e + 1) % 3] as usize]));
                *edges.entry((a, b)).or_default() += 1;
            }
        }
    }
    edges
}

/// Every directed edge of the selected triangles, by its corners' positions, has exactly one twin the
/// other way.
fn assert_closed(c: &ClusterMesh, chosen: &[Cluster], what: &str) {
    let edges = edges_by_position(c, chosen);
    for (&(a, b), &n) in &edges {
        assert!(n == 1 && edges.get(&(b, a)) == Some(&1), "{what}: edge {a:?}–{b:?} used {n} times, or no twin");
    }
}

/// The shortest distance from `p` to the triangle `t`.
fn to_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    let n = (b - a).cross(c - a).normalize();
    let q = p - n * n.dot(p - a);
    let inside = [(a, b), (b, c), (c, a)].iter().all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
    if inside {
        return (p - q).length();
    }
    let to_segment = |u: Vec3, v: Vec3| {
        let t = ((p - u).dot(v - u) / (v - u).length_squared()).clamp(0.0, 1.0);
        (p - (u + t * (v - u))).length()
    };
    to_segment(a, b).min(to_segment(b, c)).min(to_segment(c, a))
}

/// A part of one cluster (a small closed ball beside the big one) is drawn from afar at simpler levels,
/// not at full detail until it vanishes: each level three quarters or less of the last, one level chosen per
/// view and always closed, its error honest (the two surfaces lie within it of each other) and growing; an
/// emitter of one cluster keeps its full detail.
#[test]
fn a_small_part_has_simpler_levels_each_closed() {
    let ball = common::meshes::sphere(Vec3::new(3.0, 0.0, 0.0), 0.25, 6);
    assert!(ball.len() <= clusters::MAX_TRIANGLES);
    let mut lamp = common::meshes::plane(3.0, 4);
    lamp.iter_mut().for_each(|t| t.swap(1, 2));
    let mesh = common::meshes::mesh(&[
        ("big", 0, common::meshes::sphere(Vec3::ZERO, 1.0, 32)),
        ("small", 0, ball.clone()),
        ("lamp", 1, lamp),
    ]);
    let c = clusters::build(&mesh);
    let small_surface = |s: u32| mesh.surfaces[s as usize - 1].name.starts_with("small");
    let small: Vec<Cluster> = c.clusters.iter().copied().filter(|k| small_surface(k.surface)).collect();
    assert!(small.len() >= 2, "the small ball has simpler levels: {} clusters", small.len());
    let full = small[0].triangles();
    assert_eq!(full as usize, ball.len());
    for (depth, pair) in small.windows(2).enumerate() {
        let (finer, coarser) = (pair[0], pair[1]);
        assert_eq!((finer.depth, coarser.depth), (depth as u32, depth as u32 + 1));
        assert_eq!(finer.parent, coarser.own, "a level replaces exactly the one before");
        assert!(coarser.triangles() * 4 <= finer.triangles() * 3, "{} → {}", finer.triangles(), coarser.triangles());
        assert!(coarser.own.error > finer.own.error);
        // Honest both ways: the mesh's corners and centroids lie within the error of the level's surface, and
        // the level's edges' middles within it of the mesh's.
        let level: Vec<[Vec3; 3]> =
            c.triangles_of(&coarser).map(|t| t.map(|v| Vec3::from(c.positions[v as usize]))).collect();
        let strays = |points: Vec<Vec3>, surface: &[[Vec3; 3]]| {
            let nearest = |p: Vec3| surface.iter().map(|&t| to_triangle(p, t)).fold(f32::MAX, f32::min);
            points.into_iter().map(nearest).fold(0.0f32, f32::max)
        };
        let corners_and_centroids = ball.iter().flat_map(|&[a, b, c]| [a, b, c, (a + b + c) / 3.0]).collect();
        let middles = level.iter().flat_map(|&[a, b, c]| [(a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0]).collect();
        let worst = strays(corners_and_centroids, &level).max(strays(middles, &ball));
        assert!(
            worst <= coarser.own.error * (1.0 + 1e-5),
            "depth {}: {worst} off, error {}",
            coarser.depth,
            coarser.own.error
        );
    }
    let coarsest = small.last().unwrap();
    assert!(
        coarsest.triangles() * 8 <= full,
        "the coarsest of {} levels has {} of {full} triangles",
        small.len(),
        coarsest.triangles()
    );
    // From any viewpoint at any threshold: one level, closed, or nothing once the ball is under τ.
    for eye in [Vec3::new(3.0, 0.0, 0.3), Vec3::new(0.0, 0.0, 3.0), Vec3::splat(40.0)] {
        for tau in [0.0, 1e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 100.0] {
            let chosen: Vec<Cluster> = small.iter().copied().filter(|k| selected(k, eye, 1e-4, tau)).collect();
            assert!(chosen.len() <= 1, "eye {eye}, τ {tau}: {} levels at once", chosen.len());
            assert_closed(&c, &chosen, &format!("eye {eye}, τ {tau}"));
        }
    }
    let lamp: Vec<&Cluster> =
        c.clusters.iter().filter(|k| mesh.surfaces[k.surface as usize - 1].name.starts_with("lamp")).collect();
    assert!(lamp.len() == 1 && lamp[0].is_full_detail() && lamp[0].parent.error == f32::MAX, "{lamp:?}");
}

/// Which of the hall's parts hide their back faces from outside (`clusters::closed`): its boxes, pedestals
/// and spheres are closed and face out, and its shafts are open tubes whose ends the plinths and capitals
/// cap; its shell faces in, so its back faces may show. Each of their clusters carries its part's box,
/// holding all of the part's clusters; a shaft's holds its plinth and capital too.
#[test]
fn the_hall_s_closed_parts_are_its_boxes_spheres_and_capped_shafts() {
    let scene = common::hall::hall(16, 8, (32, 24));
    let mesh = &scene.mesh;
    let c = clusters::build(mesh);
    let group = |k: &Cluster| mesh.surfaces[k.surface as usize - 1].name.split('/').next().unwrap().to_owned();
    let mut closed: HashMap<String, (usize, usize)> = HashMap::new();
    for k in &c.clusters {
        let entry = closed.entry(group(k)).or_default();
        if k.closed != 0 {
            entry.0 += 1;
        } else {
            entry.1 += 1;
        }
        let part = Aabb { min: Vec3::from(k.part_min), max: Vec3::from(k.part_max) };
        for v in c.triangles_of(k).flatten().filter(|_| k.closed != 0) {
            let p = Vec3::from(c.positions[v as usize]);
            assert!(
                p.cmpge(part.min).all() && p.cmple(part.max).all(),
                "{}: a corner outside its part's box",
                group(k)
            );
        }
    }
    eprintln!("(closed, open) clusters by group: {closed:?}");
    for name in ["boxes", "pedestals", "spheres", "columns"] {
        assert!(closed[name].0 > 0 && closed[name].1 == 0, "{name}: {:?} clusters (closed, open)", closed[name]);
    }
    let shaft = c.clusters.iter().find(|k| group(k) == "columns").unwrap();
    let height = shaft.part_max[1] - shaft.part_min[1];
    assert!(height > 5.9, "a shaft's box holds its plinth and capital: {height} m high");
    for name in ["shell", "panels"] {
        assert!(closed[name].0 == 0 && closed[name].1 > 0, "{name}: {:?} clusters (closed, open)", closed[name]);
    }
}
