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

/// `(a.reverse_bits(), b.reverse_bits())`. x86-64 has no bit-reversal instruction, and
/// the scalar lowering takes 17 instructions a word; with SSSE3 both words are reversed at
/// once by two nibble-table shuffles and a byte shuffle (the bit reversals were a twentieth
/// of a cornell_grid_7 sample: three a 2D point, two a 1D one).
#[inline(always)]
fn bit_reversed_2(a: u32, b: u32) -> (u32, u32) {
    #[cfg(all(target_arch = "x86_64", target_feature = "ssse3", target_feature = "sse4.1"))]
    {
        use std::arch::x86_64::*;
        // SAFETY: register-only intrinsics, compiled only where SSSE3 and SSE4.1 are enabled
        // (the x86-64-v3 build, checked at start-up by `crate::cpu`).
        unsafe {
            let v = _mm_insert_epi32::<1>(_mm_cvtsi32_si128(a as i32), b as i32);
            let nibbles = _mm_set1_epi8(0x0f);
            // Each nibble reversed, moved to the other half of its byte.
            let high = _mm_setr_epi8(0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15);
            let low = _mm_slli_epi16::<4>(high);
            let bytes = _mm_or_si128(
                _mm_shuffle_epi8(low, _mm_and_si128(v, nibbles)),
                _mm_shuffle_epi8(high, _mm_and_si128(_mm_srli_epi16::<4>(v), nibbles)),
            );
            // And the bytes of each word in reverse order.
            let order = _mm_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
            let r = _mm_shuffle_epi8(bytes, order);
            (_mm_cvtsi128_si32(r) as u32, _mm_extract_epi32::<1>(r) as u32)
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "ssse3", target_feature = "sse4.1")))]
    (a.reverse_bits(), b.reverse_bits())
}

/// `x.reverse_bits()` as [`bit_reversed_2`] does it.
#[inline(always)]
pub fn bit_reversed(x: u32) -> u32 {
    bit_reversed_2(x, 0).0
}

/// Point of a scrambled 1D sequence for `seed`; `index_reversed` is the sample index with
/// its bits reversed (computed once per sample, see `SampleStream`).
#[inline]
pub fn sample_1d(index_reversed: u32, seed: u64) -> u32 {
    // Shuffle the index (a nested uniform scramble), then Owen-scramble the van der Corput
    // point of it; each scramble is "reverse, hash, reverse", and adjacent reversals cancel.
    let i = bit_reversed(laine_karras(index_reversed, seed as u32));
    bit_reversed(laine_karras(i, (seed >> 32) as u32))
}

/// Point of a scrambled 2D (0,2)-sequence for `seed`; `index_reversed` as in [`sample_1d`].
#[inline]
pub fn sample_2d(index_reversed: u32, seed: u64) -> (u32, u32) {
    let s = super::fmix64(seed);
    let i = bit_reversed(laine_karras(index_reversed, seed as u32));
    bit_reversed_2(laine_karras(i, s as u32), laine_karras(sobol_dim1_reversed(i), (s >> 32) as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_reverse_as_the_standard_library_reverses_them() {
        let mut x = 0x9e37_79b9u32;
        for k in 0..100_000u32 {
            x = x.wrapping_mul(0x2c1b_3c6d).wrapping_add(k) ^ (x >> 15);
            let y = x.rotate_left(k % 32) ^ k;
            assert_eq!(bit_reversed_2(x, y), (x.reverse_bits(), y.reverse_bits()), "{x:#x} {y:#x}");
        }
        for x in [0, 1, u32::MAX, 1 << 31, 0x8000_0001, 0x0f0f_0f0f] {
            assert_eq!(bit_reversed(x), x.reverse_bits(), "{x:#x}");
        }
    }

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
