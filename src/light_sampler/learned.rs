//! `learned`: the light tree, reweighted near the root by what earlier passes saw arrive.
//!
//! The tree weighs a cluster by power, distance and orientation and cannot see what stands
//! between it and the point (Vévoda et al. 2018 learn that online; this is a cheap CPU form
//! of it). Space is cut into the cells of the scene's grid (`grid.rs`: 17 along its
//! diameter, times seven normal bins, [`grid::CELLS`] in all, looked up by index); for
//! each cell and each cluster of the tree's first [`LEVELS`] levels ([`Frontier`]), every
//! light sample's unshadowed contribution `c` (luminance of f·Le·G / (pmf·pdf)) and whether
//! its shadow ray got through are summed. A cell where at least [`WORTH_LEARNING`] of that
//! contribution arrived keeps the tree as it is (little to gain, and the tree's uniform
//! shortcuts to keep); elsewhere a top node's child k gets the factor
//!
//! `v_k = (n·r + κ) / (n + κ)`, `r = Σ c·visible / Σ c` over the child's clusters,
//!
//! (`n` samples, prior [`PRIOR`] samples of full visibility, so an unseen child keeps the
//! tree's weight), and at that node the child is chosen with the **defensive mixture**
//! `β·w_k/Σw + (1−β)·w_k·v_k/Σ(w·v)` of the tree's weights `w` ([`DEFENSIVE`] = β): at
//! each of the [`LEVELS`] levels a child keeps at least β of its tree probability, so no
//! light's pmf falls below β^LEVELS of the tree's, and none is ever 0 where the tree's is
//! not. Below the top levels the tree chooses as it always does. Sampling and the pmf go
//! through the same [`LightTree::sample_reweighted`] / [`LightTree::interval_reweighted`] with
//! the same factors, so MIS at a BSDF hit sees exactly the pmf the light was sampled with.
//!
//! **Deterministic and mergeable.** The factors change only between passes, at sample
//! counts 1, 2, 4, … up to [`LEARN_UNTIL`] per pixel, from every sample before that count;
//! observations are summed in fixed point, so however the samples were grouped (by worker,
//! by pass) and in whatever order the groups are merged the sums are the same bits, and the
//! image depends neither on the thread count nor on the pass sizes. Samples from
//! [`LEARN_UNTIL`] on all use the factors learned from samples `0..LEARN_UNTIL`: a render of
//! samples `a..b` needs exactly
//! that state when `a ≥ LEARN_UNTIL` (samples `0..LEARN_UNTIL` rendered first, their
//! image discarded), and for `a` below it the states at each power of two up to `b`.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::grid::{self, SceneGrid};
use super::tree::{Frontier, LightTree, Reweight, WIDTH};
use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{Light, LightId};
use crate::math::Fixed;
use crate::math::Vec3A;
use crate::sampling::fmix64;

/// Levels of the tree whose choices are learned (up to 4³ = 64 clusters).
pub const LEVELS: u32 = 3;
/// The tree's share β in each learned choice.
pub const DEFENSIVE: f32 = 0.3;
/// Pseudo-samples of full visibility every child starts with.
pub const PRIOR: f32 = 4.0;
/// Samples per pixel after which the factors stay as they are.
pub const LEARN_UNTIL: u32 = 16;
/// Children whose factors differ by less than this ratio keep the tree's weights: nothing
/// worth the lost shortcut (the tree's uniform ends) was learned there.
pub const FLAT_FACTORS: f32 = 1.5;
/// A cell whose light samples saw at least this share of their unshadowed contribution
/// arrive samples as the tree does: perfect visibility would cut its samples' cost by at
/// most a tenth, less than reweighting costs where the tree would have ended its descent
/// with a uniform choice. Measured (160×120, 64 spp, 1 thread, paired): learned ÷ tree CPU
/// on cornell-9x9 1.18 → 1.11 and on instanced_lamps.glb 1.03, relMSE unchanged there and
/// on offices and rooms.
pub const WORTH_LEARNING: f64 = 0.9;
/// Marks a cell without learned factors in [`Factors::rows`].
const UNLEARNED: u32 = u32::MAX;

/// A hasher for integer keys (cell indices): one [`fmix64`] of the key.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = fmix64(self.0 ^ b as u64);
        }
    }
    fn write_u64(&mut self, k: u64) {
        self.0 = fmix64(self.0 ^ k);
    }
}

type KeyMap<V> = HashMap<u64, V, BuildHasherDefault<KeyHasher>>;

/// Sums for one cluster seen from one cell, in fixed point ([`Fixed`]), so that observations
/// merged in any grouping give the same bits.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    /// Σ c · visible.
    arrived: i128,
    /// Σ c.
    offered: i128,
    /// Samples.
    n: u32,
}

impl Sums {
    fn add(&mut self, other: &Sums) {
        self.arrived += other.arrived;
        self.offered += other.offered;
        self.n += other.n;
    }
}

/// What some light samples saw (one worker's share of a pass, or several merged): per cell,
/// sums per cluster. Merging is integer addition, so any grouping gives the same sums.
#[derive(Clone, Debug)]
pub struct Observations {
    cells: Vec<(u32, Vec<Sums>)>,
    index: KeyMap<u32>,
    /// The cell of the last observation and its place in `cells`: consecutive samples of a
    /// pixel mostly land in one cell, and then need no hashing.
    last: (u32, u32),
}

impl Default for Observations {
    fn default() -> Self {
        Self { cells: Vec::new(), index: KeyMap::default(), last: (UNLEARNED, 0) }
    }
}

impl Observations {
    /// The sums of cell `cell`, created with `clusters` entries when new.
    #[inline]
    fn row(&mut self, cell: u32, clusters: usize) -> &mut [Sums] {
        if self.last.0 != cell {
            let cells = &mut self.cells;
            let at = *self.index.entry(cell as u64).or_insert_with(|| {
                cells.push((cell, vec![Sums::default(); clusters]));
                (cells.len() - 1) as u32
            });
            self.last = (cell, at);
        }
        &mut self.cells[self.last.1 as usize].1
    }

    /// Adds what `other` saw.
    pub fn merge(&mut self, other: Observations) {
        if self.cells.is_empty() {
            *self = other;
            return;
        }
        for (cell, sums) in other.cells {
            for (total, s) in self.row(cell, sums.len()).iter_mut().zip(&sums) {
                total.add(s);
            }
        }
    }
}

/// What the learning cost and holds, for the render summary, `info` and `compare`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LearnedStats {
    /// Cells with learned factors.
    pub cells: usize,
    /// Light samples learned from.
    pub samples: u64,
    /// Bytes of sums and factors.
    pub memory_bytes: usize,
    /// Time spent merging observations and computing factors (between passes).
    pub learning_time: Duration,
}

/// How a `learned` sampler is laid out before it learns, for `info`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearnedLayout {
    /// Clusters of the tree's first [`LEVELS`] levels.
    pub clusters: u32,
    /// Top nodes whose choices are learned.
    pub top_nodes: usize,
    /// Edge of a grid cell, m.
    pub cell_size: f32,
    /// Most bytes the sums and factors can take ([`grid::CELLS`] cells).
    pub max_bytes: usize,
}

/// The learned factors of every cell, frozen for a pass.
#[derive(Debug, Default)]
struct Factors {
    /// Per cell: its row, or [`UNLEARNED`]; empty before anything is learned.
    rows: Vec<u32>,
    /// Per row: `v_k` for every top node and child, `slot·WIDTH + k`.
    v: Vec<f32>,
}

/// The `learned` sampler: see the module docs.
#[derive(Clone, Debug)]
pub struct LearnedSampler {
    tree: Arc<LightTree>,
    frontier: Arc<Frontier>,
    grid: SceneGrid,
    factors: Arc<Factors>,
    /// Sums over every pass learned from, per cell: one entry per cluster.
    sums: Observations,
    stats: LearnedStats,
}

impl LearnedSampler {
    /// The sampler over `lights` (non-empty) in a scene bounded by the sphere of centre
    /// `scene_centre` and radius `scene_radius`, with nothing learned yet (it samples as the
    /// tree does).
    pub fn new(lights: &[Light], scene_centre: Vec3A, scene_radius: f32) -> Self {
        let tree = LightTree::new(lights);
        let frontier = Frontier::new(&tree, LEVELS);
        Self {
            tree: Arc::new(tree),
            frontier: Arc::new(frontier),
            grid: SceneGrid::new(scene_centre, scene_radius),
            factors: Arc::default(),
            sums: Observations::default(),
            stats: LearnedStats::default(),
        }
    }

    /// The same sampler with nothing learned: what each render starts from.
    pub fn fresh(&self) -> Self {
        Self { factors: Arc::default(), sums: Observations::default(), stats: LearnedStats::default(), ..self.clone() }
    }

    /// Bytes one learned cell takes: its sums (and map entry), and its factor row.
    fn cell_bytes(&self) -> (usize, usize) {
        let sums = self.frontier.clusters as usize * std::mem::size_of::<Sums>() + 32;
        (sums, self.frontier.runs.len() * WIDTH * 4)
    }

    /// Bytes of the factors' index over the whole grid, once anything is learned.
    const INDEX_BYTES: usize = grid::CELLS * 4;

    /// Its clusters, cells and memory bound.
    pub fn layout(&self) -> LearnedLayout {
        let (sums, factors) = self.cell_bytes();
        LearnedLayout {
            clusters: self.frontier.clusters,
            top_nodes: self.frontier.runs.len(),
            cell_size: self.grid.edge(),
            max_bytes: grid::CELLS * (sums + factors) + Self::INDEX_BYTES,
        }
    }

    /// The light tree it reweights.
    pub fn tree(&self) -> &LightTree {
        &self.tree
    }

    /// What it has learned so far.
    pub fn stats(&self) -> LearnedStats {
        LearnedStats { memory_bytes: self.memory_bytes(), ..self.stats }
    }

    /// Bytes of tree, frontier, sums and factors.
    pub fn memory_bytes(&self) -> usize {
        let sums = self.cell_bytes().0;
        self.tree.stats().memory_bytes
            + self.frontier.memory_bytes()
            + self.sums.cells.len() * sums
            + self.factors.v.len() * 4
            + self.factors.rows.len() * 4
    }

    /// The learned factors at `ctx`, if its cell has any.
    #[inline]
    fn factors_at(&self, ctx: &ShadingContext) -> Option<&[f32]> {
        let row = *self.factors.rows.get(self.grid.locate(ctx).0)?;
        if row == UNLEARNED {
            return None;
        }
        let width = self.frontier.runs.len() * WIDTH;
        Some(&self.factors.v[row as usize * width..][..width])
    }

    /// The reweighting of the tree at `ctx`: the defensive mixture with its cell's factors.
    #[inline]
    fn mixture(&self, ctx: &ShadingContext) -> Mixture<'_> {
        Mixture { slot: &self.frontier.slot, v: self.factors_at(ctx) }
    }

    /// Records one light sample at `ctx`: its unshadowed contribution `c` and whether its
    /// shadow ray got through.
    #[inline]
    pub fn observe(&self, seen: &mut Observations, ctx: &ShadingContext, light: LightId, c: f32, visible: bool) {
        if !(c.is_finite() && c > 0.0) {
            return;
        }
        let cell = self.grid.locate(ctx).0 as u32;
        let cluster = self.frontier.cluster[light.0 as usize] as usize;
        let s = &mut seen.row(cell, self.frontier.clusters as usize)[cluster];
        let q = Fixed::of(c as f64, Fixed::SQUARE, Fixed::LIMIT);
        s.offered += q;
        s.arrived += if visible { q } else { 0 };
        s.n += 1;
    }

    /// Learns from what the light samples since the last call saw and recomputes the
    /// factors every cell will sample with from now on.
    pub fn learn(&mut self, seen: Observations) {
        let start = Instant::now();
        self.stats.samples += seen.cells.iter().flat_map(|(_, sums)| sums).map(|s| s.n as u64).sum::<u64>();
        self.sums.merge(seen);
        self.factors = Arc::new(self.compute_factors());
        self.stats.cells = self.factors.v.len() / (self.frontier.runs.len() * WIDTH);
        self.stats.learning_time += start.elapsed();
    }

    /// `v_k` of every cell's top nodes from the sums (see the module docs).
    fn compute_factors(&self) -> Factors {
        let width = self.frontier.runs.len() * WIDTH;
        let mut cells: Vec<&(u32, Vec<Sums>)> = self.sums.cells.iter().collect();
        cells.sort_unstable_by_key(|(cell, _)| *cell);
        let mut f = Factors { rows: vec![UNLEARNED; grid::CELLS], v: Vec::with_capacity(cells.len() * width) };
        let mut row = Vec::with_capacity(width);
        for (cell, sums) in cells {
            let (arrived, offered) = sums.iter().fold((0, 0), |(a, o), s| (a + s.arrived, o + s.offered));
            if arrived as f64 >= WORTH_LEARNING * offered as f64 {
                continue;
            }
            row.clear();
            for runs in self.frontier.runs.iter() {
                let v = runs.map(|(a, b)| {
                    let mut s = Sums::default();
                    for c in &sums[a as usize..b as usize] {
                        s.add(c);
                    }
                    let r = if s.offered > 0 { (s.arrived as f64 / s.offered as f64) as f32 } else { 1.0 };
                    let n = s.n as f32;
                    (n * r + PRIOR) / (n + PRIOR)
                });
                let (lo, hi) = v.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), &x| (lo.min(x), hi.max(x)));
                row.extend(if hi < FLAT_FACTORS * lo { [1.0; WIDTH] } else { v });
            }
            // A cell that learned nothing worth using samples as the tree does.
            if row.iter().any(|&x| x != 1.0) {
                f.rows[*cell as usize] = (f.v.len() / width) as u32;
                f.v.extend_from_slice(&row);
            }
        }
        f
    }
}

/// The defensive mixture at the top nodes, with one cell's factors `v` (see the module docs).
struct Mixture<'a> {
    slot: &'a [u32],
    v: Option<&'a [f32]>,
}

impl Reweight for Mixture<'_> {
    #[inline(always)]
    fn reweight(&self, node: usize, w: &mut [f32; WIDTH]) -> bool {
        let (Some(v), Some(&slot)) = (self.v, self.slot.get(node)) else { return false };
        if slot == u32::MAX {
            return false;
        }
        let v = &v[slot as usize * WIDTH..][..WIDTH];
        if v.iter().all(|&x| x == v[0]) {
            return false;
        }
        let total: f32 = w.iter().map(|&x| x.max(0.0)).sum();
        let seen: f32 = w.iter().zip(v).map(|(&x, &f)| x.max(0.0) * f).sum();
        if !(total.is_finite() && total > 0.0 && seen > 0.0) {
            return false;
        }
        let (a, b) = (DEFENSIVE / total, (1.0 - DEFENSIVE) / seen);
        for (x, &f) in w.iter_mut().zip(v) {
            *x = x.max(0.0) * (a + b * f);
        }
        true
    }
}

impl LightSampler for LearnedSampler {
    #[inline]
    fn sample(&self, ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        self.sample_hinting(ctx, u, |_| {})
    }

    #[inline]
    fn interval(&self, ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        self.tree.interval_reweighted(ctx, light, &self.mixture(ctx))
    }
}

impl LearnedSampler {
    /// [`LightSampler::sample`] with the tree's leaf hints (see [`LightTree::sample_hinting`]).
    #[inline]
    pub fn sample_hinting(&self, ctx: &ShadingContext, u: u64, leaf_hint: impl Fn(u32)) -> Option<SampledLight> {
        self.tree.sample_reweighted(ctx, u, leaf_hint, &self.mixture(ctx))
    }
}
