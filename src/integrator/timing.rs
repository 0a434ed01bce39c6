//! Where a render's time goes: tracing, choosing lights, connecting through glass, and
//! shading with the rest, measured
//! on one path in [`TIMED_ONE_IN`] so that the others pay one untaken branch per phase.
//!
//! Owns: [`PhaseTimes`] (CPU ticks per phase and the rays traced inside the timed paths) and
//! the clock it reads ([`ticks`]: the time-stamp counter on x86-64, a monotonic nanosecond
//! count elsewhere). Shares need no unit; rates convert ticks to seconds with the render's own
//! ticks per wall-clock second ([`ticks_per_second`]). Timing changes no random number and
//! no result: which paths are timed depends on their pixel and sample only.

use std::sync::OnceLock;
use std::time::Instant;

/// One path in this many is timed.
pub const TIMED_ONE_IN: u64 = 64;

/// Whether the path of sample `sample` of pixel `pixel` (a linear index) is timed: one in
/// [`TIMED_ONE_IN`], spread over the image and the samples.
#[inline]
pub fn is_timed(pixel: u64, sample: u64) -> bool {
    (pixel + sample).is_multiple_of(TIMED_ONE_IN)
}

/// A tick count: the time-stamp counter (constant-rate on every x86-64 CPU that runs
/// AVX2 code), else nanoseconds since the first call.
#[inline(always)]
pub fn ticks() -> u64 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: RDTSC exists on every x86-64 CPU and reads a counter only.
    unsafe {
        std::arch::x86_64::_rdtsc()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        static START: OnceLock<Instant> = OnceLock::new();
        START.get_or_init(Instant::now).elapsed().as_nanos() as u64
    }
}

/// Ticks per second of wall-clock time, measured once over 20 ms.
pub fn ticks_per_second() -> f64 {
    static RATE: OnceLock<f64> = OnceLock::new();
    *RATE.get_or_init(|| {
        let (t0, c0) = (Instant::now(), ticks());
        std::thread::sleep(std::time::Duration::from_millis(20));
        (ticks() - c0) as f64 / t0.elapsed().as_secs_f64()
    })
}

/// Ticks spent in each phase of the timed paths, and the rays those paths traced.
#[derive(Clone, Copy, Debug, Default)]
pub struct PhaseTimes {
    /// Whole timed paths.
    pub total: u64,
    /// Closest-hit queries (camera and bounce rays).
    pub closest: u64,
    /// Occlusion queries (shadow rays).
    pub shadow: u64,
    /// Choosing a light and evaluating the probability of one chosen (for MIS).
    pub choice: u64,
    /// Connections through smooth glass: the walks along light samples' straight ways, the
    /// solves, and the re-solves that weigh light BSDF sampling brought through glass.
    pub glass: u64,
    /// Closest-hit rays of the timed paths.
    pub closest_rays: u64,
    /// Shadow rays of the timed paths.
    pub shadow_rays: u64,
}

impl PhaseTimes {
    /// Adds another worker's times.
    pub fn add(&mut self, other: &PhaseTimes) {
        self.total += other.total;
        self.closest += other.closest;
        self.shadow += other.shadow;
        self.choice += other.choice;
        self.glass += other.glass;
        self.closest_rays += other.closest_rays;
        self.shadow_rays += other.shadow_rays;
    }

    /// Shares of the timed paths' time (tracing, light choice, connections through glass,
    /// shading and the rest), or `None` when no path was timed.
    pub fn shares(&self) -> Option<[f64; 4]> {
        (self.total > 0).then(|| {
            let total = self.total as f64;
            let trace = (self.closest + self.shadow) as f64 / total;
            let choice = self.choice as f64 / total;
            let glass = self.glass as f64 / total;
            [trace, choice, glass, (1.0 - trace - choice - glass).max(0.0)]
        })
    }

    /// Closest-hit and shadow rays per second of one thread's tracing time.
    pub fn rays_per_second(&self) -> (Option<f64>, Option<f64>) {
        let rate = |rays: u64, t: u64| (t > 0).then(|| rays as f64 * ticks_per_second() / t as f64);
        (rate(self.closest_rays, self.closest), rate(self.shadow_rays, self.shadow))
    }
}

/// When a phase began, on a timed path: for phases whose work needs what [`timed`]'s slot
/// borrows.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch(Option<u64>);

impl Stopwatch {
    /// Starts when `on`.
    #[inline(always)]
    pub fn start(on: bool) -> Self {
        Self(on.then(ticks))
    }

    /// Adds the ticks since the start to `slot`.
    #[inline(always)]
    pub fn stop(self, slot: &mut u64) {
        if let Some(start) = self.0 {
            *slot += ticks().wrapping_sub(start);
        }
    }
}

/// Runs `f`, adding its ticks to `slot` when `on`.
#[inline(always)]
pub fn timed<T>(on: bool, slot: &mut u64, f: impl FnOnce() -> T) -> T {
    if !on {
        return f();
    }
    let start = ticks();
    let result = f();
    *slot += ticks().wrapping_sub(start);
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_path_in_64_is_timed_in_every_run_of_64() {
        for start in [0u64, 5, 1000] {
            let n = (start..start + 64).filter(|&p| is_timed(p, 3)).count();
            assert_eq!(n, 1);
        }
        assert!(ticks_per_second() > 1e6);
    }

    #[test]
    fn shares_add_up_to_one() {
        let t =
            PhaseTimes { total: 100, closest: 20, shadow: 10, choice: 30, glass: 15, closest_rays: 4, shadow_rays: 2 };
        let [a, b, g, c] = t.shares().unwrap();
        assert!((a - 0.3).abs() < 1e-12 && (b - 0.3).abs() < 1e-12 && (g - 0.15).abs() < 1e-12);
        assert!((a + b + g + c - 1.0).abs() < 1e-12);
        assert!(PhaseTimes::default().shares().is_none());
    }
}
