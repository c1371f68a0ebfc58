//! Stop requests from outside: SIGTERM (what a batch scheduler sends at the wall-time limit)
//! and SIGINT (Ctrl-C) ask a run to finish its step, write a checkpoint and exit with
//! status 128 + the signal's number (143, 130); a second one of either ends the process at
//! once. On N ranks the request of any rank stops all of them at the same step. A reader
//! that quits (`sphdisk bench | head`) ends the other commands quietly, as it ends `cat`
//! ([`end_quietly_when_the_reader_quits`]); a run goes on to its end and writes its files.

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use signal_hook::consts::{SIGINT, SIGTERM};

static REQUESTED: OnceLock<Arc<AtomicUsize>> = OnceLock::new();

fn requested_flag() -> &'static Arc<AtomicUsize> {
    REQUESTED.get_or_init(|| Arc::new(AtomicUsize::new(0)))
}

/// Routes SIGTERM and SIGINT to a stop request (for `sphdisk run`).
pub fn install() -> anyhow::Result<()> {
    let seen = Arc::new(AtomicBool::new(false));
    for sig in [SIGTERM, SIGINT] {
        // The second signal finds `seen` set and ends the process with 128 + sig.
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&seen))?;
        signal_hook::flag::register(sig, Arc::clone(&seen))?;
        signal_hook::flag::register_usize(sig, Arc::clone(requested_flag()), sig as usize)?;
    }
    Ok(())
}

/// Restores SIGPIPE's default action (Rust ignores it, so that a write to a pipe whose
/// reader has quit fails, and `println!` then panics): the process ends at such a write,
/// quietly, with the status a shell shows as 141, as `cat` and `grep` do. For every
/// command but `run`, whose terminal report is written so that a closed pipe ends nothing.
pub fn end_quietly_when_the_reader_quits() {
    #[cfg(unix)]
    // SAFETY: sets the signal's disposition to the default before any thread starts; no
    // handler is involved.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The signal that asked the run to stop, if one did.
pub fn requested() -> Option<i32> {
    match requested_flag().load(Ordering::Relaxed) {
        0 => None,
        s => Some(s as i32),
    }
}

/// The signal's name for messages.
pub fn name(sig: i32) -> &'static str {
    match sig {
        SIGTERM => "SIGTERM",
        SIGINT => "SIGINT",
        _ => "a signal",
    }
}
