//! Warps from the unit square to the shapes we sample, each with its density.
//!
//! Owns: pure functions `[0,1)² → domain` and the matching pdf in the domain's measure.
//! References: Shirley & Chiu 1997 (concentric disk), pbrt-v4 `sampling.h` (cosine hemisphere,
//! uniform triangle in the low-distortion form of Heitz 2019), Malley's method.

use super::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

/// Concentric map of the square onto the unit disk (Shirley & Chiu); density 1/π.
///
/// The map's angle is π/4 · (a ratio in [−1, 1]) from one of the square's diagonals, so its
/// sine and cosine come from [`sin_cos_quarter`] and a swap instead of a general `sin_cos`
/// (whose range reduction cost 4 % of a Cornell-box render).
#[inline]
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // Which diagonal is nearer is a coin toss per sample: selects, not a branch to mispredict.
    // Near the x axis θ = π/4 · y/x; near the y axis θ = π/2 − π/4 · x/y, whose cosine and
    // sine are the sine and cosine of π/4 · x/y.
    let x_major = o.x.abs() > o.y.abs();
    let (r, other) = if x_major { (o.x, o.y) } else { (o.y, o.x) };
    let (s, c) = sin_cos_quarter(FRAC_PI_4 * (other / r));
    let (cos_t, sin_t) = if x_major { (c, s) } else { (s, c) };
    r * Vec2::new(cos_t, sin_t)
}

/// (sin a, cos a) for |a| ≤ π/4, within 2 ulp of the f32 functions: the minimax polynomials
/// of degree 7 and 8 that Cephes' `sinf`/`cosf` use on that interval.
#[inline]
pub fn sin_cos_quarter(a: f32) -> (f32, f32) {
    debug_assert!(a.abs() <= FRAC_PI_4 * (1.0 + 1e-6), "{a}");
    let z = a * a;
    let s = a + a * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1);
    let c = 1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
    (s, c)
}

/// Cosine-weighted direction on the +Z hemisphere (Malley's method).
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

/// Density of [`square_to_cosine_hemisphere`] in solid angle.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere; density 1/(4π).
#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`square_to_uniform_sphere`] in solid angle.
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// The unit square onto the unit sphere, equal areas to equal solid angles (Clarberg 2008,
/// "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD": the square folded as an
/// octahedron, +Z at its centre, −Z at its corners): a grid of R × R cells on the square is a
/// grid of directions of 4π/R² sr each.
#[inline]
pub fn square_to_sphere_equal_area(p: Vec2) -> Vec3A {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    // Distance from the diamond |u| + |v| = 1, which is the equator.
    let signed = 1.0 - (u.abs() + v.abs());
    let r = 1.0 - signed.abs();
    let phi = if r == 0.0 { 0.25 * PI } else { ((v.abs() - u.abs()) / r + 1.0) * 0.25 * PI };
    let z = (1.0 - r * r).copysign(signed);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3A::new(phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z)
}

/// The inverse of [`square_to_sphere_equal_area`]: where on the unit square unit direction
/// `d` lies.
#[inline]
pub fn sphere_to_square_equal_area(d: Vec3A) -> Vec2 {
    let (x, y) = (d.x.abs(), d.y.abs());
    let r = (1.0 - d.z.abs()).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let ratio = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = ratio.atan() * 2.0 * FRAC_1_PI;
    if x < y {
        phi = 1.0 - phi;
    }
    let (mut u, mut v) = (r - phi * r, phi * r);
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    Vec2::new(0.5 * (u.copysign(d.x) + 1.0), 0.5 * (v.copysign(d.y) + 1.0))
}

/// Uniform direction in the cone about +Z of half-angle α, given `1 − cos α` (> 0; passed as
/// such so that narrow cones keep their precision); density [`uniform_cone_pdf`].
#[inline]
pub fn square_to_uniform_cone(u: Vec2, one_minus_cos: f32) -> Vec3A {
    // z = 1 − u·(1 − cos α), and sin² = (1 − z)(1 + z) without cancellation.
    let one_minus_z = u.x * one_minus_cos;
    let z = 1.0 - one_minus_z;
    let r = (one_minus_z * (2.0 - one_minus_z)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`square_to_uniform_cone`] in solid angle: 1 / (2π (1 − cos α)).
#[inline]
pub fn uniform_cone_pdf(one_minus_cos: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos)
}

/// Uniform barycentrics (b0, b1, b2) on a triangle; density 1/area.
///
/// Heitz 2019, "A Low-Distortion Map Between Triangle and Square": neighbouring `u` stay
/// neighbours on the triangle, unlike the square-root map.
#[inline]
pub fn square_to_triangle(u: Vec2) -> [f32; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// ∫ f(ω) dω over the upper hemisphere by the midpoint rule on `nz × nphi` cells of
/// (cos θ, φ), where dω = d(cos θ) dφ: how tests check that a density integrates to 1.
#[cfg(test)]
pub fn hemisphere_integral(nz: usize, nphi: usize, f: impl Fn(Vec3A) -> f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..nz {
        let z = (i as f64 + 0.5) / nz as f64;
        let r = (1.0 - z * z).sqrt();
        for k in 0..nphi {
            let phi = (k as f64 + 0.5) / nphi as f64 * std::f64::consts::TAU;
            sum += f(Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32));
        }
    }
    sum * std::f64::consts::TAU / (nz * nphi) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |i| Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32))
    }

    #[test]
    fn quarter_sin_cos_agrees_with_the_library() {
        let mut worst = 0.0f32;
        for i in -10_000..=10_000 {
            let a = FRAC_PI_4 * i as f32 / 10_000.0;
            let (s, c) = sin_cos_quarter(a);
            let (ls, lc) = a.sin_cos();
            worst = worst.max((s - ls).abs()).max((c - lc).abs());
        }
        assert!(worst < 2.5e-7, "{worst}");
    }

    #[test]
    fn disk_points_lie_in_disk_and_cover_it_uniformly() {
        let n = 200;
        let mut inner = 0usize;
        for u in grid(n) {
            let p = square_to_disk_concentric(u);
            assert!(p.length() <= 1.0 + 1e-6);
            if p.length() < 0.5 {
                inner += 1;
            }
        }
        // A disk of radius 0.5 holds a quarter of the area.
        let frac = inner as f32 / (n * n) as f32;
        assert!((frac - 0.25).abs() < 0.01, "{frac}");
    }

    #[test]
    fn cosine_hemisphere_matches_its_pdf() {
        // Under p = cos θ/π: P(θ < 60°) = sin²60° = 3/4 and E[cos θ] = 2/3.
        let n = 300;
        let (mut inside, mut mean_z) = (0usize, 0.0f64);
        for u in grid(n) {
            let d = square_to_cosine_hemisphere(u);
            assert!((d.length() - 1.0).abs() < 1e-4 && d.z >= 0.0);
            inside += (d.z > 0.5) as usize;
            mean_z += d.z as f64;
        }
        let m = (n * n) as f64;
        assert!((inside as f64 / m - 0.75).abs() < 2e-3, "{}", inside as f64 / m);
        assert!((mean_z / m - 2.0 / 3.0).abs() < 1e-3, "{}", mean_z / m);
        assert!((cosine_hemisphere_pdf(1.0) - FRAC_1_PI).abs() < 1e-7 && cosine_hemisphere_pdf(-0.5) == 0.0);
    }

    #[test]
    fn uniform_sphere_is_uniform_in_z() {
        let n = 100;
        let mut hist = [0usize; 4];
        for u in grid(n) {
            let d = square_to_uniform_sphere(u);
            assert!((d.length() - 1.0).abs() < 1e-4);
            hist[(((d.z + 1.0) * 2.0) as usize).min(3)] += 1;
        }
        for h in hist {
            assert_eq!(h, n * n / 4);
        }
    }

    #[test]
    fn equal_area_sphere_map_is_uniform_continuous_and_inverts() {
        let n = 128;
        let mut hist = [0usize; 4];
        let mut octants = [0usize; 8];
        for u in grid(n) {
            let d = square_to_sphere_equal_area(u);
            assert!((d.length() - 1.0).abs() < 1e-5, "{u} → {d}");
            let back = sphere_to_square_equal_area(d);
            assert!((back - u).abs().max_element() < 1e-4, "{u} → {d} → {back}");
            hist[(((d.z + 1.0) * 2.0) as usize).min(3)] += 1;
            octants[(d.x > 0.0) as usize + 2 * (d.y > 0.0) as usize + 4 * (d.z > 0.0) as usize] += 1;
        }
        // Uniform on the sphere: z is uniform, and each octant holds an eighth.
        for h in hist {
            assert!((h as f64 / (n * n) as f64 - 0.25).abs() < 0.015, "{hist:?}");
        }
        // (cell centres on the equator count as below it).
        assert!(octants.iter().all(|&o| (o as f64 / (n * n / 8) as f64 - 1.0).abs() < 0.04), "{octants:?}");
        // The poles and the equator's corners.
        assert!((square_to_sphere_equal_area(Vec2::splat(0.5)) - Vec3A::Z).length() < 1e-6);
        assert!((square_to_sphere_equal_area(Vec2::ZERO) + Vec3A::Z).length() < 1e-6);
        assert!((square_to_sphere_equal_area(Vec2::new(1.0, 0.5)) - Vec3A::X).length() < 1e-6);
        // Neighbours on the square stay neighbours on the sphere.
        for u in grid(64) {
            let step = square_to_sphere_equal_area(u + Vec2::new(1e-3, 0.0)) - square_to_sphere_equal_area(u);
            assert!(step.length() < 0.02, "{u}");
        }
    }

    #[test]
    fn triangle_barycentrics_are_uniform() {
        let n = 200;
        let mut hist = [0usize; 4];
        for u in grid(n) {
            let b = square_to_triangle(u);
            assert!(b.iter().all(|&x| (-1e-6..=1.0 + 1e-6).contains(&x)));
            assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-6);
            // The 4 sub-triangles of the midpoint subdivision have equal area.
            let cell = if b[0] > 0.5 {
                0
            } else if b[1] > 0.5 {
                1
            } else if b[2] > 0.5 {
                2
            } else {
                3
            };
            hist[cell] += 1;
        }
        for h in hist {
            let f = h as f32 / (n * n) as f32;
            assert!((f - 0.25).abs() < 0.01, "{hist:?}");
        }
    }
}
