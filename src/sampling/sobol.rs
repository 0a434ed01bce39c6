//! Owen-scrambled, shuffled Sobol points in one and two dimensions (Burley 2020, "Practical
//! Hash-based Owen Scrambling", JCGT 9(4)).
//!
//! Every (pixel, bounce, dimension) gets its own seed. The sample index is shuffled by a
//! nested uniform scramble (which keeps every power-of-two prefix a (0,m,2)-net), then the
//! point's coordinates are Owen-scrambled by hashing. Pairs of dimensions are thus each
//! stratified like a (0,2)-sequence and independent of the other pairs ("padding", as in
//! pbrt-v4's `PaddedSobolSampler`), and any number of samples may be taken: a render stopped
//! at any spp is still stratified at the largest power of two below it.

/// Burley's improved Laine-Karras permutation: a hash in which each bit depends only on
/// itself and lower bits.
#[inline(always)]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Owen scramble in base 2: each bit flipped depending on the higher-order bits.
#[inline(always)]
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The second dimension of the Sobol sequence (the first is bit reversal).
#[inline(always)]
fn sobol_dim1(mut i: u32) -> u32 {
    let (mut v, mut y) = (1u32 << 31, 0u32);
    while i != 0 {
        if i & 1 != 0 {
            y ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    y
}

/// 32-bit fixed point in [0,1) to f32 (top 24 bits: every value exact, never 1).
#[inline(always)]
pub fn to_unit32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Point `index` of a scrambled 1D sequence for `seed`.
#[inline]
pub fn sample_1d(index: u32, seed: u64) -> u32 {
    let i = nested_uniform_scramble(index, seed as u32);
    nested_uniform_scramble(i.reverse_bits(), (seed >> 32) as u32)
}

/// Point `index` of a scrambled 2D (0,2)-sequence for `seed`.
#[inline]
pub fn sample_2d(index: u32, seed: u64) -> (u32, u32) {
    let s = super::fmix64(seed);
    let i = nested_uniform_scramble(index, seed as u32);
    (nested_uniform_scramble(i.reverse_bits(), s as u32), nested_uniform_scramble(sobol_dim1(i), (s >> 32) as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_power_of_two_prefix_is_stratified() {
        // The first 2^m points of a 2D sequence put exactly one point in every elementary
        // interval of area 2^-m (here: the 2^a × 2^(m−a) grids), whatever the seed.
        for seed in [1u64, 0xdead_beef, 42 << 40] {
            for m in [4u32, 6, 8] {
                let n = 1u32 << m;
                let pts: Vec<(u32, u32)> = (0..n).map(|i| sample_2d(i, seed)).collect();
                for a in 0..=m {
                    let mut cells = vec![0u32; n as usize];
                    for &(x, y) in &pts {
                        let cx = if a == 0 { 0 } else { x >> (32 - a) };
                        let cy = if m - a == 0 { 0 } else { y >> (32 - (m - a)) };
                        cells[((cx << (m - a)) | cy) as usize] += 1;
                    }
                    assert!(cells.iter().all(|&c| c == 1), "seed {seed:#x}, m {m}, split {a}");
                }
                // 1D: one point per 1/n stratum.
                let mut strata = vec![0u32; n as usize];
                for i in 0..n {
                    strata[(sample_1d(i, seed) >> (32 - m)) as usize] += 1;
                }
                assert!(strata.iter().all(|&c| c == 1));
            }
        }
    }

    #[test]
    fn different_seeds_give_different_points() {
        let a: Vec<_> = (0..16).map(|i| sample_2d(i, 1)).collect();
        let b: Vec<_> = (0..16).map(|i| sample_2d(i, 2)).collect();
        assert_ne!(a, b);
    }
}
