//! Collapsing the binary SAOH tree into 4-wide nodes, in parallel.
//!
//! For each 4-wide node we choose which binary descendants become its (up to four) children
//! so that Σ over lights of their depth (the expected number of nodes a sample visits, if
//! lights were picked uniformly) plus a cost per node ([`node_cost`]) is smallest: a dynamic program
//! over the cuts of the top three binary levels below each node, computed bottom-up once per
//! binary node. Minimising the node count alone leaves SAOH's unbalanced subtrees deep (13
//! levels for the 10⁴ windows of `street.ron` against 10). Every level of 4-wide nodes
//! consumes at least one binary level, so the binary depth limit bounds the trails.
//!
//! Both passes run subtrees of more than [`PARALLEL`] lights with rayon. Nodes are laid out
//! in depth-first preorder whatever the thread count: a subtree emitted on its own is
//! appended in place with its child indices shifted, so the tree is identical to a serial
//! build's.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use rayon::prelude::*;

use super::build::{BinNode, Child, Item};
use super::compact::{Node, Quantizer};
use super::{LEAF, MAX_DEPTH, NONE, WIDTH};
use crate::light::LightBounds;

/// What a node costs, in light-levels, in the collapse's objective, for a tree over `lights`
/// lights. Large trees pay 16: that keeps them below 70 bytes per light for at most one more
/// level of depth (with 0, `street.ron`'s 10⁴ lights take 71 B each). Trees of at most
/// [`FREE_NODES_UP_TO`] lights fit in cache whatever their node count, so there nodes are
/// free and only depth counts: on `cornell-9x9.ron` (81 lamps) depth 5 → 4 (28 → 31 nodes),
/// relMSE at 64 spp 0.0064 → 0.0055 (160×120, seeds 1–3, against a 512-spp render) at
/// the same CPU time; `cornell_grid_7.glb`, `offices.ron` and `cornell-5x5.ron` unchanged.
fn node_cost(lights: usize) -> u64 {
    if lights <= FREE_NODES_UP_TO { 0 } else { 16 }
}

/// The largest tree whose nodes cost nothing in the collapse ([`node_cost`]).
const FREE_NODES_UP_TO: usize = 4096;

/// Subtrees with more lights than this are collapsed and emitted in parallel.
const PARALLEL: u32 = 16_384;

/// The collapse of one binary tree (or two joined by a root).
pub struct Collapse<'a> {
    bin: &'a [BinNode],
    items: &'a [Item],
    grid: Quantizer,
    /// [`node_cost`] of this tree.
    node_cost: u64,
    /// Smallest objective (light depths + node costs) below each binary node, counted from a
    /// 4-wide node made for it; filled bottom-up before emission.
    cost: Vec<AtomicU64>,
    /// Per light, its trail; each is written once.
    trails: Vec<AtomicU64>,
}

/// The 4-wide tree: nodes in depth-first preorder (the root first), per-light trails and the
/// depth.
pub struct Collapsed {
    /// 4-wide nodes in preorder, the root first.
    pub nodes: Vec<Node>,
    /// Per light: 2-bit child choices from the root, level 0 in the lowest bits.
    pub trails: Vec<u64>,
    /// Levels of 4-wide nodes.
    pub depth: u32,
}

impl<'a> Collapse<'a> {
    /// Collapses the binary trees under `roots` (one or two: finite and directional lights)
    /// over `lights` lights.
    pub fn run(bin: &'a [BinNode], items: &'a [Item], grid: Quantizer, roots: &[Child], lights: usize) -> Collapsed {
        let c = Collapse {
            bin,
            items,
            grid,
            node_cost: node_cost(lights),
            cost: (0..bin.len()).map(|_| AtomicU64::new(0)).collect(),
            trails: (0..lights).map(|_| AtomicU64::new(0)).collect(),
        };
        for &r in roots {
            c.fill_costs(r);
        }
        let mut nodes = Vec::with_capacity(items.len() / 2);
        let depth = match *roots {
            [Child::Node(r)] => {
                let [a, b] = bin[r as usize].children;
                c.emit(a, b, 0, 0, &mut nodes)
            }
            [a, b] => c.emit(a, b, 0, 0, &mut nodes),
            [Child::Item(i)] => {
                // One light: a root with a single child.
                let mut root = Node::empty();
                root.set(0, LEAF | items[i as usize].light, &items[i as usize].bounds, &grid);
                nodes.push(root);
                1
            }
            _ => unreachable!("one or two parts"),
        };
        let trails = c.trails.into_iter().map(AtomicU64::into_inner).collect();
        Collapsed { nodes, trails, depth }
    }

    fn bounds_of(&self, c: Child) -> &LightBounds {
        match c {
            Child::Item(i) => &self.items[i as usize].bounds,
            Child::Node(n) => &self.bin[n as usize].bounds,
        }
    }

    fn lights_below(&self, c: Child) -> u32 {
        match c {
            Child::Item(_) => 1,
            Child::Node(n) => self.bin[n as usize].count,
        }
    }

    /// Fills `cost` for every binary node below and at `c`, children first.
    fn fill_costs(&self, c: Child) {
        let Child::Node(n) = c else { return };
        let node = &self.bin[n as usize];
        let [a, b] = node.children;
        if node.count > PARALLEL {
            rayon::join(|| self.fill_costs(a), || self.fill_costs(b));
        } else {
            self.fill_costs(a);
            self.fill_costs(b);
        }
        let best = (1..WIDTH).map(|j| self.slot_cost(a, j) + self.slot_cost(b, WIDTH - j)).min().unwrap();
        self.cost[n as usize].store(node.count as u64 + self.node_cost + best, Relaxed);
    }

    /// Smallest objective below binary node `n` when it becomes a 4-wide node (each of its
    /// lights is one level deeper for it, and the node costs `node_cost`).
    fn cost(&self, n: u32) -> u64 {
        self.cost[n as usize].load(Relaxed)
    }

    /// Smallest objective below the current node when entry `c` may occupy up to `k` of its
    /// slots.
    fn slot_cost(&self, c: Child, k: usize) -> u64 {
        match c {
            Child::Item(_) => 0,
            Child::Node(n) => {
                let own = self.cost(n);
                if k == 1 {
                    return own;
                }
                let [a, b] = self.bin[n as usize].children;
                let split = (1..k).map(|j| self.slot_cost(a, j) + self.slot_cost(b, k - j)).min().unwrap();
                own.min(split)
            }
        }
    }

    /// Appends to `out` the entries that realise `slot_cost(c, k)`.
    fn slot_entries(&self, c: Child, k: usize, out: &mut Vec<Child>) {
        if let Child::Node(n) = c
            && k > 1
        {
            let [a, b] = self.bin[n as usize].children;
            let (j, split) =
                (1..k).map(|j| (j, self.slot_cost(a, j) + self.slot_cost(b, k - j))).min_by_key(|x| x.1).unwrap();
            // Ties expand: fewer, fuller nodes.
            if split <= self.cost(n) {
                self.slot_entries(a, j, out);
                self.slot_entries(b, k - j, out);
                return;
            }
        }
        out.push(c);
    }

    /// Appends the 4-wide subtree for binary children `[a, b]` to `out` in depth-first
    /// preorder, its root at the current end of `out` and child indices relative to the start
    /// of `out`. Returns the subtree's depth in 4-wide levels.
    fn emit(&self, a: Child, b: Child, trail: u64, depth: u32, out: &mut Vec<Node>) -> u32 {
        assert!(depth < MAX_DEPTH, "light tree deeper than its 64-bit trails");
        let j = (1..WIDTH).min_by_key(|&j| self.slot_cost(a, j) + self.slot_cost(b, WIDTH - j)).unwrap();
        let mut entries = Vec::with_capacity(WIDTH);
        self.slot_entries(a, j, &mut entries);
        self.slot_entries(b, WIDTH - j, &mut entries);
        let index = out.len();
        out.push(Node::empty());
        let child_trail = |k: usize| trail | ((k as u64) << (2 * depth));
        // The subtree under inner entry k, appended to `out`; its depth.
        let subtree = |k: usize, n: u32, out: &mut Vec<Node>| {
            let [x, y] = self.bin[n as usize].children;
            self.emit(x, y, child_trail(k), depth + 1, out)
        };
        let mut references = [NONE; WIDTH];
        let mut below = 0;
        if entries.iter().any(|&c| self.lights_below(c) > PARALLEL) {
            // Each inner entry's subtree into its own vector, in parallel; then appended in
            // order with its indices shifted, which is where a serial emission puts them.
            let parts: Vec<Option<(Vec<Node>, u32)>> = entries
                .par_iter()
                .enumerate()
                .map(|(k, &c)| match c {
                    Child::Node(n) => {
                        let mut sub = Vec::new();
                        let d = subtree(k, n, &mut sub);
                        Some((sub, d))
                    }
                    Child::Item(_) => None,
                })
                .collect();
            for (k, part) in parts.into_iter().enumerate() {
                references[k] = match (entries[k], part) {
                    (Child::Item(i), _) => self.leaf(i, child_trail(k)),
                    (Child::Node(_), Some((sub, d))) => {
                        below = below.max(d);
                        append_shifted(out, sub)
                    }
                    (Child::Node(_), None) => unreachable!("inner entries have a part"),
                };
            }
        } else {
            for (k, &c) in entries.iter().enumerate() {
                references[k] = match c {
                    Child::Item(i) => self.leaf(i, child_trail(k)),
                    Child::Node(n) => {
                        let root = out.len() as u32;
                        below = below.max(subtree(k, n, out));
                        root
                    }
                };
            }
        }
        for (k, &c) in entries.iter().enumerate() {
            let bounds = *self.bounds_of(c);
            out[index].set(k, references[k], &bounds, &self.grid);
        }
        below + 1
    }

    /// Records the trail of item `i`'s light; its child reference.
    fn leaf(&self, i: u32, trail: u64) -> u32 {
        let light = self.items[i as usize].light;
        self.trails[light as usize].store(trail, Relaxed);
        LEAF | light
    }
}

/// Appends `sub` (indices relative to its own start) to `out`; the index of its root.
fn append_shifted(out: &mut Vec<Node>, sub: Vec<Node>) -> u32 {
    let base = out.len() as u32;
    out.extend(sub.into_iter().map(|mut node| {
        for c in &mut node.children {
            if *c != NONE && *c & LEAF == 0 {
                *c += base;
            }
        }
        node
    }));
    base
}
