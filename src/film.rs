//! The film: per-pixel sums of samples, turned into mean, variance and AOV images.
//!
//! Owns: accumulation (f64 sums of value and value², so that partial renders merge exactly and
//! variance needs no second pass), the optional first-hit AOVs, and the [`Layers`] written for
//! output. A pixel is only ever written by the worker that owns its row band, so there are no
//! locks; samples are added in sample-index order, so the sums (and the image) do not depend
//! on the thread count.

use crate::image::Layers;
use crate::integrator::FirstHit;
use crate::math::{Rgb, UVec2, Vec3A};

/// Which extra images to keep.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSet {
    /// Base colour at the first hit.
    pub albedo: bool,
    /// Shading normal at the first hit.
    pub normal: bool,
    /// Distance to the first hit (camera-ray length; 0 where the ray escapes).
    pub depth: bool,
    /// Per-pixel variance of the mean (sample variance / spp), per channel.
    pub variance: bool,
}

impl AovSet {
    /// True when a first-hit AOV is requested.
    pub fn wants_first_hit(&self) -> bool {
        self.albedo || self.normal || self.depth
    }
}

/// Accumulated samples of one pixel.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelSum {
    sum: [f64; 3],
    sum_sq: [f64; 3],
}

/// Accumulated first-hit data of one pixel.
#[derive(Clone, Copy, Debug, Default)]
pub struct AovSum {
    albedo: Vec3A,
    normal: Vec3A,
    depth: f32,
}

impl PixelSum {
    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, v: Rgb) {
        for c in 0..3 {
            let x = v[c] as f64;
            self.sum[c] += x;
            self.sum_sq[c] += x * x;
        }
    }
}

impl AovSum {
    /// Adds one sample's first hit (or nothing when the ray escaped).
    #[inline]
    pub fn add(&mut self, hit: Option<FirstHit>) {
        if let Some(h) = hit {
            self.albedo += h.albedo;
            self.normal += h.normal;
            self.depth += h.depth;
        }
    }
}

/// The film of one render.
#[derive(Clone, Debug)]
pub struct Film {
    size: UVec2,
    spp: u32,
    pixels: Vec<PixelSum>,
    aovs: Option<Vec<AovSum>>,
}

impl Film {
    /// An empty film; `first_hit` keeps AOV sums too.
    pub fn new(size: UVec2, first_hit: bool) -> Self {
        let n = (size.x * size.y) as usize;
        Self { size, spp: 0, pixels: vec![PixelSum::default(); n], aovs: first_hit.then(|| vec![AovSum::default(); n]) }
    }

    /// Image size.
    pub fn size(&self) -> UVec2 {
        self.size
    }

    /// Samples per pixel accumulated so far.
    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Records that `n` more samples were added to every pixel.
    pub fn add_spp(&mut self, n: u32) {
        self.spp += n;
    }

    /// Mutable rows `[row0, row0 + rows)` for workers: (pixel sums, AOV sums).
    pub fn bands_mut(
        &mut self,
        rows_per_band: u32,
    ) -> impl Iterator<Item = (u32, &mut [PixelSum], Option<&mut [AovSum]>)> {
        let w = self.size.x as usize;
        let chunk = w * rows_per_band as usize;
        let aov_chunks: Box<dyn Iterator<Item = Option<&mut [AovSum]>>> = match self.aovs.as_mut() {
            Some(a) => Box::new(a.chunks_mut(chunk).map(Some)),
            None => Box::new(std::iter::repeat_with(|| None)),
        };
        self.pixels
            .chunks_mut(chunk)
            .zip(aov_chunks)
            .enumerate()
            .map(move |(i, (p, a))| (i as u32 * rows_per_band, p, a))
    }

    /// Mean of pixel `i` (row-major).
    #[inline]
    pub fn mean(&self, i: usize) -> Rgb {
        let n = self.spp.max(1) as f64;
        let s = &self.pixels[i].sum;
        Rgb::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }

    /// Variance of the mean of pixel `i`: sample variance / spp (0 below 2 samples).
    pub fn variance_of_mean(&self, i: usize) -> Rgb {
        let n = self.spp as f64;
        if n < 2.0 {
            return Rgb::ZERO;
        }
        let p = &self.pixels[i];
        let v = |c: usize| {
            let mean = p.sum[c] / n;
            (((p.sum_sq[c] / n - mean * mean) * n / (n - 1.0)).max(0.0) / n) as f32
        };
        Rgb::new(v(0), v(1), v(2))
    }

    /// The mean image as colours.
    pub fn means(&self) -> Vec<Rgb> {
        (0..self.pixels.len()).map(|i| self.mean(i)).collect()
    }

    /// Adds another film's samples (same size; e.g. a later range of sample indices).
    pub fn merge(&mut self, other: &Film) {
        assert_eq!(self.size, other.size, "films of different sizes");
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            for c in 0..3 {
                a.sum[c] += b.sum[c];
                a.sum_sq[c] += b.sum_sq[c];
            }
        }
        if let (Some(a), Some(b)) = (self.aovs.as_mut(), other.aovs.as_ref()) {
            for (x, y) in a.iter_mut().zip(b) {
                x.albedo += y.albedo;
                x.normal += y.normal;
                x.depth += y.depth;
            }
        }
        self.spp += other.spp;
    }

    /// The output channels: R, G, B, then the AOVs asked for.
    pub fn layers(&self, aovs: AovSet) -> Layers {
        let n = self.pixels.len();
        let mut layers = Layers::new(self.size);
        layers.push_rgb("", &self.means());
        let inv = 1.0 / self.spp.max(1) as f32;
        if let Some(a) = &self.aovs {
            if aovs.albedo {
                layers.push_rgb("albedo", &a.iter().map(|p| p.albedo * inv).collect::<Vec<_>>());
            }
            if aovs.normal {
                // averaged normals are renormalised
                let normals: Vec<Vec3A> = a.iter().map(|p| p.normal.normalize_or_zero()).collect();
                layers.push_vectors(["N.X", "N.Y", "N.Z"], &normals);
            }
            if aovs.depth {
                layers.push("Z", a.iter().map(|p| p.depth * inv).collect());
            }
        }
        if aovs.variance {
            layers.push_rgb("variance", &(0..n).map(|i| self.variance_of_mean(i)).collect::<Vec<_>>());
        }
        layers
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_variance_of_known_samples() {
        let mut film = Film::new(UVec2::new(1, 1), false);
        for (_, px, _) in film.bands_mut(1) {
            for v in [1.0f32, 2.0, 3.0, 4.0] {
                px[0].add(Rgb::splat(v));
            }
        }
        film.add_spp(4);
        assert_eq!(film.mean(0), Rgb::splat(2.5));
        // Sample variance 5/3, variance of the mean 5/12.
        assert!((film.variance_of_mean(0).x - 5.0 / 12.0).abs() < 1e-6);
    }

    #[test]
    fn merging_equals_one_accumulation() {
        let mut a = Film::new(UVec2::new(2, 1), false);
        let mut b = a.clone();
        let mut whole = a.clone();
        for (film, vals) in [(&mut a, [1.0f32, 2.0]), (&mut b, [5.0, 7.0]), (&mut whole, [1.0, 2.0])] {
            for (_, px, _) in film.bands_mut(1) {
                for v in vals {
                    px[1].add(Rgb::splat(v));
                }
            }
            film.add_spp(2);
        }
        for (_, px, _) in whole.bands_mut(1) {
            px[1].add(Rgb::splat(5.0));
            px[1].add(Rgb::splat(7.0));
        }
        whole.add_spp(2);
        a.merge(&b);
        assert_eq!(a.mean(1), whole.mean(1));
        assert_eq!(a.variance_of_mean(1), whole.variance_of_mean(1));
        let layers = a.layers(AovSet { variance: true, ..Default::default() });
        let names: Vec<&str> = layers.channels.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["R", "G", "B", "variance.R", "variance.G", "variance.B"]);
    }
}
