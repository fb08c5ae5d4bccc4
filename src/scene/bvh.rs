//! A bounding volume hierarchy over the scene's triangles, built with binned SAH (Wald 2007), traversed
//! nearest child first. Leaves store copies of their triangles' vertices for locality. The CPU reference
//! traces with it, and the refinement casts its shadow-ray hints (`sensors::hints`). Built for a mesh
//! ([`Bvh::of_mesh`]), its rays pass through the mesh's cut-outs.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::material::Cutout;
use super::ray::{Ray, RayShear};
use super::{Aabb, Mesh, Texture, Triangle};

const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Cost of one traversal step relative to one triangle test.
const TRAVERSAL_COST: f32 = 1.0;

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Interior: index of the left child (the right one follows it). Leaf: first triangle.
    first: u32,
    /// Triangles in a leaf; 0 for an interior node.
    count: u32,
}

pub struct Bvh {
    nodes: Vec<Node>,
    vertices: Vec<[Vec3; 3]>,
    /// Original triangle index of each stored triangle.
    order: Vec<u32>,
    /// Where the mesh it was built from has cut-outs ([`Bvh::of_mesh`]), rays pass through them.
    cutouts: Option<Cutouts>,
}

/// The cut-outs of the stored triangles: each one's texture coordinates and alpha test, if it has one.
struct Cutouts {
    tests: Vec<Option<([Vec2; 3], Cutout)>>,
    textures: Arc<Vec<Texture>>,
}

impl Cutouts {
    /// Whether stored triangle `k` (corners `v`) exists at `p`: its cut-out's alpha there, bilinear at full
    /// resolution, at least the threshold, as `glsl/gbuffer.frag` and `glsl/sensor.frag` test a fragment.
    fn opaque(&self, k: usize, v: &[Vec3; 3], p: Vec3) -> bool {
        let Some((uvs, cutout)) = &self.tests[k] else { return true };
        self.textures[cutout.map].sample(super::interpolate(v, uvs, p), 0.0).w >= cutout.threshold
    }
}

/// Where a walk along a ray stops: at the nearest hit, or at any (a shadow ray's question).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Stop {
    Nearest,
    Any,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Index into the mesh's triangles.
    pub triangle: u32,
}

impl Bvh {
    pub fn build(triangles: &[Triangle]) -> Self {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<Vec3> = triangles.iter().map(|t| (t.v[0] + t.v[1] + t.v[2]) / 3.0).collect();
        let bounds: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                t.v.iter().for_each(|&p| b.grow(p));
                b
            })
            .collect();
        let mut nodes = vec![Node { bounds: Aabb::EMPTY, first: 0, count: 0 }];
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((node, start, end)) = stack.pop() {
            let mut node_bounds = Aabb::EMPTY;
            let mut centroid_bounds = Aabb::EMPTY;
            for &i in &order[start..end] {
                node_bounds = node_bounds.union(bounds[i as usize]);
                centroid_bounds.grow(centroids[i as usize]);
            }
            nodes[node].bounds = node_bounds;
            let count = end - start;
            let split = if count > MAX_LEAF {
                best_split(&order[start..end], &centroids, &bounds, node_bounds, centroid_bounds)
            } else {
                None
            };
            let Some((axis, position)) = split else {
                nodes[node].first = start as u32;
                nodes[node].count = count as u32;
                continue;
            };
            let mid = start + partition(&mut order[start..end], |i| centroids[i as usize][axis] < position);
            let mid = if mid == start || mid == end { start + count / 2 } else { mid };
            let left = nodes.len();
            nodes.push(Node { bounds: Aabb::EMPTY, first: 0, count: 0 });
            nodes.push(Node { bounds: Aabb::EMPTY, first: 0, count: 0 });
            nodes[node].first = left as u32;
            stack.push((left, start, mid));
            stack.push((left + 1, mid, end));
        }
        let vertices = order.iter().map(|&i| triangles[i as usize].v).collect();
        Self { nodes, vertices, order, cutouts: None }
    }

    /// The BVH of `mesh`'s triangles, through whose cut-outs (`Material::cutout`) rays pass.
    pub fn of_mesh(mesh: &Mesh) -> Self {
        let mut bvh = Self::build(&mesh.triangles);
        if mesh.has_cutouts() {
            let test = |i: usize| {
                let cutout = mesh.material_of(mesh.triangles[i].surface).cutout?;
                Some((mesh.uvs[i], cutout))
            };
            let tests = bvh.order.iter().map(|&i| test(i as usize)).collect();
            bvh.cutouts = Some(Cutouts { tests, textures: mesh.textures.clone() });
        }
        bvh
    }

    /// The nearest hit in `(t_min, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.walk(ray, (t_min, t_max), Stop::Nearest)
    }

    /// Whether any triangle (cut-outs passed through) lies along `ray` in `(t_min, t_max)`: a shadow ray's
    /// question, answered at the first hit the walk meets rather than the nearest. The same answer as
    /// `intersect(..).is_some()`, for less of the tree.
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.walk(ray, (t_min, t_max), Stop::Any).is_some()
    }

    /// The walk along `ray` that `stop` asks for, cut-outs passed through.
    fn walk(&self, ray: &Ray, (t_min, t_max): (f32, f32), stop: Stop) -> Option<Hit> {
        match &self.cutouts {
            Some(c) => self.intersect_where(ray, t_min, t_max, stop, |k, t| c.opaque(k, &self.vertices[k], ray.at(t))),
            None => self.intersect_where(ray, t_min, t_max, stop, |_, _| true),
        }
    }

    /// The nearest hit in `(t_min, t_max)` that `accept(stored triangle, t)`, or with [`Stop::Any`] the first
    /// one found.
    fn intersect_where(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        stop: Stop,
        accept: impl Fn(usize, f32) -> bool,
    ) -> Option<Hit> {
        let shear = RayShear::new(ray);
        let inv = ray.dir.recip();
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if slab(&node.bounds, ray.origin, inv, t_best).is_none() {
                continue;
            }
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for k in range {
                    if let Some(t) = shear.intersect(&self.vertices[k], t_best)
                        && t > t_min
                        && accept(k, t)
                    {
                        t_best = t;
                        best = Some(Hit { t, triangle: self.order[k] });
                        if stop == Stop::Any {
                            return best;
                        }
                    }
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let tl = slab(&self.nodes[l as usize].bounds, ray.origin, inv, t_best);
            let tr = slab(&self.nodes[r as usize].bounds, ray.origin, inv, t_best);
            // Push the farther child first so the nearer one is visited next.
            match (tl, tr) {
                (Some(a), Some(b)) => {
                    let (near, far) = if a <= b { (l, r) } else { (r, l) };
                    stack[top] = far;
                    stack[top + 1] = near;
                    top += 2;
                }
                (Some(_), None) => {
                    stack[top] = l;
                    top += 1;
                }
                (None, Some(_)) => {
                    stack[top] = r;
                    top += 1;
                }
                (None, None) => {}
            }
        }
        best
    }

    pub fn depth(&self) -> usize {
        fn walk(nodes: &[Node], i: usize) -> usize {
            let n = &nodes[i];
            if n.count > 0 { 1 } else { 1 + walk(nodes, n.first as usize).max(walk(nodes, n.first as usize + 1)) }
        }
        walk(&self.nodes, 0)
    }
}

/// Entry distance of the ray into `b` if it enters before `t_max`.
#[inline]
fn slab(b: &Aabb, origin: Vec3, inv: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (b.min - origin) * inv;
    let t1 = (b.max - origin) * inv;
    // NaN (0 · ∞ for a ray in a slab's plane) is dropped by min/max, keeping the test conservative.
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max);
    (near <= far).then_some(near)
}

fn best_split(
    items: &[u32],
    centroids: &[Vec3],
    bounds: &[Aabb],
    node_bounds: Aabb,
    centroid_bounds: Aabb,
) -> Option<(usize, f32)> {
    let extent = centroid_bounds.max - centroid_bounds.min;
    let leaf_cost = items.len() as f32;
    let mut best: Option<(f32, usize, f32)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of = |c: Vec3| (((c[axis] - centroid_bounds.min[axis]) * scale) as usize).min(BINS - 1);
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0usize; BINS];
        for &i in items {
            let b = bin_of(centroids[i as usize]);
            bin_bounds[b] = bin_bounds[b].union(bounds[i as usize]);
            bin_counts[b] += 1;
        }
        // Sweep from the right, then from the left, evaluating the SAH at each bin boundary.
        let mut right_area = [0.0f32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        let mut right_count = [0usize; BINS];
        for b in (1..BINS).rev() {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b];
            right_area[b] = area(&acc);
            right_count[b] = count;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for b in 1..BINS {
            acc = acc.union(bin_bounds[b - 1]);
            count += bin_counts[b - 1];
            if count == 0 || right_count[b] == 0 {
                continue;
            }
            let cost = area(&acc) * count as f32 + right_area[b] * right_count[b] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, centroid_bounds.min[axis] + b as f32 / scale));
            }
        }
    }
    let parent_area = area(&node_bounds).max(f32::MIN_POSITIVE);
    // Split when the SAH says so, and always when a leaf would be large.
    best.filter(|&(cost, _, _)| TRAVERSAL_COST + cost / parent_area < leaf_cost || items.len() > 4 * MAX_LEAF)
        .map(|(_, axis, pos)| (axis, pos))
}

fn area(b: &Aabb) -> f32 {
    let d = (b.max - b.min).max(Vec3::ZERO);
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}

/// Moves the items satisfying `pred` to the front; returns how many there are.
fn partition(items: &mut [u32], pred: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if pred(items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny deterministic generator for the test's random triangles and rays.
    fn lcg(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*state >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn bvh_agrees_with_brute_force() {
        let mut s = 7;
        let mut tris = Vec::new();
        for _ in 0..500 {
            let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0;
            let v = [c, c + Vec3::new(lcg(&mut s), lcg(&mut s), 0.1), c + Vec3::new(0.2, lcg(&mut s), lcg(&mut s))];
            tris.push(Triangle { v, normal: Vec3::Z, surface: 1 });
        }
        let bvh = Bvh::build(&tris);
        assert!(bvh.depth() < 40);
        for _ in 0..2000 {
            let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 12.0 - 1.0;
            let d = Vec3::new(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5);
            let ray = Ray::new(o, d);
            let shear = RayShear::new(&ray);
            let brute = tris
                .iter()
                .enumerate()
                .filter_map(|(i, t)| shear.intersect(&t.v, f32::INFINITY).map(|t| (t, i)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let fast = bvh.intersect(&ray, 0.0, f32::INFINITY);
            assert_eq!(brute.map(|(t, i)| (t, i as u32)), fast.map(|h| (h.t, h.triangle)));
            // A shadow ray to a point along it: blocked exactly where a triangle lies nearer than the point.
            let t_max = 0.5 + 12.0 * lcg(&mut s);
            let blocked = brute.is_some_and(|(t, _)| t < t_max);
            assert_eq!(bvh.occluded(&ray, 0.0, t_max), blocked, "ray {ray:?} to t = {t_max}");
        }
    }
}
