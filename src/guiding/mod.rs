//! Path guiding: where light came from, learned from the render's own paths, so that paths
//! are sent there more often (Müller, Gross, Novák 2017, *Practical Path Guiding*).
//!
//! Owns: [`Guide`], what paths sample from (space cut into regions by a k-d tree of
//! midpoint splits, a learned [`Directions`] per region and side), [`Records`], what paths
//! record into (the next cut, with a fixed-point light sum per leaf quadrant and a sample
//! count per region and side, each worker thread into its own, added up at the end: integer
//! sums, so neither the thread count nor the order of the records changes a bit), and
//! [`Guiding`], the state that turns one iteration's records into the next [`Guide`] and
//! the next cut. An iteration is a learning pass of
//! [`crate::learning`] (samples 0..1, 1..2, 2..4, … up to its last power of two); the
//! distributions a pass samples from are a function of the samples before it alone.
//!
//! A record is the light a path's remainder brought back through a vertex, luminance over
//! the density of the direction it left by: summed per quadrant, an estimate of the light
//! arriving through it (Müller et al.'s estimator). A region whose iteration saw more than
//! [`SPLIT_SAMPLES`]·√(spp of the iteration) records is halved for the next (along x, y, z
//! in turn, copies of its cut each), and each quadtree is re-cut by the light it saw
//! ([`Quadtree::refined`]); the number of quadtree nodes is capped at [`MAX_NODES`].

mod directions;

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

pub use directions::{Directions, Quadtree, from_square, solid_angle_per_area, to_square};

use crate::math::{Fixed, Vec3A};

/// Samples per pixel after which the guide stays as it is.
pub const GUIDE_UNTIL: u32 = 64;
/// Records a region may take in an iteration of one sample per pixel before it is halved
/// (Müller et al.'s c, which grows with √spp).
pub const SPLIT_SAMPLES: f64 = 4000.0;
/// Most quadtree nodes over all regions.
pub const MAX_NODES: usize = 1 << 18;
/// Bytes of a quadtree node's cut (its four children).
const CUT_BYTES: usize = 16;
/// Bytes of a quadtree node's learned distribution.
const DISTRIBUTION_BYTES: usize = 32;
/// Bytes of a quadtree node's sums, per worker thread that records.
const SUMS_BYTES: usize = 32;
/// Fractional bits of a recorded value.
const RECORD_BITS: i32 = 20;
/// Largest value a record keeps (a firefly's weight in what is learned is capped; the image
/// is not touched).
const RECORD_LIMIT: f64 = (1u64 << 23) as f64;
/// Directional distributions per region: one per side a surface faces (±x, ±y, ±z by its
/// normal's largest component), so that a floor and a wall or the two sides of a glass
/// sheet in one region do not share what they learn.
pub const SIDES: usize = 6;
/// Deepest level of the k-d tree (the bits of a [`Space::key`]).
const MAX_REGION_DEPTH: u32 = 63;
/// An entry of [`Regions`] that is a region's index rather than a node's.
const LEAF: u32 = 1 << 31;
/// Cells of the grid a point is placed on along each side of the cube (21 bits).
const GRID: u32 = 1 << 21;

/// The most guiding holds when `threads` worker threads record.
pub fn max_bytes(threads: usize) -> usize {
    MAX_NODES * (CUT_BYTES + DISTRIBUTION_BYTES + SUMS_BYTES * threads)
}

/// Which of the [`SIDES`] a surface of normal `n` faces.
#[inline]
fn side(n: Vec3A) -> usize {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + (n[axis] < 0.0) as usize
}

/// The scene's space as the unit cube: the cube around its bounding sphere.
#[derive(Clone, Copy, Debug)]
struct Space {
    min: Vec3A,
    scale: f32,
}

impl Space {
    fn new(center: Vec3A, radius: f32) -> Self {
        let radius = radius.max(1e-6);
        Self { min: center - Vec3A::splat(radius), scale: 0.5 / radius }
    }

    /// Where `p` lies in the unit cube (clamped into it), as the Morton code of its
    /// coordinates on a 2²¹ grid, x's bit first: bit 62 − d is the side of the k-d tree's
    /// level-d cut it lies on.
    #[inline]
    fn key(&self, p: Vec3A) -> u64 {
        let q = ((p - self.min) * (self.scale * GRID as f32)).clamp(Vec3A::ZERO, Vec3A::splat((GRID - 1) as f32));
        crate::math::morton3(q.z as u32, q.y as u32, q.x as u32)
    }
}

/// Space cut into regions: a k-d tree whose level `d` halves its cell along axis `d mod 3`.
/// An entry with [`LEAF`] set is a region's index, otherwise a node's.
#[derive(Clone, Debug)]
struct Regions {
    root: u32,
    nodes: Vec<[u32; 2]>,
    count: usize,
}

impl Regions {
    fn whole() -> Self {
        Self { root: LEAF, nodes: Vec::new(), count: 1 }
    }

    /// The region holding the point of Morton code `key` ([`Space::key`]).
    #[inline]
    fn locate(&self, key: u64) -> usize {
        let (mut entry, mut depth) = (self.root, 0);
        while entry & LEAF == 0 {
            entry = self.nodes[entry as usize][(key >> (62 - depth)) as usize & 1];
            depth += 1;
        }
        (entry & !LEAF) as usize
    }

    /// The cut with region `r` halved `halvings(r)` times over (2^k regions in its place);
    /// and for each new region, the old one it lies in.
    fn split(&self, halvings: impl Fn(usize) -> u32) -> (Regions, Vec<usize>) {
        let mut out = Regions { root: 0, nodes: Vec::new(), count: 0 };
        let mut origin = Vec::new();
        out.root = out.copy(self, self.root, 0, &halvings, &mut origin);
        (out, origin)
    }

    fn copy(
        &mut self,
        old: &Regions,
        entry: u32,
        depth: u32,
        halvings: &impl Fn(usize) -> u32,
        origin: &mut Vec<usize>,
    ) -> u32 {
        if entry & LEAF != 0 {
            let r = (entry & !LEAF) as usize;
            // A key has 63 bits: no cell is cut finer than that.
            return self.halve(r, halvings(r).min(MAX_REGION_DEPTH - depth), origin);
        }
        let [a, b] = old.nodes[entry as usize];
        let node = self.nodes.len();
        self.nodes.push([0; 2]);
        let a = self.copy(old, a, depth + 1, halvings, origin);
        let b = self.copy(old, b, depth + 1, halvings, origin);
        self.nodes[node] = [a, b];
        node as u32
    }

    fn halve(&mut self, r: usize, times: u32, origin: &mut Vec<usize>) -> u32 {
        if times == 0 {
            origin.push(r);
            self.count += 1;
            return LEAF | (self.count - 1) as u32;
        }
        let node = self.nodes.len();
        self.nodes.push([0; 2]);
        let a = self.halve(r, times - 1, origin);
        let b = self.halve(r, times - 1, origin);
        self.nodes[node] = [a, b];
        node as u32
    }
}

/// What paths sample directions from: a learned distribution per region of space and side
/// (none where nothing was learned there).
#[derive(Clone, Debug)]
pub struct Guide {
    space: Space,
    regions: Regions,
    directions: Vec<Option<Directions>>,
}

impl Guide {
    /// The distribution learned for the region holding `p`, on the side normal `n` faces.
    #[inline]
    pub fn at(&self, p: Vec3A, n: Vec3A) -> Option<&Directions> {
        self.directions[self.regions.locate(self.space.key(p)) * SIDES + side(n)].as_ref()
    }
}

/// What paths record into during an iteration: the cut, and per worker thread its own sums
/// (so that no two threads add to one cache line), added up when the iteration ends.
#[derive(Debug)]
pub struct Records {
    space: Space,
    regions: Regions,
    /// Per region and side (region × [`SIDES`] + side).
    trees: Vec<Quadtree>,
    /// Where each region's leaf quadrants start in a [`Sums`]' `light`.
    offsets: Vec<usize>,
    /// Leaf quadrants over all regions and sides.
    quadrants: usize,
    /// One per rayon worker thread, by its index (filled on its first record).
    slots: Vec<Mutex<Sums>>,
}

/// One thread's sums over an iteration.
#[derive(Debug, Default)]
struct Sums {
    /// Light per leaf quadrant, fixed point with [`RECORD_BITS`] fractional bits.
    light: Vec<u64>,
    /// Records per region and side.
    counts: Vec<u64>,
}

impl Sums {
    /// Zeros for `records`' cut.
    fn zero(records: &Records) -> Self {
        Sums { light: vec![0; records.quadrants], counts: vec![0; records.trees.len()] }
    }
}

/// A worker thread's hold on its sums, for the records of one path.
pub struct Recorder<'a> {
    records: &'a Records,
    sums: MutexGuard<'a, Sums>,
}

impl Recorder<'_> {
    /// Records that light of luminance `value` (over the density it was sampled with)
    /// arrived at `p`, on the side normal `n` faces, from direction `wi`.
    #[inline]
    pub fn record(&mut self, p: Vec3A, n: Vec3A, wi: Vec3A, value: f32) {
        let r = &self.records;
        if self.sums.counts.is_empty() {
            *self.sums = Sums::zero(r);
        }
        let slot = r.regions.locate(r.space.key(p)) * SIDES + side(n);
        self.sums.counts[slot] += 1;
        let q = Fixed::of(value as f64, RECORD_BITS, RECORD_LIMIT).max(0) as u64;
        if q > 0 {
            let leaf = r.trees[slot].leaf(to_square(wi));
            self.sums.light[r.offsets[slot] + leaf] += q;
        }
    }
}

impl Records {
    fn new(space: Space, regions: Regions, trees: Vec<Quadtree>) -> Self {
        let offsets: Vec<usize> =
            trees.iter().scan(0, |start, t| Some(std::mem::replace(start, *start + 4 * t.nodes()))).collect();
        let quadrants = trees.iter().map(|t| 4 * t.nodes()).sum();
        let slots = (0..rayon::current_num_threads().max(1)).map(|_| Mutex::default()).collect();
        Self { space, regions, trees, offsets, quadrants, slots }
    }

    /// The calling thread's sums, to record into (a thread outside rayon's pool shares the
    /// first).
    pub fn recorder(&self) -> Recorder<'_> {
        let slot = &self.slots[rayon::current_thread_index().unwrap_or(0) % self.slots.len()];
        Recorder { records: self, sums: slot.lock().unwrap_or_else(|e| e.into_inner()) }
    }

    /// Every thread's sums added up: integer sums, whatever thread recorded what.
    fn total(&self) -> Sums {
        let mut total = Sums::zero(self);
        for slot in &self.slots {
            let sums = slot.lock().unwrap_or_else(|e| e.into_inner());
            for (t, s) in total.light.iter_mut().zip(&sums.light) {
                *t += s;
            }
            for (t, s) in total.counts.iter_mut().zip(&sums.counts) {
                *t += s;
            }
        }
        total
    }

    /// Bytes it holds (the sums of the threads that recorded).
    fn bytes(&self) -> usize {
        let nodes: usize = self.trees.iter().map(Quadtree::nodes).sum();
        let filled = self.slots.iter().filter(|s| !s.lock().unwrap_or_else(|e| e.into_inner()).counts.is_empty());
        nodes * (CUT_BYTES + SUMS_BYTES * filled.count()) + self.trees.len() * 8 + self.regions.nodes.len() * 8
    }
}

/// What guiding has learned, for the summary, `info` and `compare`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GuideStats {
    /// Regions of space with a learned distribution.
    pub regions: usize,
    /// Quadtree nodes over them.
    pub nodes: usize,
    /// Records learned from.
    pub records: u64,
    /// Bytes of the guide and its records.
    pub memory_bytes: usize,
    /// Time spent learning (between passes).
    pub learning_time: Duration,
}

/// The guiding state of a render: the guide paths sample from now, the records of the
/// iteration under way.
#[derive(Debug)]
pub struct Guiding {
    guide: Guide,
    records: Arc<Records>,
    stats: GuideStats,
}

impl Guiding {
    /// Nothing learned yet, for a scene within the sphere (`center`, `radius`).
    pub fn new(center: Vec3A, radius: f32) -> Self {
        let space = Space::new(center, radius);
        let guide = Guide { space, regions: Regions::whole(), directions: vec![None; SIDES] };
        let records = Arc::new(Records::new(space, Regions::whole(), vec![Quadtree::default(); SIDES]));
        Self { guide, records, stats: GuideStats::default() }
    }

    /// What paths sample from now.
    pub fn guide(&self) -> &Guide {
        &self.guide
    }

    /// What paths record into now.
    pub fn records(&self) -> Arc<Records> {
        Arc::clone(&self.records)
    }

    /// Ends an iteration of `spp` samples per pixel: its records become the guide, and the
    /// next iteration records into a cut refined by them.
    pub fn learn(&mut self, spp: u32) {
        let start = Instant::now();
        let old = &self.records;
        let Sums { light, counts } = old.total();
        let recorded_bytes = old.bytes();
        let sums: Vec<Vec<[u64; 4]>> =
            old.trees.iter().zip(&old.offsets).map(|(t, &o)| t.sums(&light[o..][..4 * t.nodes()])).collect();
        let directions: Vec<Option<Directions>> =
            old.trees.iter().zip(&sums).map(|(t, s)| Directions::new(t, s)).collect();
        let refined: Vec<Quadtree> = old.trees.iter().zip(&sums).map(|(t, s)| t.refined(s)).collect();
        // Halve where an iteration's records passed the threshold, while the nodes fit.
        let threshold = SPLIT_SAMPLES * (spp.max(1) as f64).sqrt();
        let mut room = MAX_NODES.saturating_sub(refined.iter().map(Quadtree::nodes).sum());
        let halvings: Vec<u32> = refined
            .chunks(SIDES)
            .zip(counts.chunks(SIDES))
            .map(|(trees, counts)| {
                let (nodes, n) = (trees.iter().map(Quadtree::nodes).sum::<usize>(), counts.iter().sum::<u64>());
                let mut k = 0;
                // Going from 2^k copies of the trees to 2^(k+1) adds 2^k.
                while n as f64 / (1u64 << k) as f64 > threshold && nodes << k <= room {
                    room -= nodes << k;
                    k += 1;
                }
                k
            })
            .collect();
        let (regions, origin) = old.regions.split(|r| halvings[r]);
        let trees = origin.iter().flat_map(|&o| refined[o * SIDES..][..SIDES].iter().cloned()).collect();
        let space = old.space;
        self.guide = Guide { space, regions: old.regions.clone(), directions };
        self.records = Arc::new(Records::new(space, regions, trees));
        let learned = self.guide.directions.iter().flatten();
        self.stats = GuideStats {
            regions: learned.clone().count(),
            nodes: learned.clone().map(Directions::nodes).sum(),
            records: self.stats.records + counts.iter().sum::<u64>(),
            // What the iteration's records held and what was learned from them: the most at once.
            memory_bytes: learned.map(Directions::bytes).sum::<usize>() + recorded_bytes,
            learning_time: self.stats.learning_time + start.elapsed(),
        };
    }

    /// What it has learned so far.
    pub fn stats(&self) -> GuideStats {
        self.stats
    }
}
