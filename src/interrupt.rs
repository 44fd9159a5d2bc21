//! Ctrl-C (SIGINT) and SIGTERM during `run` and `resume`: the run stops at the end of
//! its current slice of steps (or controller window), writes what it has — the trace
//! up to there, summary.json with `"status": "interrupted"` — and exits 130 saying so
//! and how a long run can be continued instead (`--checkpoint-every`, `resume`).
//! Without this a Ctrl-C killed the process mid-write, left a `.trace.csv.tmp.*` file
//! until the next run and said nothing. A second Ctrl-C exits at once (130).
//!
//! `sweep` installs it too: no point starts after it, the running points stop as a run
//! does (marked interrupted, without their done.json, so `sweep --resume` reruns them),
//! and the sweep exits 130 counting the points finished and giving the `--resume`
//! command. Every other command keeps the default (the process ends at once).

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the handler (once per process; a failure to install leaves the default).
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// Asks every run, controlled run and sweep of the process to stop as Ctrl-C does: an
/// embedding that owns the signals (the Python package, whose interpreter takes SIGINT)
/// calls it when its own handler fires.
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Withdraws a stop asked by [`request`] once the work it stopped has returned, so the
/// next call of the embedding runs.
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}
