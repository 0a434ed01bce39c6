//! The film: per-pixel sums of samples, turned into mean, variance and AOV images.
//!
//! Owns: accumulation, the optional first-hit AOVs, and the [`Layers`] written for output. A
//! pixel is only ever written by the worker that owns its row band, so there are no locks.
//!
//! **Sums are exact.** Every sample is turned into a fixed-point integer ([`Fixed`]: value ×
//! 2⁶², value² × 2³², AOVs × 2³², as i128) and summed as integers, so the sums do not depend
//! on the order samples are added in: a render split into sample ranges and merged
//! ([`Film::merge`]) holds exactly the sums, and gives exactly the image, one render of the
//! union makes, whatever the split, the thread count or the order of the parts. Samples are
//! clamped to ±2³¹ (2.1·10⁹, beyond any radiance a scene should make) so that 2³² of them
//! cannot overflow; value² keeps 2⁻³² absolute resolution (the variance of pixels darker
//! than ~10⁻⁵ is coarse), the mean 2⁻⁶².

use crate::image::Layers;
use crate::integrator::FirstHit;
use crate::math::{Fixed, Rgb, UVec2, Vec3A};

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
    /// Every AOV by its name (as `--aov` and part files spell them).
    const NAMES: [&'static str; 4] = ["albedo", "normal", "depth", "variance"];

    /// The set of the AOVs named (unknown names are ignored).
    pub fn from_names<S: AsRef<str>>(names: &[S]) -> Self {
        let has = |n: &str| names.iter().any(|s| s.as_ref() == n);
        Self { albedo: has("albedo"), normal: has("normal"), depth: has("depth"), variance: has("variance") }
    }

    /// The names of the AOVs in the set, in [`AovSet::NAMES`] order.
    pub fn names(&self) -> Vec<String> {
        let on = [self.albedo, self.normal, self.depth, self.variance];
        Self::NAMES.iter().zip(on).filter(|(_, on)| *on).map(|(n, _)| n.to_string()).collect()
    }

    /// True when a first-hit AOV is requested.
    pub fn wants_first_hit(&self) -> bool {
        self.albedo || self.normal || self.depth
    }
}

/// Accumulated samples of one pixel: Σx and Σx² per channel, in fixed point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelSum {
    sum: [i128; 3],
    sum_sq: [i128; 3],
}

/// Accumulated first-hit data of one pixel, in fixed point with [`Fixed::SQUARE`] bits:
/// albedo, normal, depth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSum {
    albedo: [i128; 3],
    normal: [i128; 3],
    depth: i128,
}

impl PixelSum {
    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, v: Rgb) {
        for c in 0..3 {
            let x = v[c] as f64;
            self.sum[c] += Fixed::of(x, Fixed::VALUE, Fixed::LIMIT);
            self.sum_sq[c] += Fixed::of(x * x, Fixed::SQUARE, Fixed::LIMIT * Fixed::LIMIT);
        }
    }

    fn merge(&mut self, o: &PixelSum) {
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.sum_sq[c] += o.sum_sq[c];
        }
    }
}

impl AovSum {
    /// Adds one sample's first hit (or nothing when the ray escaped).
    #[inline]
    pub fn add(&mut self, hit: Option<FirstHit>) {
        if let Some(h) = hit {
            let q = |x: f32| Fixed::of(x as f64, Fixed::SQUARE, Fixed::LIMIT);
            for c in 0..3 {
                self.albedo[c] += q(h.albedo[c]);
                self.normal[c] += q(h.normal[c]);
            }
            self.depth += q(h.depth);
        }
    }

    fn merge(&mut self, o: &AovSum) {
        for c in 0..3 {
            self.albedo[c] += o.albedo[c];
            self.normal[c] += o.normal[c];
        }
        self.depth += o.depth;
    }

    /// The sums as floats: (albedo, normal, depth).
    fn floats(&self) -> (Vec3A, Vec3A, f32) {
        let f = |q: i128| Fixed::to_f64(q, Fixed::SQUARE) as f32;
        (Vec3A::from(self.albedo.map(f)), Vec3A::from(self.normal.map(f)), f(self.depth))
    }
}

/// Light a light path brought to a pixel ([`Film::splat`]).
#[derive(Clone, Copy, Debug)]
pub struct Splat {
    /// Row-major pixel index.
    pub pixel: u32,
    /// What it adds to the pixel's sum of samples.
    pub value: Rgb,
}

/// A film's splat sums while workers render: any of them adds its splats, a batch at a time
/// (integer sums: the order batches arrive in changes no bit).
pub struct SplatSums<'a>(std::sync::Mutex<&'a mut [PixelSum]>);

impl SplatSums<'_> {
    /// Adds `batch` and empties it.
    pub fn add(&self, batch: &mut Vec<Splat>) {
        let mut sums = self.0.lock().unwrap_or_else(|e| e.into_inner());
        for s in batch.drain(..) {
            sums[s.pixel as usize].add(s.value);
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
    /// Light paths' contributions per pixel, when the render traces them: added to the
    /// samples' sums for the mean, their squares to its variance (they are independent of
    /// the pixel's own samples).
    splats: Option<Vec<PixelSum>>,
}

impl Film {
    /// An empty film; `first_hit` keeps AOV sums too.
    pub fn new(size: UVec2, first_hit: bool) -> Self {
        let n = (size.x * size.y) as usize;
        Self {
            size,
            spp: 0,
            pixels: vec![PixelSum::default(); n],
            aovs: first_hit.then(|| vec![AovSum::default(); n]),
            splats: None,
        }
    }

    /// The same film keeping the sums of light paths' splats too.
    pub fn with_splats(self) -> Self {
        let n = self.pixels.len();
        Self { splats: Some(self.splats.unwrap_or_else(|| vec![PixelSum::default(); n])), ..self }
    }

    /// Whether the film keeps light paths' splats.
    pub fn has_splats(&self) -> bool {
        self.splats.is_some()
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

    /// Mutable rows `[row0, row0 + rows)` for workers: (pixel sums, AOV sums); and the splat
    /// sums, which any worker may add to (light paths reach any pixel).
    #[allow(clippy::type_complexity)]
    pub fn bands_mut(
        &mut self,
        rows_per_band: u32,
    ) -> (impl Iterator<Item = (u32, &mut [PixelSum], Option<&mut [AovSum]>)>, Option<SplatSums<'_>>) {
        let w = self.size.x as usize;
        let chunk = w * rows_per_band as usize;
        let aov_chunks: Box<dyn Iterator<Item = Option<&mut [AovSum]>>> = match self.aovs.as_mut() {
            Some(a) => Box::new(a.chunks_mut(chunk).map(Some)),
            None => Box::new(std::iter::repeat_with(|| None)),
        };
        let bands = self
            .pixels
            .chunks_mut(chunk)
            .zip(aov_chunks)
            .enumerate()
            .map(move |(i, (p, a))| (i as u32 * rows_per_band, p, a));
        (bands, self.splats.as_deref_mut().map(|s| SplatSums(std::sync::Mutex::new(s))))
    }

    /// Mean of pixel `i` (row-major).
    #[inline]
    pub fn mean(&self, i: usize) -> Rgb {
        let n = self.spp.max(1) as f64;
        let splat = self.splats.as_ref().map_or([0; 3], |s| s[i].sum);
        let s = [0, 1, 2].map(|c| Fixed::to_f64(self.pixels[i].sum[c] + splat[c], Fixed::VALUE) / n);
        Rgb::new(s[0] as f32, s[1] as f32, s[2] as f32)
    }

    /// Variance of the mean of pixel `i`: sample variance / spp (0 below 2 samples).
    pub fn variance_of_mean(&self, i: usize) -> Rgb {
        let n = self.spp as f64;
        if n < 2.0 {
            return Rgb::ZERO;
        }
        let p = &self.pixels[i];
        let v = |c: usize| {
            let mean = Fixed::to_f64(p.sum[c], Fixed::VALUE) / n;
            let mean_sq = Fixed::to_f64(p.sum_sq[c], Fixed::SQUARE) / n;
            let splats = self.splats.as_ref().map_or(0.0, |s| Fixed::to_f64(s[i].sum_sq[c], Fixed::SQUARE) / (n * n));
            (((mean_sq - mean * mean) * n / (n - 1.0)).max(0.0) / n + splats) as f32
        };
        Rgb::new(v(0), v(1), v(2))
    }

    /// The mean image as colours.
    pub fn means(&self) -> Vec<Rgb> {
        (0..self.pixels.len()).map(|i| self.mean(i)).collect()
    }

    /// Adds another film's samples (same size; e.g. another range of sample indices): the
    /// sums become exactly those of one film that took both films' samples.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!(self.size, other.size, "films of different sizes");
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            a.merge(b);
        }
        if let (Some(a), Some(b)) = (self.aovs.as_mut(), other.aovs.as_ref()) {
            for (x, y) in a.iter_mut().zip(b) {
                x.merge(y);
            }
        }
        if let (Some(a), Some(b)) = (self.splats.as_mut(), other.splats.as_ref()) {
            for (x, y) in a.iter_mut().zip(b) {
                x.merge(y);
            }
        }
        self.spp += other.spp;
    }

    /// Bytes of [`Film::sums_bytes`] per pixel: with or without first-hit sums and splats.
    pub fn bytes_per_pixel(first_hit: bool, splats: bool) -> usize {
        6 * 16 + if first_hit { 7 * 16 } else { 0 } + if splats { 6 * 16 } else { 0 }
    }

    /// Whether the film keeps first-hit (AOV) sums.
    pub fn has_first_hit(&self) -> bool {
        self.aovs.is_some()
    }

    /// The sums as bytes (little-endian i128s, pixel by pixel, then the AOV sums, then the
    /// splats'): what a partial render stores so that a merge is exact.
    pub fn sums_bytes(&self) -> Vec<u8> {
        let per_pixel = Self::bytes_per_pixel(self.aovs.is_some(), self.splats.is_some());
        let mut out = Vec::with_capacity(self.pixels.len() * per_pixel);
        for p in &self.pixels {
            for q in p.sum.iter().chain(&p.sum_sq) {
                out.extend_from_slice(&q.to_le_bytes());
            }
        }
        for a in self.aovs.iter().flatten() {
            for q in a.albedo.iter().chain(&a.normal).chain([&a.depth]) {
                out.extend_from_slice(&q.to_le_bytes());
            }
        }
        for p in self.splats.iter().flatten() {
            for q in p.sum.iter().chain(&p.sum_sq) {
                out.extend_from_slice(&q.to_le_bytes());
            }
        }
        out
    }

    /// The film whose [`sums_bytes`](Self::sums_bytes) are `bytes`, of `size` pixels and `spp`
    /// samples; `None` when the length does not fit.
    pub fn from_sums_bytes(size: UVec2, spp: u32, first_hit: bool, splats: bool, bytes: &[u8]) -> Option<Self> {
        let n = size.x as usize * size.y as usize;
        if bytes.len() != n.checked_mul(Self::bytes_per_pixel(first_hit, splats))? {
            return None;
        }
        let mut words = bytes.chunks_exact(16).map(|b| i128::from_le_bytes(b.try_into().expect("16 bytes")));
        let mut next = || words.next().expect("length checked");
        let pixel_sums = |next: &mut dyn FnMut() -> i128| -> Vec<PixelSum> {
            (0..n).map(|_| PixelSum { sum: [next(), next(), next()], sum_sq: [next(), next(), next()] }).collect()
        };
        let pixels = pixel_sums(&mut next);
        let aovs = first_hit.then(|| {
            (0..n)
                .map(|_| AovSum { albedo: [next(), next(), next()], normal: [next(), next(), next()], depth: next() })
                .collect()
        });
        let splats = splats.then(|| pixel_sums(&mut next));
        Some(Self { size, spp, pixels, aovs, splats })
    }

    /// Whether two films hold the same sums (the same samples, bit for bit).
    pub fn same_sums(&self, other: &Film) -> bool {
        self.size == other.size
            && self.spp == other.spp
            && self.pixels == other.pixels
            && self.aovs == other.aovs
            && self.splats == other.splats
    }

    /// The output channels: R, G, B, then the AOVs asked for.
    pub fn layers(&self, aovs: AovSet) -> Layers {
        let n = self.pixels.len();
        let mut layers = Layers::new(self.size);
        layers.push_rgb("", &self.means());
        let inv = 1.0 / self.spp.max(1) as f32;
        if let Some(a) = &self.aovs {
            let sums: Vec<(Vec3A, Vec3A, f32)> = a.iter().map(AovSum::floats).collect();
            if aovs.albedo {
                layers.push_rgb("albedo", &sums.iter().map(|p| p.0 * inv).collect::<Vec<_>>());
            }
            if aovs.normal {
                // averaged normals are renormalised
                let normals: Vec<Vec3A> = sums.iter().map(|p| p.1.normalize_or_zero()).collect();
                layers.push_vectors(["N.X", "N.Y", "N.Z"], &normals);
            }
            if aovs.depth {
                layers.push("Z", sums.iter().map(|p| p.2 * inv).collect());
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
        for (_, px, _) in film.bands_mut(1).0 {
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
    fn splats_add_to_the_mean_and_their_squares_to_its_variance_in_any_order() {
        let film = |order: &[usize]| {
            let mut film = Film::new(UVec2::new(2, 1), false).with_splats();
            let (bands, splats) = film.bands_mut(1);
            for (_, px, _) in bands {
                for v in [1.0f32, 2.0, 3.0, 4.0] {
                    px[0].add(Rgb::splat(v));
                }
            }
            let all = [Splat { pixel: 0, value: Rgb::splat(2.0) }, Splat { pixel: 0, value: Rgb::splat(6.0) }];
            let mut batch: Vec<Splat> = order.iter().map(|&k| all[k]).collect();
            splats.expect("a film with splats").add(&mut batch);
            assert!(batch.is_empty());
            film.add_spp(4);
            film
        };
        let (a, b) = (film(&[0, 1]), film(&[1, 0]));
        assert!(a.same_sums(&b));
        // (1 + 2 + 3 + 4 + 2 + 6) / 4; 5/12 for the samples plus (2² + 6²) / 4² for the splats.
        assert_eq!(a.mean(0), Rgb::splat(4.5));
        assert!((a.variance_of_mean(0).x - (5.0 / 12.0 + 40.0 / 16.0)).abs() < 1e-5);
        assert_eq!(a.mean(1), Rgb::ZERO);
        let bytes = a.sums_bytes();
        assert_eq!(bytes.len(), 2 * Film::bytes_per_pixel(false, true));
        assert!(Film::from_sums_bytes(a.size(), 4, false, true, &bytes).is_some_and(|f| f.same_sums(&a)));
        assert!(Film::from_sums_bytes(a.size(), 4, false, false, &bytes).is_none(), "splats' bytes are counted");
    }

    #[test]
    fn any_split_of_the_samples_merges_to_the_same_bits() {
        // Values over 30 decades, both signs, the clamp and NaN: however the samples are cut
        // into parts and in whatever order the parts merge, the sums are the same.
        let values: Vec<f32> = (0..200)
            .map(|i| {
                let t = (i as f32 * 0.618).fract();
                let v = 10f32.powf(30.0 * t - 15.0) * if i % 7 == 0 { -1.0 } else { 1.0 };
                match i {
                    13 => 1e12,
                    14 => f32::NAN,
                    _ => v,
                }
            })
            .collect();
        let film_of = |vals: &[f32]| {
            let mut f = Film::new(UVec2::new(1, 1), true);
            for (_, px, aov) in f.bands_mut(1).0 {
                let aov = aov.unwrap();
                for &v in vals {
                    px[0].add(Rgb::new(v, 2.0 * v, 0.5));
                    aov[0].add(Some(FirstHit {
                        albedo: Rgb::splat(v.abs().min(1.0)),
                        normal: Vec3A::Y,
                        depth: v.abs(),
                    }));
                }
            }
            f.add_spp(vals.len() as u32);
            f
        };
        let whole = film_of(&values);
        for cuts in [[1usize, 2, 199], [50, 120, 150], [0, 100, 200]] {
            let parts = [&values[..cuts[0]], &values[cuts[0]..cuts[1]], &values[cuts[1]..cuts[2]], &values[cuts[2]..]];
            let mut merged = film_of(parts[3]);
            for p in parts[..3].iter().rev() {
                merged.merge(&film_of(p));
            }
            assert_eq!(merged.pixels, whole.pixels);
            assert_eq!(merged.aovs, whole.aovs);
            assert_eq!(merged.mean(0).to_array().map(f32::to_bits), whole.mean(0).to_array().map(f32::to_bits));
        }
        // And the clamp holds the sums finite: the mean is the clamped value's share.
        assert!(whole.mean(0).is_finite());
    }

    #[test]
    fn merging_equals_one_accumulation() {
        let mut a = Film::new(UVec2::new(2, 1), false);
        let mut b = a.clone();
        let mut whole = a.clone();
        for (film, vals) in [(&mut a, [1.0f32, 2.0]), (&mut b, [5.0, 7.0]), (&mut whole, [1.0, 2.0])] {
            for (_, px, _) in film.bands_mut(1).0 {
                for v in vals {
                    px[1].add(Rgb::splat(v));
                }
            }
            film.add_spp(2);
        }
        for (_, px, _) in whole.bands_mut(1).0 {
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
