//! Where light paths leave their lights: per light, a distribution of directions that favours
//! those meeting glossy surfaces, found once before the render by probe rays.
//!
//! A point light sends most of its light at walls and ceilings, where a light path ends at
//! once (only glossy surfaces start one of its highlights), and a glossy floor under an open
//! sky mirrors it where the camera sees nothing. The probes (a fixed grid of directions, so
//! every render and every sample range finds the same) tell, per cell of an equal-area grid
//! over the sphere, how much of the light's intensity meets a surface that may be glossy;
//! light paths then go there 90 % of the time, and 10 % spread over every cell the light
//! shines into. A probe that meets such a surface also follows its mirror direction: a scene
//! where none lands on a surface the camera sees traces no light paths. (Weighing the cells by
//! such landings instead sent light paths to mirror directions alone: materials.glb's error
//! rose from 0.022 to 0.026.) Where the probes missed a small glossy object, light paths still reach
//! it through that share, and wherever the density is zero next-event estimation takes the
//! whole path (the weights are computed from the same density on both sides), so no light is
//! lost either way.

use crate::geometry::{Ray, offset_toward};
use crate::light::Light;
use crate::math::{UVec2, Vec2, Vec3A, luminance, warp};
use crate::scene::Scene;
use rayon::prelude::*;

/// Cells per side of the equal-area square (R² cells of 4π/R² sr: about 13° across).
const R: usize = 16;

/// The share of directions spread over every cell the light shines into.
const SPREAD: f32 = 0.1;

/// Lights up to this many are probed with 2 × 2 rays per cell, up to [`MAX_PROBED`] with one;
/// beyond, light paths leave uniformly (probing would outweigh the render).
const FINE_PROBES_UP_TO: usize = 1024;
const MAX_PROBED: usize = 4096;

/// How a light's light paths choose their direction.
#[derive(Clone, Debug)]
pub enum Directions {
    /// Uniformly over the sphere (point) or the cone (spot).
    Uniform,
    /// Over the cells of the equal-area square with these cumulative probabilities, uniformly
    /// within a cell.
    Cells(Box<[f32]>),
}

/// What probing found of one light: its directions, the share of its intensity (summed over
/// the probes) that meets surfaces which may be glossy, and whether a probe found a highlight
/// the camera sees.
pub struct Probed {
    pub directions: Directions,
    pub glossy_share: f32,
    pub sees_highlight: bool,
}

/// The intensity (luminance) of `light` towards unit direction `dir`.
fn intensity(light: &Light, dir: Vec3A) -> f32 {
    match light {
        Light::Point(l) => luminance(l.intensity),
        Light::Spot(s) => luminance(s.intensity) * s.falloff(s.direction.dot(dir)),
        _ => 0.0,
    }
}

/// Where `light` (a point or spot light) emits from.
pub(super) fn position(light: &Light) -> Vec3A {
    match light {
        Light::Point(l) => l.position,
        Light::Spot(s) => s.position,
        _ => unreachable!("light paths start from point and spot lights"),
    }
}

/// Probes each of `lights` (point and spot lights of `scene`, rendered at `resolution`), in
/// parallel, in their order.
pub fn probe_all(scene: &Scene, lights: &[u32], resolution: UVec2) -> Vec<Probed> {
    let per_side = match lights.len() {
        n if n <= FINE_PROBES_UP_TO => 2,
        n if n <= MAX_PROBED => 1,
        _ => 0,
    };
    lights.par_iter().map(|&id| probe(scene, &scene.lights[id as usize], per_side, resolution)).collect()
}

/// What light along `dir` from `origin` meets: a surface that may be glossy (`None`: not),
/// and whether, mirrored there (about its shading normal), it lands on a surface the camera
/// sees in an image of `resolution`.
fn probe_ray(scene: &Scene, origin: Vec3A, dir: Vec3A, resolution: UVec2) -> Option<bool> {
    let hit = scene.intersect(&Ray::new(origin, dir), f32::INFINITY)?;
    if !scene.materials[hit.material as usize].may_reflect_glossily() {
        return None;
    }
    Some(lands_in_view(scene, &hit, dir, resolution))
}

/// Whether light arriving along `dir` at `hit`, mirrored about its shading normal, lands on a
/// surface the camera sees.
fn lands_in_view(scene: &Scene, hit: &crate::geometry::SurfaceHit, dir: Vec3A, resolution: UVec2) -> bool {
    let n = if hit.n_shading.dot(dir) > 0.0 { -hit.n_shading } else { hit.n_shading };
    let mirrored = dir - 2.0 * dir.dot(n) * n;
    let start = offset_toward(hit.p, hit.n_geom, mirrored);
    let Some(seen) = scene.intersect(&Ray::new(start, mirrored), f32::INFINITY) else { return false };
    if scene.camera.project(seen.p, resolution).is_none() {
        return false;
    }
    let to_camera = scene.camera.position() - seen.p;
    let from = offset_toward(seen.p, seen.n_geom, to_camera);
    !scene.occluded(&Ray::new(from, scene.camera.position() - from), 1.0)
}

/// Probes `light` with `per_side`² rays per cell (none: uniform directions, share 1).
fn probe(scene: &Scene, light: &Light, per_side: usize, resolution: UVec2) -> Probed {
    if per_side == 0 {
        return Probed { directions: Directions::Uniform, glossy_share: 1.0, sees_highlight: true };
    }
    let origin = position(light);
    let (mut glossy, mut lit) = (vec![0.0f64; R * R], vec![0.0f64; R * R]);
    let mut sees_highlight = false;
    for (cell, (g, l)) in glossy.iter_mut().zip(lit.iter_mut()).enumerate() {
        for k in 0..per_side * per_side {
            let within = Vec2::new((k % per_side) as f32 + 0.5, (k / per_side) as f32 + 0.5) / per_side as f32;
            let dir = warp::square_to_sphere_equal_area((cell_corner(cell) + within) / R as f32);
            let i = intensity(light, dir) as f64;
            if i > 0.0 {
                *l += i;
                if let Some(lands) = probe_ray(scene, origin, dir, resolution) {
                    *g += i;
                    sees_highlight |= lands;
                }
            }
        }
    }
    let (total_glossy, total_lit): (f64, f64) = (glossy.iter().sum(), lit.iter().sum());
    if !(total_lit > 0.0) {
        return Probed { directions: Directions::Uniform, glossy_share: 0.0, sees_highlight: false };
    }
    let share = (total_glossy / total_lit) as f32;
    let spread = if total_glossy > 0.0 { SPREAD as f64 } else { 1.0 };
    let mut running = 0.0f64;
    let mut cdf: Box<[f32]> = glossy
        .iter()
        .zip(&lit)
        .map(|(g, l)| {
            let w = if total_glossy > 0.0 { (1.0 - spread) * g / total_glossy } else { 0.0 };
            running += w + spread * l / total_lit;
            running as f32
        })
        .collect();
    *cdf.last_mut().expect("R² cells") = 1.0;
    Probed { directions: Directions::Cells(cdf), glossy_share: share, sees_highlight }
}

/// The lower-left corner of `cell` on the R × R square, in cells.
#[inline]
fn cell_corner(cell: usize) -> Vec2 {
    Vec2::new((cell % R) as f32, (cell / R) as f32)
}

/// The probability of `cell` under cumulative probabilities `cdf`.
#[inline]
fn cell_probability(cdf: &[f32], cell: usize) -> f32 {
    cdf[cell] - if cell > 0 { cdf[cell - 1] } else { 0.0 }
}

impl Directions {
    /// A direction from `light` for `u ∈ [0,1)²`, and its density per solid angle (0: none).
    #[inline]
    pub fn sample(&self, light: &Light, u: Vec2) -> (Vec3A, f32) {
        match self {
            Directions::Uniform => match light {
                Light::Spot(s) => {
                    let local = warp::square_to_uniform_cone(u, 1.0 - s.cos_outer);
                    let dir = crate::math::frame::Frame::from_normal(s.direction).to_world(local);
                    (dir, warp::uniform_cone_pdf(1.0 - s.cos_outer))
                }
                _ => (warp::square_to_uniform_sphere(u), warp::UNIFORM_SPHERE_PDF),
            },
            Directions::Cells(cdf) => {
                let cell = cdf.partition_point(|&c| c <= u.x).min(R * R - 1);
                let p = cell_probability(cdf, cell);
                let before = if cell > 0 { cdf[cell - 1] } else { 0.0 };
                // u.x's place within the cell's share, and u.y, place the direction in it.
                let x = ((u.x - before) / p).clamp(0.0, 0.999_999);
                let dir = warp::square_to_sphere_equal_area((cell_corner(cell) + Vec2::new(x, u.y)) / R as f32);
                (dir, p * (R * R) as f32 * warp::UNIFORM_SPHERE_PDF)
            }
        }
    }

    /// The density of [`sample`](Self::sample) returning unit direction `dir` from `light`.
    #[inline]
    pub fn pdf(&self, light: &Light, dir: Vec3A) -> f32 {
        match self {
            Directions::Uniform => match light {
                Light::Spot(s) if s.direction.dot(dir) >= s.cos_outer => warp::uniform_cone_pdf(1.0 - s.cos_outer),
                Light::Spot(_) => 0.0,
                _ => warp::UNIFORM_SPHERE_PDF,
            },
            Directions::Cells(cdf) => {
                let at = warp::sphere_to_square_equal_area(dir) * R as f32;
                let cell = (at.x as usize).min(R - 1) + R * (at.y as usize).min(R - 1);
                cell_probability(cdf, cell) * (R * R) as f32 * warp::UNIFORM_SPHERE_PDF
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{PointLight, SpotCurve, SpotLight};
    use crate::math::Rgb;

    /// Cells weighted unevenly (some empty), as probing leaves them.
    fn uneven() -> Directions {
        let weights: Vec<f64> = (0..R * R).map(|k| if k % 7 == 3 { 0.0 } else { (1 + k % 5) as f64 }).collect();
        let total: f64 = weights.iter().sum();
        let mut running = 0.0;
        Directions::Cells(weights.iter().map(|w| (running + w / total, running += w / total).0 as f32).collect())
    }

    fn point() -> Light {
        Light::Point(PointLight { position: Vec3A::ZERO, intensity: Rgb::ONE })
    }

    /// Independent draws land in the cells as often as their probabilities say (chi-square),
    /// each with the density `pdf` reports for its direction.
    #[test]
    fn cells_are_drawn_as_their_density_says() {
        let (dirs, light) = (uneven(), point());
        let Directions::Cells(cdf) = &dirs else { unreachable!() };
        let n = 200_000;
        let mut counts = vec![0u64; R * R];
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state = crate::sampling::fmix64(state.wrapping_add(0x9e37_79b9_7f4a_7c15));
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..n {
            let (d, pdf) = dirs.sample(&light, Vec2::new(next(), next()));
            assert!((d.length() - 1.0).abs() < 1e-4);
            let at = warp::sphere_to_square_equal_area(d) * R as f32;
            let cell = (at.x as usize).min(R - 1) + R * (at.y as usize).min(R - 1);
            counts[cell] += 1;
            assert!((dirs.pdf(&light, d) - pdf).abs() <= 1e-3 * pdf, "{pdf} against {}", dirs.pdf(&light, d));
        }
        let mut chi2 = 0.0;
        let mut dof = 0;
        for (cell, &c) in counts.iter().enumerate() {
            let expected = cell_probability(cdf, cell) as f64 * n as f64;
            if expected == 0.0 {
                assert_eq!(c, 0, "cell {cell} has no probability but was drawn");
                continue;
            }
            chi2 += (c as f64 - expected).powi(2) / expected;
            dof += 1;
        }
        // 99.9 % quantile of χ² with ~220 degrees of freedom is about 300.
        assert!(chi2 < dof as f64 + 5.0 * (2.0 * dof as f64).sqrt(), "χ² {chi2} over {dof} cells");
    }

    /// Every density integrates to 1 over the sphere (the spot's uniform one over its cone).
    #[test]
    fn densities_integrate_to_one() {
        let spot = Light::Spot(SpotLight {
            position: Vec3A::ZERO,
            direction: Vec3A::new(0.3, -1.0, 0.2).normalize(),
            intensity: Rgb::ONE,
            cos_inner: 0.9,
            cos_outer: 0.8,
            curve: SpotCurve::Smoothstep,
        });
        for (dirs, light) in [(uneven(), point()), (Directions::Uniform, point()), (Directions::Uniform, spot)] {
            let n = 400;
            let integral: f64 = (0..n * n)
                .map(|i| {
                    let u = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
                    dirs.pdf(&light, warp::square_to_sphere_equal_area(u)) as f64
                })
                .sum::<f64>()
                * 4.0
                * std::f64::consts::PI
                / (n * n) as f64;
            assert!((integral - 1.0).abs() < 0.01, "{dirs:?}: {integral}");
        }
    }
}
