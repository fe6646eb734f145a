//! Ctrl-C (SIGINT), SIGTERM or SIGHUP during a long command: the hidden temporary files it was writing are
//! removed, a line says what state the outputs are in, then the process exits 128 + the signal's number (130 for
//! Ctrl-C); while outputs are being moved into place, the interruption waits until they are.

use std::ffi::CString;
use std::path::PathBuf;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

/// The line printed on an interruption, set once before the handler is installed.
static MESSAGE: OnceLock<Vec<u8>> = OnceLock::new();
/// The temporary files removed on an interruption, set once before the handler is installed.
static TEMPORARY: OnceLock<Vec<CString>> = OnceLock::new();
/// Set while outputs are moved into place: an interruption then only records that it came.
static MOVING: AtomicBool = AtomicBool::new(false);
/// The signal that came while outputs were moved (0: none).
static INTERRUPTED: AtomicI32 = AtomicI32::new(0);

/// The signals handled: Ctrl-C, `kill` and a closed terminal.
#[cfg(unix)]
const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

#[cfg(unix)]
extern "C" fn on_signal(signal: libc::c_int) {
    if MOVING.load(Ordering::SeqCst) {
        INTERRUPTED.store(signal, Ordering::SeqCst);
        return;
    }
    for path in TEMPORARY.get().into_iter().flatten() {
        // SAFETY: unlink(2) is async-signal-safe; the string is NUL-terminated and lives as long as the program.
        unsafe {
            libc::unlink(path.as_ptr());
        }
    }
    if let Some(m) = MESSAGE.get() {
        // SAFETY: write(2) is async-signal-safe; the buffer is initialised and lives as long as the program.
        unsafe {
            libc::write(2, m.as_ptr().cast(), m.len());
        }
    }
    // SAFETY: _exit(2) is async-signal-safe and ends the process at once, as the signal's default action would.
    unsafe { libc::_exit(128 + signal) }
}

/// On Ctrl-C, SIGTERM or SIGHUP: removes `temporary` (hidden files being written, that no later run would find),
/// prints `message` (a line) to stderr and exits 128 + the signal's number, unless [`moving`] is on.
pub fn on_interrupt(message: String, temporary: Vec<PathBuf>) {
    let _ = MESSAGE.set(format!("\n{message}\n").into_bytes());
    let _ =
        TEMPORARY.set(temporary.iter().filter_map(|p| CString::new(p.as_os_str().as_encoded_bytes()).ok()).collect());
    #[cfg(unix)]
    for signal in SIGNALS {
        // SAFETY: the handler touches only atomics and the data set above, and calls only async-signal-safe
        // functions (unlink, write, _exit).
        unsafe {
            libc::signal(signal, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
        }
    }
}

/// Runs `f` with interruptions held back (moving outputs into place); returns its result and the exit code of
/// the interruption that came meanwhile, if one did.
pub fn moving<T>(f: impl FnOnce() -> T) -> (T, Option<u8>) {
    MOVING.store(true, Ordering::SeqCst);
    let out = f();
    MOVING.store(false, Ordering::SeqCst);
    let signal = INTERRUPTED.load(Ordering::SeqCst);
    (out, (signal > 0).then(|| u8::try_from(128 + signal).unwrap_or(130)))
}
