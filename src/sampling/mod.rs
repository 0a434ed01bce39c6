//! Random numbers with addresses: every number is a pure function of (seed, pixel, sample
//! index, bounce, [`Dim`], sub-index).
//!
//! Owns: [`SampleStream`] (and [`PixelStreams`], what a pixel's streams share). There is no
//! state to advance, so results do not depend on thread count, tile order or on how many
//! numbers another code path consumed (pbrt-v4 samplers, Cycles `path_rng_1D`). Each (seed,
//! pixel, bounce, dimension) selects a differently scrambled Sobol sequence (`sobol.rs`) and
//! the sample index is the position in it: the samples of a pixel are stratified in every
//! dimension and every pair of 2D dimensions, which independent random numbers are not.
//! Seeds are mixed with MurmurHash3's `fmix64`. Depends on `math` only.

mod dimension;
mod sobol;

pub use dimension::Dim;

use crate::math::Vec2;

/// MurmurHash3's 64-bit finaliser: a bijective avalanche mix.
#[inline]
pub fn fmix64(mut k: u64) -> u64 {
    k ^= k >> 33;
    k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
    k ^= k >> 33;
    k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    k ^= k >> 33;
    k
}

/// The random numbers of one camera sample of one pixel.
#[derive(Clone, Copy, Debug)]
pub struct SampleStream {
    key: u64,
    /// The sample index with its bits reversed, as the Sobol points take it.
    sample_reversed: u32,
}

/// The streams of one pixel's samples: what their keys share, worked out once for all of them.
#[derive(Clone, Copy, Debug)]
pub struct PixelStreams {
    /// The pixel's key under the seed.
    key: u64,
    /// The sample key of the first 2³² samples (every render's).
    first: u64,
}

impl PixelStreams {
    /// The streams of pixel `pixel` (a linear index) under `seed`.
    #[inline]
    pub fn new(seed: u64, pixel: u64) -> Self {
        let k = fmix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let key = fmix64(k ^ pixel.wrapping_mul(0xd1b5_4a32_d192_ed03));
        Self { key, first: Self::sample_key(key, 0) }
    }

    /// Beyond 2³² samples per pixel the sequence repeats with a fresh scramble.
    #[inline]
    fn sample_key(key: u64, high: u64) -> u64 {
        fmix64(key ^ high)
    }

    /// The stream of sample `sample`.
    #[inline]
    pub fn sample(&self, sample: u64) -> SampleStream {
        let high = sample >> 32;
        let key = if high == 0 { self.first } else { Self::sample_key(self.key, high) };
        SampleStream { key, sample_reversed: sobol::bit_reversed(sample as u32) }
    }
}

impl SampleStream {
    /// The stream of sample `sample` of pixel `pixel` (a linear index) under `seed`
    /// ([`PixelStreams`] where a pixel takes several).
    #[inline]
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        PixelStreams::new(seed, pixel).sample(sample)
    }

    /// The scramble seed of one dimension.
    #[inline]
    fn seed(&self, bounce: u32, slot: u64, sub: u32) -> u64 {
        let addr = ((bounce as u64) * Dim::SLOTS + slot) | ((sub as u64) << 32);
        fmix64(self.key ^ addr.wrapping_mul(0x9e37_79b9_7f4a_7c15))
    }

    /// One number in `[0,1)` for `dim` at `bounce`; `sub` tells apart several draws of the
    /// same dimension (the `all` estimator's per-light points).
    #[inline]
    pub fn get_1d(&self, bounce: u32, dim: Dim, sub: u32) -> f32 {
        sobol::to_unit32(sobol::sample_1d(self.sample_reversed, self.seed(bounce, dim as u64, sub)))
    }

    /// A 64-bit number for `dim` at `bounce`, all 2⁶⁴ values equally likely: the 32 bits of
    /// the point [`get_1d`](Self::get_1d) takes its number from on top (stratified as that
    /// is), 32 hashed bits below. Light selection takes it, so that choosing among 10⁶ or more
    /// lights is exact (24 or even 32 bits leave a few values per light).
    #[inline]
    pub fn get_1d_u64(&self, bounce: u32, dim: Dim, sub: u32) -> u64 {
        let seed = self.seed(bounce, dim as u64, sub);
        let high = sobol::sample_1d(self.sample_reversed, seed) as u64;
        let low = fmix64(seed.rotate_left(29) ^ self.sample_reversed as u64) >> 32;
        (high << 32) | low
    }

    /// Two 64-bit numbers for a 2D `dim`, stratified together as [`get_2d`](Self::get_2d)'s
    /// (whose numbers are their top 24 bits, see [`unit_f32`]), with 32 hashed bits below each.
    #[inline]
    pub fn get_2d_u64(&self, bounce: u32, dim: Dim, sub: u32) -> [u64; 2] {
        let seed = self.seed(bounce, dim as u64, sub);
        let (x, y) = sobol::sample_2d(self.sample_reversed, seed);
        let low = fmix64(seed.rotate_left(29) ^ self.sample_reversed as u64);
        [((x as u64) << 32) | (low >> 32), ((y as u64) << 32) | (low & 0xffff_ffff)]
    }

    /// [`get_2d_u64`](Self::get_2d_u64)'s numbers with their hashed low 32 bits left 0, for
    /// a user that reads only the top ones.
    #[inline]
    pub fn get_2d_u64_top(&self, bounce: u32, dim: Dim, sub: u32) -> [u64; 2] {
        let (x, y) = sobol::sample_2d(self.sample_reversed, self.seed(bounce, dim as u64, sub));
        [(x as u64) << 32, (y as u64) << 32]
    }

    /// Two numbers in `[0,1)²` for a 2D `dim`, stratified together.
    #[inline]
    pub fn get_2d(&self, bounce: u32, dim: Dim, sub: u32) -> Vec2 {
        let (x, y) = sobol::sample_2d(self.sample_reversed, self.seed(bounce, dim as u64, sub));
        Vec2::new(sobol::to_unit32(x), sobol::to_unit32(y))
    }
}

/// A 64-bit number as a float in `[0,1)`: its top 24 bits, the same float the 32-bit
/// getters give for the same point.
#[inline]
pub fn unit_f32(u: u64) -> f32 {
    sobol::to_unit32((u >> 32) as u32)
}

/// A reproducible stream of numbers in [0, 1) for tests that want arbitrary inputs (not
/// sample points).
#[cfg(test)]
pub fn test_numbers(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = fmix64(s.wrapping_add(0x9e37_79b9_7f4a_7c15));
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_pure_functions_of_their_address() {
        let a = SampleStream::new(7, 123, 4);
        let b = SampleStream::new(7, 123, 4);
        assert_eq!(a.get_1d(2, Dim::LightSelect, 0), b.get_1d(2, Dim::LightSelect, 0));
        assert_ne!(a.get_1d(2, Dim::LightSelect, 0), a.get_1d(3, Dim::LightSelect, 0));
        assert_ne!(a.get_1d(2, Dim::LightSelect, 0), a.get_1d(2, Dim::BsdfLobe, 0));
        assert_ne!(a.get_1d(2, Dim::LightSelect, 0), a.get_1d(2, Dim::LightSelect, 1));
        assert_ne!(a.get_1d(0, Dim::LightSelect, 0), SampleStream::new(8, 123, 4).get_1d(0, Dim::LightSelect, 0));
        let v = a.get_2d(0, Dim::BsdfDirection, 0);
        assert_ne!(v.x, v.y);
        // The 64-bit number has the 1D number's point on top.
        let wide = a.get_1d_u64(2, Dim::LightSelect, 0);
        assert_eq!((wide >> 40) as f32 / (1u32 << 24) as f32, a.get_1d(2, Dim::LightSelect, 0));
        assert_ne!(wide & 0xffff_ffff, SampleStream::new(7, 123, 5).get_1d_u64(2, Dim::LightSelect, 0) & 0xffff_ffff);
        let [x, y] = a.get_2d_u64(1, Dim::LightPoint, 3);
        assert_eq!(Vec2::new(unit_f32(x), unit_f32(y)), a.get_2d(1, Dim::LightPoint, 3));
    }

    #[test]
    fn a_pixels_streams_are_its_samples_streams() {
        for sample in [0u64, 1, 77, (1 << 32) - 1, 1 << 32, (5 << 32) + 3] {
            let (a, b) = (PixelStreams::new(9, 1234).sample(sample), SampleStream::new(9, 1234, sample));
            assert_eq!((a.key, a.sample_reversed), (b.key, b.sample_reversed));
            assert_eq!(a.sample_reversed, (sample as u32).reverse_bits());
            assert_ne!(a.key, PixelStreams::new(9, 1234).sample(sample + (1 << 32)).key, "a fresh scramble");
        }
    }

    #[test]
    fn numbers_are_uniform_and_uncorrelated() {
        // Chi-square over 64 cells of consecutive samples, and the lag-1 correlation
        // between two dimensions.
        let n = 64_000u64;
        let mut cells = [0u32; 64];
        let (mut sxy, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
        for s in 0..n {
            let st = SampleStream::new(1, s % 97, s / 97);
            let x = st.get_1d(0, Dim::LightSelect, 0);
            let y = st.get_1d(0, Dim::BsdfLobe, 0);
            assert!((0.0..1.0).contains(&x));
            cells[(x * 64.0) as usize] += 1;
            sxy += (x * y) as f64;
            sx += x as f64;
            sy += y as f64;
        }
        let e = n as f64 / 64.0;
        let chi2: f64 = cells.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        // 63 degrees of freedom: the 0.999 quantile is 103.4.
        assert!(chi2 < 103.4, "chi2 {chi2}");
        let nf = n as f64;
        let cov = sxy / nf - (sx / nf) * (sy / nf);
        assert!(cov.abs() < 4.0 / 12.0 / nf.sqrt(), "cov {cov}");
    }
}
