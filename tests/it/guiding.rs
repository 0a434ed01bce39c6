//! Path guiding: learned directional distributions sample what their density says (chi-square
//! over the sphere, independent draws), so does the mixture with the BSDF that paths use, and
//! guided renders are the unguided picture (the same at any thread count and split).

use crate::common::{chi_square, sidak};
use myriad::guiding::{Directions, Guiding, Quadtree, from_square, solid_angle_per_area, to_square};
use myriad::integrator::guided::Scattering;
use myriad::material::{Bsdf, Diffuse, Principled, ShadingPoint};
use myriad::math::{Rgb, Vec2, Vec3A};
use myriad::sampling::SampleStream;

/// Bins along each side of the square directions are counted in (a power of two: each bin
/// holds whole quadrants or lies in one).
const BINS: usize = 32;
/// Draws per chi-square test.
const DRAWS: usize = 400_000;

/// Light arriving from direction `d`: a bright small patch, a broad lobe and a faint floor.
fn light(d: Vec3A) -> f64 {
    let spot = Vec3A::new(0.3, -0.5, 0.81).normalize();
    let broad = Vec3A::new(-0.6, 0.2, -0.3).normalize();
    let c = d.dot(spot).max(0.0) as f64;
    200.0 * c.powi(400) + 3.0 * (d.dot(broad).max(0.0) as f64).powi(4) + 0.02
}

/// A learned distribution of [`light`]: a quadtree refined by it a few times over.
fn learned() -> Directions {
    let sums_of = |tree: &Quadtree| {
        let mut leaves = vec![0u64; tree.nodes() * 4];
        for i in 0..256 * 256 {
            let s = Vec2::new((i % 256) as f32 + 0.5, (i / 256) as f32 + 0.5) / 256.0;
            leaves[tree.leaf(s)] += (light(from_square(s)) * 1000.0) as u64;
        }
        tree.sums(&leaves)
    };
    let mut tree = Quadtree::default();
    for _ in 0..6 {
        tree = tree.refined(&sums_of(&tree));
    }
    Directions::new(&tree, &sums_of(&tree)).expect("light was recorded")
}

/// Chi-square of `n` directions drawn by `draw(k)` against `pdf`, over the bins of the square.
fn directions_match(label: &str, draw: impl Fn(usize) -> Option<Vec3A>, pdf: impl Fn(Vec3A) -> f32, alpha: f64) {
    let mut observed = vec![0.0; BINS * BINS];
    for k in 0..DRAWS {
        if let Some(d) = draw(k) {
            assert!((d.length() - 1.0).abs() < 1e-3, "{label}: not a unit direction {d}");
            let s = to_square(d);
            let bin =
                ((s.x * BINS as f32) as usize).min(BINS - 1) + ((s.y * BINS as f32) as usize).min(BINS - 1) * BINS;
            observed[bin] += 1.0;
        }
    }
    // The density integrated over each bin (in solid angle: `solid_angle_per_area`).
    const SUB: usize = 16;
    let expected: Vec<f64> = (0..BINS * BINS)
        .map(|bin| {
            let (bx, by) = (bin % BINS, bin / BINS);
            let mut sum = 0.0;
            for j in 0..SUB * SUB {
                let s = Vec2::new((bx * SUB + j % SUB) as f32 + 0.5, (by * SUB + j / SUB) as f32 + 0.5)
                    / (BINS * SUB) as f32;
                sum += pdf(from_square(s)) as f64 * solid_angle_per_area(s) as f64;
            }
            sum / (BINS * BINS * SUB * SUB) as f64 * DRAWS as f64
        })
        .collect();
    let total: f64 = expected.iter().sum();
    assert!(total <= DRAWS as f64 * 1.01, "{label}: the density integrates to {}", total / DRAWS as f64);
    let r = chi_square(&observed, &expected);
    assert!(r.p > alpha, "{label}: chi² {:.1} over {} dof, p = {:.2e}", r.chi2, r.dof, r.p);
}

#[test]
fn a_learned_distribution_samples_what_its_density_says() {
    let d = learned();
    assert!(d.nodes() > 20, "the bright patch is cut finer: {} nodes", d.nodes());
    // Its density integrates to one (midpoints of a grid finer than its deepest quadrant
    // would be exact; this grid is close).
    let n = 512;
    let integral: f64 = (0..n * n)
        .map(|i| {
            let s = Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32;
            d.pdf(from_square(s)) as f64 * solid_angle_per_area(s) as f64
        })
        .sum::<f64>()
        / (n * n) as f64;
    assert!((integral - 1.0).abs() < 0.01, "integral {integral}");
    // Each draw's own density is the one `pdf` reports for its direction.
    let stream = |k: usize| SampleStream::new(3, k as u64, 0);
    for k in 0..2000 {
        let (dir, p) = d.sample(stream(k).get_2d(0, myriad::sampling::Dim::GuideDirection, 0));
        assert!((p - d.pdf(dir)).abs() <= 1e-3 * p, "draw {k}: {p} against {}", d.pdf(dir));
    }
    let draw = |k: usize| Some(d.sample(stream(k).get_2d(0, myriad::sampling::Dim::GuideDirection, 0)).0);
    directions_match("learned", draw, |dir| d.pdf(dir), sidak(3));
}

/// A guide that has learned [`light`] everywhere, from one iteration of records.
fn guiding() -> Guiding {
    let mut g = Guiding::new(Vec3A::ZERO, 1.0);
    for _ in 0..3 {
        let records = g.records();
        let mut recorder = records.recorder();
        for i in 0..128 * 128 {
            let s = Vec2::new((i % 128) as f32 + 0.5, (i / 128) as f32 + 0.5) / 128.0;
            recorder.record(Vec3A::ZERO, Vec3A::Z, from_square(s), light(from_square(s)) as f32);
        }
        drop(recorder);
        g.learn(1);
    }
    g
}

#[test]
fn the_guided_mixture_samples_what_its_density_says() {
    let g = guiding();
    let guide = g.guide();
    assert!(guide.at(Vec3A::ZERO, Vec3A::Z).is_some(), "learned at the origin, facing +z");
    assert!(guide.at(Vec3A::ZERO, -Vec3A::Z).is_none(), "nothing learned facing -z");
    let wo = Vec3A::new(0.3, 0.2, 0.93).normalize();
    let plastic = Principled::new(Rgb::new(0.6, 0.3, 0.2), 0.0, 0.5, 1.5, 1.0, Rgb::ONE);
    let bsdfs = [
        ("lambert", Bsdf::Diffuse(Diffuse { albedo: Rgb::splat(0.7) })),
        ("plastic", Bsdf::Principled(plastic)),
        ("rough glass", Bsdf::Principled(plastic.with_transmission(1.0, 1.5))),
    ];
    for (label, bsdf) in bsdfs {
        let sp = ShadingPoint::new(bsdf, Vec3A::Z, Vec3A::Z, None, wo);
        let s = Scattering::new(&sp, Vec3A::ZERO, Some(guide));
        let draw = |k: usize| s.sample(&SampleStream::new(11, k as u64, 0), 0).map(|b| b.wi);
        // Every draw reports the mixture's density and the weight f·cos/pdf.
        for k in 0..500 {
            if let Some(b) = s.sample(&SampleStream::new(11, k as u64, 0), 0) {
                let pdf = s.pdf(b.wi);
                assert!((b.pdf - pdf).abs() <= 1e-3 * pdf, "{label}: pdf {} against {pdf}", b.pdf);
                let w = sp.eval_cos(b.wi) / pdf;
                assert!((b.weight - w).abs().max_element() <= 1e-3 * w.max_element(), "{label}: weight {}", b.weight);
            }
        }
        // A direction the BSDF sends no light to ends the path (it would add nothing).
        directions_match(label, draw, |d| if sp.eval_cos(d) == Rgb::ZERO { 0.0 } else { s.pdf(d) }, sidak(3));
    }
}
