//! A bounding volume hierarchy over the scene's triangles, built binary with binned SAH (Wald 2007), then
//! collapsed to four children a node (Dammertz et al. 2008, "Shallow bounding volume hierarchies"), whose
//! boxes one walk step tests at once, four lanes wide; traversed nearest child first. A ray's walk is
//! bound by memory, not arithmetic: in a 0.55 M-triangle hall a shadow ray tested about 50 boxes in 27
//! steps of the binary tree, and visits about 14 nodes of this one, each two cache lines. Leaves store
//! copies of their triangles' vertices for locality. The CPU reference traces with it, and the refinement
//! casts its shadow-ray hints (`sensors::hints`). Built for a mesh ([`Bvh::of_mesh`]), its rays pass
//! through the mesh's cut-outs.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::material::Cutout;
use super::ray::{Ray, RayShear};
use super::{Aabb, Mesh, Texture, Triangle};

const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Cost of one traversal step relative to one triangle test.
const TRAVERSAL_COST: f32 = 1.0;

/// A node of the binary tree that the SAH build makes and [`Node4`]s are collapsed from.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Interior: index of the left child (the right one follows it). Leaf: first triangle.
    first: u32,
    /// Triangles in a leaf; 0 for an interior node.
    count: u32,
}

/// Up to four children's boxes, one lane each (x, y, z of the minimum corners, then of the maximum), and
/// what each child is: a [`Child`]. Lanes past `lanes` hold empty boxes and are masked off.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node4 {
    min: [Vec4; 3],
    max: [Vec4; 3],
    child: [Child; 4],
    /// One bit a child that exists.
    lanes: u32,
}

/// A [`Node4`]'s child: another node (its index in `nodes`), or a leaf (`LEAF` set: the index in `leaves`).
type Child = u32;
const LEAF: Child = 1 << 31;

/// A leaf's stored triangles.
#[derive(Clone, Copy, Debug)]
struct Leaf {
    first: u32,
    count: u32,
}

pub struct Bvh {
    nodes: Vec<Node4>,
    leaves: Vec<Leaf>,
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
        let mut stack = vec![(0usize, 0usize, order.len(), 1usize)];
        while let Some((node, start, end, depth)) = stack.pop() {
            let mut node_bounds = Aabb::EMPTY;
            let mut centroid_bounds = Aabb::EMPTY;
            for &i in &order[start..end] {
                node_bounds = node_bounds.union(bounds[i as usize]);
                centroid_bounds.grow(centroids[i as usize]);
            }
            nodes[node].bounds = node_bounds;
            let count = end - start;
            if count > MAX_LEAF && depth >= MEDIAN_DEPTH {
                // Deep enough that SAH's uneven splits could outgrow the walk's stack: halve by the median.
                let axis = (centroid_bounds.max - centroid_bounds.min).max_position();
                let key = |&i: &u32| centroids[i as usize][axis];
                order[start..end].select_nth_unstable_by(count / 2, |a, b| key(a).total_cmp(&key(b)));
                let left = nodes.len();
                nodes.extend([Node { bounds: Aabb::EMPTY, first: 0, count: 0 }; 2]);
                nodes[node].first = left as u32;
                stack.extend([
                    (left, start, start + count / 2, depth + 1),
                    (left + 1, start + count / 2, end, depth + 1),
                ]);
                continue;
            }
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
            stack.push((left, start, mid, depth + 1));
            stack.push((left + 1, mid, end, depth + 1));
        }
        let vertices = order.iter().map(|&i| triangles[i as usize].v).collect();
        let (nodes, leaves) = collapse(&nodes);
        Self { nodes, leaves, vertices, order, cutouts: None }
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
        let origin = ray.origin.to_array().map(Vec4::splat);
        let inv = ray.dir.recip().to_array().map(Vec4::splat);
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        // Each entry: a child, and where the ray enters its box (tested when its parent was visited, so that
        // a box is tested once, and a child skipped once a nearer hit has been found). A node pushes at most
        // three children beside the one visited next, so the stack holds three a level.
        let mut stack = [(0 as Child, 0.0f32); 3 * MAX_DEPTH + 1];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (child, t_enter) = stack[top];
            if t_enter > t_best {
                continue;
            }
            if child & LEAF != 0 {
                let leaf = self.leaves[(child & !LEAF) as usize];
                for k in leaf.first as usize..(leaf.first + leaf.count) as usize {
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
            let node = &self.nodes[child as usize];
            let (near, hit) = slabs(node, origin, inv, t_best);
            // The children entered, pushed farthest first so that the nearest is visited next: an insertion
            // sort in place on the stack (a copy of a few entries from elsewhere compiled to a `memmove` call,
            // 15 % of the supersampling's time).
            let base = top;
            let mut lanes = hit;
            while lanes != 0 {
                let lane = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let mut i = top;
                while i > base && stack[i - 1].1 < near[lane] {
                    stack[i] = stack[i - 1];
                    i -= 1;
                }
                stack[i] = (node.child[lane], near[lane]);
                top += 1;
            }
        }
        best
    }

    /// Nodes from the root to the deepest leaf, the leaf counted.
    pub fn depth(&self) -> usize {
        fn walk(nodes: &[Node4], child: Child) -> usize {
            if child & LEAF != 0 {
                return 1;
            }
            let node = &nodes[child as usize];
            let children = (0..4).filter(|&lane| node.lanes & (1 << lane) != 0);
            1 + children.map(|lane| walk(nodes, node.child[lane])).max().unwrap_or(0)
        }
        walk(&self.nodes, 0)
    }
}

/// From this depth on the binary build halves a node at its median instead of by SAH, so that no tree is
/// deeper than [`MAX_DEPTH`] whatever the mesh (SAH may peel a few triangles off at each level).
const MEDIAN_DEPTH: usize = 48;
/// The deepest the binary tree, and so the [`Node4`] tree collapsed from it (each of whose levels takes at
/// least one of the binary tree's on every path), may be: [`MEDIAN_DEPTH`], then halvings of at most 2³²
/// triangles. The walk's stack is sized by it.
const MAX_DEPTH: usize = MEDIAN_DEPTH + 32;

/// The four-wide tree of the binary one `binary` (root at 0): each node takes its binary node's two children
/// and opens the largest interior one of them (by surface area) until it has four; a binary leaf stays a
/// leaf. Its root is node 0; the leaves are listed apart.
fn collapse(binary: &[Node]) -> (Vec<Node4>, Vec<Leaf>) {
    let mut nodes = Vec::new();
    let mut leaves = Vec::new();
    let root = &binary[0];
    if binary.len() == 1 {
        // A tree of one leaf: a root node with that leaf as its only child, none where it is empty.
        leaves.push(Leaf { first: root.first, count: root.count });
        let children = [(root.bounds, LEAF)];
        nodes.push(node4(&children[..(root.count > 0) as usize]));
        return (nodes, leaves);
    }
    // (binary interior node, the Node4 slot that becomes it)
    nodes.push(node4(&[]));
    let mut stack = vec![(0usize, 0usize)];
    while let Some((b, slot)) = stack.pop() {
        let first = binary[b].first as usize;
        let mut open = vec![first, first + 1];
        while open.len() < 4 {
            let largest = (0..open.len())
                .filter(|&i| binary[open[i]].count == 0)
                .max_by(|&i, &j| area(&binary[open[i]].bounds).total_cmp(&area(&binary[open[j]].bounds)));
            let Some(i) = largest else { break };
            let c = binary[open.swap_remove(i)].first as usize;
            open.extend([c, c + 1]);
        }
        let children: Vec<(Aabb, Child)> = open
            .iter()
            .map(|&c| {
                let n = &binary[c];
                if n.count > 0 {
                    leaves.push(Leaf { first: n.first, count: n.count });
                    (n.bounds, LEAF | (leaves.len() - 1) as Child)
                } else {
                    nodes.push(node4(&[]));
                    stack.push((c, nodes.len() - 1));
                    (n.bounds, (nodes.len() - 1) as Child)
                }
            })
            .collect();
        nodes[slot] = node4(&children);
    }
    (nodes, leaves)
}

/// A node of `children` (at most four): their boxes lane by lane, the other lanes empty and off.
fn node4(children: &[(Aabb, Child)]) -> Node4 {
    let mut node = Node4 { min: [Vec4::INFINITY; 3], max: [Vec4::NEG_INFINITY; 3], child: [0; 4], lanes: 0 };
    for (lane, &(b, child)) in children.iter().enumerate() {
        for axis in 0..3 {
            node.min[axis][lane] = b.min[axis];
            node.max[axis][lane] = b.max[axis];
        }
        node.child[lane] = child;
        node.lanes |= 1 << lane;
    }
    node
}

/// Where the ray enters each of `node`'s children's boxes, and one bit a child whose box it enters before
/// `t_max` (the lanes of no child masked off).
#[inline]
fn slabs(node: &Node4, origin: [Vec4; 3], inv: [Vec4; 3], t_max: f32) -> ([f32; 4], u32) {
    let t0: [Vec4; 3] = std::array::from_fn(|a| (node.min[a] - origin[a]) * inv[a]);
    let t1: [Vec4; 3] = std::array::from_fn(|a| (node.max[a] - origin[a]) * inv[a]);
    // NaN (0 · ∞ for a ray in a slab's plane): a lane's vector min/max with a NaN gives the next operand, so
    // a NaN only lowers `near` or raises `far` (the last operands, 0 and `t_max`, are numbers): the test stays
    // conservative.
    let near = t0[0].min(t1[0]).max(t0[1].min(t1[1])).max(t0[2].min(t1[2])).max(Vec4::ZERO);
    let far = t0[0].max(t1[0]).min(t0[1].max(t1[1])).min(t0[2].max(t1[2])).min(Vec4::splat(t_max));
    (near.to_array(), near.cmple(far).bitmask() & node.lanes)
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
        let empty = Bvh::build(&[]);
        assert!(empty.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), 0.0, f32::INFINITY).is_none(), "no triangles");
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
