//! A last word when the process dies by a fatal signal. A crash inside the Vulkan driver or a layer (C and C++
//! code, in this process) would otherwise end `strata` with no message at all: a non-zero exit and an empty
//! stderr, which tells a user, or a CI log, nothing.

/// The signals that end the process from inside native code, with their names.
const FATAL: [(libc::c_int, &str); 4] =
    [(libc::SIGSEGV, "SIGSEGV"), (libc::SIGBUS, "SIGBUS"), (libc::SIGILL, "SIGILL"), (libc::SIGFPE, "SIGFPE")];

/// Installs, for each fatal signal, a handler that names the signal on stderr and then lets it take the
/// process down as it would have (the handler resets itself, so the re-raised signal still sets the exit status
/// a parent sees, and a core dump where those are on). It replaces the Rust runtime's SIGSEGV handler, which
/// tells a stack overflow apart; the message below names that case too.
pub fn report_fatal_signals() {
    for (signal, _) in FATAL {
        // SAFETY: a zeroed sigaction is valid (empty mask, no flags) before the fields below are set, and the
        // handler only calls async-signal-safe functions (write, raise).
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

extern "C" fn on_fatal_signal(signal: libc::c_int) {
    let name = FATAL.iter().find(|(s, _)| *s == signal).map(|(_, n)| *n).unwrap_or("a fatal signal");
    // No allocation or formatting here: only write(2) of fixed pieces is safe inside a signal handler.
    let pieces: [&[u8]; 3] = [
        b"\nstrata: crashed with ",
        name.as_bytes(),
        b" (inside the Vulkan driver or a layer, most likely, or a stack overflow). Files are written only once a frame is finished, \
          each whole or not at all, so none is left half-written. `strata info` checks the setup; please report \
          the command that crashed.\n",
    ];
    for piece in pieces {
        // SAFETY: write(2) on stderr with a valid buffer and length.
        unsafe { libc::write(libc::STDERR_FILENO, piece.as_ptr().cast(), piece.len()) };
    }
    // SAFETY: raise(3) is async-signal-safe; SA_RESETHAND restored the default action, which now ends the process.
    unsafe { libc::raise(signal) };
}
