//! Points on area lights: the points a light samples, seen from a receiver, are distributed
//! as the solid-angle density it reports for them, and that density integrates to one over
//! the light (both against quadrature of the reported density, not against the sampler).

use crate::common::{chi_square, draw, sidak};
use myriad::light::{AreaEmission, Light, QuadLight};
use myriad::math::{Rgb, Vec3A};

/// Bins along each edge of the quad.
const BINS: usize = 8;
/// Midpoints along each edge of a bin for the quadrature of the density.
const QUADRATURE: usize = 24;

/// (s, t) of a point `q` of the parallelogram `corner + s·e1 + t·e2`.
fn coordinates(q: Vec3A, corner: Vec3A, e1: Vec3A, e2: Vec3A) -> (f64, f64) {
    let d = (q - corner).as_dvec3();
    let (a, b) = (e1.as_dvec3(), e2.as_dvec3());
    let (aa, ab, bb, da, db) = (a.dot(a), a.dot(b), b.dot(b), d.dot(a), d.dot(b));
    let det = aa * bb - ab * ab;
    ((da * bb - db * ab) / det, (db * aa - da * ab) / det)
}

/// Per bin, the probability the light's reported density gives it: ∫ pdf_li · |cos θq| / d² dA.
fn expected_shares(light: &Light, q: &QuadLight, p: Vec3A) -> Vec<f64> {
    let cell = q.area as f64 / (BINS * BINS * QUADRATURE * QUADRATURE) as f64;
    let m = BINS * QUADRATURE;
    let mut shares = vec![0.0; BINS * BINS];
    for i in 0..m * m {
        let (s, t) = (((i % m) as f32 + 0.5) / m as f32, ((i / m) as f32 + 0.5) / m as f32);
        let point = q.p0 + s * q.e1 + t * q.e2;
        let d = (point - p).as_dvec3();
        let jacobian = q.n.as_dvec3().dot(d).abs() / d.length().powi(3);
        let bin = (i % m) / QUADRATURE + (i / m) / QUADRATURE * BINS;
        shares[bin] += light.pdf_li(p, point, q.n) as f64 * jacobian * cell;
    }
    shares
}

#[test]
fn quad_samples_follow_the_density_they_report_near_and_far() {
    let e = |two_sided| AreaEmission { radiance: Rgb::ONE, two_sided };
    let (corner, e1, e2) = (Vec3A::new(-0.5, 2.0, -0.25), Vec3A::new(1.0, 0.0, 0.0), Vec3A::new(0.0, 0.0, 0.5));
    let rectangle = QuadLight::new(corner, e1, e2, e(false)).unwrap();
    let two_sided = QuadLight::new(corner, e1, e2, e(true)).unwrap();
    let skewed = QuadLight::new(corner, e1 + Vec3A::new(0.0, 0.0, 0.3), e2, e(false)).unwrap();
    // Near (the density swings 14× over the quad), grazing, far, behind a two-sided one,
    // and a parallelogram that is no rectangle.
    let cases = [
        (&rectangle, Vec3A::new(0.1, 1.7, 0.0)),
        (&rectangle, Vec3A::new(0.7, 1.85, 0.3)),
        (&rectangle, Vec3A::new(0.0, -4.0, 0.0)),
        (&two_sided, Vec3A::new(-0.2, 2.4, 0.1)),
        (&skewed, Vec3A::new(0.1, 1.7, 0.0)),
    ];
    let alpha = sidak(cases.len());
    let draws = 200_000u64;
    for (i, &(q, p)) in cases.iter().enumerate() {
        let light = Light::Quad(q.clone());
        let expected = expected_shares(&light, q, p);
        let total: f64 = expected.iter().sum();
        assert!((total - 1.0).abs() < 2e-3, "case {i}: the density integrates to {total}");
        let mut observed = vec![0.0; BINS * BINS];
        for k in 0..draws {
            let sample = light.sample_li(p, [draw(k, 2 * i as u64), draw(k, 2 * i as u64 + 1)], &[]).unwrap();
            let reported = light.pdf_li(p, sample.p, q.n);
            assert!(
                (sample.pdf / reported - 1.0).abs() < 1e-5,
                "case {i}: sampled {}, reported {reported}",
                sample.pdf
            );
            let (s, t) = coordinates(sample.p, q.p0, q.e1, q.e2);
            assert!((-1e-4..=1.0 + 1e-4).contains(&s) && (-1e-4..=1.0 + 1e-4).contains(&t), "case {i}: ({s}, {t})");
            let bin = |x: f64| ((x * BINS as f64) as usize).min(BINS - 1);
            observed[bin(s) + bin(t) * BINS] += 1.0;
        }
        let expected: Vec<f64> = expected.iter().map(|x| x / total * draws as f64).collect();
        let r = chi_square(&observed, &expected);
        assert!(r.p > alpha, "case {i}: chi² {} on {} degrees of freedom, p = {}", r.chi2, r.dof, r.p);
    }
}
