//! Binned SAOH build of a binary light BVH (Conty Estevez & Kulla 2018, §4; pbrt-v4
//! `BVHLightSampler::buildBVH`; Cycles `light_tree.cpp`).
//!
//! Per node: 12 buckets on every axis of the centroid box; bucket bounds with prefix and
//! suffix sweeps (Cycles' cumulative arrays, so all 11 splits of an axis cost O(12), where
//! pbrt's loop is O(12²) and never tries the split after bucket 0); cost
//! `Kr · (M(left) + M(right))`, `M = φ · area · M_Ω`. Degenerate nodes (all centroids equal,
//! no split with both sides filled) and nodes past a depth limit split at the median, so the
//! tree's depth stays within what a trail can hold. The two halves are built with
//! `rayon::join` above 4096 lights, and binning itself runs in parallel above 65536.
//!
//! Inner nodes live in one array indexed by their split position (Karras 2012): the node
//! splitting items `[s, e)` at `mid` sits in slot `mid − 1`, so the slots of a subtree are a
//! contiguous range and parallel builds write disjoint slices with no locks.

use rayon::prelude::*;

use crate::light::LightBounds;
use crate::math::Vec3A;
use std::f32::consts::{FRAC_PI_2, PI};

const BUCKETS: usize = 12;
const PARALLEL_BUILD: usize = 4096;
const PARALLEL_BINNING: usize = 65536;

/// A light to place in the tree.
#[derive(Clone, Copy, Debug)]
pub struct Item {
    /// What the light can emit where ([`LightBounds`]).
    pub bounds: LightBounds,
    /// The point it is binned by.
    pub centroid: Vec3A,
    /// Index in the scene's light list.
    pub light: u32,
}

/// A child reference: an item (leaf) or an inner node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Child {
    /// Index into the (reordered) items.
    Item(u32),
    /// Index into the inner nodes.
    Node(u32),
}

/// An inner node of the binary tree.
#[derive(Clone, Copy, Debug)]
pub struct BinNode {
    /// Union of its children's bounds.
    pub bounds: LightBounds,
    /// Its two children.
    pub children: [Child; 2],
    /// Lights below it.
    pub count: u32,
}

/// Direction-cone measure M_Ω (Conty & Kulla eq. 1) of normal-cone half-angle θo and
/// emission spread θe.
fn m_omega(theta_o: f32, theta_e: f32) -> f32 {
    let theta_w = (theta_o + theta_e).min(PI);
    let (sin_o, cos_o) = theta_o.sin_cos();
    2.0 * PI * (1.0 - cos_o)
        + FRAC_PI_2 * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + cos_o)
}

const EMPTY: LightBounds = LightBounds {
    min: Vec3A::ZERO,
    max: Vec3A::ZERO,
    phi: 0.0,
    w: Vec3A::Z,
    cos_theta_o: 1.0,
    cos_theta_e: 1.0,
    two_sided: false,
    infinite: false,
};

/// What a bucket accumulates: the lights' boxes and power and, instead of a
/// running cone union (three `acos` and a rotation per light), the box of their cone axes
/// with the widest θo and θe. [`Acc::theta_o`] turns that into a cone once per candidate
/// split. The cone only steers the SAOH cost; the nodes' own bounds are exact unions.
#[derive(Clone, Copy)]
struct Acc {
    min: Vec3A,
    max: Vec3A,
    phi: f32,
    axis_min: Vec3A,
    axis_max: Vec3A,
    cos_theta_o: f32,
    cos_theta_e: f32,
    count: u32,
}

impl Acc {
    const EMPTY: Acc = Acc {
        min: Vec3A::splat(f32::MAX),
        max: Vec3A::splat(f32::MIN),
        phi: 0.0,
        axis_min: Vec3A::splat(f32::MAX),
        axis_max: Vec3A::splat(f32::MIN),
        cos_theta_o: 1.0,
        cos_theta_e: 1.0,
        count: 0,
    };

    #[inline]
    fn add(&mut self, b: &LightBounds) {
        self.min = self.min.min(b.min);
        self.max = self.max.max(b.max);
        self.phi += b.phi;
        self.axis_min = self.axis_min.min(b.w);
        self.axis_max = self.axis_max.max(b.w);
        self.cos_theta_o = self.cos_theta_o.min(b.cos_theta_o);
        self.cos_theta_e = self.cos_theta_e.min(b.cos_theta_e);
        self.count += 1;
    }

    fn merge(&self, o: &Acc) -> Acc {
        Acc {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
            phi: self.phi + o.phi,
            axis_min: self.axis_min.min(o.axis_min),
            axis_max: self.axis_max.max(o.axis_max),
            cos_theta_o: self.cos_theta_o.min(o.cos_theta_o),
            cos_theta_e: self.cos_theta_e.min(o.cos_theta_e),
            count: self.count + o.count,
        }
    }

    /// Half-angle of a normal cone around everything added: centred on the axis box, it
    /// reaches the box's farthest corner (the box is convex, so no axis inside it is farther),
    /// widened by the widest θo; a box spread beyond 90° counts as the whole sphere.
    fn theta_o(&self) -> f32 {
        let theta_o = crate::math::safe_acos(self.cos_theta_o);
        if self.cos_theta_o <= -1.0 || self.axis_min == self.axis_max {
            return theta_o;
        }
        let Some(w) = (0.5 * (self.axis_min + self.axis_max)).try_normalize() else { return PI };
        let mut cos_box = 1.0f32;
        for k in 0..8 {
            let corner =
                Vec3A::select(glam::BVec3A::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), self.axis_max, self.axis_min);
            cos_box = cos_box.min(w.dot(corner) / corner.length().max(1e-30));
        }
        if cos_box <= 0.0 { PI } else { (crate::math::safe_acos(cos_box) + theta_o).min(PI) }
    }

    /// SAOH measure: power × spatial extent × directional extent (M_Ω).
    fn measure(&self, infinite: bool) -> f32 {
        if self.count == 0 || self.phi == 0.0 {
            return 0.0;
        }
        let spatial = if infinite {
            1.0
        } else {
            let d = self.max - self.min;
            let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
            // Collinear or coincident lights: Cycles' fallback to the diagonal.
            if area > 0.0 { area } else { d.length() }
        };
        self.phi * spatial * m_omega(self.theta_o(), crate::math::safe_acos(self.cos_theta_e))
    }
}

/// One accumulator per bucket per axis.
#[derive(Clone, Copy)]
struct Bins([[Acc; BUCKETS]; 3]);

impl Bins {
    fn new() -> Self {
        Self([[Acc::EMPTY; BUCKETS]; 3])
    }

    /// Bins of a slice of items.
    fn of(items: &[Item], lo: Vec3A, scale: Vec3A) -> Self {
        let mut bins = Self::new();
        for it in items {
            for a in 0..3 {
                bins.0[a][bucket(it.centroid[a], lo[a], scale[a])].add(&it.bounds);
            }
        }
        bins
    }

    fn merge(mut self, o: Self) -> Self {
        for a in 0..3 {
            for b in 0..BUCKETS {
                self.0[a][b] = self.0[a][b].merge(&o.0[a][b]);
            }
        }
        self
    }
}

#[inline]
fn bucket(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BUCKETS - 1)
}

/// Partitions `items` and returns the split position in `1..len`.
fn split(items: &mut [Item], force_median: bool) -> usize {
    let m = items.len();
    // Centroid box and the node's spatial box (its direction cone is not needed here).
    let (mut clo, mut chi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
    let (mut blo, mut bhi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
    for it in items.iter() {
        clo = clo.min(it.centroid);
        chi = chi.max(it.centroid);
        blo = blo.min(it.bounds.min);
        bhi = bhi.max(it.bounds.max);
    }
    let ext = chi - clo;
    let median = |items: &mut [Item]| {
        let axis = ext.max_position();
        items.select_nth_unstable_by(m / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        m / 2
    };
    if force_median || m == 2 || ext.max_element() <= 0.0 {
        return median(items);
    }
    let scale = Vec3A::select(ext.cmpgt(Vec3A::ZERO), Vec3A::splat(BUCKETS as f32) / ext, Vec3A::ZERO);
    let bins = if m > PARALLEL_BINNING {
        items.par_chunks(8192).map(|c| Bins::of(c, clo, scale)).reduce(Bins::new, Bins::merge)
    } else {
        Bins::of(items, clo, scale)
    };
    let infinite = items[0].bounds.infinite;
    let node_ext = if infinite { ext } else { bhi - blo };
    let (mut best, mut best_cost) = (None, f32::INFINITY);
    for a in 0..3 {
        if ext[a] <= 0.0 {
            continue;
        }
        let kr = node_ext.max_element() / node_ext[a].max(1e-30);
        let buckets = &bins.0[a];
        // suffix[i] = buckets i.. together; the prefix is swept alongside.
        let mut suffix = [Acc::EMPTY; BUCKETS + 1];
        for i in (0..BUCKETS).rev() {
            suffix[i] = suffix[i + 1].merge(&buckets[i]);
        }
        let mut prefix = Acc::EMPTY;
        for i in 0..BUCKETS - 1 {
            prefix = prefix.merge(&buckets[i]);
            if prefix.count == 0 || suffix[i + 1].count == 0 {
                continue;
            }
            let cost = kr * (prefix.measure(infinite) + suffix[i + 1].measure(infinite));
            if cost < best_cost {
                best_cost = cost;
                best = Some((a, i));
            }
        }
    }
    let Some((axis, last_left)) = best else { return median(items) };
    // In-place partition: items in buckets ≤ last_left first.
    let mut i = 0;
    let mut j = m;
    while i < j {
        if bucket(items[i].centroid[axis], clo[axis], scale[axis]) <= last_left {
            i += 1;
        } else {
            j -= 1;
            items.swap(i, j);
        }
    }
    if i == 0 || i == m { median(items) } else { i }
}

/// Builds the subtree over `items` (global offset `offset`) into `slots` (this range's inner
/// nodes). Returns the subtree's root and bounds.
pub fn build_range(
    items: &mut [Item],
    offset: u32,
    slots: &mut [BinNode],
    depth: u32,
    median_depth: u32,
) -> (Child, LightBounds) {
    let m = items.len();
    if m == 1 {
        return (Child::Item(offset), items[0].bounds);
    }
    let mid = split(items, depth >= median_depth);
    let (left_slots, rest) = slots.split_at_mut(mid - 1);
    let (node_slot, right_slots) = rest.split_first_mut().expect("a range of m items has m − 1 slots");
    let (left_items, right_items) = items.split_at_mut(mid);
    let mut build_left = || build_range(left_items, offset, left_slots, depth + 1, median_depth);
    let mut build_right = || build_range(right_items, offset + mid as u32, right_slots, depth + 1, median_depth);
    let ((lc, lb), (rc, rb)) =
        if m > PARALLEL_BUILD { rayon::join(build_left, build_right) } else { (build_left(), build_right()) };
    let bounds = lb.union(&rb);
    *node_slot = BinNode { bounds, children: [lc, rc], count: m as u32 };
    (Child::Node(offset + mid as u32 - 1), bounds)
}

/// Builds a binary tree over `items` (reordered in place). Returns the inner nodes and the
/// root; depth never exceeds `max_depth` (median splits take over before it would).
pub fn build(items: &mut [Item], max_depth: u32) -> (Vec<BinNode>, Child, LightBounds) {
    assert!(!items.is_empty());
    let n = items.len();
    let balanced = usize::BITS - (n - 1).leading_zeros(); // ⌈log2 n⌉
    let median_depth = max_depth.saturating_sub(balanced + 1);
    let mut slots = vec![BinNode { bounds: EMPTY, children: [Child::Item(0); 2], count: 0 }; n - 1];
    let (root, bounds) = build_range(items, 0, &mut slots, 0, median_depth);
    (slots, root, bounds)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(x: f32, phi: f32, light: u32) -> Item {
        let p = Vec3A::new(x, 0.0, 0.0);
        let bounds = LightBounds {
            min: p,
            max: p,
            phi,
            w: Vec3A::Y,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
            infinite: false,
        };
        Item { bounds, centroid: p, light }
    }

    fn depth(nodes: &[BinNode], c: Child) -> u32 {
        match c {
            Child::Item(_) => 0,
            Child::Node(i) => 1 + nodes[i as usize].children.iter().map(|&k| depth(nodes, k)).max().unwrap(),
        }
    }

    fn leaves(nodes: &[BinNode], c: Child, out: &mut Vec<u32>) {
        match c {
            Child::Item(i) => out.push(i),
            Child::Node(i) => nodes[i as usize].children.iter().for_each(|&k| leaves(nodes, k, out)),
        }
    }

    #[test]
    fn every_item_is_a_leaf_once_and_bounds_add_up() {
        let mut items: Vec<Item> =
            (0..5000).map(|i| item(((i * 7919) % 5000) as f32, 1.0 + (i % 3) as f32, i)).collect();
        let total: f32 = items.iter().map(|i| i.bounds.phi).sum();
        let (nodes, root, bounds) = build(&mut items, 64);
        let mut l = Vec::new();
        leaves(&nodes, root, &mut l);
        l.sort();
        assert_eq!(l, (0..5000).collect::<Vec<u32>>());
        assert!((bounds.phi - total).abs() < 1e-3 * total);
        assert!(depth(&nodes, root) <= 64);
    }

    #[test]
    fn stacked_lights_split_evenly_and_depth_is_capped() {
        // All centroids equal: median splits, a balanced tree.
        let mut items: Vec<Item> = (0..1024).map(|i| item(0.0, 1.0, i)).collect();
        let (nodes, root, _) = build(&mut items, 64);
        assert_eq!(depth(&nodes, root), 10);
        // A power law along a line tempts SAOH into peeling one light at a time; the depth
        // limit forces median splits before the trail would overflow.
        let mut items: Vec<Item> = (0..3000).map(|i| item(i as f32, 10f32.powf(-(i as f32) / 100.0), i)).collect();
        let (nodes, root, _) = build(&mut items, 24);
        assert!(depth(&nodes, root) <= 24, "{}", depth(&nodes, root));
    }
}
