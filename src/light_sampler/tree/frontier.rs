//! The top of the tree as a learned sampler and `cells` see it: the nodes of its first
//! levels, and the clusters their descent ends in there (the *frontier*).
//!
//! Clusters are numbered depth-first, so every top node's child covers one run of them; a
//! child's statistics are the sums over its run, and a light's observations need only its
//! cluster.

use super::super::ShadingContext;
use super::{LEAF, LightTree, NONE, WIDTH};

/// Where a descent below a cluster starts: the cluster's child slot content (a node, or
/// [`LEAF`] and a light) and its level (the trail entries above it).
#[derive(Clone, Copy, Debug)]
pub struct Cluster {
    pub(super) head: u32,
    pub(super) level: u32,
}

/// The first levels of a [`LightTree`] and the clusters below them.
#[derive(Clone, Debug)]
pub struct Frontier {
    /// Per node: its index among the top nodes, or `u32::MAX` below them.
    pub slot: Vec<u32>,
    /// Per top node and child: the run of clusters under the child, `(first, end)`.
    pub runs: Vec<[(u32, u32); WIDTH]>,
    /// Per light: the cluster it lies in.
    pub cluster: Vec<u32>,
    /// Number of clusters.
    pub clusters: u32,
    /// Per top node: its index in the tree.
    tops: Vec<u32>,
    /// Per cluster: where a descent below it starts.
    heads: Vec<Cluster>,
}

impl Frontier {
    /// The nodes of the first `levels` levels (at least 1) of `tree` and the clusters below.
    pub fn new(tree: &LightTree, levels: u32) -> Self {
        let mut f = Frontier {
            slot: vec![u32::MAX; tree.nodes.len()],
            runs: Vec::new(),
            cluster: vec![0; tree.trails.len()],
            clusters: 0,
            tops: Vec::new(),
            heads: Vec::new(),
        };
        f.visit(tree, 0, 0, levels.max(1));
        f
    }

    fn visit(&mut self, tree: &LightTree, node: usize, depth: u32, levels: u32) {
        let slot = self.runs.len();
        self.slot[node] = slot as u32;
        self.runs.push([(0, 0); WIDTH]);
        self.tops.push(node as u32);
        for (k, &c) in tree.nodes[node].children.iter().enumerate() {
            let first = self.clusters;
            if c == NONE {
                continue;
            } else if c & LEAF != 0 {
                self.cluster[(c & !LEAF) as usize] = first;
            } else if depth + 1 < levels {
                self.visit(tree, c as usize, depth + 1, levels);
            } else {
                self.mark(tree, c as usize, first);
            }
            if self.clusters == first {
                self.heads.push(Cluster { head: c, level: depth + 1 });
                self.clusters += 1;
            }
            self.runs[slot][k] = (first, self.clusters);
        }
    }

    /// Whether child slot content `c` of a top node is a cluster (not a top node itself).
    #[inline]
    fn is_cluster(&self, c: u32) -> bool {
        c != NONE && (c & LEAF != 0 || self.slot[c as usize] == u32::MAX)
    }

    /// Where the descent below cluster `id` starts.
    #[inline]
    pub fn head(&self, id: u32) -> Cluster {
        self.heads[id as usize]
    }

    /// Fills `out` with every cluster's importance at `ctx` (as its parent weighs it), in
    /// cluster order.
    pub fn importances(&self, tree: &LightTree, ctx: &ShadingContext, out: &mut Vec<f32>) {
        out.clear();
        out.resize(self.clusters as usize, 0.0);
        for (slot, &node) in self.tops.iter().enumerate() {
            let n = &tree.nodes[node as usize];
            let imp = n.decode(&tree.grid).importance(ctx.p, ctx.n).to_array();
            for (k, &c) in n.children.iter().enumerate() {
                if self.is_cluster(c) {
                    out[self.runs[slot][k].0 as usize] = imp[k];
                }
            }
        }
    }

    /// Puts every light under `node` in cluster `id`.
    fn mark(&mut self, tree: &LightTree, node: usize, id: u32) {
        for &c in &tree.nodes[node].children {
            if c == NONE {
                continue;
            } else if c & LEAF != 0 {
                self.cluster[(c & !LEAF) as usize] = id;
            } else {
                self.mark(tree, c as usize, id);
            }
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.slot.len() * 4
            + self.runs.len() * (std::mem::size_of::<[(u32, u32); WIDTH]>() + 4)
            + self.cluster.len() * 4
            + self.heads.len() * std::mem::size_of::<Cluster>()
    }
}
