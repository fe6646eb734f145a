//! Ctrl-C during a long command: a line saying what state the outputs are in, then exit 130; while outputs are
//! being moved into place, the interruption waits until they are.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

/// The line printed on Ctrl-C, set once before the handler is installed.
static MESSAGE: OnceLock<Vec<u8>> = OnceLock::new();
/// Set while outputs are moved into place: Ctrl-C then only records that it came.
static MOVING: AtomicBool = AtomicBool::new(false);
/// Set when Ctrl-C came while outputs were moved.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_sigint(_: libc::c_int) {
    if MOVING.load(Ordering::SeqCst) {
        INTERRUPTED.store(true, Ordering::SeqCst);
        return;
    }
    if let Some(m) = MESSAGE.get() {
        // SAFETY: write(2) is async-signal-safe; the buffer is initialised and lives as long as the program.
        unsafe {
            libc::write(2, m.as_ptr().cast(), m.len());
        }
    }
    // SAFETY: _exit(2) is async-signal-safe and ends the process at once, as the default SIGINT action would.
    unsafe { libc::_exit(130) }
}

/// On Ctrl-C: prints `message` (a line) to stderr and exits 130, unless [`moving`] is on.
pub fn on_ctrl_c(message: String) {
    let _ = MESSAGE.set(format!("\n{message}\n").into_bytes());
    #[cfg(unix)]
    // SAFETY: the handler touches only atomics and the message set above, and calls only async-signal-safe
    // functions (write, _exit).
    unsafe {
        libc::signal(libc::SIGINT, on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t);
    }
}

/// Runs `f` with Ctrl-C held back (moving outputs into place); returns its result and whether Ctrl-C came.
pub fn moving<T>(f: impl FnOnce() -> T) -> (T, bool) {
    MOVING.store(true, Ordering::SeqCst);
    let out = f();
    MOVING.store(false, Ordering::SeqCst);
    (out, INTERRUPTED.load(Ordering::SeqCst))
}
