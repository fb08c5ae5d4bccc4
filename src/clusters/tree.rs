//! A bounding tree over the clusters, so that selecting what one viewpoint draws costs in proportion to what
//! it selects, not to the whole hierarchy (docs/DESIGN.md §9). In the manner of Nanite's hierarchy: one
//! tree per level of the hierarchy (the clusters of one depth, whose errors are of one scale), each level's
//! root a child of the one root.
//!
//! ```text
//!                          root
//!          ┌─────────────┬──┴───────────┬─────────── …
//!      level 0        level 1        level 2          (one tree per depth, terminal clusters apart)
//!     ┌──┬┴─┬──┐     ┌──┬┴─┐          …
//!     n  n  n  n     n  n  n          ≤ BRANCH children per node, split at the median of the longest axis
//!    ┌┴┐ …           …
//!   leaf: ≤ LEAF clusters (as indices into `CullTree::items`)
//! ```
//!
//! Each node bounds its clusters three ways, each holding theirs: `sphere` (their triangles' bounding
//! spheres: view culling), `parent` (a box) with the *largest* parent error and `own` (a box) with the
//! *smallest* own error. From any eye the node's projected parent error is then at least each cluster's
//! and its own error over the distance to its box's farthest point at most each cluster's projected own
//! error, so where [`TreeNode::may_select`] says no, no cluster below is selected (`own ≤ τ < parent`,
//! `select::selected`), and a walk that stops there selects exactly what testing every cluster would
//! ([`CullTree::select`]; tests/clusters.rs).

use glam::Vec3;

use super::{ClusterMesh, ErrorBounds, projected_error};
use crate::scene::Aabb;

/// Children per inner node at most: wide, so that the tree is shallow (the GPU walks it one depth per
/// dispatch). Typical 8.
pub const BRANCH: usize = 8;
/// Clusters per leaf at most (one GPU invocation tests them in turn). Typical 8.
pub const LEAF: usize = 8;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TreeNode {
    /// Holds the bounding spheres of every cluster below (centre, radius).
    pub sphere: [f32; 4],
    /// A box holding every cluster's `parent` box, with the largest of their errors
    /// (`ErrorBounds::TERMINAL` if any is terminal).
    pub parent: ErrorBounds,
    /// A box holding every cluster's `own` box, with the smallest of their errors (0 if any is full
    /// detail).
    pub own: ErrorBounds,
    /// Leaf: `CullTree::items[first..first + count]` are its clusters; else `nodes[first..first + count]`
    /// are its children.
    pub first: u32,
    pub count: u32,
    pub leaf: bool,
    /// Whether any cluster below belongs to an emitter.
    pub emitter: bool,
}

impl TreeNode {
    /// Whether a cluster below may be selected from `eye` at threshold `tau` (as `select::selected` with
    /// the same `near`): false when even the largest parent error projects to at most `tau` (everything
    /// below is replaced by a coarser version), or the smallest own error to more (everything below is too
    /// coarse).
    pub fn may_select(&self, eye: Vec3, near: f32, tau: f32) -> bool {
        projected_error(&self.parent, eye, near) > tau
            && self.own.error / self.own.aabb().farthest(eye).max(near) <= tau
    }
}

/// The tree: `nodes[root]` is the root; every node but it is some node's child.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CullTree {
    pub nodes: Vec<TreeNode>,
    /// Cluster indices, leaf by leaf.
    pub items: Vec<u32>,
    pub root: u32,
    /// Nodes at each depth: `[1, …]` (the root alone at depth 0).
    pub per_depth: Vec<u32>,
}

impl CullTree {
    /// The tree over `mesh`'s clusters; `emitter(surface)` says which surfaces emit.
    pub fn build(mesh: &ClusterMesh, emitter: impl Fn(u32) -> bool) -> Self {
        // Levels: the clusters of one depth; terminal ones (nothing replaces them: emitters, small surfaces)
        // apart, since a terminal cluster makes every node holding it unprunable by error.
        let mut levels: Vec<((u32, bool), Vec<u32>)> = Vec::new();
        for (i, c) in mesh.clusters.iter().enumerate() {
            let key = (c.depth, c.parent.error == ErrorBounds::TERMINAL);
            match levels.iter_mut().find(|(k, _)| *k == key) {
                Some((_, members)) => members.push(i as u32),
                None => levels.push((key, vec![i as u32])),
            }
        }
        levels.sort_by_key(|(k, _)| *k);
        let mut tree = CullTree::default();
        let builder = Builder { mesh, emitter: &emitter };
        let roots: Vec<TreeNode> = levels.into_iter().map(|(_, mut m)| builder.node(&mut tree, &mut m)).collect();
        let root = match roots.len() {
            0 => builder.leaf(&mut tree, &[]),
            _ => builder.inner(&mut tree, roots),
        };
        tree.root = tree.nodes.len() as u32;
        tree.nodes.push(root);
        tree.per_depth = tree.count_depths();
        tree
    }

    /// Depth of the deepest node (the root is at 0): a walk takes that many steps plus one.
    pub fn depth(&self) -> u32 {
        self.per_depth.len() as u32 - 1
    }

    fn count_depths(&self) -> Vec<u32> {
        let mut per_depth = Vec::new();
        let mut level = vec![self.root];
        while !level.is_empty() {
            per_depth.push(level.len() as u32);
            level = level
                .iter()
                .map(|&n| &self.nodes[n as usize])
                .filter(|n| !n.leaf)
                .flat_map(|n| n.first..n.first + n.count)
                .collect();
        }
        per_depth
    }

    /// The clusters a walk from the root takes: it enters a node only where `enter` says so (the root
    /// always), and takes a leaf's cluster where `take` says so. With `enter` = [`TreeNode::may_select`]
    /// (and any culling that holds for a node's sphere when it holds for each cluster's) and `take` = the
    /// same rule per cluster, this is exactly the clusters that `take` alone accepts.
    pub fn select(&self, enter: impl Fn(&TreeNode) -> bool, take: impl Fn(u32) -> bool) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack = vec![self.root];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            let range = node.first as usize..(node.first + node.count) as usize;
            if node.leaf {
                out.extend(self.items[range].iter().copied().filter(|&c| take(c)));
            } else {
                stack.extend(range.filter(|&c| enter(&self.nodes[c])).map(|c| c as u32));
            }
        }
        out
    }
}

struct Builder<'a, F> {
    mesh: &'a ClusterMesh,
    emitter: &'a F,
}

impl<F: Fn(u32) -> bool> Builder<'_, F> {
    /// The subtree over `members` (cluster indices), its nodes below it pushed into `tree`.
    fn node(&self, tree: &mut CullTree, members: &mut [u32]) -> TreeNode {
        if members.len() <= LEAF {
            return self.leaf(tree, members);
        }
        let mut parts = Vec::with_capacity(BRANCH);
        self.split(members, BRANCH, &mut parts);
        let children = parts.into_iter().map(|part| self.node(tree, part)).collect();
        self.inner(tree, children)
    }

    /// Splits `members` into at most `ways` parts of nearly equal size, halving at the median along the
    /// longest axis of their centres.
    fn split<'m>(&self, members: &'m mut [u32], ways: usize, parts: &mut Vec<&'m mut [u32]>) {
        if ways <= 1 || members.len() <= LEAF {
            parts.push(members);
            return;
        }
        let centre = |c: u32| Vec3::from_slice(&self.mesh.clusters[c as usize].sphere[..3]);
        let centres = Aabb::of(members.iter().map(|&c| centre(c)));
        let axis = (centres.max - centres.min).max_position();
        let mid = members.len() / 2;
        members.select_nth_unstable_by(mid, |&a, &b| centre(a)[axis].total_cmp(&centre(b)[axis]));
        let (left, right) = members.split_at_mut(mid);
        self.split(left, ways / 2, parts);
        self.split(right, ways - ways / 2, parts);
    }

    fn leaf(&self, tree: &mut CullTree, members: &[u32]) -> TreeNode {
        let clusters = members.iter().map(|&c| &self.mesh.clusters[c as usize]);
        let node = TreeNode {
            sphere: enclose(clusters.clone().map(|c| (Vec3::from_slice(&c.sphere[..3]), c.sphere[3]))),
            parent: bound(clusters.clone().map(|c| c.parent), f32::max),
            own: bound(clusters.clone().map(|c| c.own), f32::min),
            first: tree.items.len() as u32,
            count: members.len() as u32,
            leaf: true,
            emitter: clusters.clone().any(|c| (self.emitter)(c.surface)),
        };
        tree.items.extend_from_slice(members);
        node
    }

    /// An inner node over `children`, which are pushed into `tree` side by side.
    fn inner(&self, tree: &mut CullTree, children: Vec<TreeNode>) -> TreeNode {
        let node = TreeNode {
            sphere: enclose(children.iter().map(|c| (Vec3::from_slice(&c.sphere[..3]), c.sphere[3]))),
            parent: bound(children.iter().map(|c| c.parent), f32::max),
            own: bound(children.iter().map(|c| c.own), f32::min),
            first: tree.nodes.len() as u32,
            count: children.len() as u32,
            leaf: false,
            emitter: children.iter().any(|c| c.emitter),
        };
        tree.nodes.extend(children);
        node
    }
}

/// The error `pick` chooses among `bounds` (max or min), with a box holding those whose error decides
/// anything: neither full detail (0 projects to 0 from anywhere) nor terminal (projects past any
/// threshold). If the chosen error is one of those, the box decides nothing.
fn bound(bounds: impl Iterator<Item = ErrorBounds> + Clone, pick: fn(f32, f32) -> f32) -> ErrorBounds {
    let error = bounds.clone().map(|b| b.error).reduce(pick).unwrap_or(ErrorBounds::FULL_DETAIL);
    let finite = bounds.filter(|b| b.error != ErrorBounds::FULL_DETAIL && b.error != ErrorBounds::TERMINAL);
    let all = finite.fold(Aabb::EMPTY, |all, b| all.union(b.aabb()));
    // None: a point, whose finite distance keeps a terminal error projecting past any threshold.
    ErrorBounds::new(if all.is_empty() { Aabb { min: Vec3::ZERO, max: Vec3::ZERO } } else { all }, error)
}

/// A sphere holding every sphere of `spheres` (centre of their box, radius to the farthest), a little
/// larger than exact so that it still holds them after rounding on the GPU.
fn enclose(spheres: impl Iterator<Item = (Vec3, f32)> + Clone) -> [f32; 4] {
    let boxes = spheres.clone().fold(Aabb::EMPTY, |all, (c, r)| all.union(Aabb { min: c - r, max: c + r }));
    if boxes.is_empty() {
        return [0.0; 4];
    }
    let centre = boxes.center();
    let radius = spheres.map(|(c, r)| c.distance(centre) + r).fold(0.0f32, f32::max);
    let slack = 1e-5 * (radius + centre.abs().max_element());
    centre.extend(radius + slack).to_array()
}
