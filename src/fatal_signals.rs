//! A last word when the process dies by a fatal signal. A crash inside the Vulkan driver or a layer (C and C++
//! code, in this process) would otherwise end `strata` with no message at all: a non-zero exit and an empty
//! stderr, which tells a user, or a CI log, nothing.

use std::sync::atomic::{AtomicPtr, Ordering};

/// The signals that end the process from inside native code, with their names.
const FATAL: [(libc::c_int, &str); 4] =
    [(libc::SIGSEGV, "SIGSEGV"), (libc::SIGBUS, "SIGBUS"), (libc::SIGILL, "SIGILL"), (libc::SIGFPE, "SIGFPE")];

/// What `strata` tells a user after a crash.
const RENDER_ADVICE: &str = "Files are written only once a frame is finished, each whole or not at all, so none is \
     left half-written. `strata info` checks the setup; please report the command that crashed.";

/// The message's last sentence, and what was running (`set_running`). Each points at a leaked `&'static str`,
/// so the handler reads a whole string with one atomic load and no lock.
static ADVICE: AtomicPtr<&'static str> = AtomicPtr::new(std::ptr::null_mut());
static RUNNING: AtomicPtr<&'static str> = AtomicPtr::new(std::ptr::null_mut());

/// Installs, for each fatal signal, a handler that names the signal on stderr and then lets it take the
/// process down as it would have (the handler resets itself, so the re-raised signal still sets the exit status
/// a parent sees, and a core dump where those are on). It replaces the Rust runtime's SIGSEGV handler, which
/// tells a stack overflow apart; the message below names that case too.
pub fn report_fatal_signals() {
    report_fatal_signals_with(RENDER_ADVICE);
}

/// The same, ending the message with `advice` instead of what `strata render` tells a user (test harnesses).
pub fn report_fatal_signals_with(advice: &'static str) {
    ADVICE.store(Box::leak(Box::new(advice)), Ordering::Release);
    for (signal, _) in FATAL {
        // SAFETY: a zeroed sigaction is valid (empty mask, no flags) before the fields below are set, and the
        // handler only calls async-signal-safe functions (write, raise) and reads atomics.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_fatal_signal as *const () as libc::sighandler_t;
            // On the alternate stack where the thread has one (Rust's threads do), so that a stack overflow
            // can still be reported.
            action.sa_flags = libc::SA_RESETHAND | libc::SA_ONSTACK;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
    }
}

/// Names what the process is doing now, for the crash message ("… while running `what`"); `None` clears it.
/// A test harness names the test that holds the GPU, so that a crash in the driver says which test caused it.
pub fn set_running(what: Option<&str>) {
    let named: *mut &'static str = match what {
        Some(what) => {
            let text: &'static str = Box::leak(what.to_owned().into_boxed_str());
            Box::leak(Box::new(text))
        }
        None => std::ptr::null_mut(),
    };
    // The previous name is leaked, not freed: the handler may be reading it on another thread.
    RUNNING.store(named, Ordering::Release);
}

fn loaded(slot: &AtomicPtr<&'static str>) -> Option<&'static str> {
    let pointer = slot.load(Ordering::Acquire);
    // SAFETY: every non-null pointer stored in a slot comes from `Box::leak` and is never freed.
    (!pointer.is_null()).then(|| unsafe { *pointer })
}

extern "C" fn on_fatal_signal(signal: libc::c_int) {
    let name = FATAL.iter().find(|(s, _)| *s == signal).map(|(_, n)| *n).unwrap_or("a fatal signal");
    let (while_running, running) = match loaded(&RUNNING) {
        Some(what) => (" while running ".as_bytes(), what.as_bytes()),
        None => (&b""[..], &b""[..]),
    };
    // No allocation or formatting here: only write(2) of fixed pieces is safe inside a signal handler.
    let pieces: [&[u8]; 7] = [
        b"\nstrata: crashed with ",
        name.as_bytes(),
        while_running,
        running,
        b" (inside the Vulkan driver or a layer, most likely, or a stack overflow). ",
        loaded(&ADVICE).unwrap_or(RENDER_ADVICE).as_bytes(),
        b"\n",
    ];
    for piece in pieces {
        // SAFETY: write(2) on stderr with a valid buffer and length.
        unsafe { libc::write(libc::STDERR_FILENO, piece.as_ptr().cast(), piece.len()) };
    }
    // SAFETY: raise(3) is async-signal-safe; SA_RESETHAND restored the default action, which now ends the process.
    unsafe { libc::raise(signal) };
}
