//! `cells`: the per-point weighting of `local`, tabulated once per cell of space where a table
//! can stand for the cell, and the light tree where it cannot.
//!
//! Space is cut into the cells of the scene's grid (`grid.rs`: cubes of an eighth of its
//! radius, times seven normal bins: the dominant axis and sign of the normal, and one for
//! points off surfaces). The first time a shading point falls in a cell,
//! the cell is built: every light's importance (`BoundsPacket::importance`, as `local` and the
//! tree weigh lights) is taken along the bin's axis at the cell's centre and eight corners
//! (a surface through the cell, a floor on its face, may pass near any of them), as a share
//! of their sum; the table is the mean of those shares, mixed with a uniform share
//! [`UNIFORM_SHARE`] so that no light has pmf 0 anywhere in the cell. Where at one of the
//! nine points some light would get more than [`TRUST`] times the table's probability (a
//! lamp or a point light close by, a spot's cone edge through the cell), the table would
//! starve it there: the cell is split into its eight halves, each built the same way when a
//! point first lands in it, down to [`SPLITS`] halvings (fewer where memory is short:
//! [`halvings`]), where the test relaxes to [`LAST_TRUST`]; a cell that fails even that
//! leaves the choice to the light tree at the point itself. Elsewhere a choice is a count
//! over the cell's [`Table16`] (lights in `local`'s Morton order, 2¹⁶ values shared among
//! them: with the uniform share each of at
//! most [`MAX_LIGHTS`] lights owns at least 6), with no importance evaluated, where the
//! tree evaluates eight on every level it descends.
//!
//! Over more than [`MAX_LIGHTS`] lights the tables choose among the light tree's clusters
//! instead (the nodes at its first levels, as many levels as keep them within
//! [`MAX_LIGHTS`]: [`Entries::Clusters`]), weighed by their bounds as their parents in the
//! tree weigh them, and the tree chooses below the chosen cluster with the values that
//! chose it. It does so at diffuse (Lambert) points only, and the tree chooses at the
//! others: there the tables' cell-wide weights starve a point or spot light whose highlight
//! the surface mirrors (on `lobby.glb` they halved the error of most pixels but made a seed
//! in ten 100× worse; the performance page). At diffuse points they are 1.25× the tree's
//! efficiency on `street.ron`, 1.13–1.16× on `rooms.ron` and `instanced_lamps.glb`.
//!
//! A cell's content is a pure function of the cell, so which thread builds it first changes
//! nothing: images are bit-identical for any thread count and any split of the samples, and
//! the pmf at a BSDF hit is the one the light was sampled with (the same cell, the same table
//! or the same tree). Only cells that shading points reach are built, 2 bytes per entry each
//! ([`most_bytes`] bounds them, and [`halvings`] keeps the bound within a quarter of the
//! memory limit); the sampler takes [`MIN_LIGHTS`] lights or more (with fewer, or where not
//! even whole grid cells fit, `LightStrategy::build` takes the `tree` in its place, and the
//! render summary says so).

use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::grid::{self, SceneGrid};
use super::local::LocalSampler;
use super::tree::{Frontier, LightTree};
use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{Light, LightId};
use crate::math::Vec3A;
use crate::math::distribution::Table16;

/// Share of every table's probability spread evenly over all lights.
pub const UNIFORM_SHARE: f32 = 0.1;
/// A table stands for its cell when no light's share at a corner exceeds this many times
/// its probability in the table. 3 since the importance bounds emitters and receivers
/// through their boxes (which keeps near lights at grazing angles from failing the test):
/// with 4, offices.ron (160×120, 64 spp) split 441 cells instead of 996 and its relMSE
/// rose 17 % (0.00245 against 0.00210); with 3 it is 0.00212 at 4 % fewer instructions a
/// sample than before, and the Cornell grids do not change (2 costs offices 13 % more CPU
/// for 8 % less error).
pub const TRUST: f32 = 3.0;
/// [`TRUST`] at a cell's last halving, below which only the tree could do better. A table's
/// probability for a light is at least (1 − [`UNIFORM_SHARE`])/9 of its largest share at the
/// nine points, so no light is ever starved by more than 10× there; 8 leaves the tree only the
/// sharpest cases (a point light a millimetre off the floor), where with [`TRUST`] it took
/// the cells around glass.glb's bulb, 7.6 % of all choices, at about ten times a table's
/// cost. 64 spp, 8 seeds, 160×120, against 2048–4096 spp: glass relMSE·spp without the worst
/// 0.1 % of pixels 11.94 → 11.93 at 7053 → 6784 instructions a sample (136 cells on the tree
/// → 0; `power` 11.97 at 6490), offices.ron 0.1290 → 0.1287 at 17 700 → 17 566 (91 → 0),
/// and a Cornell box with 12 point lights 5 mm off its walls 87.23 → 87.22 at 7238 → 7110
/// (356 → 0).
pub const LAST_TRUST: f32 = 8.0;
/// Fewest lights the sampler takes: below, the tree is a node or two, and its per-point
/// weights are worth their cost (punctual.glb, 3 lights: relMSE per sample 4.6e-4 against
/// the tree's 2.9e-4, 0.86 of its efficiency; panels.glb, 4 lights: 0.93–1.12 of the tree's
/// efficiency over four runs of `tools/equal_time.py`, no clear gain).
pub const MIN_LIGHTS: usize = 8;
/// Halvings of a grid cell whose table would not do, before the tree takes over. Two leave
/// fewer points to the tree's costlier choice: on glass.glb, where the points around the
/// bulb's globe are the ones split, 102 small cells on the tree instead of 40 larger ones,
/// and `cells` CPU time 0.97× (one halving: `cells` 1.16× the time of `power`, two: 1.14×;
/// medians of 12–15 pairs); the error on cornell_grid_7.glb is the same. The bound on
/// memory ([`most_bytes`]) grows eight times with it, so a sampler halves fewer times where
/// that bound would not fit ([`halvings`]).
pub const SPLITS: u32 = 2;
/// Most entries a table chooses among: up to this many lights, the lights; above, the
/// clusters of the light tree's first levels ([`Entries::Clusters`]). With 16-bit tables
/// drawn through their summary, 1024 lights pay: cornell-32x32, 64 spp, 8 seeds, relMSE·spp 0.289 against the tree's 0.309 and
/// uniform's 0.411, at 7241 instructions a sample against 9831 and 6901; offices.ron, 768
/// lights, 0.137 against the tree's 0.146 at 18 252 instructions against 24 743 (with
/// 8-byte tables cornell-32x32 had been 0.88 of the tree's efficiency). With the uniform
/// share each of this many lights owns at least 6 of a table's 2¹⁶ values.
pub const MAX_LIGHTS: usize = 1024;
const _: () = assert!(MAX_LIGHTS <= Table16::MAX && UNIFORM_SHARE / MAX_LIGHTS as f32 * Table16::VALUES as f32 >= 6.0);
/// What a cell chooses with.
#[derive(Debug)]
enum Cell {
    /// The cell's own table.
    Table(Table16),
    /// Its eight halves, built on first use (octant bit 0: upper x, bit 1: y, bit 2: z).
    Split(Box<[OnceLock<Cell>; 8]>),
    /// The light tree, at the point itself.
    Tree,
}

/// The most bytes a sampler over `lights` lights halving its cells up to `splits` times can
/// come to: every grid cell and bin reached and split as far as it may, a slot for each
/// cell and its halves, and a table in each of the smallest (a split cell has none, so at
/// most 8^`splits` tables a grid cell).
pub fn most_bytes(lights: usize, splits: u32) -> u64 {
    let grid = grid::CELLS as u64;
    let slots: u64 = (0..=splits).map(|l| 8u64.pow(l)).sum();
    let tables = 8u64.pow(splits);
    grid * (slots * std::mem::size_of::<OnceLock<Cell>>() as u64 + tables * Table16::bytes_for(lights) as u64)
}

/// How many times a sampler over `lights` lights halves its cells: up to [`SPLITS`], as
/// many as keep [`most_bytes`] within a quarter of the memory limit (1.30 GB at 256 lights
/// and two halvings, 0.61 GB at 1024 and one). `None` outside [`MIN_LIGHTS`] to
/// [`MAX_LIGHTS`], or where not even whole grid cells fit: `LightStrategy::build` builds
/// the tree there instead.
pub fn halvings(lights: usize) -> Option<u32> {
    halvings_within(lights, crate::limits::memory_limit().bytes / 4)
}

/// [`halvings`] with `budget` bytes for the sampler.
fn halvings_within(lights: usize, budget: u64) -> Option<u32> {
    let fits = |splits: &u32| most_bytes(lights, *splits) <= budget;
    (MIN_LIGHTS..=MAX_LIGHTS).contains(&lights).then(|| (0..=SPLITS).rev().find(fits)).flatten()
}

/// What a [`CellSampler`] has built, for the render summary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellStats {
    /// Edge of a grid cell.
    pub edge: f32,
    /// Most halvings of a grid cell ([`halvings`]).
    pub halvings: u32,
    /// The tree's clusters the tables choose among, or 0 where they choose among the lights.
    pub clusters: usize,
    /// Cells (grid cells and halves of them) with a table.
    pub tables: usize,
    /// Cells split into halves.
    pub splits: usize,
    /// Cells left to the tree.
    pub on_tree: usize,
    /// Bytes of the sampler (tree, grid and tables).
    pub memory_bytes: usize,
}

/// What a cell's table chooses among.
#[derive(Clone, Debug)]
enum Entries {
    /// Every light, in `local`'s Morton order: up to [`MAX_LIGHTS`] lights.
    Lights(LocalSampler),
    /// The clusters of the tree's first levels, as many levels as keep them within
    /// [`MAX_LIGHTS`] (in depth-first order, so neighbours in space): the tree chooses below
    /// the cluster a table chose, with the values that chose it, so a light's pmf is still
    /// exactly the share of the 2⁶⁴ values that reach it. At points whose BSDF is not
    /// Lambert's the tree chooses from its root ([`CellSampler::sample_at`]).
    Clusters(Frontier),
}

impl Entries {
    /// The entries for `lights` lights over `tree`: the lights themselves, or the largest
    /// frontier of the tree within [`MAX_LIGHTS`] clusters.
    fn over(lights: &[Light], tree: &LightTree) -> Self {
        if lights.len() <= MAX_LIGHTS {
            return Entries::Lights(LocalSampler::new(lights));
        }
        let mut frontier = Frontier::new(tree, 1);
        for levels in 2..=tree.stats().depth {
            let deeper = Frontier::new(tree, levels);
            if deeper.clusters as usize > MAX_LIGHTS {
                break;
            }
            frontier = deeper;
        }
        Entries::Clusters(frontier)
    }

    fn len(&self) -> usize {
        match self {
            Entries::Lights(local) => local.lights(),
            Entries::Clusters(f) => f.clusters as usize,
        }
    }

    /// Every entry's importance at `ctx`, in entry order.
    fn importances(&self, tree: &LightTree, ctx: &ShadingContext, out: &mut Vec<f32>) {
        match self {
            Entries::Lights(local) => local.importances(ctx, out),
            Entries::Clusters(f) => f.importances(tree, ctx, out),
        }
    }

    fn memory_bytes(&self) -> usize {
        match self {
            Entries::Lights(local) => local.memory_bytes(),
            Entries::Clusters(f) => f.memory_bytes(),
        }
    }
}

/// Per-cell tables over the lights, or over clusters of them where there are more than
/// [`MAX_LIGHTS`]; the tree where they fail.
#[derive(Debug)]
pub struct CellSampler {
    entries: Entries,
    tree: LightTree,
    grid: SceneGrid,
    /// Most halvings of a grid cell before the tree takes over.
    halvings: u32,
    /// Every grid cell, built on first use.
    cells: Vec<OnceLock<Cell>>,
    /// Cells built so far with a table, split, and left to the tree.
    tables: AtomicUsize,
    splits: AtomicUsize,
    on_tree: AtomicUsize,
}

impl Clone for CellSampler {
    /// A sampler over the same lights with no cell built yet (each rebuilds the same).
    fn clone(&self) -> Self {
        Self {
            entries: self.entries.clone(),
            tree: self.tree.clone(),
            cells: empty_cells(),
            tables: AtomicUsize::new(0),
            splits: AtomicUsize::new(0),
            on_tree: AtomicUsize::new(0),
            ..*self
        }
    }
}

fn empty_cells() -> Vec<OnceLock<Cell>> {
    (0..grid::CELLS).map(|_| OnceLock::new()).collect()
}

impl CellSampler {
    /// A sampler over `lights`, whose light tree is `tree`, in a scene whose bounding sphere
    /// has centre `centre` and radius `radius`; the tree back where tables would not do
    /// (fewer than [`MIN_LIGHTS`] lights, or not even whole grid cells fit: [`halvings`]).
    pub fn new(lights: &[Light], tree: LightTree, centre: Vec3A, radius: f32) -> Result<Self, Box<LightTree>> {
        let entries = Entries::over(lights, &tree);
        match halvings(entries.len()) {
            Some(halvings) => Ok(Self::with(entries, tree, centre, radius, halvings)),
            None => Err(Box::new(tree)),
        }
    }

    /// A sampler choosing among `entries`, halving its cells up to `halvings` (at most
    /// [`SPLITS`]) times.
    fn with(entries: Entries, tree: LightTree, centre: Vec3A, radius: f32, halvings: u32) -> Self {
        assert!(halvings <= SPLITS, "at most {SPLITS} halvings");
        Self {
            entries,
            tree,
            grid: SceneGrid::new(centre, radius),
            halvings,
            cells: empty_cells(),
            tables: AtomicUsize::new(0),
            splits: AtomicUsize::new(0),
            on_tree: AtomicUsize::new(0),
        }
    }

    /// What it has built so far.
    pub fn stats(&self) -> CellStats {
        let load = |c: &AtomicUsize| c.load(Ordering::Relaxed);
        let (tables, splits, on_tree) = (load(&self.tables), load(&self.splits), load(&self.on_tree));
        let memory_bytes = self.entries.memory_bytes()
            + self.tree.stats().memory_bytes
            + (self.cells.len() + 8 * splits) * std::mem::size_of::<OnceLock<Cell>>()
            + tables * Table16::bytes_for(self.entries.len());
        let clusters = match &self.entries {
            Entries::Lights(_) => 0,
            Entries::Clusters(f) => f.clusters as usize,
        };
        CellStats { edge: self.grid.edge(), halvings: self.halvings, clusters, tables, splits, on_tree, memory_bytes }
    }

    /// The tree's choice, out of line: it is the rare case, and inlined beside the table's
    /// it would crowd the hot loop's code out of the instruction cache.
    #[inline(never)]
    fn tree_sample(&self, ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        self.tree.sample(ctx, u)
    }

    /// The tree's interval, out of line (see [`tree_sample`](Self::tree_sample)).
    #[inline(never)]
    fn tree_interval(&self, ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        self.tree.interval(ctx, light)
    }

    /// The light tree it chooses with where a table would not do.
    pub fn tree(&self) -> &LightTree {
        &self.tree
    }

    /// What chooses at `ctx`: the table of the smallest cell holding it, or the tree. Cells
    /// are built on first use.
    #[inline]
    fn choice(&self, ctx: &ShadingContext) -> Option<&Table16> {
        let (index, mut corner) = self.grid.locate(ctx);
        let (mut edge, mut level) = (self.grid.edge(), 0);
        let bin = index % grid::BINS;
        let mut cell = self.built(&self.cells[index], corner, edge, bin, level);
        loop {
            match cell {
                Cell::Table(t) => return Some(t),
                Cell::Tree => return None,
                Cell::Split(octants) => {
                    (edge, level) = (0.5 * edge, level + 1);
                    let upper = (ctx.p - corner).cmpge(Vec3A::splat(edge));
                    corner += Vec3A::select(upper, Vec3A::splat(edge), Vec3A::ZERO);
                    cell = self.built(&octants[upper.bitmask() as usize], corner, edge, bin, level);
                }
            }
        }
    }

    /// The cell in `slot`, built (see [`build`](Self::build)) if no point has reached it yet.
    #[inline(always)]
    fn built<'a>(&self, slot: &'a OnceLock<Cell>, corner: Vec3A, edge: f32, bin: usize, level: u32) -> &'a Cell {
        match slot.get() {
            Some(cell) => cell,
            None => self.first_use(slot, corner, edge, bin, level),
        }
    }

    /// [`built`](Self::built)'s rare case, out of line so that the common one keeps its
    /// arguments in registers.
    #[cold]
    #[inline(never)]
    fn first_use<'a>(&self, slot: &'a OnceLock<Cell>, corner: Vec3A, edge: f32, bin: usize, level: u32) -> &'a Cell {
        slot.get_or_init(|| self.build(corner, edge, bin, level))
    }

    /// Every entry's importance at `p` along `n` as a share of their sum (`None` when all
    /// are 0); `w` is scratch.
    fn shares(&self, p: Vec3A, n: Vec3A, w: &mut Vec<f32>) -> Option<Vec<f64>> {
        self.entries.importances(&self.tree, &ShadingContext::new(p, n), w);
        let total: f64 = w.iter().map(|&x| x.max(0.0) as f64).sum();
        (total > 0.0 && total.is_finite()).then(|| w.iter().map(|&x| x.max(0.0) as f64 / total).collect())
    }

    /// The cube at `corner` of edge `edge`, `level` halvings below the grid, for receivers
    /// of normal bin `bin`: its [`table`](Self::table) under [`TRUST`], or where none will
    /// do, its eight halves; at its most halvings, its table under [`LAST_TRUST`] or the tree.
    fn build(&self, corner: Vec3A, edge: f32, bin: usize, level: u32) -> Cell {
        let last = level == self.halvings;
        let trust = if last { LAST_TRUST } else { TRUST };
        let cell = self.table(corner, edge, grid::bin_normal(bin), trust).map_or_else(
            || {
                if !last { Cell::Split(Box::new(std::array::from_fn(|_| OnceLock::new()))) } else { Cell::Tree }
            },
            Cell::Table,
        );
        let counter = match cell {
            Cell::Table(_) => &self.tables,
            Cell::Split(_) => &self.splits,
            Cell::Tree => &self.on_tree,
        };
        counter.fetch_add(1, Ordering::Relaxed);
        cell
    }

    /// The table of a cube: the mean of the entries' shares at its centre and its eight
    /// corners (a surface through the cube may pass near any of them), or `None` when at
    /// one of those points some entry would get more than `trust` times the table's
    /// probability.
    fn table(&self, corner: Vec3A, edge: f32, n: Vec3A, trust: f32) -> Option<Table16> {
        let count = self.entries.len();
        let points = (0..8)
            .map(|k| corner + Vec3A::new((k & 1) as f32, ((k >> 1) & 1) as f32, (k >> 2) as f32) * edge)
            .chain([corner + Vec3A::splat(0.5 * edge)]);
        let (mut w, mut seen) = (Vec::new(), Vec::new());
        let mut mean = vec![0.0f64; count];
        for p in points {
            let Some(shares) = self.shares(p, n, &mut w) else { continue };
            mean.iter_mut().zip(&shares).for_each(|(m, x)| *m += x);
            seen.push(shares);
        }
        let even = UNIFORM_SHARE as f64 / count as f64;
        let probabilities: Vec<f64> = if seen.is_empty() {
            vec![1.0 / count as f64; count]
        } else {
            mean.iter().map(|m| (1.0 - UNIFORM_SHARE as f64) * m / seen.len() as f64 + even).collect()
        };
        let starved = seen.iter().any(|s| s.iter().zip(&probabilities).any(|(&x, &p)| x > trust as f64 * p));
        if starved {
            return None;
        }
        let weights: Vec<f32> = probabilities.iter().map(|&p| p as f32).collect();
        Some(Table16::new(&weights).expect("every weight has the positive uniform share"))
    }
}

impl CellSampler {
    /// [`LightSampler::sample`] at a point whose BSDF is Lambert's or not (`diffuse`),
    /// calling `leaf_hint` as [`LightTree::sample_hinting`] does where the tree chooses.
    /// Tables over clusters choose at diffuse points only; at the others the tree does (see
    /// [`Entries::Clusters`]).
    #[inline]
    pub fn sample_at(
        &self,
        ctx: &ShadingContext,
        diffuse: bool,
        u: u64,
        leaf_hint: impl Fn(u32),
    ) -> Option<SampledLight> {
        if !diffuse && self.tree_at_glossy() {
            return self.tree.sample_hinting(ctx, u, leaf_hint);
        }
        let Some(t) = self.choice(ctx) else { return self.tree_sample(ctx, u) };
        let (index, pmf) = t.sample(u);
        match &self.entries {
            Entries::Lights(local) => Some(SampledLight { light: local.light_at(index), pmf }),
            Entries::Clusters(f) => {
                let (start, end) = t.interval(index);
                self.tree.sample_below(ctx, f.head(index as u32), u as u128 - start, end - start, leaf_hint)
            }
        }
    }

    /// [`LightSampler::interval`] at a point whose BSDF is Lambert's or not (`diffuse`): what
    /// [`sample_at`](Self::sample_at) chooses `light` with.
    #[inline]
    pub fn interval_at(&self, ctx: &ShadingContext, diffuse: bool, light: LightId) -> (u128, u128) {
        if !diffuse && self.tree_at_glossy() {
            return self.tree.interval(ctx, light);
        }
        let Some(t) = self.choice(ctx) else { return self.tree_interval(ctx, light) };
        match &self.entries {
            Entries::Lights(local) => t.interval(local.slot_of(light)),
            Entries::Clusters(f) => {
                let cluster = f.cluster[light.0 as usize];
                let (start, end) = t.interval(cluster as usize);
                self.tree.interval_below_cluster(ctx, light, f.head(cluster), (start, end - start))
            }
        }
    }

    /// Whether the tree chooses at points whose BSDF is not Lambert's: where tables choose
    /// among clusters.
    #[inline]
    fn tree_at_glossy(&self) -> bool {
        matches!(self.entries, Entries::Clusters(_))
    }
}

/// The sampler at diffuse points (its tables wherever they stand).
impl LightSampler for CellSampler {
    #[inline]
    fn sample(&self, ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        self.sample_at(ctx, true, u, |_| {})
    }

    #[inline]
    fn interval(&self, ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        self.interval_at(ctx, true, light)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{AreaEmission, PointLight, QuadLight};
    use crate::math::Rgb;

    fn lamps(n: usize) -> Vec<Light> {
        (0..n)
            .map(|i| {
                let e = AreaEmission { radiance: Rgb::splat(1.0 + (i % 3) as f32), two_sided: false };
                let p = Vec3A::new((i % 8) as f32 * 0.5, 2.0, (i / 8) as f32 * 0.5);
                Light::Quad(QuadLight::new(p, Vec3A::X * 0.1, Vec3A::Z * 0.1, e).unwrap())
            })
            .collect()
    }

    fn sampler(lights: &[Light]) -> CellSampler {
        let tree = LightTree::new(lights);
        CellSampler::with(Entries::over(lights, &tree), tree, Vec3A::new(1.75, 1.5, 1.0), 4.0, SPLITS)
    }

    #[test]
    fn far_from_the_lamps_a_table_keeps_every_light_choosable_and_its_cells_tile() {
        let lights = lamps(40);
        let s = sampler(&lights);
        // Above the lamps, facing up: no lamp faces this point, so only the uniform share is
        // left, and it is even, up to the one of a table's 2¹⁶ values a light may get more
        // or less than its share.
        let value = 1.0 / Table16::VALUES as f32;
        let above = ShadingContext::new(Vec3A::new(1.0, 3.5, 1.0), Vec3A::Y);
        for l in 0..40 {
            assert!((s.pmf(&above, LightId(l)) - 1.0 / 40.0).abs() <= value);
        }
        let below = ShadingContext::new(Vec3A::new(0.2, 0.0, 0.2), Vec3A::Y);
        assert!(s.choice(&below).is_some(), "2 m from the lamps a table will do");
        for l in 0..40 {
            assert!(s.pmf(&below, LightId(l)) >= UNIFORM_SHARE / 40.0 - value);
        }
        assert!(s.pmf(&below, LightId(0)) > 2.0 * s.pmf(&below, LightId(39)), "the near lamp weighs more");
        check_tiling(&s, &below, 40);
        assert_eq!((s.stats().tables, s.stats().splits, s.stats().on_tree), (2, 0, 0));
    }

    #[test]
    fn next_to_a_point_light_cells_split_and_the_last_halving_takes_a_looser_table() {
        let mut lights = lamps(8);
        lights.push(Light::Point(PointLight { position: Vec3A::new(0.26, 0.001, 0.51), intensity: Rgb::splat(0.01) }));
        let s = sampler(&lights);
        let near = ShadingContext::new(Vec3A::new(0.3, 0.0, 0.55), Vec3A::Y);
        assert!(s.choice(&near).is_some(), "a point light 1 mm above the floor, 1 cm off a corner: {:?}", s.stats());
        let st = s.stats();
        assert_eq!((st.splits, st.on_tree), (SPLITS as usize, 0), "{st:?}");
        // The cell `near` ended in (edge 0.5 m halved twice, corner on the lattice): the
        // light starves there under TRUST, not under LAST_TRUST.
        let corner = Vec3A::new(0.25, 0.0, 0.5);
        assert!(s.table(corner, 0.125, Vec3A::Y, TRUST).is_none());
        assert!(s.table(corner, 0.125, Vec3A::Y, LAST_TRUST).is_some());
        check_tiling(&s, &near, 9);
        // A metre and more away a table does at once.
        let off = ShadingContext::new(Vec3A::new(0.6, 0.0, -0.7), Vec3A::Y);
        assert!(s.choice(&off).is_some());
        check_tiling(&s, &off, 9);
    }

    #[test]
    fn a_point_light_on_a_last_cells_corner_leaves_the_cell_to_the_tree() {
        let mut lights = lamps(8);
        // A tenth of a millimetre off the corner (0.25, 0, 0.5): nearly all of the light
        // there, almost none at the other eight points, more than LAST_TRUST times the mean.
        lights.push(Light::Point(PointLight {
            position: Vec3A::new(0.2501, 0.0001, 0.5001),
            intensity: Rgb::splat(0.01),
        }));
        let s = sampler(&lights);
        let near = ShadingContext::new(Vec3A::new(0.3, 0.0, 0.55), Vec3A::Y);
        assert!(s.choice(&near).is_none(), "{:?}", s.stats());
        for l in 0..9 {
            assert_eq!(s.pmf(&near, LightId(l)), s.tree.pmf(&near, LightId(l)));
        }
        let st = s.stats();
        assert_eq!((st.splits, st.on_tree), (SPLITS as usize, 1), "{st:?}");
    }

    /// Every light's cell at `ctx` is as its pmf says, and the cells tile the 2⁶⁴ values.
    fn check_tiling(s: &CellSampler, ctx: &ShadingContext, n: u32) {
        let mut cells: Vec<_> = (0..n).map(|l| s.interval(ctx, LightId(l))).collect();
        for (l, c) in cells.iter().enumerate() {
            assert_eq!(s.pmf(ctx, LightId(l as u32)), crate::math::distribution::probability(c.1 - c.0));
        }
        cells.sort();
        assert!(cells.windows(2).all(|c| c[0].1 == c[1].0) && cells[0].0 == 0 && cells.last().unwrap().1 == 1 << 64);
    }

    #[test]
    fn over_more_lights_than_a_table_takes_tables_choose_clusters_and_the_tree_within_them() {
        // A ceiling of 1500 lamps: more than MAX_LIGHTS, so tables over the tree's clusters.
        let lights = lamps(1500);
        let s = sampler(&lights);
        let Entries::Clusters(f) = &s.entries else { panic!("1500 lights: clusters") };
        assert!((64..=MAX_LIGHTS as u32).contains(&f.clusters), "{} clusters", f.clusters);
        for ctx in [
            ShadingContext::new(Vec3A::new(1.0, 0.0, 40.0), Vec3A::Y),
            ShadingContext::new(Vec3A::new(2.0, 1.9, 90.0), Vec3A::Y),
            ShadingContext::new(Vec3A::new(3.0, 1.0, 20.0), Vec3A::ZERO),
        ] {
            assert!(s.choice(&ctx).is_some(), "{ctx:?}: a table");
            check_tiling(&s, &ctx, 1500);
            // Every value picks the light whose interval holds it, with that interval's pmf.
            for k in 0..2000u64 {
                let u = k.wrapping_mul(0x9e37_79b9_7f4a_7c15);
                let Some(picked) = s.sample(&ctx, u) else { continue };
                let (a, b) = s.interval(&ctx, picked.light);
                assert!(a <= u as u128 && (u as u128) < b);
                assert_eq!(picked.pmf, crate::math::distribution::probability(b - a));
            }
        }
        assert!(s.stats().tables >= 3, "{:?}", s.stats());
    }

    #[test]
    fn over_clusters_the_tree_chooses_at_glossy_points_and_the_tables_at_diffuse_ones() {
        let lights = lamps(1500);
        let s = sampler(&lights);
        let ctx = ShadingContext::new(Vec3A::new(1.0, 0.0, 40.0), Vec3A::Y);
        let (mut same, mut differ) = (0, 0);
        for k in 0..500u64 {
            let u = k.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            assert_eq!(s.sample_at(&ctx, false, u, |_| {}), s.tree.sample(&ctx, u));
            let picked = s.sample_at(&ctx, true, u, |_| {}).expect("a lamp above");
            let (a, b) = s.interval_at(&ctx, true, picked.light);
            assert!(a <= u as u128 && (u as u128) < b);
            let light = picked.light;
            assert_eq!(s.interval_at(&ctx, false, light), s.tree.interval(&ctx, light));
            if s.interval_at(&ctx, true, light) == s.tree.interval(&ctx, light) { same += 1 } else { differ += 1 }
        }
        assert!(differ > same, "the tables choose otherwise than the tree: {differ} against {same}");
        // Over the lights themselves, the tables choose at glossy points too.
        let few = sampler(&lamps(40));
        let below = ShadingContext::new(Vec3A::new(0.2, 0.0, 0.2), Vec3A::Y);
        for l in 0..40 {
            assert_eq!(few.interval_at(&below, false, LightId(l)), few.interval_at(&below, true, LightId(l)));
        }
    }

    #[test]
    fn on_a_machine_of_8_gb_cells_halve_twice_at_256_lights_and_once_at_512_to_1024() {
        // Limit 3/4 of 8 GB, a quarter of it for the sampler.
        let budget = 8_000_000_000 / 4 * 3 / 4;
        assert_eq!(halvings_within(MIN_LIGHTS - 1, budget), None);
        assert_eq!(halvings_within(256, budget), Some(2));
        assert_eq!(halvings_within(512, budget), Some(1));
        assert_eq!(halvings_within(MAX_LIGHTS, budget), Some(1));
        assert_eq!(halvings_within(MAX_LIGHTS + 1, budget), None);
        assert!(most_bytes(MAX_LIGHTS, 1) <= budget && most_bytes(MAX_LIGHTS, 2) > budget);
        // With little memory, whole grid cells only, then the tree.
        assert_eq!(halvings_within(MAX_LIGHTS, most_bytes(MAX_LIGHTS, 0)), Some(0));
        assert_eq!(halvings_within(MAX_LIGHTS, most_bytes(MAX_LIGHTS, 0) - 1), None);
    }

    #[test]
    fn a_clone_builds_the_same_cells() {
        let lights = lamps(20);
        let a = sampler(&lights);
        let ctx = ShadingContext::new(Vec3A::new(0.7, 0.3, 1.1), -Vec3A::X);
        let picked = a.sample(&ctx, 0x1234_5678_9abc_def0);
        let b = a.clone();
        assert_eq!(b.stats().tables, 0);
        assert_eq!(b.sample(&ctx, 0x1234_5678_9abc_def0), picked);
    }
}
