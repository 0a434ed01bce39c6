//! `tree`: a light BVH that gives the per-point weighting of `local` in O(log n).
//!
//! Conty Estevez & Kulla 2018 as in pbrt-v4 and Cycles, with what those two miss:
//! - **8-wide nodes with the children's bounds stored in the parent.** The binary SAOH tree
//!   (`build.rs`) is collapsed so that one decision weighs eight tighter clusters instead of
//!   two looser ones (Psychopath and Luminary report wider trees sample better); a node is
//!   256 bytes (`compact.rs`) and one AVX evaluation yields all eight importances. A descent
//!   is a chain of dependent steps, so fewer, wider levels are what makes it fast: against
//!   4-wide nodes, see the performance page.
//! - **One 64-bit number, split exactly down the tree**: each node shares the values that
//!   reached it among its children by [`NodeSplit`], and passes the chosen child's run on, so
//!   the stratification of `u` survives, 20+ levels do not collapse neighbouring `u` onto one
//!   light, and a light's pmf is exactly the share of the 2⁶⁴ values that reach it.
//! - **The pmf by replaying the light's path**: a 128-bit trail (3 bits per level) per light
//!   leads to the same splits, so `pmf` reports bit for bit what `sample` does; the build
//!   caps the depth so the trail cannot overflow (pbrt's 32-bit trail can).
//! - **Directional lights inside the tree**: they form their own subtree under the root,
//!   with importance = irradiance × the best cosine to the receiver, so a sun below the
//!   horizon gets no samples and a bright sun is not starved by a fixed share (pbrt gives
//!   infinite lights a fixed probability).
//! - **Glossy points weigh clusters by the BSDF too** ([`GlossyLobes`](crate::material::GlossyLobes), the min angle from
//!   the mirror direction to each child's bounding sphere): a point light a glossy floor
//!   mirrors is chosen as often as it is seen there, not as any light as far away; part of
//!   each level's choice stays with the irradiance alone ([`IRRADIANCE_SHARE`]).
//!
//! `sample` returns `None` only where every cluster has importance 0, which the bounds make
//! happen only where no light can contribute; the pmf then sums to 0 as well.

mod build;
mod collapse;
mod compact;
mod frontier;

pub use frontier::{Cluster, Frontier};

use std::time::{Duration, Instant};

use rayon::prelude::*;

use self::build::{BinNode, Child, Item};
use self::collapse::{Collapse, Collapsed};
use self::compact::{Node, Quantizer};
use super::{LightSampler, SampledLight, ShadingContext, prefetch};
use crate::light::{Lanes, Light, LightId};
use crate::math::Vec3A;
use crate::math::distribution::{NodeSplit, RANGE, even_interval, even_pick, probability};

/// Children per node.
pub const WIDTH: usize = 8;
/// Marks a child slot that holds a light, not a node.
const LEAF: u32 = 1 << 31;
/// An unused child slot.
const NONE: u32 = u32::MAX;
/// Bits a trail spends on a level's choice among [`WIDTH`] children.
const TRAIL_BITS: u32 = WIDTH.trailing_zeros();
/// Levels a 128-bit trail can record.
const MAX_DEPTH: u32 = u128::BITS / TRAIL_BITS;
/// Levels the binary tree may have below the root that joins its finite and directional
/// parts: every collapsed level consumes at least one, so the trails cannot overflow.
const BINARY_DEPTH: u32 = 31;
const _: () = assert!(BINARY_DEPTH < MAX_DEPTH && WIDTH.is_power_of_two() && WIDTH == crate::light::LANES);

/// Build statistics, for `info` and the render summary.
#[derive(Clone, Copy, Debug, Default)]
pub struct TreeStats {
    /// Wall time of the build.
    pub build_time: Duration,
    /// Number of 8-wide nodes.
    pub nodes: usize,
    /// Levels of 8-wide nodes from the root to the deepest light.
    pub depth: u32,
    /// Bytes of nodes and trails.
    pub memory_bytes: usize,
}

/// The light BVH: quantised 8-wide nodes over the lights' bounds, sampled by splitting one
/// 64-bit number down from the root.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Per light: [`TRAIL_BITS`]-bit child choices from the root, level 0 in the lowest bits.
    trails: Vec<u128>,
    /// Per node: its lights' run in `order` (first, count), the count 0 unless their
    /// intensities are even enough to be chosen uniformly ([`EVEN_RATIO`]).
    spans: Vec<(u32, u32)>,
    /// The lights in depth-first leaf order (every node's lights are one run of it).
    order: Vec<u32>,
    /// Per light: its place in `order`.
    rank: Vec<u32>,
    grid: Quantizer,
    /// Whether a descent fetches the next level's nodes and lights ahead ([`FETCH_AHEAD_FROM`]).
    fetch_ahead: bool,
    stats: TreeStats,
}

/// Bytes of nodes from which a descent fetches every child node and light ahead while it
/// weighs them: a tree beyond a core's L2 cache (10⁶ lights: 40 MB) misses it level after
/// level, while a smaller one is in cache and the fetches only cost instructions.
const FETCH_AHEAD_FROM: usize = 1 << 20;

/// Changes the importances of node `node`'s children before they are split (a learned
/// sampler's reweighting near the root). The same reweighting must be given to `sample`
/// and `interval` for a pmf to match its sample.
pub trait Reweight {
    /// Changes the weights `w` of node `node`'s children; returns whether it changed any.
    fn reweight(&self, node: usize, w: &mut [f32; WIDTH]) -> bool;
}

/// The tree's own weights.
struct AsBuilt;

impl Reweight for AsBuilt {
    #[inline(always)]
    fn reweight(&self, _: usize, _: &mut [f32; WIDTH]) -> bool {
        false
    }
}

/// At glossy points, the share of each level's choice that stays with the irradiance bounds
/// alone (the rest follows them weighed by the BSDF's lobes). The lobes' weights come from
/// bounds, level after level, and a light that is nearly in the lobe can lose a few times at
/// each level to a sibling cluster whose sphere holds the mirror direction: without this
/// share one lobby.glb seed in twelve had a point light mirrored by a metal ball chosen ten
/// times less often than by the plain tree. 0.15, 0.3 and 0.5 gave the same mean relMSE over
/// twelve seeds (0.044–0.045 against 0.094 without lobes); 0.3 is the middle.
const IRRADIANCE_SHARE: f32 = 0.3;

/// The children's importances `imp` at a glossy point, mixed from their shares weighed by
/// the BSDF's lobes (`lobe_weights`) and their shares by irradiance alone
/// ([`IRRADIANCE_SHARE`]).
#[inline(always)]
fn lobe_weighted(imp: Lanes, lobe_weights: Lanes) -> Lanes {
    let weighted = imp * lobe_weights;
    let (by_lobes, alone) = (weighted.reduce_add(), imp.reduce_add());
    if !(by_lobes > 0.0 && by_lobes.is_finite() && alone > 0.0 && alone.is_finite()) {
        return imp;
    }
    weighted * ((1.0 - IRRADIANCE_SHARE) / by_lobes) + imp * (IRRADIANCE_SHARE / alone)
}

/// Weights of a node's children at `ctx` (0 for empty slots; weighed by the BSDF's lobes
/// where `ctx` has them), reweighted, and whether `reweight` changed them. How selection
/// values split among them is [`NodeSplit::over`] them, asked for only where the node does not
/// end the descent uniformly ([`LightTree::flat`]).
#[inline(always)]
fn children_weights(
    nodes: &[Node],
    node: usize,
    grid: &Quantizer,
    ctx: &ShadingContext,
    reweight: &impl Reweight,
) -> ([f32; WIDTH], bool) {
    let packet = nodes[node].decode(grid);
    let imp = match &ctx.lobes {
        None => packet.importance(ctx.p, ctx.n),
        Some(lobes) => {
            let (imp, weights) = packet.importance_and_lobe_weights(ctx.p, ctx.n, lobes);
            lobe_weighted(imp, weights)
        }
    };
    let mut imp = imp.to_array();
    let changed = reweight.reweight(node, &mut imp);
    (imp, changed)
}

/// A node whose lights' intensities φ differ by at most this factor may choose among them
/// uniformly once its children look alike from the shading point ([`FLAT_RATIO`]).
const EVEN_RATIO: f32 = 1.5;

/// Children whose importances differ by at most this factor look alike: the rest of the
/// descent would choose among nearly equal clusters, so a node of even lights ends it by
/// choosing one of its lights uniformly (exactly, by count), saving the levels below.
/// Measured with `tools/equal_time.py` (160×120, 2 s, 2 seeds): cornell-32x32 tree
/// efficiency 140 → 187 (uniform 190), cornell_grid_7.glb 184 → 220; relMSE per sample on
/// cornell_grid_7 (320×240, 64 spp) 0.0050 → 0.0053.
const FLAT_RATIO: f32 = 2.0;

/// The runs of lights under every node in depth-first leaf order, which nodes may choose
/// uniformly, and each light's place in that order. `phi`: per light, NaN for directional.
fn runs(nodes: &[Node], phi: &[f32]) -> (Vec<(u32, u32)>, Vec<u32>, Vec<u32>) {
    fn visit(nodes: &[Node], node: usize, phi: &[f32], spans: &mut [(u32, u32)], order: &mut Vec<u32>) -> (f32, f32) {
        let first = order.len() as u32;
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for &c in &nodes[node].children {
            let (a, b) = if c == NONE {
                continue;
            } else if c & LEAF != 0 {
                order.push(c & !LEAF);
                let p = phi[(c & !LEAF) as usize];
                (p, p)
            } else {
                visit(nodes, c as usize, phi, spans, order)
            };
            // NaN (a directional light) poisons the run: min/max ignore it, so test it here.
            (lo, hi) = if a.is_nan() || b.is_nan() { (f32::NAN, f32::NAN) } else { (lo.min(a), hi.max(b)) };
        }
        let count = order.len() as u32 - first;
        let even = lo > 0.0 && hi <= EVEN_RATIO * lo;
        spans[node] = (first, if even { count } else { 0 });
        (lo, hi)
    }
    let mut spans = vec![(0, 0); nodes.len()];
    let mut order = Vec::with_capacity(phi.len());
    visit(nodes, 0, phi, &mut spans, &mut order);
    let mut rank = vec![0u32; phi.len()];
    for (r, &l) in order.iter().enumerate() {
        rank[l as usize] = r as u32;
    }
    (spans, order, rank)
}

impl LightTree {
    /// The number of lights `node` chooses among uniformly at `ctx`, given its children's
    /// importances there, or `None` when the descent goes on.
    #[inline]
    fn flat(&self, node: usize, imp: &[f32; WIDTH]) -> Option<u32> {
        let m = self.spans[node].1;
        if m == 0 {
            return None;
        }
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for (k, &c) in self.nodes[node].children.iter().enumerate() {
            if c != NONE {
                (lo, hi) = (lo.min(imp[k]), hi.max(imp[k]));
            }
        }
        (lo > 0.0 && hi <= FLAT_RATIO * lo).then_some(m)
    }

    /// Builds the tree over `lights` (non-empty) in the current rayon pool.
    pub fn new(lights: &[Light]) -> Self {
        assert!(!lights.is_empty() && lights.len() < (LEAF - 1) as usize, "1 to 2^31 − 2 lights");
        let start = Instant::now();
        // Directional lights are binned by direction; their box is meaningless.
        let (infinite, finite): (Vec<Item>, Vec<Item>) = lights
            .par_iter()
            .enumerate()
            .map(|(i, l)| {
                let bounds = l.bounds();
                let centroid = if bounds.infinite { bounds.w } else { bounds.centroid() };
                Item { bounds, centroid, light: i as u32 }
            })
            .partition(|it| it.bounds.infinite);
        let (mut lo, mut hi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
        for it in &finite {
            lo = lo.min(it.bounds.min);
            hi = hi.max(it.bounds.max);
        }
        let grid = Quantizer::new(lo.min(hi), hi.max(lo));

        // Each part gets its own binary tree (depth ≤ 31, so that with the joining root the
        // collapsed tree fits the levels of a trail); a root joins them.
        let mut bin: Vec<BinNode> = Vec::new();
        let mut items: Vec<Item> = Vec::with_capacity(lights.len());
        let mut roots = Vec::new();
        for mut part in [finite, infinite] {
            if part.is_empty() {
                continue;
            }
            let (nodes, root, _) = build::build(&mut part, BINARY_DEPTH);
            let (node_base, item_base) = (bin.len() as u32, items.len() as u32);
            let shift = |c: Child| match c {
                Child::Item(i) => Child::Item(i + item_base),
                Child::Node(n) => Child::Node(n + node_base),
            };
            bin.extend(nodes.into_iter().map(|n| BinNode { children: n.children.map(shift), ..n }));
            items.extend(part);
            roots.push(shift(root));
        }
        let Collapsed { mut nodes, trails, depth } = Collapse::run(&bin, &items, grid, &roots, lights.len());
        nodes.shrink_to_fit();
        let phi: Vec<f32> = items.iter().fold(vec![0.0; lights.len()], |mut phi, it| {
            phi[it.light as usize] = if it.bounds.infinite { f32::NAN } else { it.bounds.phi };
            phi
        });
        let (spans, order, rank) = runs(&nodes, &phi);
        let memory_bytes = nodes.capacity() * std::mem::size_of::<Node>()
            + trails.capacity() * std::mem::size_of::<u128>()
            + spans.len() * 8
            + order.len() * 8;
        let stats = TreeStats { build_time: start.elapsed(), nodes: nodes.len(), depth, memory_bytes };
        let fetch_ahead = nodes.len() * std::mem::size_of::<Node>() >= FETCH_AHEAD_FROM;
        Self { nodes, trails, spans, order, rank, grid, fetch_ahead, stats }
    }

    /// Build statistics.
    pub fn stats(&self) -> TreeStats {
        self.stats
    }
}

impl LightTree {
    /// [`LightSampler::sample`], calling `leaf_hint(light)` for the lights among the
    /// children of each node visited before choosing (in a tree that outgrows the cache): the
    /// caller can start fetching the light it will shade (at 10⁶ lights, otherwise a certain
    /// cache miss per sample).
    #[inline]
    pub fn sample_hinting(&self, ctx: &ShadingContext, u: u64, leaf_hint: impl Fn(u32)) -> Option<SampledLight> {
        self.sample_reweighted(ctx, u, leaf_hint, &AsBuilt)
    }

    /// [`sample_hinting`](Self::sample_hinting) with the children's weights changed by
    /// `reweight` (a node whose weights it changes never ends the descent uniformly).
    #[inline]
    pub fn sample_reweighted(
        &self,
        ctx: &ShadingContext,
        u: u64,
        leaf_hint: impl Fn(u32),
        reweight: &impl Reweight,
    ) -> Option<SampledLight> {
        self.descend(ctx, 0, u as u128, RANGE, leaf_hint, reweight)
    }

    /// The descent below `head` (a child slot's content: a node, or [`LEAF`] and a light)
    /// for the selection values that reached it: `u`, an offset into their run of `range`.
    /// `cells` starts it at the cluster its table chose.
    #[inline]
    fn descend(
        &self,
        ctx: &ShadingContext,
        head: u32,
        mut u: u128,
        mut range: u128,
        leaf_hint: impl Fn(u32),
        reweight: &impl Reweight,
    ) -> Option<SampledLight> {
        if head & LEAF != 0 {
            return Some(SampledLight { light: LightId(head & !LEAF), pmf: probability(range) });
        }
        let mut node = head as usize;
        for _ in 0..MAX_DEPTH {
            let n = &self.nodes[node];
            // The chosen child is known only after the importances: fetch all children
            // meanwhile (the lower levels of a 10⁶-light tree miss every cache).
            if self.fetch_ahead {
                for &c in &n.children {
                    if c & LEAF == 0 {
                        prefetch(&self.nodes, c as usize);
                    } else if c != NONE {
                        leaf_hint(c & !LEAF);
                    }
                }
            }
            let (imp, changed) = children_weights(&self.nodes, node, &self.grid, ctx, reweight);
            if !changed && let Some(m) = self.flat(node, &imp) {
                let k = even_pick(u, m, range);
                let (a, b) = even_interval(k, m, range);
                let width = b - a;
                let light = self.order[(self.spans[node].0 + k) as usize];
                return Some(SampledLight { light: LightId(light), pmf: probability(width) });
            }
            // The child whose interval holds u (the intervals tile the range, so one does).
            let (k, (start, end)) = NodeSplit::over(range, &imp)?.find(u);
            (u, range) = (u - start, end - start);
            let child = n.children[k];
            if child & LEAF != 0 {
                return Some(SampledLight { light: LightId(child & !LEAF), pmf: probability(range) });
            }
            node = child as usize;
        }
        unreachable!("light tree deeper than MAX_DEPTH")
    }
}

impl LightSampler for LightTree {
    #[inline]
    fn sample(&self, ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        self.sample_hinting(ctx, u, |_| {})
    }

    #[inline]
    fn interval(&self, ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        self.interval_reweighted(ctx, light, &AsBuilt)
    }
}

impl LightTree {
    /// [`LightSampler::interval`] under the weights `reweight` gives, as
    /// [`sample_reweighted`](Self::sample_reweighted) draws with them.
    #[inline]
    pub fn interval_reweighted(&self, ctx: &ShadingContext, light: LightId, reweight: &impl Reweight) -> (u128, u128) {
        self.interval_below(ctx, light, 0, 0, (0, RANGE), reweight)
    }

    /// The choice below `cluster` (of a [`Frontier`] of this tree) for the selection values
    /// that reached it: `u`, an offset into their run of `range`; `leaf_hint` as for
    /// [`sample_hinting`](Self::sample_hinting).
    #[inline]
    pub fn sample_below(
        &self,
        ctx: &ShadingContext,
        cluster: Cluster,
        u: u128,
        range: u128,
        leaf_hint: impl Fn(u32),
    ) -> Option<SampledLight> {
        self.descend(ctx, cluster.head, u, range, leaf_hint, &AsBuilt)
    }

    /// The interval of `light`, which lies below `cluster`, when the selection values
    /// `(start, start + range)` reached the cluster: what [`sample_below`](Self::sample_below)
    /// chooses it with.
    #[inline]
    pub fn interval_below_cluster(
        &self,
        ctx: &ShadingContext,
        light: LightId,
        cluster: Cluster,
        reached: (u128, u128),
    ) -> (u128, u128) {
        self.interval_below(ctx, light, cluster.head, cluster.level, reached, &AsBuilt)
    }

    /// [`interval_reweighted`](Self::interval_reweighted) of `light` below `head` (a child
    /// slot's content, `level` levels below the root, on the light's path) for the selection
    /// values `(start, start + range)` that reached it.
    #[inline]
    fn interval_below(
        &self,
        ctx: &ShadingContext,
        light: LightId,
        head: u32,
        level: u32,
        (mut start, mut range): (u128, u128),
        reweight: &impl Reweight,
    ) -> (u128, u128) {
        if head & LEAF != 0 {
            debug_assert_eq!(head & !LEAF, light.0, "the head is another light");
            return (start, start + range);
        }
        let (mut trail, mut node) = (self.trails[light.0 as usize] >> (level * TRAIL_BITS), head as usize);
        for _ in level..MAX_DEPTH {
            let n = &self.nodes[node];
            let k = (trail % WIDTH as u128) as usize;
            trail >>= TRAIL_BITS;
            // The path is known: fetch the next node while this one is evaluated.
            if self.fetch_ahead && n.children[k] & LEAF == 0 {
                prefetch(&self.nodes, n.children[k] as usize);
            }
            let (imp, changed) = children_weights(&self.nodes, node, &self.grid, ctx, reweight);
            if !changed && let Some(m) = self.flat(node, &imp) {
                let k = self.rank[light.0 as usize] - self.spans[node].0;
                let (a, b) = even_interval(k, m, range);
                return (start + a, start + b);
            }
            let Some(split) = NodeSplit::over(range, &imp) else {
                return (start, start);
            };
            let (a, b) = split.interval(k);
            (start, range) = (start + a, b - a);
            let child = n.children[k];
            if child & LEAF != 0 || range == 0 {
                debug_assert!(range == 0 || child & !LEAF == light.0, "trail leads to another light");
                return (start, start + range);
            }
            node = child as usize;
        }
        unreachable!("light tree deeper than MAX_DEPTH")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{AreaEmission, DistantLight, PointLight, QuadLight};
    use crate::material::GlossyLobes;
    use crate::math::Rgb;

    /// The selection number at fraction `f` of its range.
    fn at(f: f64) -> u64 {
        (f * RANGE as f64) as u64
    }

    fn grid(n: usize) -> Vec<Light> {
        (0..n)
            .map(|i| {
                let e = AreaEmission { radiance: Rgb::splat(1.0 + (i % 5) as f32), two_sided: false };
                let p = Vec3A::new((i % 37) as f32 * 0.1, 2.0, (i / 37) as f32 * 0.1);
                Light::Quad(QuadLight::new(p, Vec3A::X * 0.05, Vec3A::Z * 0.05, e).unwrap())
            })
            .collect()
    }

    /// `n` equally bright lamps facing down at height 2, `columns` to a row, `spacing` apart.
    fn equal_lamps(n: usize, columns: usize, spacing: f32) -> Vec<Light> {
        (0..n)
            .map(|i| {
                let e = AreaEmission { radiance: Rgb::ONE, two_sided: false };
                let p = Vec3A::new((i % columns) as f32 * spacing, 2.0, (i / columns) as f32 * spacing);
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
        let plain = ShadingContext::new(Vec3A::new(1.0, 0.0, 1.0), Vec3A::Y);
        // And at a glossy point, whose lobe weighs the clusters too.
        let mirror = Vec3A::new(0.3, 1.0, 0.2).normalize();
        let glossy = ShadingContext { lobes: Some(GlossyLobes::new(mirror, 0.3, [(0.7, 0.1), (0.0, 1.0)])), ..plain };
        for ctx in [plain, glossy] {
            for k in 0..10_000 {
                let u = at((k as f64 + 0.5) / 10_000.0);
                let s = tree.sample(&ctx, u).unwrap();
                assert_eq!(tree.pmf(&ctx, s.light), s.pmf);
                let (start, end) = tree.interval(&ctx, s.light);
                assert!(start <= u as u128 && (u as u128) < end);
            }
            // The intervals tile the range.
            let mut intervals: Vec<_> = (0..lights.len()).map(|i| tree.interval(&ctx, LightId(i as u32))).collect();
            intervals.sort();
            assert!(
                intervals.windows(2).all(|c| c[0].1 == c[1].0)
                    && intervals[0].0 == 0
                    && intervals.last().unwrap().1 == RANGE
            );
        }
    }

    #[test]
    fn a_glossy_point_chooses_the_light_its_lobe_mirrors_and_keeps_the_others() {
        let position = |i: u32| Vec3A::new((i % 8) as f32 - 3.5, 2.0, (i / 8) as f32 - 3.5);
        let lights: Vec<Light> =
            (0..64).map(|i| Light::Point(PointLight { position: position(i), intensity: Rgb::ONE })).collect();
        let tree = LightTree::new(&lights);
        let plain = ShadingContext::new(Vec3A::new(0.3, 0.0, -0.2), Vec3A::Y);
        for (target, alpha) in [(27, 0.1), (5, 0.2), (60, 0.05)] {
            let mirror = (position(target) - plain.p).normalize();
            let glossy =
                ShadingContext { lobes: Some(GlossyLobes::new(mirror, 0.1, [(0.9, alpha), (0.0, 1.0)])), ..plain };
            let (before, after) = (tree.pmf(&plain, LightId(target)), tree.pmf(&glossy, LightId(target)));
            assert!(after > 3.0 * before, "light {target}, α {alpha}: pmf {before} → {after}");
            // Every light keeps a share, and the shares still sum to 1.
            let pmfs: Vec<f32> = (0..64).map(|i| tree.pmf(&glossy, LightId(i))).collect();
            assert!(pmfs.iter().all(|&p| p > 0.0), "{pmfs:?}");
            assert!((pmfs.iter().sum::<f32>() - 1.0).abs() < 1e-4);
        }
    }

    #[test]
    fn far_even_lights_are_chosen_uniformly_and_their_cells_still_tile() {
        // Equal lamps seen from far away: the root's children look alike, so the choice is
        // uniform over all of them, and sample, pmf and intervals agree as everywhere else.
        let lights = equal_lamps(1000, 40, 0.1);
        let tree = LightTree::new(&lights);
        let far = ShadingContext::new(Vec3A::new(2.0, -500.0, 1.2), Vec3A::Y);
        for k in 0..2000 {
            let u = at((k as f64 + 0.5) / 2000.0);
            let s = tree.sample(&far, u).unwrap();
            assert!((s.pmf * 1000.0 - 1.0).abs() < 1e-4, "pmf {}", s.pmf);
            assert_eq!(tree.pmf(&far, s.light), s.pmf);
            let (start, end) = tree.interval(&far, s.light);
            assert!(start <= u as u128 && (u as u128) < end);
        }
        let near = ShadingContext::new(Vec3A::new(0.3, 1.9, 0.3), Vec3A::Y);
        for ctx in [far, near] {
            let mut intervals: Vec<_> = (0..lights.len()).map(|i| tree.interval(&ctx, LightId(i as u32))).collect();
            intervals.sort();
            assert!(intervals.windows(2).all(|c| c[0].1 == c[1].0) && intervals[0].0 == 0 && intervals[999].1 == RANGE);
        }
        // Close to one corner the choice is not uniform.
        assert!(tree.pmf(&near, LightId(0)) > 2.0 * tree.pmf(&near, LightId(999)));
    }

    #[test]
    fn a_small_tree_is_as_shallow_as_its_nodes_allow() {
        // 81 equal lamps in a 9 × 9 ceiling grid (cornell-9x9.ron): 8³ ≥ 81 > 8². Charging
        // nodes in the collapse, as for large trees, left 4-wide trees a level deeper.
        assert_eq!(LightTree::new(&equal_lamps(81, 9, 0.2)).stats().depth, 3);
    }

    #[test]
    fn the_tree_does_not_depend_on_the_thread_count() {
        // Large enough that the build, the collapse and the emission all run in parallel.
        let lights = grid(60_000);
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| LightTree::new(&lights))
        };
        let (one, three) = (build(1), build(3));
        assert_eq!(one.trails, three.trails);
        assert_eq!((one.stats.nodes, one.stats.depth), (three.stats.nodes, three.stats.depth));
        for (a, b) in one.nodes.iter().zip(&three.nodes) {
            assert_eq!(a.children, b.children);
        }
        let ctx = ShadingContext::new(Vec3A::new(1.0, 0.0, 1.0), Vec3A::Y);
        for k in 0..100 {
            let u = at((k as f64 + 0.5) / 100.0);
            assert_eq!(one.sample(&ctx, u), three.sample(&ctx, u));
        }
    }

    #[test]
    fn memory_per_light_is_small() {
        let tree = LightTree::new(&grid(100_000));
        let per_light = tree.stats().memory_bytes as f64 / 100_000.0;
        assert!(per_light < 72.0, "{per_light} bytes per light");
    }

    #[test]
    fn a_single_light_is_a_tree() {
        let lights = grid(1);
        let tree = LightTree::new(&lights);
        let ctx = ShadingContext::new(Vec3A::ZERO, Vec3A::Y);
        assert_eq!(tree.sample(&ctx, at(0.3)), Some(SampledLight { light: LightId(0), pmf: 1.0 }));
        // Below the horizon: nothing to sample.
        let under = ShadingContext::new(Vec3A::new(0.0, 3.0, 0.0), Vec3A::Y);
        assert_eq!(tree.sample(&under, at(0.3)), None);
        assert_eq!(tree.pmf(&under, LightId(0)), 0.0);
    }
}
