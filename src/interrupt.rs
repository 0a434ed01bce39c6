//! Ctrl-C and termination: a render stops cleanly, and no output is ever left half-written.
//!
//! Owns: the signal handlers (installed by the binary with [`install`]) and what the rest of
//! the library asks of them. What a signal does depends on the phase:
//! - while a scene loads, nothing has been written: the process exits at once (status 130);
//! - while a render runs, a first Ctrl-C (SIGINT) asks it to finish the pass under way and
//!   write what was rendered ([`Stop::AfterPass`]); a second one, or SIGTERM or SIGHUP, asks
//!   it to stop at once and write nothing ([`Stop::Now`]);
//! - while outputs are written, any signal makes the writer discard its temporary file and
//!   leave the previous output as it was ([`crate::io::write_atomically`] checks).
//!
//! Without [`install`] (the library in a test, say) nothing ever asks to stop.

use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering};

/// What the user has asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stop {
    /// Nothing: go on.
    No = 0,
    /// Finish the pass under way, write what was rendered, stop.
    AfterPass = 1,
    /// Stop now and write nothing.
    Now = 2,
}

/// The exit status of a process stopped by a signal (128 + SIGINT, as shells report it).
pub const EXIT_STATUS: u8 = 130;

static STOP: AtomicU8 = AtomicU8::new(0);
/// How many renders or writes run (while any does, signals are requests, not exits).
static BUSY: AtomicUsize = AtomicUsize::new(0);

/// What has been asked so far.
pub fn requested() -> Stop {
    match STOP.load(Ordering::SeqCst) {
        0 => Stop::No,
        1 => Stop::AfterPass,
        _ => Stop::Now,
    }
}

/// Asks to stop (what the handlers do; also for tests of the library).
pub fn request(stop: Stop) {
    STOP.fetch_max(stop as u8, Ordering::SeqCst);
}

/// While the value lives, signals are requests to the work under way instead of exits.
pub struct Busy(());

/// Marks the start of work that handles interruptions itself (rendering, writing).
pub fn busy() -> Busy {
    BUSY.fetch_add(1, Ordering::SeqCst);
    Busy(())
}

impl Drop for Busy {
    fn drop(&mut self) {
        BUSY.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Installs the handlers for SIGINT, SIGTERM and SIGHUP (Unix; elsewhere, a no-op).
pub fn install() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        for signal in [SIGINT, SIGTERM, SIGHUP] {
            // SAFETY: the handler only touches atomics and calls _exit, both async-signal-safe.
            unsafe {
                signal_hook::low_level::register(signal, move || {
                    if BUSY.load(Ordering::SeqCst) == 0 {
                        signal_hook::low_level::exit(EXIT_STATUS as i32);
                    }
                    let first_ctrl_c = signal == SIGINT && STOP.load(Ordering::SeqCst) == 0;
                    STOP.fetch_max(if first_ctrl_c { Stop::AfterPass } else { Stop::Now } as u8, Ordering::SeqCst);
                })?;
            }
        }
    }
    Ok(())
}
