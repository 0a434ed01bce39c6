//! Choosing an index in proportion to weights with one 64-bit random number, exactly.
//!
//! Owns: [`Split`], the rule light samplers use to share the 2⁶⁴ equally likely values of a
//! selection number among a list of weights, [`Distribution1D`], a table of that rule (the
//! `power` sampler), [`Table16`], the rule over 2¹⁶ values for a few positive weights
//! (`cells`' per-cell tables), and [`NodeSplit`], a light tree node's split among its eight
//! children in fixed-point integers with the same guarantees. A weight's *interval* is the
//! run of values that choose it, so its probability is exactly `interval width / 2⁶⁴`: the
//! pmf a sampler reports is the probability it realises, not an approximation of it (an f32
//! CDF drawn with a 24-bit number, as before, gave each of 10⁶ lights 16 or 17 of 2²⁴
//! values, up to 5 % off its reported pmf, and never chose a light below 2⁻²⁴).
//!
//! [`Split`]'s rule: with `P` positive weights summing to `T` over a range of `R` values,
//! the interval of weight `i` ends at `positive(≤ i) + ⌊acc(≤ i) / T · (R − P)⌋`, and the
//! last positive interval ends at `R`. Every positive weight thus owns at least one value
//! (so anything with a positive weight can be chosen, as MIS assumes), a zero weight owns
//! none, and the intervals tile the range. Weights are f32 summed in f64 in index order, the
//! same order at sampling and at pmf time, so both see the same intervals bit for bit. NaN
//! and negative weights count as 0; when some weights are infinite, they share the range
//! equally and the finite ones get nothing.

use wide::{CmpEq, CmpGt, f32x8};

/// Number of equally likely values of a selection number (`u64`): 2⁶⁴.
pub const RANGE: u128 = 1 << 64;

/// Probability of an interval of `width` values out of [`RANGE`].
#[inline]
pub fn probability(width: u128) -> f32 {
    // u64 → f64 is one instruction where u128 → f64 is a library call; a width of 2⁶⁴ (the
    // only one above u64::MAX) is probability 1. Both round to the same f64.
    let w = if width > u64::MAX as u128 { RANGE as f64 } else { width as u64 as f64 };
    (w * (1.0 / RANGE as f64)) as f32
}

/// The interval of entry `k` when `range` values are shared equally among `m` entries:
/// `⌈k·range/m⌉ .. ⌈(k+1)·range/m⌉`, so every entry owns ⌊range/m⌋ or ⌈range/m⌉ values.
#[inline]
pub fn even_interval(k: u32, m: u32, range: u128) -> (u128, u128) {
    let start = |k: u32| (k as u128 * range).div_ceil(m as u128);
    (start(k), start(k + 1))
}

/// The entry whose [`even_interval`] holds `u` (`u < range`): ⌊u·m/range⌋.
#[inline]
pub fn even_pick(u: u128, m: u32, range: u128) -> u32 {
    // The whole range is 2⁶⁴: a shift, not a 128-bit division.
    if range == RANGE { ((u * m as u128) >> 64) as u32 } else { (u * m as u128 / range) as u32 }
}

/// Sharing `range` values among a sequence of weights, one interval after another.
#[derive(Clone, Copy, Debug)]
pub struct Split {
    range: u128,
    /// `range − positive` (values beyond the one each positive weight is given), or 0.
    spread: u128,
    /// `spread / total`: values per unit of weight.
    scale: f64,
    positive: u32,
    infinite: bool,
    /// Sum of the weights consumed so far.
    acc: f64,
    /// Positive weights consumed so far.
    seen: u32,
    /// End of the last interval.
    end: u128,
}

/// A weight as the rule counts it (see the module docs).
#[inline(always)]
fn clean(w: f32, infinite: bool) -> f64 {
    if infinite {
        if w == f32::INFINITY { 1.0 } else { 0.0 }
    } else if w > 0.0 {
        w as f64
    } else {
        0.0
    }
}

impl Split {
    /// Prepares to split `range` (at most 2⁶⁴) among `weights` (fewer than 2³²; which
    /// [`Split::next`] must then see in the same order); `None` when no weight is positive.
    #[inline(always)]
    pub fn new(range: u128, weights: impl IntoIterator<Item = f32> + Clone) -> Option<Self> {
        let sum = |infinite: bool| {
            weights.clone().into_iter().fold((0.0f64, 0u32), |(total, positive), w| {
                let c = clean(w, infinite);
                (total + c, positive + (c > 0.0) as u32)
            })
        };
        // Fewer than 2³² finite f32 weights cannot overflow an f64 sum: an infinite total
        // means an infinite weight.
        let (mut total, mut positive) = sum(false);
        let infinite = total.is_infinite();
        if infinite {
            (total, positive) = sum(true);
        }
        Self::with_totals(range, total, positive, infinite)
    }

    #[inline(always)]
    fn with_totals(range: u128, total: f64, positive: u32, infinite: bool) -> Option<Self> {
        debug_assert!(range <= RANGE);
        if positive == 0 {
            return None;
        }
        let spread = range.saturating_sub(positive as u128);
        // u64 → f64 is one instruction where u128 → f64 is a library call.
        let scale = (spread.min(u64::MAX as u128) as u64) as f64 / total;
        Some(Self { range, spread, scale, positive, infinite, acc: 0.0, seen: 0, end: 0 })
    }

    /// The interval of the next weight: `start..end` as (start, end).
    #[inline(always)]
    pub fn next(&mut self, w: f32) -> (u128, u128) {
        let c = clean(w, self.infinite);
        let start = self.end;
        if c > 0.0 {
            self.acc += c;
            self.seen += 1;
            self.end = if self.seen == self.positive {
                self.range
            } else if self.range >= self.positive as u128 {
                // f64 → u64 saturates, and the share never passes the spread.
                let share = ((self.acc * self.scale) as u64 as u128).min(self.spread);
                self.seen as u128 + share
            } else {
                // Fewer values than positive weights (a range already narrowed to a few
                // values): the first ones get one value each.
                (self.seen as u128).min(self.range)
            };
        }
        (start, self.end)
    }
}

/// Bits of the fixed-point shares a [`NodeSplit`] divides a node's values by.
const SHARE_BITS: u32 = 26;
/// What a [`NodeSplit`]'s shares sum to, up to rounding: just below 2^[`SHARE_BITS`], so
/// that f32 rounding (a few parts in 2²⁴) and the one share each tiny weight is given cannot
/// take the sum past it, and shares × values per share never pass the range. The
/// remainder, up to 2⁻¹⁹ of the range, goes to the last positive weight.
const SHARES: f32 = ((1u32 << SHARE_BITS) - 128) as f32;

/// How a light tree node shares the values that reached it among its eight children, in
/// integers and eight-wide: weight `i`'s interval ends at `acc(≤ i) · ⌊range / 2²⁶⌋`, with
/// `acc` the running sum of the weights' fixed-point shares (26 bits in all, at least 1 for
/// a positive weight), and the last positive weight's at `range`, which takes the remainder.
/// As with [`Split`], every positive weight owns a value, a zero weight (NaN, negative) none,
/// infinite weights share the range equally, the intervals tile it, and the pmf is the
/// realised interval width, exact; but no child costs f64 or 128-bit work (Split's running
/// sums in f64 and its `u128` bounds were most of a tree level's choice). Below 2²⁶ values
/// (a node reached with probability under 2⁻³⁸) each positive weight but the last gets one.
#[derive(Clone, Copy, Debug)]
pub struct NodeSplit {
    /// Per weight where its interval ends, for those before the last positive one.
    ends: [u64; 8],
    /// The last positive weight: its interval and those after it end at `range`.
    last: usize,
    range: u128,
}

impl NodeSplit {
    /// Prepares to split `range` (at most 2⁶⁴) among `weights`; `None` when none is positive.
    #[inline(always)]
    pub fn over(range: u128, weights: &[f32; 8]) -> Option<Self> {
        debug_assert!(range <= RANGE);
        let (shares, positive) = Self::shares(f32x8::from(*weights));
        if positive == 0 {
            return None;
        }
        let last = (u32::BITS - 1 - positive.leading_zeros()) as usize;
        let per_share = (range >> SHARE_BITS) as u64;
        let ends = if per_share > 0 {
            let ends = Self::scaled_running_sums(&shares, per_share);
            debug_assert!(
                last == 0 || ends[last - 1] / per_share <= 1 << SHARE_BITS,
                "shares overflow before the last"
            );
            ends
        } else {
            // Too few values to share out: one to each positive weight, while they last.
            let (mut acc, mut ends) = (0u64, [0u64; 8]);
            for (end, &q) in ends.iter_mut().zip(&shares).take(last) {
                acc += (q > 0) as u64;
                *end = acc.min(range as u64);
            }
            ends
        };
        Some(Self { ends, last, range })
    }

    /// Per weight, the running sum of `shares` up to it times `per_share` (< 2³⁸; so below
    /// 2⁶⁴ where the sum is at most 2²⁶, as before the last positive weight; the entries
    /// from the last on are not read).
    #[inline(always)]
    fn scaled_running_sums(shares: &[i32; 8], per_share: u64) -> [u64; 8] {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
        {
            // SAFETY: compiled only where AVX2 is enabled (and checked at start-up, `crate::cpu`).
            unsafe { Self::scaled_running_sums_avx2(shares, per_share) }
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        {
            Self::scaled_running_sums_scalar(shares, per_share)
        }
    }

    /// [`scaled_running_sums`](Self::scaled_running_sums) one weight after another (builds
    /// without AVX2, and the test of the AVX2 form).
    #[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
    fn scaled_running_sums_scalar(shares: &[i32; 8], per_share: u64) -> [u64; 8] {
        let mut acc = 0u64;
        shares.map(|q| {
            acc += q as u64;
            acc.wrapping_mul(per_share)
        })
    }

    /// [`scaled_running_sums`](Self::scaled_running_sums) with AVX2: the running sums by two
    /// shifted adds per 128-bit half and the low half's total carried into the high one, and
    /// the products as `sum · low 32 bits + (sum · high bits) << 32` of per_share (each
    /// 32 × 32-bit product exact in 64 bits), instead of a chain of eight adds and multiplies.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[inline(always)]
    unsafe fn scaled_running_sums_avx2(shares: &[i32; 8], per_share: u64) -> [u64; 8] {
        use std::arch::x86_64::*;
        // SAFETY: AVX2 is available (the caller's contract); the load reads the 32 bytes of
        // `shares` and the stores write the 64 bytes of `ends`.
        unsafe {
            let q = _mm256_loadu_si256(shares.as_ptr().cast());
            let q = _mm256_add_epi32(q, _mm256_slli_si256::<4>(q));
            let q = _mm256_add_epi32(q, _mm256_slli_si256::<8>(q));
            let low_total = _mm256_permutevar8x32_epi32(q, _mm256_set1_epi32(3));
            let sums = _mm256_add_epi32(q, _mm256_blend_epi32::<0b1111_0000>(_mm256_setzero_si256(), low_total));
            let (lo, hi) = (_mm256_set1_epi64x(per_share as u32 as i64), _mm256_set1_epi64x((per_share >> 32) as i64));
            let scale = |s: __m256i| {
                _mm256_add_epi64(_mm256_mul_epu32(s, lo), _mm256_slli_epi64::<32>(_mm256_mul_epu32(s, hi)))
            };
            let mut ends = [0u64; 8];
            _mm256_storeu_si256(ends.as_mut_ptr().cast(), scale(_mm256_cvtepu32_epi64(_mm256_castsi256_si128(sums))));
            _mm256_storeu_si256(
                ends.as_mut_ptr().add(4).cast(),
                scale(_mm256_cvtepu32_epi64(_mm256_extracti128_si256::<1>(sums))),
            );
            ends
        }
    }

    /// Fixed-point shares of `weights` (see [`SHARES`]), 0 for those that count as 0, and
    /// the mask of the positive ones (bit i: weight i).
    #[inline(always)]
    fn shares(weights: f32x8) -> ([i32; 8], u32) {
        let zero = f32x8::ZERO;
        let infinite = weights.cmp_eq(f32x8::splat(f32::INFINITY));
        if infinite.any() {
            let mask = infinite.move_mask() as u32;
            let each = f32x8::splat((SHARES / mask.count_ones() as f32).floor());
            return (infinite.blend(each, zero).fast_trunc_int().to_array(), mask);
        }
        let positive = weights.cmp_gt(zero);
        let mut counted = positive.blend(weights, zero);
        let mut per_weight = SHARES / counted.reduce_add();
        if !per_weight.is_normal() {
            // Weights whose sum overflows (an eighth of each cannot) or so small that
            // SHARES / sum does (2⁶⁴ times each cannot): scaled by a power of two, exactly.
            counted = counted * if per_weight == 0.0 { 0.125 } else { 2f32.powi(64) };
            per_weight = SHARES / counted.reduce_add();
        }
        let scaled = (counted * per_weight).min(f32x8::splat(SHARES)).max(f32x8::ONE);
        (positive.blend(scaled, zero).fast_trunc_int().to_array(), positive.move_mask() as u32)
    }

    /// The weight whose interval holds `u` (`u < range`), and its interval as (start, end).
    #[inline(always)]
    pub fn find(&self, u: u128) -> (usize, (u128, u128)) {
        let u = u as u64;
        let k = self.ends[..self.last].iter().map(|&end| (end <= u) as usize).sum();
        (k, self.interval(k))
    }

    /// The interval of weight `k` as (start, end).
    #[inline(always)]
    pub fn interval(&self, k: usize) -> (u128, u128) {
        let end = |i: usize| if i < self.last { self.ends[i] as u128 } else { self.range };
        (if k == 0 { 0 } else { end(k - 1) }, end(k))
    }
}

/// A discrete distribution over `0..len()`, drawn with one `u64`.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    /// `starts[i]`: the first value of interval `i` (intervals are consecutive), up to the last
    /// positive weight's, which ends at 2⁶⁴.
    starts: Vec<u64>,
    /// Entries in all, counting the zero weights after the last positive one (whose empty
    /// intervals start at 2⁶⁴, past what a `u64` holds).
    len: usize,
}

/// One draw from a [`Distribution1D`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscreteSample {
    /// Index drawn.
    pub index: usize,
    /// Its probability: its interval's width / 2⁶⁴.
    pub pmf: f32,
    /// Where in its interval the number fell, in `[0,1)`: uniform given the index, free for a
    /// continuous position within the entry (piecewise-constant densities).
    pub offset: f32,
}

impl Distribution1D {
    /// Builds the distribution; `None` when no weight is positive.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let mut split = Split::new(RANGE, weights.iter().copied())?;
        // The last positive weight's interval ends at 2⁶⁴; the starts up to it fit a u64.
        let last = weights.iter().rposition(|&w| clean(w, split.infinite) > 0.0)?;
        let starts = weights[..=last].iter().map(|&w| split.next(w).0 as u64).collect();
        Some(Self { starts, len: weights.len() })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the distribution has no entries (never true for a built one).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The values that choose `index`, as (start, end).
    #[inline]
    pub fn interval(&self, index: usize) -> (u128, u128) {
        assert!(index < self.len, "index {index} out of {} entries", self.len);
        match self.starts.get(index) {
            Some(&start) => (start as u128, self.starts.get(index + 1).map_or(RANGE, |&s| s as u128)),
            None => (RANGE, RANGE),
        }
    }

    /// Probability of `index`.
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        let (start, end) = self.interval(index);
        probability(end - start)
    }

    /// Draws an index with `u` (all 2⁶⁴ values equally likely). Entries of weight 0 own no
    /// values and are never returned.
    #[inline]
    pub fn sample(&self, u: u64) -> DiscreteSample {
        // The last interval starting at or before u; empty intervals share their start with the
        // next one, so the last of them is the non-empty interval holding u.
        let index = self.starts.partition_point(|&s| s <= u) - 1;
        let (start, end) = self.interval(index);
        let offset = ((u as u128 - start) as f64 / (end - start) as f64).min(1.0 - f64::EPSILON) as f32;
        DiscreteSample { index, pmf: probability(end - start), offset: offset.min(1.0 - f32::EPSILON / 2.0) }
    }

    /// Bytes held by the table.
    pub fn memory_bytes(&self) -> usize {
        self.starts.capacity() * std::mem::size_of::<u64>()
    }
}

/// A discrete distribution over a few positive weights in 2¹⁶ values: a quarter of a
/// [`Distribution1D`]'s bytes, drawn with the top 16 bits of a `u64` by counting the intervals
/// below it with vector compares, whose loads do not wait on one another as the steps of a
/// binary search do: what a table that is mostly cold in the cache wants (`cells`' per-cell
/// tables). Up to [`Table16::FLAT`] stored values (two cache lines) are counted in one pass;
/// a longer table keeps a summary, the last value of each block of [`Table16::LANES`] intervals,
/// and a draw counts the blocks below the value, then the intervals below it in its block: two
/// short runs of the table instead of all of it (on glass.glb, 241 lights, the draw's share of
/// the render's time fell from 3.2 % to 1.6 %). Its intervals are [`Split`]'s over 2¹⁶ values, scaled to the
/// 2⁶⁴ of a selection number, so `interval width / 2⁶⁴` is still the probability it realises.
#[derive(Clone, Debug)]
pub struct Table16 {
    /// The summary (none up to [`Table16::FLAT`] interval values), then the intervals. The summary is
    /// the last value of each block of intervals, padded with `u16::MAX` to a multiple of
    /// [`Table16::LANES`]: the blocks wholly below a value `v` are those whose last value is
    /// `< v`. The intervals are the last value of every
    /// interval but the last (consecutive, none empty), then at least one `u16::MAX` up to a
    /// multiple of [`Table16::LANES`]: the intervals wholly below `v` are those whose last value
    /// is `< v`, and the padding never is, so the block holding `v` is never past the end.
    values: Box<[u16]>,
    /// Entries.
    len: u16,
    /// Length of the summary.
    summary: u16,
}

impl Table16 {
    /// Most entries: each must own at least one of the 2¹⁶ values, and the weights of
    /// more than this many would be shared out too coarsely for a table of this kind.
    pub const MAX: usize = 4096;
    /// The values it shares among its entries.
    pub const VALUES: u32 = 1 << 16;
    /// Intervals in a block, and what the summary is padded to (one 256-bit compare).
    const LANES: usize = 16;
    /// Most stored interval values counted in one pass, with no summary.
    const FLAT: usize = 64;
    /// Bits a selection number is shifted by: its top 16 choose.
    const SHIFT: u32 = 48;
    /// Most bytes of a table prefetched whole when it is sampled.
    const PREFETCHED: usize = 2048;

    /// The table of `weights`; `None` unless there are 1 to [`Table16::MAX`] of them, all
    /// positive and finite.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let fine = (1..=Self::MAX).contains(&weights.len()) && weights.iter().all(|w| w.is_finite() && *w > 0.0);
        if !fine {
            return None;
        }
        let mut split = Split::new(Self::VALUES as u128, weights.iter().copied())?;
        let mut lasts: Vec<u16> = weights.iter().map(|&w| (split.next(w).1 - 1) as u16).collect();
        lasts.pop();
        lasts.resize(Self::intervals_padded(weights.len()), u16::MAX);
        let summary = Self::summary_padded(weights.len());
        let mut values: Vec<u16> =
            lasts.chunks_exact(Self::LANES).map(|block| block[Self::LANES - 1]).take(summary).collect();
        values.resize(summary, u16::MAX);
        values.extend_from_slice(&lasts);
        Some(Self { values: values.into_boxed_slice(), len: weights.len() as u16, summary: summary as u16 })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True when the table has no entries (never true for a built one).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The last value of every interval but the last, then the padding.
    #[inline]
    fn lasts(&self) -> &[u16] {
        &self.values[self.summary as usize..]
    }

    /// The selection numbers that choose `index`, as (start, end) out of [`RANGE`].
    #[inline]
    pub fn interval(&self, index: usize) -> (u128, u128) {
        let (start, end) = self.interval16(index);
        ((start as u128) << Self::SHIFT, (end as u128) << Self::SHIFT)
    }

    /// The interval of `index` among the 2¹⁶ values. The first padding value is the last
    /// interval's last value, so every interval ends one past its entry's stored value.
    #[inline]
    fn interval16(&self, index: usize) -> (u32, u32) {
        assert!(index < self.len(), "index {index} out of {} entries", self.len);
        let lasts = self.lasts();
        let start = if index == 0 { 0 } else { lasts[index - 1] as u32 + 1 };
        (start, lasts[index] as u32 + 1)
    }

    /// Draws an index with `u` (all 2⁶⁴ values equally likely) and its probability.
    #[inline]
    pub fn sample(&self, u: u64) -> (usize, f32) {
        let v = (u >> Self::SHIFT) as u16;
        // Which block is read after the summary is known only from the summary: a table
        // with one, of up to `PREFETCHED` bytes, is asked for whole first, so that reading
        // its block does not wait on memory a second time (`cells`' tables over clusters;
        // docs/performance.md).
        if self.summary > 0 && self.values.len() * size_of::<u16>() <= Self::PREFETCHED {
            crate::cpu::prefetch(&*self.values, usize::MAX);
        }
        let (summary, lasts) = self.values.split_at(self.summary as usize);
        let index = if summary.is_empty() {
            Self::below(lasts, v)
        } else {
            let first = Self::below(summary, v) * Self::LANES;
            first + Self::below(&lasts[first..first + Self::LANES], v)
        };
        let (start, end) = self.interval16(index);
        // Exact: at most 2¹⁶ over 2¹⁶, the same f32 as `probability` of the 2⁶⁴-scaled interval.
        (index, (end - start) as f32 / Self::VALUES as f32)
    }

    /// How many of `values` (ascending, a whole number of blocks) are below `v`: one
    /// 16-lane compare a block, up to the first block not wholly below.
    #[inline(always)]
    fn below(values: &[u16], v: u16) -> usize {
        let mut count = 0;
        for block in values.chunks_exact(Self::LANES) {
            let block: &[u16; Self::LANES] = block.try_into().expect("chunks are whole blocks");
            let n = block.iter().fold(0u16, |n, &last| n + (last < v) as u16) as usize;
            count += n;
            if n < Self::LANES {
                break;
            }
        }
        count
    }

    /// Bytes held by the table.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&*self.values)
    }

    /// Bytes a table of `len` entries holds.
    pub fn bytes_for(len: usize) -> usize {
        (Self::summary_padded(len) + Self::intervals_padded(len)) * std::mem::size_of::<u16>()
    }

    /// Stored interval values for `len` entries: the last values of all but the last, and at
    /// least one of padding.
    fn intervals_padded(len: usize) -> usize {
        len.max(1).next_multiple_of(Self::LANES)
    }

    /// Stored summary values for `len` entries.
    fn summary_padded(len: usize) -> usize {
        match Self::intervals_padded(len) {
            intervals if intervals <= Self::FLAT => 0,
            intervals => (intervals / Self::LANES).next_multiple_of(Self::LANES),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The intervals of `weights` over `range`, in order.
    fn intervals(range: u128, weights: &[f32]) -> Vec<(u128, u128)> {
        let mut s = Split::new(range, weights.iter().copied()).unwrap();
        weights.iter().map(|&w| s.next(w)).collect()
    }

    /// The intervals of a node's `weights` over `range`, in order, each also found by
    /// [`NodeSplit::find`] from its first and last value.
    fn node_intervals(range: u128, weights: &[f32; 8]) -> Option<Vec<(u128, u128)>> {
        let split = NodeSplit::over(range, weights)?;
        let c: Vec<_> = (0..8).map(|k| split.interval(k)).collect();
        for (k, &(a, b)) in c.iter().enumerate().filter(|(_, (a, b))| b > a) {
            assert_eq!(split.find(a), (k, (a, b)), "{weights:?} over {range}");
            assert_eq!(split.find(b - 1), (k, (a, b)), "{weights:?} over {range}");
        }
        Some(c)
    }

    #[test]
    fn a_node_split_tiles_the_range_and_follows_the_weights() {
        let cases: [[f32; 8]; 7] = [
            [1.0, 0.0, 3.5, 2.0, 0.0, 1e-30, 7.0, 0.25],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0],
            [f32::NAN, -1.0, 2.0, f32::INFINITY, 0.0, 5.0, f32::INFINITY, 1.0],
            [3e38, 3e38, 3e38, 1e-38, 0.0, 1.0, 2.0, 3.0],
            [1.0; 8],
            [1e-45, 0.0, 1e-45, 0.0, 0.0, 0.0, 0.0, 0.0],
            [5.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ];
        for w in cases {
            let infinite = w.contains(&f32::INFINITY);
            let counted = w.map(|x| if infinite { (x == f32::INFINITY) as u32 as f64 } else { x.max(0.0) as f64 });
            let total: f64 = counted.iter().sum();
            for range in [RANGE, RANGE - 1, 1 << 40, 12345, 8, 3, 1] {
                let c = node_intervals(range, &w).unwrap();
                assert_eq!((c[0].0, c[7].1), (0, range), "{w:?} over {range}");
                assert!(c.windows(2).all(|p| p[0].1 == p[1].0), "{w:?} over {range}: {c:?}");
                let positive = counted.iter().filter(|&&x| x > 0.0).count() as u128;
                for (i, &(a, b)) in c.iter().enumerate() {
                    if counted[i] == 0.0 || range >= positive {
                        assert_eq!(b > a, counted[i] > 0.0, "{w:?} over {range}: {i}");
                    }
                    if range == RANGE {
                        let p = (b - a) as f64 / RANGE as f64;
                        assert!((p - counted[i] / total).abs() < 2e-6, "{w:?}: {i}: {p}");
                    }
                }
            }
        }
        assert!(NodeSplit::over(RANGE, &[0.0, -2.0, f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]).is_none());
        // Three values among four positive weights: the first three get one each.
        let c = node_intervals(3, &[1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
        assert_eq!(c[..4], [(0, 1), (1, 2), (2, 3), (3, 3)]);
    }

    #[test]
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    fn running_sums_with_avx2_are_the_scalar_ones() {
        let mut next = crate::sampling::test_numbers(11);
        for _ in 0..10_000 {
            let shares: [i32; 8] = std::array::from_fn(|_| (next() * (1 << 23) as f32) as i32);
            let bits = |n: u32, x: f32| (x * (1u32 << n) as f32) as u64;
            let per_share = bits(24, next()) << 14 | bits(14, next());
            // SAFETY: this test is compiled only where AVX2 is enabled.
            let avx2 = unsafe { NodeSplit::scaled_running_sums_avx2(&shares, per_share) };
            assert_eq!(avx2, NodeSplit::scaled_running_sums_scalar(&shares, per_share), "{shares:?} × {per_share}");
        }
    }

    #[test]
    fn probability_is_the_share_of_the_range_as_the_u128_conversion_gives_it() {
        assert_eq!(probability(RANGE), 1.0);
        assert_eq!(probability(RANGE / 2), 0.5);
        let mut w = 0x9e37_79b9_7f4a_7c15u128;
        for _ in 0..1000 {
            w = (w * 6364136223846793005 + 1442695040888963407) % RANGE;
            assert_eq!(probability(w), (w as f64 / RANGE as f64) as f32, "{w}");
        }
    }

    #[test]
    fn cells_tile_the_range_and_follow_the_weights() {
        let w = [0.0, 1.0, 3.0, 0.0, 4.0, 0.5, 0.0];
        for range in [RANGE, 1000, 7, 4] {
            let c = intervals(range, &w);
            assert_eq!(c[0].0, 0);
            assert_eq!(c.last().unwrap().1, range);
            for k in 1..c.len() {
                assert_eq!(c[k].0, c[k - 1].1, "contiguous");
            }
            for (i, &(a, b)) in c.iter().enumerate() {
                assert_eq!(b == a, w[i] == 0.0, "range {range}, interval {i}");
                if range == RANGE {
                    let p = (b - a) as f64 / RANGE as f64;
                    assert!((p - w[i] as f64 / 8.5).abs() < 1e-15, "{i}: {p}");
                }
            }
        }
        // Three values among four positive weights: the first three get one each.
        assert_eq!(intervals(3, &[1.0, 1.0, 1.0, 1.0]), [(0, 1), (1, 2), (2, 3), (3, 3)]);
    }

    #[test]
    fn a_tiny_weight_still_owns_a_value() {
        let mut w = vec![1.0f32; 1000];
        w[500] = 1e-30;
        let c = intervals(RANGE, &w);
        assert!(c[500].1 > c[500].0);
    }

    #[test]
    fn odd_weights_are_defined() {
        assert!(Split::new(RANGE, [0.0f32, -1.0, f32::NAN]).is_none());
        assert!(Distribution1D::new(&[]).is_none());
        // Infinite weights share everything; finite ones get nothing.
        let c = intervals(RANGE, &[1.0, f32::INFINITY, 5.0, f32::INFINITY]);
        let half = c[1].1;
        assert!(half.abs_diff(RANGE / 2) <= 1, "{half}");
        assert_eq!(c, [(0, 0), (0, half), (half, half), (half, RANGE)]);
        let c = intervals(RANGE, &[f32::NAN, 2.0, -3.0]);
        assert_eq!(c, [(0, 0), (0, RANGE), (RANGE, RANGE)]);
    }

    #[test]
    fn every_cell_draws_its_own_index_and_reports_its_width() {
        let mut w: Vec<f32> = (0..5000).map(|i| if i % 7 == 3 { 0.0 } else { 10f32.powi(i % 13 - 6) }).collect();
        w.extend([0.0, 0.0]);
        let d = Distribution1D::new(&w).unwrap();
        let mut end = 0u128;
        for (i, &weight) in w.iter().enumerate() {
            let (a, b) = d.interval(i);
            assert_eq!(a, end);
            end = b;
            assert_eq!(d.pmf(i), probability(b - a));
            if b > a {
                for u in [a, b - 1, (a + b) / 2] {
                    let s = d.sample(u as u64);
                    assert_eq!((s.index, s.pmf), (i, d.pmf(i)));
                    assert!((0.0..1.0).contains(&s.offset));
                }
                assert_eq!(d.sample(a as u64).offset, 0.0);
            } else {
                assert_eq!(weight, 0.0);
            }
        }
        assert_eq!(end, RANGE);
        assert_eq!(d.sample(0).index, 0);
        assert_eq!(d.sample(u64::MAX).index, 4999);
        assert_eq!(d.len(), 5002);
    }

    #[test]
    fn a_table16_draws_each_entry_in_its_cell_and_tiles_the_range() {
        for n in [1usize, 2, 15, 16, 17, 63, 64, 65, 241, 256, 257, Table16::MAX] {
            let w: Vec<f32> =
                (0..n).map(|i| 1.0 + (i % 11) as f32 * 0.37 + if i % 97 == 5 { 1e-20 } else { 0.0 }).collect();
            let t = Table16::new(&w).unwrap();
            assert_eq!(t.len(), n);
            assert_eq!(t.memory_bytes(), Table16::bytes_for(n));
            // The same intervals as the rule over 2¹⁶ values, scaled to 2⁶⁴.
            let rule = intervals(Table16::VALUES as u128, &w);
            let mut end = 0u128;
            for (i, &(a, b)) in rule.iter().enumerate() {
                let (start, stop) = t.interval(i);
                assert_eq!((start, stop), (a << 48, b << 48), "{n} entries, interval {i}");
                assert!(stop > start && start == end);
                end = stop;
                for u in [start, stop - 1, (start + stop) / 2] {
                    assert_eq!(t.sample(u as u64), (i, probability(stop - start)), "{n} entries, value {u}");
                }
            }
            assert_eq!(end, RANGE);
        }
    }

    #[test]
    fn a_table16_refuses_what_it_cannot_share() {
        assert!(Table16::new(&[]).is_none());
        assert!(Table16::new(&[1.0, 0.0]).is_none());
        assert!(Table16::new(&[1.0, f32::NAN]).is_none());
        assert!(Table16::new(&[1.0, f32::INFINITY]).is_none());
        assert!(Table16::new(&vec![1.0; Table16::MAX + 1]).is_none());
        // A weight 10⁶ times below the rest still owns a value.
        let mut w = vec![1.0f32; 300];
        w[7] = 1e-6;
        let t = Table16::new(&w).unwrap();
        assert_eq!(t.interval(7).1 - t.interval(7).0, 1 << 48);
    }
}
