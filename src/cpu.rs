//! The CPU this build needs, checked before anything else runs.
//!
//! Owns: the start-up test that the machine has every instruction-set extension the binary
//! was compiled for. On x86-64, `.cargo/config.toml` compiles for `x86-64-v3` (AVX2, FMA,
//! BMI1/2, LZCNT, POPCNT, SSE4.2: Intel since 2013, AMD since 2015), which renders with 3–14 %
//! less CPU than the 2003 baseline (docs/rendering.md, "Building for a CPU"). A binary built so executes
//! illegal instructions on an older CPU, so [`require_build_features`] tells the user which
//! extensions are missing and how to rebuild, instead of letting the process die on SIGILL.
//!
//! Also the one home of the cache-prefetch hint ([`prefetch`]) the samplers give ahead of
//! loads that would otherwise wait on each other.
//!
//! It must run before any code that the compiler may have vectorised with those extensions:
//! it reads CPUID and XCR0 itself, walks a `static` table and writes fixed byte strings, so
//! that it passes through no 16- or 32-byte copies the compiler could encode with AVX.

/// What the OS must save on a context switch for an extension's registers to be usable.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, PartialEq)]
enum State {
    /// Nothing beyond SSE's.
    Sse,
    /// The 256-bit YMM registers (AVX and what builds on it).
    Ymm,
    /// The AVX-512 opmask and 512-bit ZMM registers.
    Zmm,
}

/// The CPUID output register an extension's bit is in.
#[cfg(target_arch = "x86_64")]
enum Register {
    Ebx,
    Ecx,
}

/// One instruction-set extension: its name as rustc spells it (with a leading space, for the
/// message), whether this binary was compiled for it, and where CPUID reports it.
#[cfg(target_arch = "x86_64")]
struct Extension {
    name: &'static [u8],
    built: bool,
    leaf: u32,
    register: Register,
    bit: u32,
    state: State,
}

#[cfg(target_arch = "x86_64")]
macro_rules! extension {
    ($name:tt, $leaf:expr, $register:ident, $bit:expr, $state:ident) => {
        Extension {
            name: concat!(" ", $name).as_bytes(),
            built: cfg!(target_feature = $name),
            leaf: $leaf,
            register: Register::$register,
            bit: $bit,
            state: State::$state,
        }
    };
}

/// The extensions a build may be compiled for: x86-64-v2, v3 and v4's (Intel SDM vol. 2A,
/// CPUID). In a `static`, not built on the stack: building it could use the very vector
/// stores being checked for.
#[cfg(target_arch = "x86_64")]
static EXTENSIONS: [Extension; 17] = [
    extension!("sse3", 1, Ecx, 0, Sse),
    extension!("ssse3", 1, Ecx, 9, Sse),
    extension!("fma", 1, Ecx, 12, Ymm),
    extension!("sse4.1", 1, Ecx, 19, Sse),
    extension!("sse4.2", 1, Ecx, 20, Sse),
    extension!("movbe", 1, Ecx, 22, Sse),
    extension!("popcnt", 1, Ecx, 23, Sse),
    extension!("avx", 1, Ecx, 28, Ymm),
    extension!("f16c", 1, Ecx, 29, Ymm),
    extension!("bmi1", 7, Ebx, 3, Sse),
    extension!("avx2", 7, Ebx, 5, Ymm),
    extension!("bmi2", 7, Ebx, 8, Sse),
    extension!("avx512f", 7, Ebx, 16, Zmm),
    extension!("avx512dq", 7, Ebx, 17, Zmm),
    extension!("avx512bw", 7, Ebx, 30, Zmm),
    extension!("avx512vl", 7, Ebx, 31, Zmm),
    extension!("lzcnt", 0x8000_0001, Ecx, 5, Sse),
];

/// Whether this CPU (and its OS) offers `e`, from CPUID itself: the standard library's
/// `is_x86_feature_detected!` answers "yes" without asking for whatever the binary was
/// compiled for, which is exactly what must be asked here.
#[cfg(target_arch = "x86_64")]
fn offers(e: &Extension) -> bool {
    use std::arch::x86_64::{__cpuid, __cpuid_count};
    let max = __cpuid(e.leaf & 0x8000_0000).eax;
    if max < e.leaf {
        return false;
    }
    let r = __cpuid_count(e.leaf, 0);
    let bits = match e.register {
        Register::Ebx => r.ebx,
        Register::Ecx => r.ecx,
    };
    if bits >> e.bit & 1 == 0 {
        return false;
    }
    if e.state == State::Sse {
        return true;
    }
    // OSXSAVE: the OS manages the extended state, and XCR0 says which parts.
    if __cpuid(1).ecx >> 27 & 1 == 0 {
        return false;
    }
    // SAFETY: XGETBV is present when CPUID reports OSXSAVE (checked just above).
    let xcr0 = unsafe { xgetbv0() };
    let need = if e.state == State::Ymm { 0b110 } else { 0b1110_0110 };
    xcr0 & need == need
}

/// XCR0, read with XGETBV (in assembly: the intrinsic needs the `xsave` feature enabled).
///
/// # Safety
/// The CPU must have XGETBV (CPUID.1:ECX.OSXSAVE).
#[cfg(target_arch = "x86_64")]
unsafe fn xgetbv0() -> u64 {
    let (lo, hi): (u32, u32);
    // SAFETY: the caller guarantees XGETBV exists; it reads a register and touches no memory.
    unsafe { std::arch::asm!("xgetbv", in("ecx") 0u32, out("eax") lo, out("edx") hi, options(nomem, nostack)) };
    u64::from(hi) << 32 | u64::from(lo)
}

/// Ends the process with a message naming what is missing when this CPU lacks an
/// instruction-set extension the binary was compiled for. Does nothing where it has all of
/// them, and on other architectures.
#[inline(never)]
pub fn require_build_features() {
    #[cfg(target_arch = "x86_64")]
    {
        use std::io::Write;
        if EXTENSIONS.iter().all(|e| !e.built || offers(e)) {
            return;
        }
        let mut err = std::io::stderr().lock();
        let _ = err.write_all(b"error: this myriad was compiled for CPUs with extensions this one lacks:");
        for e in EXTENSIONS.iter().filter(|e| e.built && !offers(e)) {
            let _ = err.write_all(e.name);
        }
        let _ = err.write_all(
            b"\nrebuild it for this machine: RUSTFLAGS='-C target-cpu=native' cargo build --release\n\
              (or for any x86-64 CPU with RUSTFLAGS='-C target-cpu=x86-64'; docs/rendering.md)\n",
        );
        std::process::exit(2);
    }
}

/// Asks the CPU to bring the cache lines `data` spans (at most `most` of them, from its start)
/// into its caches ahead of their use: a hint, with no effect on any result, and none at all
/// on targets without the instruction.
#[inline(always)]
pub fn prefetch<T: ?Sized>(data: &T, most: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        let p = (data as *const T).cast::<i8>();
        let lines = (p as usize % 64 + std::mem::size_of_val(data)).div_ceil(64).min(most);
        for line in 0..lines {
            // SAFETY: a prefetch has no architectural effect and never faults; `wrapping_add`
            // stays within the last line `data` touches.
            unsafe {
                use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
                _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64 * line));
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (data, most);
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    #[test]
    fn prefetching_any_span_is_only_a_hint() {
        let data = [7u16; 700];
        for (start, len) in [(0, 0), (1, 1), (3, 32), (0, 700), (33, 600)] {
            prefetch(&data[start..start + len], usize::MAX);
            prefetch(&data[start..start + len], 2);
        }
        prefetch(&0u8, 1);
        assert!(data.iter().all(|&v| v == 7));
    }

    #[test]
    fn this_machine_offers_what_the_tests_were_built_for() {
        for e in EXTENSIONS.iter().filter(|e| e.built) {
            assert!(offers(e), "{}", String::from_utf8_lossy(e.name));
        }
    }

    #[test]
    fn cpuid_agrees_with_the_standard_library() {
        // Where the build does not enable an extension, std asks the CPU too.
        let by_std = [
            ("sse4.2", std::is_x86_feature_detected!("sse4.2")),
            ("popcnt", std::is_x86_feature_detected!("popcnt")),
            ("avx2", std::is_x86_feature_detected!("avx2")),
            ("fma", std::is_x86_feature_detected!("fma")),
            ("bmi2", std::is_x86_feature_detected!("bmi2")),
            ("lzcnt", std::is_x86_feature_detected!("lzcnt")),
            ("avx512f", std::is_x86_feature_detected!("avx512f")),
            ("avx512vl", std::is_x86_feature_detected!("avx512vl")),
        ];
        for (name, has) in by_std {
            let e = EXTENSIONS.iter().find(|e| &e.name[1..] == name.as_bytes()).unwrap();
            assert_eq!(offers(e), has, "{name}");
        }
    }
}
