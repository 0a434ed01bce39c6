//! `tree`: a light BVH that gives the per-point weighting of `local` in O(log n).
//!
//! Conty Estevez & Kulla 2018 as in pbrt-v4 and Cycles, with what those two miss:
//! - **4-wide nodes with the children's bounds stored in the parent.** The binary SAOH tree
//!   (`build.rs`) is collapsed so that one decision weighs four tighter clusters instead of
//!   two looser ones (Psychopath and Luminary report wider trees sample better); a node is
//!   128 bytes (`compact.rs`) and one SSE evaluation yields all four importances.
//! - **One number, remapped down the tree in f64**, so the stratification of `u` survives
//!   and 20+ levels do not collapse neighbouring `u` onto one light.
//! - **Exact pmf by replaying the light's path**: a 64-bit trail (2 bits per level) per
//!   light; the build caps the depth so the trail cannot overflow (pbrt's 32-bit trail can).
//! - **Directional lights inside the tree**: they form their own subtree under the root,
//!   with importance = irradiance × the best cosine to the receiver, so a sun below the
//!   horizon gets no samples and a bright sun is not starved by a fixed share (pbrt gives
//!   infinite lights a fixed probability).
//!
//! `sample` returns `None` only where every cluster has importance 0, which the bounds make
//! happen only where no light can contribute; the pmf then sums to 0 as well.

mod build;
mod compact;

use std::time::{Duration, Instant};

use self::build::{BinNode, Child, Item};
use self::compact::{Node, Quantizer};
use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{Light, LightBounds, LightId};
use crate::math::Vec3A;

/// Children per node.
const WIDTH: usize = 4;
/// Marks a child slot that holds a light, not a node.
const LEAF: u32 = 1 << 31;
/// An unused child slot.
const NONE: u32 = u32::MAX;
/// Levels a 64-bit trail of 2-bit choices can record.
const MAX_DEPTH: u32 = 32;

/// Build statistics, for `info` and the render summary.
#[derive(Clone, Copy, Debug, Default)]
pub struct TreeStats {
    /// Wall time of the build.
    pub build_time: Duration,
    /// Number of 4-wide nodes.
    pub nodes: usize,
    /// Levels of 4-wide nodes from the root to the deepest light.
    pub depth: u32,
    /// Bytes of nodes and trails.
    pub memory_bytes: usize,
}

/// The light BVH.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Per light: 2-bit child choices from the root, level 0 in the lowest bits.
    trails: Vec<u64>,
    grid: Quantizer,
    stats: TreeStats,
}

/// Asks the memory system for node `index` (both cache lines) ahead of its use.
#[inline(always)]
fn prefetch(nodes: &[Node], index: u32) {
    #[cfg(target_arch = "x86_64")]
    if let Some(n) = nodes.get(index as usize) {
        let p = (n as *const Node).cast::<i8>();
        // SAFETY: prefetching is a hint with no architectural effect; the address is that of
        // a live node, and `wrapping_add` stays inside it (128 bytes).
        unsafe {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64));
        }
    }
}

/// Importances of a node's children at `ctx` (0 for empty slots), and their sum.
#[inline]
fn importances(node: &Node, grid: &Quantizer, ctx: &ShadingContext) -> ([f64; WIDTH], f64) {
    let imp = node.decode(grid).importance(ctx.p, ctx.n).to_array().map(|x| x as f64);
    (imp, imp.iter().sum())
}

/// What a node costs, in light-levels, in the collapse's objective: 16 keeps trees below 60
/// bytes per light (`street.ron` 57, `instanced_lamps.glb` 55, where 0 gives 60 and 66) for
/// at most one more level of depth.
const NODE_COST: u64 = 16;

/// Turns the binary tree into 4-wide nodes, choosing for each node which binary
/// descendants become its (up to four) children so that Σ over lights of their depth (the
/// expected number of nodes a sample visits, if lights were picked uniformly) plus
/// [`NODE_COST`] per node is smallest: a dynamic program over the cuts of the top three
/// binary levels, memoised per binary node. Minimising the node count alone leaves SAOH's
/// unbalanced subtrees deep (13 levels for the 10⁴ windows of `street.ron` against 10).
/// Every level of 4-wide nodes consumes at least one binary level, so the binary depth limit
/// (32) bounds the trails.
struct Collapser<'a> {
    bin: &'a [BinNode],
    items: &'a [Item],
    grid: Quantizer,
    /// Smallest objective (light depths + node costs) below each binary node, counted from a
    /// 4-wide node made for it (0 = not computed yet).
    cost: Vec<u64>,
    nodes: Vec<Node>,
    trails: Vec<u64>,
    depth: u32,
}

impl Collapser<'_> {
    fn bounds_of(&self, c: Child) -> &LightBounds {
        match c {
            Child::Item(i) => &self.items[i as usize].bounds,
            Child::Node(n) => &self.bin[n as usize].bounds,
        }
    }

    /// Smallest objective below binary node `n`, when `n` becomes a 4-wide node (each of its
    /// lights is one level deeper for it, and the node costs [`NODE_COST`]).
    fn cost(&mut self, n: u32) -> u64 {
        if self.cost[n as usize] == 0 {
            let [a, b] = self.bin[n as usize].children;
            let best = (1..WIDTH).map(|j| self.slot_cost(a, j) + self.slot_cost(b, WIDTH - j)).min().unwrap();
            self.cost[n as usize] = self.bin[n as usize].count as u64 + NODE_COST + best;
        }
        self.cost[n as usize]
    }

    /// Smallest objective below the current node when entry `c` may occupy up to `k` of its
    /// slots.
    fn slot_cost(&mut self, c: Child, k: usize) -> u64 {
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
    fn slot_entries(&mut self, c: Child, k: usize, out: &mut Vec<Child>) {
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

    /// Emits the 4-wide node for binary children `[a, b]` (depth-first); returns its index.
    fn emit(&mut self, a: Child, b: Child, trail: u64, depth: u32) -> u32 {
        assert!(depth < MAX_DEPTH, "light tree deeper than its 64-bit trails");
        self.depth = self.depth.max(depth + 1);
        let j = (1..WIDTH).min_by_key(|&j| self.slot_cost(a, j) + self.slot_cost(b, WIDTH - j)).unwrap();
        let mut entries = Vec::with_capacity(WIDTH);
        self.slot_entries(a, j, &mut entries);
        self.slot_entries(b, WIDTH - j, &mut entries);
        let index = self.nodes.len();
        self.nodes.push(Node::empty());
        for (k, &c) in entries.iter().enumerate() {
            let child_trail = trail | ((k as u64) << (2 * depth));
            let reference = match c {
                Child::Item(i) => {
                    let light = self.items[i as usize].light;
                    self.trails[light as usize] = child_trail;
                    LEAF | light
                }
                Child::Node(n) => {
                    let [x, y] = self.bin[n as usize].children;
                    self.emit(x, y, child_trail, depth + 1)
                }
            };
            let bounds = *self.bounds_of(c);
            self.nodes[index].set(k, reference, &bounds, &self.grid);
        }
        index as u32
    }
}

impl LightTree {
    /// Builds the tree over `lights` (non-empty) in the current rayon pool.
    pub fn new(lights: &[Light]) -> Self {
        assert!(!lights.is_empty() && lights.len() < (LEAF - 1) as usize, "1 to 2^31 − 2 lights");
        let start = Instant::now();
        let (mut finite, mut infinite): (Vec<Item>, Vec<Item>) = (Vec::new(), Vec::new());
        for (i, l) in lights.iter().enumerate() {
            let bounds = l.bounds();
            // Directional lights are binned by direction; their box is meaningless.
            let (list, centroid) =
                if bounds.infinite { (&mut infinite, bounds.w) } else { (&mut finite, bounds.centroid()) };
            list.push(Item { bounds, centroid, light: i as u32 });
        }
        let (mut lo, mut hi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
        for it in &finite {
            lo = lo.min(it.bounds.min);
            hi = hi.max(it.bounds.max);
        }
        let grid = Quantizer::new(lo.min(hi), hi.max(lo));

        // Each part gets its own binary tree (depth ≤ 31, so that with the joining root the
        // collapsed tree fits the 32 levels of a trail); a root joins them.
        let mut bin: Vec<BinNode> = Vec::new();
        let mut items: Vec<Item> = Vec::with_capacity(lights.len());
        let mut roots = Vec::new();
        for mut part in [finite, infinite] {
            if part.is_empty() {
                continue;
            }
            let (nodes, root, _) = build::build(&mut part, MAX_DEPTH - 1);
            let (node_base, item_base) = (bin.len() as u32, items.len() as u32);
            let shift = |c: Child| match c {
                Child::Item(i) => Child::Item(i + item_base),
                Child::Node(n) => Child::Node(n + node_base),
            };
            bin.extend(nodes.into_iter().map(|n| BinNode { children: n.children.map(shift), ..n }));
            items.extend(part);
            roots.push(shift(root));
        }
        let mut c = Collapser {
            bin: &bin,
            items: &items,
            grid,
            cost: vec![0; bin.len()],
            nodes: Vec::new(),
            trails: vec![0; lights.len()],
            depth: 0,
        };
        match roots[..] {
            [Child::Node(r)] => {
                let [a, b] = bin[r as usize].children;
                c.emit(a, b, 0, 0);
            }
            [a, b] => {
                c.emit(a, b, 0, 0);
            }
            [Child::Item(i)] => {
                // One light: a root with a single child.
                let mut root = Node::empty();
                root.set(0, LEAF | items[i as usize].light, &items[i as usize].bounds, &grid);
                c.nodes.push(root);
                c.depth = 1;
            }
            _ => unreachable!("one or two parts"),
        }
        let (mut nodes, trails, depth) = (c.nodes, c.trails, c.depth);
        nodes.shrink_to_fit();
        let memory_bytes = nodes.capacity() * std::mem::size_of::<Node>() + trails.capacity() * 8;
        let stats = TreeStats { build_time: start.elapsed(), nodes: nodes.len(), depth, memory_bytes };
        Self { nodes, trails, grid, stats }
    }

    /// Build statistics.
    pub fn stats(&self) -> TreeStats {
        self.stats
    }
}

impl LightSampler for LightTree {
    #[inline]
    fn sample(&self, ctx: &ShadingContext, u: f32) -> Option<SampledLight> {
        let (mut u, mut pmf, mut node) = (u as f64, 1.0f64, 0usize);
        for _ in 0..MAX_DEPTH {
            let n = &self.nodes[node];
            // The chosen child is known only after the importances: fetch all inner children
            // meanwhile (the lower levels of a 10⁶-light tree miss every cache).
            for &c in &n.children {
                if c & LEAF == 0 {
                    prefetch(&self.nodes, c);
                }
            }
            let (imp, total) = importances(n, &self.grid, ctx);
            if !(total > 0.0) {
                return None;
            }
            // The child whose cumulative range holds u·total; the last positive child takes
            // any round-off remainder.
            let target = u * total;
            let last = (0..WIDTH).rev().find(|&j| imp[j] > 0.0).expect("total > 0");
            let (mut k, mut below) = (last, 0.0);
            for (j, &w) in imp[..last].iter().enumerate() {
                if w > 0.0 {
                    if target < below + w {
                        k = j;
                        break;
                    }
                    below += w;
                }
            }
            u = ((target - below) / imp[k]).clamp(0.0, 1.0 - f64::EPSILON);
            pmf *= imp[k] / total;
            let child = n.children[k];
            if child & LEAF != 0 {
                return Some(SampledLight { light: LightId(child & !LEAF), pmf: pmf as f32 });
            }
            node = child as usize;
        }
        unreachable!("light tree deeper than MAX_DEPTH")
    }

    #[inline]
    fn pmf(&self, ctx: &ShadingContext, light: LightId) -> f32 {
        let (mut trail, mut p, mut node) = (self.trails[light.0 as usize], 1.0f64, 0usize);
        for _ in 0..MAX_DEPTH {
            let n = &self.nodes[node];
            let k = (trail & 3) as usize;
            // The path is known: fetch the next node while this one is evaluated.
            if n.children[k] & LEAF == 0 {
                prefetch(&self.nodes, n.children[k]);
            }
            let (imp, total) = importances(n, &self.grid, ctx);
            trail >>= 2;
            if !(imp[k] > 0.0) {
                return 0.0;
            }
            p *= imp[k] / total;
            let child = n.children[k];
            if child & LEAF != 0 {
                debug_assert_eq!(child & !LEAF, light.0, "trail leads to another light");
                return p as f32;
            }
            node = child as usize;
        }
        unreachable!("light tree deeper than MAX_DEPTH")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{AreaEmission, DistantLight, QuadLight};
    use crate::math::Rgb;

    fn grid(n: usize) -> Vec<Light> {
        (0..n)
            .map(|i| {
                let e = AreaEmission { radiance: Rgb::splat(1.0 + (i % 5) as f32), two_sided: false };
                let p = Vec3A::new((i % 37) as f32 * 0.1, 2.0, (i / 37) as f32 * 0.1);
                Light::Quad(QuadLight::new(p, Vec3A::X * 0.05, Vec3A::Z * 0.05, e).unwrap())
            })
            .collect()
    }

    #[test]
    fn trails_replay_to_the_sampled_light() {
        let mut lights = grid(3000);
        lights.push(Light::Distant(DistantLight { direction: -Vec3A::Y, irradiance: Rgb::ONE }));
        let tree = LightTree::new(&lights);
        assert!(tree.stats().depth <= 12, "{:?}", tree.stats());
        let ctx = ShadingContext { p: Vec3A::new(1.0, 0.0, 1.0), n: Vec3A::Y };
        for k in 0..10_000 {
            let s = tree.sample(&ctx, (k as f32 + 0.5) / 10_000.0).unwrap();
            let p = tree.pmf(&ctx, s.light);
            assert!((p - s.pmf).abs() <= 1e-5 * p, "{} vs {p}", s.pmf);
        }
        let total: f64 = (0..lights.len()).map(|i| tree.pmf(&ctx, LightId(i as u32)) as f64).sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
    }

    #[test]
    fn memory_per_light_is_small() {
        let tree = LightTree::new(&grid(100_000));
        let per_light = tree.stats().memory_bytes as f64 / 100_000.0;
        assert!(per_light < 64.0, "{per_light} bytes per light");
    }

    #[test]
    fn a_single_light_is_a_tree() {
        let lights = grid(1);
        let tree = LightTree::new(&lights);
        let ctx = ShadingContext { p: Vec3A::ZERO, n: Vec3A::Y };
        assert_eq!(tree.sample(&ctx, 0.3), Some(SampledLight { light: LightId(0), pmf: 1.0 }));
        // Below the horizon: nothing to sample.
        let under = ShadingContext { p: Vec3A::new(0.0, 3.0, 0.0), n: Vec3A::Y };
        assert_eq!(tree.sample(&under, 0.3), None);
        assert_eq!(tree.pmf(&under, LightId(0)), 0.0);
    }
}
