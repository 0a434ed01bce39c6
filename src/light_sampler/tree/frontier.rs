//! The top of the tree as a learned sampler sees it: the nodes of its first levels, and the
//! clusters their descent ends in there (the *frontier*).
//!
//! Clusters are numbered depth-first, so every top node's child covers one run of them; a
//! child's statistics are the sums over its run, and a light's observations need only its
//! cluster.

use super::{LEAF, LightTree, NONE, WIDTH};

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
}

impl Frontier {
    /// The nodes of the first `levels` levels (at least 1) of `tree` and the clusters below.
    pub fn new(tree: &LightTree, levels: u32) -> Self {
        let mut f = Frontier {
            slot: vec![u32::MAX; tree.nodes.len()],
            runs: Vec::new(),
            cluster: vec![0; tree.trails.len()],
            clusters: 0,
        };
        f.visit(tree, 0, 0, levels.max(1));
        f
    }

    fn visit(&mut self, tree: &LightTree, node: usize, depth: u32, levels: u32) {
        let slot = self.runs.len();
        self.slot[node] = slot as u32;
        self.runs.push([(0, 0); WIDTH]);
        for (k, &c) in tree.nodes[node].children.iter().enumerate() {
            let first = self.clusters;
            if c == NONE {
                continue;
            } else if c & LEAF != 0 {
                self.cluster[(c & !LEAF) as usize] = first;
                self.clusters += 1;
            } else if depth + 1 < levels {
                self.visit(tree, c as usize, depth + 1, levels);
            } else {
                self.mark(tree, c as usize, first);
                self.clusters += 1;
            }
            self.runs[slot][k] = (first, self.clusters);
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
        self.slot.len() * 4 + self.runs.len() * std::mem::size_of::<[(u32, u32); WIDTH]>() + self.cluster.len() * 4
    }
}
