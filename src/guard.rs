//! The last line of defence: a dependency that panics on input myriad's checks let through
//! becomes an [`Error`] naming the file, not a crash.
//!
//! Owns: [`contain`]. Loaders check what they read before walking it (every index, count
//! and size), so a panic caught here is a bug in those checks; the error says so and names
//! the file and the place that panicked, so it can be reported and the check added. While a
//! section is contained, the panic message is captured rather than printed (on the thread that
//! runs the section, and on rayon's workers, whose panics rayon hands back to it).

use std::any::Any;
use std::cell::Cell;
use std::panic::{AssertUnwindSafe, PanicHookInfo};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, Once};

use crate::error::{Error, Result};

thread_local! {
    /// Contained sections running on this thread.
    static DEPTH: Cell<usize> = const { Cell::new(0) };
}
/// Contained sections running on any thread.
static ACTIVE: AtomicUsize = AtomicUsize::new(0);
/// The first captured panic's location and message.
static CAUGHT: Mutex<Option<String>> = Mutex::new(None);
static HOOK: Once = Once::new();

/// The words every contained panic's error carries (tests look for them).
pub const BUG_REPORT: &str = "this is a bug in myriad's input checks; please report it with the file";

fn install_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info: &PanicHookInfo| {
            let here = DEPTH.with(Cell::get) > 0;
            let worker = ACTIVE.load(Ordering::SeqCst) > 0 && rayon::current_thread_index().is_some();
            if here || worker {
                let location = info.location().map_or(String::new(), |l| format!(" at {}:{}", l.file(), l.line()));
                let mut caught = CAUGHT.lock().unwrap_or_else(|e| e.into_inner());
                caught.get_or_insert_with(|| format!("{}{location}", payload_text(info.payload())));
            } else {
                previous(info);
            }
        }));
    });
}

fn payload_text(payload: &(dyn Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into())
}

/// Runs `f`; a panic inside it (or inside the rayon work it starts) becomes an error about
/// `file`.
pub fn contain<T>(file: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    install_hook();
    DEPTH.with(|d| d.set(d.get() + 1));
    ACTIVE.fetch_add(1, Ordering::SeqCst);
    let result = std::panic::catch_unwind(AssertUnwindSafe(f));
    ACTIVE.fetch_sub(1, Ordering::SeqCst);
    DEPTH.with(|d| d.set(d.get() - 1));
    result.unwrap_or_else(|payload| {
        let caught = CAUGHT.lock().unwrap_or_else(|e| e.into_inner()).take();
        let what = caught.unwrap_or_else(|| payload_text(payload.as_ref()));
        Err(Error::scene(
            file,
            "file",
            format!("could not be read: a library myriad uses failed on it ({what}); {BUG_REPORT}"),
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_an_error_naming_the_file_and_the_place() {
        let e = contain::<()>("broken.glb", || panic!("index out of bounds")).unwrap_err().to_string();
        assert!(e.contains("broken.glb") && e.contains("index out of bounds") && e.contains("guard.rs"), "{e}");
        assert!(e.contains(BUG_REPORT));
        // In rayon's workers too.
        let e = contain::<()>("par.gltf", || {
            use rayon::prelude::*;
            (0..64).into_par_iter().for_each(|i| assert!(i != 37, "light {i}"));
            Ok(())
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("par.gltf") && e.contains("light 37"), "{e}");
        assert_eq!(contain("fine.ron", || Ok(5)).unwrap(), 5);
    }
}
