//! Directional distributions over the sphere: Müller et al.'s quadtrees.
//!
//! A direction maps to the unit square by x = (cos θ + 1)/2, θ from world +z, and y = t/4,
//! t ∈ [0, 4) the *diamond angle* of its azimuth (quadrant k of the xy-plane plus
//! u = |second|/(|first| + |second|) of the direction's coordinates turned into the first
//! quadrant): monotone in the azimuth and computed without trigonometry either way (a
//! direction back from u is (1 − u, u) normalised). A patch of the square of area A covers a
//! solid angle of A · 8 / J, J = (1 − u)² + u² ∈ [½, 1] ([`solid_angle_per_area`]), so a
//! density on the square is one in solid angle times 8/J. A [`Quadtree`] cuts the square
//! into quadrants, finer where more light arrived; a [`Directions`] is one with a
//! probability per quadrant, sampled by descending and reporting the product of the choices
//! as its exact density. Quadrants are numbered `x ≥ ½` + 2·(`y ≥ ½`).

use crate::math::{Vec2, Vec3A};

/// Deepest level a quadrant may be cut to (2⁻⁸ of the square's side).
pub const MAX_DEPTH: u32 = 8;
/// A quadrant holding more than this share of a region's light is cut in four
/// (Müller et al.'s ρ).
pub const SPLIT_SHARE: f64 = 0.01;

/// The largest value below 1 a square coordinate keeps.
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// A direction's point on the unit square (see the module's documentation).
#[inline]
pub fn to_square(d: Vec3A) -> Vec2 {
    let x = ((d.z + 1.0) * 0.5).clamp(0.0, 1.0);
    let (a, b) = (d.x, d.y);
    let sum = a.abs() + b.abs();
    // The diamond angle: quadrant by the signs, then the share of the second coordinate.
    let t = if sum == 0.0 {
        0.0
    } else if b >= 0.0 {
        if a > 0.0 { b / sum } else { 1.0 - a / sum }
    } else if a < 0.0 {
        2.0 - b / sum
    } else {
        3.0 + a / sum
    };
    Vec2::new(x, (t * 0.25).min(BELOW_ONE))
}

/// The direction of a point on the unit square.
#[inline]
pub fn from_square(s: Vec2) -> Vec3A {
    let cos = 2.0 * s.x - 1.0;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let t = 4.0 * s.y;
    let k = (t as u32).min(3);
    let u = t - k as f32;
    let norm = sin / ((1.0 - u) * (1.0 - u) + u * u).sqrt();
    let (a, b) = ((1.0 - u) * norm, u * norm);
    let (x, y) = match k {
        0 => (a, b),
        1 => (-b, a),
        2 => (-a, -b),
        _ => (b, -a),
    };
    Vec3A::new(x, y, cos)
}

/// The solid angle per unit area of the square at `s` (8/J, see the module's documentation).
#[inline]
pub fn solid_angle_per_area(s: Vec2) -> f32 {
    let t = 4.0 * s.y;
    let u = t - (t as u32).min(3) as f32;
    8.0 / ((1.0 - u) * (1.0 - u) + u * u)
}

/// The quadrant of `s` in a node and `s` within it, rescaled to the unit square.
#[inline]
fn quadrant(s: Vec2) -> (usize, Vec2) {
    let (qx, qy) = (s.x >= 0.5, s.y >= 0.5);
    let q = qx as usize + 2 * qy as usize;
    let inner = Vec2::new(2.0 * s.x - qx as u32 as f32, 2.0 * s.y - qy as u32 as f32);
    (q, inner.min(Vec2::splat(BELOW_ONE)))
}

/// How a region's directions are cut: node 0 the whole square, `children[n][q]` the node
/// quadrant `q` of node `n` is cut into (0: not cut, a leaf quadrant).
#[derive(Clone, Debug, PartialEq)]
pub struct Quadtree {
    children: Vec<[u32; 4]>,
}

impl Default for Quadtree {
    /// The square in four quadrants.
    fn default() -> Self {
        Self { children: vec![[0; 4]] }
    }
}

impl Quadtree {
    /// Nodes (each of four quadrants).
    pub fn nodes(&self) -> usize {
        self.children.len()
    }

    /// The leaf quadrant `s` falls in, as node × 4 + quadrant.
    #[inline]
    pub fn leaf(&self, mut s: Vec2) -> usize {
        let mut node = 0;
        loop {
            let (q, inner) = quadrant(s);
            match self.children[node][q] {
                0 => return node * 4 + q,
                c => (node, s) = (c as usize, inner),
            }
        }
    }

    /// Light per quadrant of every node, from the light per leaf quadrant (`leaves`, indexed
    /// as [`leaf`](Self::leaf)): a cut quadrant holds the sum of its node's four.
    pub fn sums(&self, leaves: &[u64]) -> Vec<[u64; 4]> {
        let mut sums: Vec<[u64; 4]> = leaves.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        // Children always come after their parent: a backward sweep completes each node first.
        for n in (0..self.children.len()).rev() {
            for q in 0..4 {
                let c = self.children[n][q] as usize;
                if c != 0 {
                    sums[n][q] = sums[c].iter().sum();
                }
            }
        }
        sums
    }

    /// The next iteration's cut, from the light per quadrant this one's recorded (`sums`,
    /// from [`sums`](Self::sums)): a quadrant holding more than [`SPLIT_SHARE`] of the whole
    /// is cut (a leaf's light shared evenly among its four for the decisions below it), one
    /// holding less is joined back, down to [`MAX_DEPTH`]; nothing learned keeps the cut.
    pub fn refined(&self, sums: &[[u64; 4]]) -> Quadtree {
        let total: u64 = sums[0].iter().sum();
        if total == 0 {
            return self.clone();
        }
        let mut out = Quadtree { children: vec![[0; 4]] };
        // (new node, old node if it exists, its quadrants' light, depth)
        let mut stack = vec![(0usize, Some(0usize), sums[0].map(|s| s as f64), 1u32)];
        while let Some((node, old, light, depth)) = stack.pop() {
            for (q, &quadrant_light) in light.iter().enumerate() {
                if depth >= MAX_DEPTH || quadrant_light <= SPLIT_SHARE * total as f64 {
                    continue;
                }
                let child = out.children.len();
                out.children.push([0; 4]);
                out.children[node][q] = child as u32;
                let old_child = old.map(|o| self.children[o][q] as usize).filter(|&c| c != 0);
                let below = match old_child {
                    Some(c) => sums[c].map(|s| s as f64),
                    None => [quadrant_light / 4.0; 4],
                };
                stack.push((child, old_child, below, depth + 1));
            }
        }
        // A node is pushed after its parent: children always come after their parent.
        out
    }
}

/// A learned directional distribution: a [`Quadtree`]'s cut with each node's probability
/// per quadrant.
#[derive(Clone, Debug)]
pub struct Directions {
    nodes: Vec<Node>,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    children: [u32; 4],
    /// Probability of each quadrant given the node (summing to 1).
    p: [f32; 4],
}

impl Directions {
    /// The distribution of the light `sums` holds per quadrant of `tree`'s nodes; `None`
    /// when no light was recorded at all.
    pub fn new(tree: &Quadtree, sums: &[[u64; 4]]) -> Option<Self> {
        if sums[0].iter().all(|&s| s == 0) {
            return None;
        }
        let nodes = tree
            .children
            .iter()
            .zip(sums)
            .map(|(&children, s)| {
                let total: f64 = s.iter().map(|&x| x as f64).sum();
                let p = if total > 0.0 { s.map(|x| (x as f64 / total) as f32) } else { [0.25; 4] };
                Node { children, p }
            })
            .collect();
        Some(Self { nodes })
    }

    /// Nodes (each of four quadrants).
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes it holds.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
    }

    /// A direction for the point `u` of the unit square, and its solid-angle density.
    #[inline]
    pub fn sample(&self, mut u: Vec2) -> (Vec3A, f32) {
        let (mut node, mut density) = (0usize, 1.0f32);
        let (mut origin, mut size) = (Vec2::ZERO, 1.0f32);
        loop {
            let p = self.nodes[node].p;
            // The column (x half) by the columns' sums, then the quadrant within it; a side
            // of probability 0 is never taken, whatever rounding says.
            let (left, right) = (p[0] + p[2], p[1] + p[3]);
            let column = right > 0.0 && (left <= 0.0 || u.x >= left);
            let ux = if column { (u.x - left) / right } else { u.x / left };
            let column = column as usize;
            let (low, high) = (p[column], p[column + 2]);
            let split = u.y * (low + high);
            let up = high > 0.0 && (low <= 0.0 || split >= low);
            let uy = if up { (split - low) / high } else { split / low };
            let q = column + 2 * up as usize;
            density *= 4.0 * p[q];
            size *= 0.5;
            origin += Vec2::new(column as f32, up as u32 as f32) * size;
            u = Vec2::new(ux, uy).clamp(Vec2::ZERO, Vec2::splat(BELOW_ONE));
            match self.nodes[node].children[q] {
                0 => break,
                c => node = c as usize,
            }
        }
        let s = (origin + u * size).min(Vec2::splat(BELOW_ONE));
        (from_square(s), density / solid_angle_per_area(s))
    }

    /// The solid-angle density of [`sample`](Self::sample) returning `d` (unit).
    #[inline]
    pub fn pdf(&self, d: Vec3A) -> f32 {
        let square = to_square(d);
        let (mut node, mut density, mut s) = (0usize, 1.0f32, square);
        loop {
            let (q, inner) = quadrant(s);
            let n = &self.nodes[node];
            density *= 4.0 * n.p[q];
            match n.children[q] {
                0 => return density / solid_angle_per_area(square),
                c => (node, s) = (c as usize, inner),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_square_map_is_inverse_both_ways() {
        for k in 0..200 {
            let s = Vec2::new((k % 20) as f32 / 20.0 + 0.013, (k / 20) as f32 / 10.0 + 0.031);
            let back = to_square(from_square(s));
            assert!((back - s).abs().max_element() < 1e-5, "{s} → {back}");
        }
    }

    #[test]
    fn refining_cuts_where_light_is_and_joins_where_it_is_not() {
        let tree = Quadtree::default();
        // All the light in quadrant 3: it is cut, and its parts while a part's even share
        // (25, 6.25, 1.6, 0.4 % of the whole) is over 1 %.
        let fine = tree.refined(&tree.sums(&[0, 0, 0, 1000]));
        assert_eq!(fine.nodes(), 1 + 1 + 4 + 16 + 64);
        // Evenly spread light: every quadrant is cut while a quadrant holds over 1 %.
        let even = tree.refined(&tree.sums(&[250; 4]));
        assert_eq!(even.nodes(), 1 + 4 + 16 + 64);
        // Light in one point: cut along one path down to the deepest level.
        let mut deep = Quadtree::default();
        for _ in 0..MAX_DEPTH + 2 {
            let leaves: Vec<u64> = (0..deep.nodes() * 4).map(|i| (i == deep.leaf(Vec2::splat(0.1))) as u64).collect();
            deep = deep.refined(&deep.sums(&leaves));
        }
        assert_eq!(deep.nodes(), MAX_DEPTH as usize);
        // The fine tree, now seeing light only in quadrant 0, joins everything else back.
        let leaves: Vec<u64> = (0..fine.nodes() * 4).map(|i| (i == 0) as u64).collect();
        let back = fine.refined(&fine.sums(&leaves));
        assert_eq!(back.children[0][3], 0);
    }
}
