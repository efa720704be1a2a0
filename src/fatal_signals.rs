//! A last word when the process dies by a fatal signal. A crash inside the Vulkan driver or a layer (C and C++
//! code, in this process) would otherwise end `strata` with no message at all: a non-zero exit and an empty
//! stderr, which tells a user, or a CI log, nothing. The message names the signal, what was running, the thread,
//! the faulting address, and the call stack by library and offset (`addr2line -e LIBRARY OFFSET` names the
//! function where the library has symbols), so that a crash seen once, on a machine nobody can log into (a CI
//! run), says where it happened.

use std::sync::atomic::{AtomicPtr, Ordering};

/// The signals that end the process from inside native code, with their names. SIGABRT too: glibc aborts when it
/// finds its heap corrupted ("malloc(): unaligned fastbin chunk detected", seen once in a test run), as does a
/// failed assertion in a driver or layer.
const FATAL: [(libc::c_int, &str); 5] = [
    (libc::SIGSEGV, "SIGSEGV"),
    (libc::SIGBUS, "SIGBUS"),
    (libc::SIGILL, "SIGILL"),
    (libc::SIGFPE, "SIGFPE"),
    (libc::SIGABRT, "SIGABRT"),
];

/// What `strata` tells a user after a crash.
const RENDER_ADVICE: &str = "Files are written only once a frame is finished, each whole or not at all, so none is \
     left half-written. `strata info` checks the setup; please report the command that crashed.";

/// The variable through which lavapipe (llvmpipe) takes its SIMD width in bits.
const VECTOR_WIDTH_VARIABLE: &str = "LP_NATIVE_VECTOR_WIDTH";

/// What a crash message adds where the user set lavapipe's vector width: Mesa 25.0's shader cache does not tell
/// the widths apart, and lavapipe crashes running code it cached at another width (docs/performance.md,
/// "lavapipe's vector width and Mesa's cache"), a crash nothing else in the message would explain.
fn vector_width_advice(width: &std::ffi::OsStr) -> String {
    format!(
        "{VECTOR_WIDTH_VARIABLE} is set (to {}): Mesa's shader cache does not tell lavapipe's vector widths apart, \
         and lavapipe crashes on code it cached at another width; give each width its own MESA_SHADER_CACHE_DIR.",
        width.to_string_lossy()
    )
}

/// The message's last sentence, and what was running (`set_running`). Each points at a leaked `&'static str`,
/// so the handler reads a whole string with one atomic load and no lock.
static ADVICE: AtomicPtr<&'static str> = AtomicPtr::new(std::ptr::null_mut());
static RUNNING: AtomicPtr<&'static str> = AtomicPtr::new(std::ptr::null_mut());

/// The most frames of the call stack the message lists.
const MOST_FRAMES: usize = 48;

extern "C" {
    // glibc's <execinfo.h>; the libc crate does not bind them.
    fn backtrace(buffer: *mut *mut libc::c_void, size: libc::c_int) -> libc::c_int;
    fn backtrace_symbols_fd(buffer: *const *mut libc::c_void, size: libc::c_int, fd: libc::c_int);
}

/// Installs, for each fatal signal, a handler that names the signal on stderr and then lets it take the
/// process down as it would have (the handler resets itself, so the re-raised signal still sets the exit status
/// a parent sees, and a core dump where those are on). It replaces the Rust runtime's SIGSEGV handler, which
/// tells a stack overflow apart; the message below names that case too.
pub fn report_fatal_signals() {
    report_fatal_signals_with(RENDER_ADVICE);
}

/// The same, ending the message with `advice` instead of what `strata render` tells a user (test harnesses).
pub fn report_fatal_signals_with(advice: &'static str) {
    let advice: &'static str = match std::env::var_os(VECTOR_WIDTH_VARIABLE) {
        Some(width) => Box::leak(format!("{advice} {}", vector_width_advice(&width)).into_boxed_str()),
        None => advice,
    };
    ADVICE.store(Box::leak(Box::new(advice)), Ordering::Release);
    // glibc loads the unwinder (libgcc_s) on the first call, which allocates: done here, so that the handler's
    // call does not.
    let mut frames = [std::ptr::null_mut(); 2];
    // SAFETY: the buffer holds the two frames asked for.
    unsafe { backtrace(frames.as_mut_ptr(), 2) };
    for (signal, _) in FATAL {
        // SAFETY: a zeroed sigaction is valid (empty mask, no flags) before the fields below are set, and the
        // handler only reads atomics and calls async-signal-safe functions (write, prctl, raise) and glibc's
        // backtrace functions, which write straight to the descriptor once the unwinder is loaded (above).
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_fatal_signal as *const () as libc::sighandler_t;
            // On the alternate stack where the thread has one (Rust's threads do), so that a stack overflow
            // can still be reported.
            action.sa_flags = libc::SA_RESETHAND | libc::SA_ONSTACK | libc::SA_SIGINFO;
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

/// Writes `bytes` to stderr with write(2), the one way to print that is safe inside a signal handler.
fn write_stderr(bytes: &[u8]) {
    // SAFETY: write(2) on stderr with a valid buffer and length.
    unsafe { libc::write(libc::STDERR_FILENO, bytes.as_ptr().cast(), bytes.len()) };
}

/// `value` as `0x` and lowercase hexadecimal digits, in `buffer`, with no allocation.
fn hex(value: usize, buffer: &mut [u8; 18]) -> &[u8] {
    let digits = (usize::BITS - value.leading_zeros()).div_ceil(4).max(1) as usize;
    buffer[0] = b'0';
    buffer[1] = b'x';
    for i in 0..digits {
        let nibble = (value >> (4 * (digits - 1 - i))) & 0xf;
        buffer[2 + i] = b"0123456789abcdef"[nibble];
    }
    &buffer[..2 + digits]
}

extern "C" fn on_fatal_signal(signal: libc::c_int, info: *mut libc::siginfo_t, _context: *mut libc::c_void) {
    let name = FATAL.iter().find(|(s, _)| *s == signal).map(|(_, n)| *n).unwrap_or("a fatal signal");
    let (while_running, running) = match loaded(&RUNNING) {
        Some(what) => (" while running ".as_bytes(), what.as_bytes()),
        None => (&b""[..], &b""[..]),
    };
    // No allocation or formatting here: only write(2) of fixed pieces and stack buffers.
    for piece in [
        &b"\nstrata: crashed with "[..],
        name.as_bytes(),
        while_running,
        running,
        b" (inside the Vulkan driver or a layer, most likely, or a stack overflow). ",
        loaded(&ADVICE).unwrap_or(RENDER_ADVICE).as_bytes(),
        b"\n",
    ] {
        write_stderr(piece);
    }
    // The thread: the test's, a driver's worker (lavapipe names its own) or the main one. PR_GET_NAME writes at
    // most 16 bytes, the last a NUL.
    let mut thread = [0u8; 16];
    // SAFETY: prctl(2) is a system call; PR_GET_NAME fills the 16 bytes given.
    unsafe { libc::prctl(libc::PR_GET_NAME, thread.as_mut_ptr()) };
    let thread_name = &thread[..thread.iter().position(|&b| b == 0).unwrap_or(thread.len())];
    write_stderr(b"strata: in the thread \"");
    write_stderr(thread_name);
    write_stderr(b"\"");
    // SAFETY: the kernel passes a valid siginfo_t to an SA_SIGINFO handler.
    let info = unsafe { &*info };
    // A positive code means the kernel raised the signal for a fault at an address; kill(2) and raise(3) do not.
    if info.si_code > 0 {
        let mut buffer = [0u8; 18];
        write_stderr(b", at the address ");
        // SAFETY: si_addr is set for the fault signals this handler is installed for.
        write_stderr(hex(unsafe { info.si_addr() } as usize, &mut buffer));
    } else {
        write_stderr(b", sent by a process (kill or raise), not a fault");
    }
    write_stderr(b"; the call stack, innermost first:\n");
    let mut frames = [std::ptr::null_mut(); MOST_FRAMES];
    // SAFETY: the buffer holds MOST_FRAMES frames; the unwinder was loaded when the handler was installed.
    unsafe {
        let depth = backtrace(frames.as_mut_ptr(), MOST_FRAMES as libc::c_int);
        backtrace_symbols_fd(frames.as_ptr(), depth, libc::STDERR_FILENO);
    }
    // SAFETY: raise(3) is async-signal-safe; SA_RESETHAND restored the default action, which now ends the process.
    unsafe { libc::raise(signal) };
}

#[cfg(test)]
mod tests {
    use super::hex;

    #[test]
    fn hex_writes_every_digit_and_no_leading_zeros() {
        let mut buffer = [0u8; 18];
        assert_eq!(hex(0, &mut buffer), b"0x0");
        assert_eq!(hex(0x10, &mut buffer), b"0x10");
        assert_eq!(hex(0x7f3a_09bc_dd01, &mut buffer), b"0x7f3a09bcdd01");
        assert_eq!(hex(usize::MAX, &mut buffer), b"0xffffffffffffffff");
    }
}
