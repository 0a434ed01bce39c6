//! Error metrics between an image and a reference (docs/conventions.md): MSE, relMSE,
//! efficiency, per-pixel relative error, and the bias check. Pure functions; no rendering.

use crate::error::{Error, Result};
use crate::math::Rgb;

/// ε of relMSE = mean((x − ref)² / (ref² + ε)): keeps dark pixels from dominating.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// Significance of the bias flag over all samplers of a comparison (each is tested at the
/// Šidák-corrected level).
pub const BIAS_ALPHA: f64 = 0.001;

/// Error of an image against a reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ErrorMetrics {
    /// Mean squared error over pixels and channels.
    pub mse: f64,
    /// Mean relative squared error over pixels and channels.
    pub rel_mse: f64,
}

/// An error unless the two images have as many pixels.
fn same_size(image: &[Rgb], reference: &[Rgb]) -> Result<()> {
    if image.len() != reference.len() {
        return Err(Error::Usage(format!("images differ in size: {} vs {} pixels", image.len(), reference.len())));
    }
    Ok(())
}

/// MSE and relMSE of `image` against `reference` (same length).
pub fn error_metrics(image: &[Rgb], reference: &[Rgb]) -> Result<ErrorMetrics> {
    same_size(image, reference)?;
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (x, y) in image.iter().zip(reference) {
        for c in 0..3 {
            let (x, y) = (x[c] as f64, y[c] as f64);
            let d2 = (x - y) * (x - y);
            se += d2;
            rel += d2 / (y * y + REL_MSE_EPSILON);
        }
    }
    let n = (3 * image.len().max(1)) as f64;
    Ok(ErrorMetrics { mse: se / n, rel_mse: rel / n })
}

/// Share of the pixels [`trimmed_rel_mse`] leaves out, those of largest error: 0.1 %.
pub const TRIMMED_SHARE: f64 = 0.001;

/// relMSE over the pixels left when the `share` of them with the largest relative error
/// are dropped (`floor(share · pixels)` of them, at most all but one).
///
/// A caustic firefly (a diffuse point seeing a small lamp through a glossy bounce, which no
/// light sampler reaches) lands in a few pixels with errors 10⁴–10⁵ times the rest: on
/// materials.glb at 64 spp the worst 0.1 % of pixels hold 99 % of the relMSE, whichever
/// sampler rendered it, so the full relMSE says which seed drew a firefly. Without them
/// the samplers' own differences show (there `cells` 0.0061, `power` 0.0125, steady from
/// seed to seed, against full values of 0.05–0.58 for both).
pub fn trimmed_rel_mse(image: &[Rgb], reference: &[Rgb], share: f64) -> Result<f64> {
    same_size(image, reference)?;
    let mut errors: Vec<f64> = image.iter().zip(reference).map(|(x, y)| pixel_rel_error(*x, *y)).collect();
    let n = errors.len();
    let kept = n - ((n as f64 * share.clamp(0.0, 1.0)) as usize).min(n.saturating_sub(1));
    if kept < n {
        errors.select_nth_unstable_by(kept, f64::total_cmp);
    }
    Ok(errors[..kept].iter().sum::<f64>() / (3 * kept.max(1)) as f64)
}

/// A pixel's relative squared error, summed over its channels: Σ (x − y)²/(y² + ε).
#[inline]
fn pixel_rel_error(x: Rgb, y: Rgb) -> f64 {
    (0..3)
        .map(|c| {
            let (x, y) = (x[c] as f64, y[c] as f64);
            (x - y) * (x - y) / (y * y + REL_MSE_EPSILON)
        })
        .sum()
}

/// Per-pixel relative RMS error √(mean over channels of (x − y)²/(y² + ε)), for error maps.
pub fn relative_error_map(image: &[Rgb], reference: &[Rgb]) -> Vec<f32> {
    image.iter().zip(reference).map(|(x, y)| (pixel_rel_error(*x, *y) / 3.0).sqrt() as f32).collect()
}

/// Efficiency 1/(relMSE · seconds): the inverse of the time needed to reach a given error,
/// once error falls as 1/t.
pub fn efficiency(rel_mse: f64, seconds: f64) -> f64 {
    if rel_mse > 0.0 && seconds > 0.0 { 1.0 / (rel_mse * seconds) } else { f64::INFINITY }
}

/// Result of testing whether a mean image agrees with the reference.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BiasCheck {
    /// Mean difference (image − reference) over pixels and channels.
    pub mean_difference: f64,
    /// Its z-score (NaN when there was no variance to test against).
    pub z: f64,
    /// Two-sided p-value (NaN likewise).
    pub p: f64,
    /// True when p is below the threshold: the sampler (or the reference) looks biased.
    pub flagged: bool,
}

/// Two-sided p-value of a standard normal z (Abramowitz & Stegun 7.1.26 erfc; error < 1.5e-7).
pub fn normal_p_value(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly =
        t * (0.254_829_592 + t * (-0.284_496_736 + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    (poly * (-x * x).exp()).clamp(0.0, 1.0)
}

/// Tests whether `mean` (an average of renders, per-pixel variance of the mean
/// `mean_variance`) agrees with `reference` (its own variance, or zeros) at significance
/// `alpha`: a z-test on a weighted sum of the residuals, each pixel weighted by
/// 1/(|reference| + 0.05) (channels averaged, worst-case correlated variance). Without any
/// variance (a single 1-spp render and no reference variance) the test cannot be made: `z` and
/// `p` are NaN and nothing is flagged.
///
/// The weights make the test relative, so the few very noisy bright pixels (directly seen
/// lamps) do not drown a bias spread over the image, which a plain sum of residuals would
/// miss. They depend on the reference only: weights computed from the tested renders
/// themselves (inverse-variance, standardised residuals) correlate with their noise and, at
/// low spp where pixel estimates are skewed, flag unbiased samplers.
pub fn bias_check(
    mean: &[Rgb],
    mean_variance: &[Rgb],
    reference: &[Rgb],
    reference_variance: &[Rgb],
    alpha: f64,
) -> BiasCheck {
    let (mut sum_r, mut sum_w, mut var) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..mean.len() {
        let r: f64 = (0..3).map(|c| (mean[i][c] - reference[i][c]) as f64).sum::<f64>() / 3.0;
        let sd: f64 =
            (0..3).map(|c| ((mean_variance[i][c] + reference_variance[i][c]) as f64).max(0.0).sqrt()).sum::<f64>()
                / 3.0;
        let w = 1.0 / ((0..3).map(|c| reference[i][c].abs() as f64).sum::<f64>() / 3.0 + 0.05);
        sum_r += r;
        sum_w += w * r;
        var += w * w * sd * sd;
    }
    let mean_difference = sum_r / mean.len().max(1) as f64;
    // Without the runs' own variance (one sample of each pixel in all) the reference's alone
    // would make any run's noise look like bias: nothing to test against.
    if !(var > 0.0) || mean_variance.iter().all(|v| *v == Rgb::ZERO) {
        return BiasCheck { mean_difference, z: f64::NAN, p: f64::NAN, flagged: false };
    }
    let z = sum_w / var.sqrt();
    let p = normal_p_value(z);
    BiasCheck { mean_difference, z, p, flagged: p < alpha }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_match_hand_computed_values() {
        let reference = [Rgb::new(1.0, 0.0, 0.5), Rgb::new(0.0, 2.0, 1.0)];
        let image = [Rgb::new(1.5, 0.0, 0.5), Rgb::new(0.0, 2.0, 0.0)];
        let m = error_metrics(&image, &reference).unwrap();
        // Squared errors 0.25 (R of pixel 0) and 1 (B of pixel 1) over 6 values.
        assert!((m.mse - 1.25 / 6.0).abs() < 1e-12);
        let rel = 0.25 / (1.0 + 0.01) + 1.0 / (1.0 + 0.01);
        assert!((m.rel_mse - rel / 6.0).abs() < 1e-12);
        let map = relative_error_map(&image, &reference);
        assert!((map[0] as f64 - (0.25 / 1.01 / 3.0f64).sqrt()).abs() < 1e-6);
        assert!((efficiency(0.5, 4.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn the_trimmed_rel_mse_drops_the_worst_pixels_and_only_those() {
        let n = 2000;
        let reference = vec![Rgb::ONE; n];
        // Every pixel off by 1/8 in each channel, two of them (0.1 % of 2000) by 100.
        let mut image = vec![Rgb::splat(1.125); n];
        image[7] = Rgb::splat(101.0);
        image[1500] = Rgb::new(1.125, 1.125, 101.0);
        let rel = |d: f64| d * d / 1.01;
        let trimmed = trimmed_rel_mse(&image, &reference, TRIMMED_SHARE).unwrap();
        assert!((trimmed - rel(0.125)).abs() < 1e-9, "{trimmed}");
        // The full relMSE, and a share too small to drop a whole pixel, keep them.
        let full = error_metrics(&image, &reference).unwrap().rel_mse;
        assert!(full > 20.0 * trimmed);
        assert!((trimmed_rel_mse(&image, &reference, 0.0).unwrap() - full).abs() < 1e-9 * full);
        assert!((trimmed_rel_mse(&image, &reference, 0.4 / n as f64).unwrap() - full).abs() < 1e-9 * full);
        // Dropping one pixel drops the worst one: the other still counts.
        let one = trimmed_rel_mse(&image, &reference, 1.0 / n as f64).unwrap();
        let expected = ((n - 2) as f64 * 3.0 * rel(0.125) + 2.0 * rel(0.125) + rel(100.0)) / (3 * (n - 1)) as f64;
        assert!((one - expected).abs() < 1e-9 * expected, "{one} vs {expected}");
        // Everything dropped leaves the best pixel; empty images have no error.
        assert!((trimmed_rel_mse(&image, &reference, 1.0).unwrap() - rel(0.125)).abs() < 1e-9);
        assert_eq!(trimmed_rel_mse(&[], &[], TRIMMED_SHARE).unwrap(), 0.0);
        assert!(trimmed_rel_mse(&image, &reference[1..], TRIMMED_SHARE).is_err());
    }

    #[test]
    fn an_image_against_itself_has_zero_error_and_no_bias() {
        let img: Vec<Rgb> = (0..100).map(|i| Rgb::splat(i as f32 * 0.1)).collect();
        assert_eq!(error_metrics(&img, &img).unwrap(), ErrorMetrics { mse: 0.0, rel_mse: 0.0 });
        let zero = vec![Rgb::ZERO; 100];
        let b = bias_check(&img, &zero, &img, &zero, 0.001);
        assert!(!b.flagged && b.mean_difference == 0.0);
        // Without any variance a difference cannot be judged: not flagged, z unknown.
        let shifted: Vec<Rgb> = img.iter().map(|x| *x + Rgb::splat(0.1)).collect();
        let b = bias_check(&shifted, &zero, &img, &zero, 0.001);
        assert!(!b.flagged && b.z.is_nan() && (b.mean_difference - 0.1).abs() < 1e-6);
        // Nor with the reference's variance alone (runs of one sample per pixel): the runs'
        // own noise would read as bias.
        let b = bias_check(&shifted, &zero, &img, &vec![Rgb::splat(1e-6); 100], 0.001);
        assert!(!b.flagged && b.z.is_nan());
        assert!(error_metrics(&img, &img[..50]).is_err());
    }

    #[test]
    fn bias_check_flags_a_scaled_image_but_not_noise() {
        // Deterministic "noise" with known variance around a smooth image.
        let n = 4000;
        let truth: Vec<Rgb> = (0..n).map(|i| Rgb::splat(0.5 + 0.3 * (i as f32 * 0.01).sin())).collect();
        let sigma = 0.05f32;
        let noise = |i: usize| sigma * 3f32.sqrt() * (2.0 * ((i as f32 * 0.754_877_7).fract()) - 1.0);
        let noisy: Vec<Rgb> = truth.iter().enumerate().map(|(i, t)| *t + Rgb::splat(noise(i))).collect();
        let var = vec![Rgb::splat(sigma * sigma); n];
        let zero = vec![Rgb::ZERO; n];
        assert!(!bias_check(&noisy, &var, &truth, &zero, 0.001).flagged);
        let biased: Vec<Rgb> = noisy.iter().map(|x| *x * 1.02).collect();
        let b = bias_check(&biased, &var, &truth, &zero, 0.001);
        assert!(b.flagged && b.z > 0.0, "{b:?}");
    }

    #[test]
    fn p_values_are_right() {
        assert!((normal_p_value(1.959_964) - 0.05).abs() < 1e-6);
        assert!((normal_p_value(3.290_527) - 0.001).abs() < 1e-6);
        assert!((normal_p_value(0.0) - 1.0).abs() < 1e-6);
    }
}
