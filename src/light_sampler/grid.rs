//! The grid over the scene that `cells` tabulates and `learned` learns by: cubes of
//! 1/[`CELLS_PER_RADIUS`] of the scene's radius over the cube about its bounding sphere
//! ([`SIDE`] along each axis), times [`BINS`] normal bins. A shading point's cell is where
//! it is and which way its surface faces: a floor and a ceiling a few centimetres apart see
//! different lights.

use super::ShadingContext;
use crate::math::Vec3A;

/// Grid cells along the scene's radius (a cell's edge is radius / this). 8: the scale at
/// which a room's lamps look different from one cell to the next, and small enough that
/// 17³ × 7 cells of a few bytes each cost little.
pub const CELLS_PER_RADIUS: f32 = 8.0;
/// Cells along each axis: the scene's diameter, and one more for a point on the sphere's
/// far side that rounds up.
pub const SIDE: usize = 2 * CELLS_PER_RADIUS as usize + 1;
/// Normal bins: ±x, ±y, ±z ([`normal_bin`]) and one for points off surfaces.
pub const BINS: usize = 7;
/// Cells of the grid, every position and bin.
pub const CELLS: usize = SIDE * SIDE * SIDE * BINS;

/// The bin of a receiver normal: 2·axis + (negative) for its dominant axis and sign, 6 for
/// no normal (a point off surfaces).
#[inline]
pub fn normal_bin(n: Vec3A) -> usize {
    let a = n.abs();
    // x where it is the largest, else y where it is at least z, else z: in arithmetic,
    // which compiles without branches (this runs at every light choice of `cells`).
    let not_x = !(a.x >= a.y && a.x >= a.z) as usize;
    let axis = not_x * (1 + !(a.y >= a.z) as usize);
    let negative = (n.cmplt(Vec3A::ZERO).bitmask() as usize >> axis) & 1;
    if n == Vec3A::ZERO { 6 } else { 2 * axis + negative }
}

/// The receiver normal that stands for bin `bin` (zero for the bin of points off surfaces).
pub fn bin_normal(bin: usize) -> Vec3A {
    let mut n = Vec3A::ZERO;
    if bin < 6 {
        n[bin / 2] = if bin & 1 == 0 { 1.0 } else { -1.0 };
    }
    n
}

/// The grid over one scene's bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneGrid {
    /// The grid's lowest corner.
    origin: Vec3A,
    /// Edge of a cell.
    edge: f32,
    /// Its reciprocal.
    per_edge: f32,
}

impl SceneGrid {
    /// The grid over the sphere of centre `centre` and radius `radius`.
    pub fn new(centre: Vec3A, radius: f32) -> Self {
        let radius = radius.max(1e-6);
        Self {
            origin: centre - Vec3A::splat(radius),
            edge: radius / CELLS_PER_RADIUS,
            per_edge: CELLS_PER_RADIUS / radius,
        }
    }

    /// Edge of a cell, m.
    pub fn edge(&self) -> f32 {
        self.edge
    }

    /// The cell of `ctx`: its index among [`CELLS`] (the position clamped to the grid, so a
    /// point that rounds off the scene's sphere lands in the nearest cell; then the normal
    /// bin) and the cell's lowest corner.
    #[inline]
    pub fn locate(&self, ctx: &ShadingContext) -> (usize, Vec3A) {
        let f = ((ctx.p - self.origin) * self.per_edge).clamp(Vec3A::ZERO, Vec3A::splat(SIDE as f32 - 0.5));
        // Non-negative, so truncation floors (one instruction a lane, where glam's `floor`
        // takes several); whole numbers below 2²⁴ throughout, so exact in f32: one
        // conversion for the three.
        let q = Vec3A::new(f.x.trunc(), f.y.trunc(), f.z.trunc());
        let flat = q.dot(Vec3A::new((SIDE * SIDE) as f32, SIDE as f32, 1.0)) as u32 as usize;
        (flat * BINS + normal_bin(ctx.n), self.origin + q * self.edge)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_normal_falls_in_the_bin_of_its_dominant_axis_and_sign() {
        let bins = [(Vec3A::X, 0), (-Vec3A::X, 1), (Vec3A::Y, 2), (-Vec3A::Y, 3), (Vec3A::Z, 4), (-Vec3A::Z, 5)];
        for (n, bin) in bins {
            assert_eq!(normal_bin(n), bin, "{n}");
            assert_eq!(bin_normal(bin), n);
            // Tilted towards the other axes, short of them.
            assert_eq!(normal_bin(n + 0.6 * (Vec3A::ONE - n.abs())), bin, "{n}");
        }
        // Ties go to the earlier axis; zero has its own bin, whatever the sign of its zeros.
        assert_eq!(normal_bin(Vec3A::new(-1.0, 1.0, 1.0)), 1);
        assert_eq!(normal_bin(Vec3A::new(0.0, -1.0, 1.0)), 3);
        assert_eq!(normal_bin(Vec3A::new(0.2, 0.5, -0.5)), 2);
        assert_eq!(normal_bin(Vec3A::ZERO), 6);
        assert_eq!(normal_bin(-Vec3A::ZERO), 6);
        assert_eq!(bin_normal(6), Vec3A::ZERO);
    }

    #[test]
    fn points_land_in_the_cell_that_holds_them_and_points_outside_in_the_nearest() {
        let grid = SceneGrid::new(Vec3A::ZERO, 8.0);
        assert_eq!(grid.edge(), 1.0);
        let at = |p: Vec3A| grid.locate(&ShadingContext::new(p, Vec3A::Y));
        // (−8, −8, −8) is the lowest corner; (0.5, 0.5, 0.5) is in cell (8, 8, 8).
        let (index, corner) = at(Vec3A::splat(0.5));
        assert_eq!(corner, Vec3A::ZERO);
        assert_eq!(index, ((8 * SIDE + 8) * SIDE + 8) * BINS + 2);
        // A cell's faces belong to the cell above them.
        assert_eq!(at(Vec3A::new(1.0, 0.5, 0.5)).1, Vec3A::new(1.0, 0.0, 0.0));
        // Outside the grid: clamped to the border cells, never past the last index.
        assert_eq!(at(Vec3A::splat(-100.0)).1, Vec3A::splat(-8.0));
        let (last, corner) = at(Vec3A::splat(100.0));
        assert_eq!(corner, Vec3A::splat(8.0));
        assert!(last < CELLS);
    }
}
