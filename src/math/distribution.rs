//! Piecewise-constant discrete distribution: the CDF sampler behind `power` and `local`.
//!
//! Owns: building a normalised CDF from non-negative weights, drawing an index with one
//! uniform number (and handing back the remapped number, as pbrt's `SampleDiscrete` does), and
//! the pmf of any index. Prefix sums are accumulated in f64 so that 10⁶ small weights do not
//! lose mass; the table is stored in f32 (8 bytes per entry).

/// A discrete distribution over `0..len()`.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    /// `cdf[i]` = P(index < i); `cdf[0] = 0`, `cdf[n] = 1` exactly.
    cdf: Vec<f32>,
    /// Normalised weights.
    pmf: Vec<f32>,
}

/// One draw from a [`Distribution1D`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscreteSample {
    /// Index drawn.
    pub index: usize,
    /// Its probability.
    pub pmf: f32,
    /// The input number rescaled to `[0,1)` within the chosen cell, free for reuse.
    pub u_remapped: f32,
}

impl Distribution1D {
    /// Builds the distribution; `None` when the weights do not sum to a positive finite value
    /// or any weight is negative or NaN.
    pub fn new(weights: impl IntoIterator<Item = f32>) -> Option<Self> {
        let mut weights: Vec<f32> = weights.into_iter().collect();
        if weights.iter().any(|w| !(*w >= 0.0)) {
            return None;
        }
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        cdf.push(0.0f32);
        let mut acc = 0.0f64;
        for w in weights.iter_mut() {
            acc += *w as f64;
            cdf.push((acc / total) as f32);
            *w = (*w as f64 / total) as f32;
        }
        *cdf.last_mut().unwrap() = 1.0;
        Some(Self { cdf, pmf: weights })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// True when the distribution has no entries (never true for a built one).
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Probability of `index`.
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        self.pmf[index]
    }

    /// Draws an index with `u ∈ [0,1)`. Entries of weight 0 are never returned.
    #[inline]
    pub fn sample(&self, u: f32) -> DiscreteSample {
        debug_assert!((0.0..1.0).contains(&u));
        // First cdf entry > u, minus one: cdf[i] <= u < cdf[i+1].
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, self.pmf.len()) - 1;
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        let u_remapped = if hi > lo { ((u - lo) / (hi - lo)).min(1.0 - f32::EPSILON / 2.0) } else { 0.0 };
        DiscreteSample { index: i, pmf: self.pmf[i], u_remapped }
    }

    /// Bytes held by the tables.
    pub fn memory_bytes(&self) -> usize {
        (self.cdf.capacity() + self.pmf.capacity()) * std::mem::size_of::<f32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_weights() {
        assert!(Distribution1D::new([]).is_none());
        assert!(Distribution1D::new([0.0, 0.0]).is_none());
        assert!(Distribution1D::new([1.0, -1.0]).is_none());
        assert!(Distribution1D::new([1.0, f32::NAN]).is_none());
        assert!(Distribution1D::new([1.0, f32::INFINITY]).is_none());
    }

    #[test]
    fn pmf_sums_to_one_and_samples_follow_it() {
        let w = [0.0, 1.0, 3.0, 0.0, 4.0, 0.5, 0.0];
        let d = Distribution1D::new(w).unwrap();
        let s: f32 = (0..d.len()).map(|i| d.pmf(i)).sum();
        assert!((s - 1.0).abs() < 1e-6);
        let n = 85_000;
        let mut counts = vec![0usize; w.len()];
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let smp = d.sample(u);
            assert_eq!(smp.pmf, d.pmf(smp.index));
            assert!((0.0..1.0).contains(&smp.u_remapped));
            counts[smp.index] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            let expect = d.pmf(i) as f64 * n as f64;
            assert!((c as f64 - expect).abs() <= 1.0, "{i}: {c} vs {expect}");
            if w[i] == 0.0 {
                assert_eq!(c, 0);
            }
        }
        // The extremes of u stay in range.
        assert_eq!(d.sample(0.0).index, 1);
        assert_eq!(d.sample(1.0 - f32::EPSILON / 2.0).index, 5);
    }

    #[test]
    fn remapped_u_is_uniform_within_a_cell() {
        let d = Distribution1D::new([1.0, 1.0]).unwrap();
        let s = d.sample(0.75);
        assert_eq!(s.index, 1);
        assert!((s.u_remapped - 0.5).abs() < 1e-6);
    }
}
