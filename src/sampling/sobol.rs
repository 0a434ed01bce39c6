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
/// itself and lower bits. Applied to bit-reversed values ("reverse, hash, reverse") it is a
/// nested uniform (Owen) scramble: each bit flipped depending on the higher-order bits.
#[inline(always)]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// The second dimension of the Sobol sequence (the first is bit reversal), bit by bit: the
/// definition, which [`SOBOL_DIM1`] tabulates.
const fn sobol_dim1_bits(mut i: u32) -> u32 {
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

/// [`sobol_dim1_bits`] of each byte of the index in each of its four positions, bit-reversed
/// (the scramble that follows works on reversed bits): the dimension is linear over GF(2), so
/// four lookups replace a loop of up to 32 unpredictable branches (the shuffled indices use
/// all 32 bits) and a bit reversal.
static SOBOL_DIM1_REVERSED: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            t[k][b] = sobol_dim1_bits((b as u32) << (8 * k)).reverse_bits();
            b += 1;
        }
        k += 1;
    }
    t
};

/// `sobol_dim1_bits(i).reverse_bits()`, from [`SOBOL_DIM1_REVERSED`].
#[inline(always)]
fn sobol_dim1_reversed(i: u32) -> u32 {
    let t = &SOBOL_DIM1_REVERSED;
    let b = i.to_le_bytes();
    t[0][b[0] as usize] ^ t[1][b[1] as usize] ^ t[2][b[2] as usize] ^ t[3][b[3] as usize]
}

#[inline(always)]
pub fn to_unit32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Point of a scrambled 1D sequence for `seed`; `index_reversed` is the sample index with
/// its bits reversed (computed once per sample, see `SampleStream`).
#[inline]
pub fn sample_1d(index_reversed: u32, seed: u64) -> u32 {
    // Shuffle the index (a nested uniform scramble), then Owen-scramble the van der Corput
    // point of it; each scramble is "reverse, hash, reverse", and adjacent reversals cancel.
    let i = laine_karras(index_reversed, seed as u32).reverse_bits();
    laine_karras(i, (seed >> 32) as u32).reverse_bits()
}

/// Point of a scrambled 2D (0,2)-sequence for `seed`; `index_reversed` as in [`sample_1d`].
#[inline]
pub fn sample_2d(index_reversed: u32, seed: u64) -> (u32, u32) {
    let s = super::fmix64(seed);
    let i = laine_karras(index_reversed, seed as u32).reverse_bits();
    (laine_karras(i, s as u32).reverse_bits(), laine_karras(sobol_dim1_reversed(i), (s >> 32) as u32).reverse_bits())
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
                let pts: Vec<(u32, u32)> = (0..n).map(|i| sample_2d(i.reverse_bits(), seed)).collect();
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
                    strata[(sample_1d(i.reverse_bits(), seed) >> (32 - m)) as usize] += 1;
                }
                assert!(strata.iter().all(|&c| c == 1));
            }
        }
    }

    #[test]
    fn the_table_is_the_definition() {
        for k in 0..100_000u32 {
            let i = k.wrapping_mul(0x9e37_79b9) ^ (k >> 3);
            assert_eq!(sobol_dim1_reversed(i), sobol_dim1_bits(i).reverse_bits(), "{i:#x}");
        }
    }

    #[test]
    fn different_seeds_give_different_points() {
        let a: Vec<_> = (0..16u32).map(|i| sample_2d(i.reverse_bits(), 1)).collect();
        let b: Vec<_> = (0..16u32).map(|i| sample_2d(i.reverse_bits(), 2)).collect();
        assert_ne!(a, b);
    }
}
