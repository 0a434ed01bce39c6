//! Fixed-point integers for sums that must not depend on the order of their terms: integer
//! addition is associative where float addition is not, so sums of the same terms split into
//! any parts and added in any order are the same bits (the film's pixel sums, a learning
//! light sampler's statistics).

/// Fixed-point conversions of samples: what the film sums (and a learning light sampler).
pub struct Fixed;

/// 2⁶³: scaled values below it in magnitude convert through an `i64`.
const I64_RANGE: f64 = 9_223_372_036_854_775_808.0;

impl Fixed {
    /// Fractional bits of a value.
    pub const VALUE: i32 = 62;
    /// Fractional bits of a squared value.
    pub const SQUARE: i32 = 32;
    /// Largest magnitude a sample keeps.
    pub const LIMIT: f64 = (1u64 << 31) as f64;

    /// `x` × 2^`frac`, truncated towards zero, as an integer; `x` clamped to ±2³¹ (±LIMIT²
    /// for a square), NaN as 0. Exact: an `i64` conversion below 2⁶³, the f64's bits above
    /// (no float-to-i128 call).
    #[inline]
    pub fn of(x: f64, frac: i32, limit: f64) -> i128 {
        let x = if x.is_nan() { 0.0 } else { x.clamp(-limit, limit) };
        // Scaling by 2^frac (|frac| < 1023) is exact, and below 2⁶³ the conversion truncates
        // towards zero as the bit arithmetic below does: one instruction for nearly every
        // sample (the film converts six numbers a sample).
        let scaled = x * f64::from_bits(((1023 + frac) as u64) << 52);
        if scaled.abs() < I64_RANGE {
            // SAFETY: finite (NaN fails the test) and within an i64: one instruction, where
            // `as` adds the saturation that cannot happen here.
            return unsafe { scaled.to_int_unchecked::<i64>() } as i128;
        }
        Self::by_bits(x, frac)
    }

    /// `x` × 2^`frac` truncated towards zero, from the f64's bits.
    fn by_bits(x: f64, frac: i32) -> i128 {
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        if exp == 0 {
            return 0; // zero or subnormal: far below the resolution
        }
        let mantissa = ((bits & ((1 << 52) - 1)) | (1 << 52)) as i128;
        // x = mantissa · 2^(exp − 1075)
        let shift = exp - 1075 + frac;
        let q = if shift >= 0 {
            mantissa << shift
        } else if shift > -64 {
            mantissa >> -shift
        } else {
            0
        };
        if bits >> 63 != 0 { -q } else { q }
    }

    /// A fixed-point integer with `frac` fractional bits back as a float.
    #[inline]
    pub fn to_f64(q: i128, frac: i32) -> f64 {
        q as f64 * (-frac as f64).exp2()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_keeps_values_to_its_resolution() {
        for x in [1.0f64, -2.5, 1e-12, 3.0e9, -7.25e-3, 0.1] {
            let q = Fixed::of(x, Fixed::VALUE, Fixed::LIMIT);
            let back = Fixed::to_f64(q, Fixed::VALUE);
            let expect = x.clamp(-Fixed::LIMIT, Fixed::LIMIT);
            assert!((back - expect).abs() <= 2f64.powi(-Fixed::VALUE) + 1e-15 * expect.abs(), "{x}: {back}");
        }
        assert_eq!(Fixed::of(f64::NAN, Fixed::VALUE, Fixed::LIMIT), 0);
        // The i64 shortcut gives the bit arithmetic's integers, over every magnitude.
        let mut next = crate::sampling::test_numbers(5);
        for _ in 0..100_000 {
            let x = (next() as f64 - 0.5) * 2f64.powf(90.0 * next() as f64 - 60.0);
            for frac in [Fixed::VALUE, Fixed::SQUARE] {
                assert_eq!(
                    Fixed::of(x, frac, Fixed::LIMIT),
                    Fixed::by_bits(x.clamp(-Fixed::LIMIT, Fixed::LIMIT), frac),
                    "{x}"
                );
            }
        }
        // Either side of the shortcut's bound.
        for (x, frac, q) in [
            (1.5, 62, 3i128 << 61),
            (-1.5, 62, -(3i128 << 61)),
            (2.0, 62, 1i128 << 63),
            (-2.0, 62, -(1i128 << 63)),
            (3.0e9, 62, 1i128 << 93), // clamped to 2³¹
            (1.0 + 2f64.powi(-40), 62, (1i128 << 62) + (1i128 << 22)),
            (2f64.powi(-70), 62, 0),
            (-0.75 * 2f64.powi(-61), 62, -1),
        ] {
            assert_eq!(Fixed::of(x, frac, Fixed::LIMIT), q, "{x} at {frac} bits");
        }
        assert_eq!(Fixed::of(0.0, Fixed::VALUE, Fixed::LIMIT), 0);
    }
}
