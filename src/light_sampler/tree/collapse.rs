//! Collapsing the binary SAOH tree into 8-wide nodes, in parallel.
//!
//! For each 8-wide node we choose which binary descendants become its (up to eight) children
//! so that Σ over lights of their depth (the expected number of nodes a sample visits, if
//! lights were picked uniformly) plus a cost per node ([`node_cost`]) is smallest: a dynamic
//! program over the cuts below each node, its table (the best cost of a subtree given 1 to 8
//! slots) computed bottom-up once per binary node. Minimising the node count alone leaves SAOH's unbalanced subtrees deep (13
//! levels for the 10⁴ windows of `street.ron` against 10). Every level of 8-wide nodes
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
use super::{LEAF, MAX_DEPTH, NONE, TRAIL_BITS, WIDTH};
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
    /// Per binary node, for 1 to [`WIDTH`] slots: the smallest objective (light depths + node
    /// costs) below it when it may occupy that many slots of the node above (one slot: it
    /// becomes a wide node itself); filled bottom-up before emission.
    slots: Vec<[AtomicU64; WIDTH]>,
    /// Per light, its trail as low and high halves; each is written once.
    trails: Vec<[AtomicU64; 2]>,
}

/// The 8-wide tree: nodes in depth-first preorder (the root first), per-light trails and the
/// depth.
pub struct Collapsed {
    /// 8-wide nodes in preorder, the root first.
    pub nodes: Vec<Node>,
    /// Per light: [`TRAIL_BITS`]-bit child choices from the root, level 0 in the lowest bits.
    pub trails: Vec<u128>,
    /// Levels of 8-wide nodes.
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
            slots: (0..bin.len()).map(|_| std::array::from_fn(|_| AtomicU64::new(0))).collect(),
            trails: (0..lights).map(|_| [AtomicU64::new(0), AtomicU64::new(0)]).collect(),
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
        let trails =
            c.trails.into_iter().map(|[lo, hi]| (hi.into_inner() as u128) << 64 | lo.into_inner() as u128).collect();
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

    /// Fills `slots` for every binary node below and at `c`, children first.
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
        let split = |k: usize| (1..k).map(|j| self.slot_cost(a, j) + self.slot_cost(b, k - j)).min();
        let own = node.count as u64 + self.node_cost + split(WIDTH).expect("WIDTH > 1");
        for (k, slot) in (1..=WIDTH).zip(&self.slots[n as usize]) {
            slot.store(split(k).map_or(own, |s| s.min(own)), Relaxed);
        }
    }

    /// Smallest objective below binary node `n` when it becomes a wide node (each of its
    /// lights is one level deeper for it, and the node costs `node_cost`).
    fn cost(&self, n: u32) -> u64 {
        self.slots[n as usize][0].load(Relaxed)
    }

    /// Smallest objective below the current node when entry `c` may occupy up to `k` of its
    /// slots.
    fn slot_cost(&self, c: Child, k: usize) -> u64 {
        match c {
            Child::Item(_) => 0,
            Child::Node(n) => self.slots[n as usize][k - 1].load(Relaxed),
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

    /// Appends the wide subtree for binary children `[a, b]` to `out` in depth-first
    /// preorder, its root at the current end of `out` and child indices relative to the start
    /// of `out`. Returns the subtree's depth in wide levels.
    fn emit(&self, a: Child, b: Child, trail: u128, depth: u32, out: &mut Vec<Node>) -> u32 {
        assert!(depth < MAX_DEPTH, "light tree deeper than its trails");
        let j = (1..WIDTH).min_by_key(|&j| self.slot_cost(a, j) + self.slot_cost(b, WIDTH - j)).unwrap();
        let mut entries = Vec::with_capacity(WIDTH);
        self.slot_entries(a, j, &mut entries);
        self.slot_entries(b, WIDTH - j, &mut entries);
        let index = out.len();
        out.push(Node::empty());
        let child_trail = |k: usize| trail | ((k as u128) << (TRAIL_BITS * depth));
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
    fn leaf(&self, i: u32, trail: u128) -> u32 {
        let light = self.items[i as usize].light;
        let [lo, hi] = &self.trails[light as usize];
        lo.store(trail as u64, Relaxed);
        hi.store((trail >> 64) as u64, Relaxed);
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
