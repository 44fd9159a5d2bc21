//! Terminal progress for long runs: an `indicatif` bar on stderr that appears only when
//! stderr is a terminal and the run has already taken more than [`QUIET_FOR`], so
//! short runs and scripted runs stay quiet. Reads the wall clock only to decide whether
//! to draw; nothing here reaches a trace.
//!
//! An embedding that draws its own bar (the Python package's tqdm) gives a
//! [`Listener`] with [`reporting_to`]: every bar made on that thread inside it reports
//! its positions there too, terminal or not (bars made inside [`quietly`] report
//! nothing, as they draw nothing).

use std::sync::Arc;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

thread_local! {
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    static LISTENER: std::cell::RefCell<Option<Listener>> = const { std::cell::RefCell::new(None) };
}

/// Where a bar's positions also go: `(position, total, unit)`, called from the thread
/// that ticks the bar (not per step: per slice of 1024 steps, per window, per point).
pub type Listener = Arc<dyn Fn(u64, u64, &str) + Send + Sync>;

/// Runs `f` with every bar made on this thread inside it reporting to `listener` (none:
/// as outside). Work that moves to another thread takes the listener with it by
/// [`listener`] and `reporting_to` there (a run's driver on rayon's pool does).
pub fn reporting_to<T>(listener: Option<Listener>, f: impl FnOnce() -> T) -> T {
    let before = LISTENER.with(|l| l.replace(listener));
    let out = f();
    LISTENER.with(|l| *l.borrow_mut() = before);
    out
}

/// The listener bars made on this thread now report to.
pub fn listener() -> Option<Listener> {
    LISTENER.with(|l| l.borrow().clone())
}

/// `--quiet`: no bar anywhere in the process.
static SILENT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Hides every bar of the process from now on (`dsmcosim -q`).
pub fn silence() {
    SILENT.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// Runs `f` with every bar created on this thread inside it hidden (a sweep's points,
/// whose own bars would draw over the sweep's).
pub fn quietly<T>(f: impl FnOnce() -> T) -> T {
    let before = QUIET.with(|q| q.replace(true));
    let out = f();
    QUIET.with(|q| q.set(before));
    out
}

/// How long a run stays silent before its bar appears.
pub const QUIET_FOR: Duration = Duration::from_secs(2);

/// A lazily shown progress bar over `total` units.
pub struct Progress {
    bar: ProgressBar,
    started: Instant,
    shown: bool,
    enabled: bool,
    unit: String,
    total: u64,
    listener: Option<Listener>,
}

impl Progress {
    /// A bar over `total` steps (hidden until [`QUIET_FOR`] has passed).
    pub fn new(total: u64) -> Progress {
        Progress::with_unit(total, "steps")
    }

    /// A bar over `total` units named `unit` (e.g. `windows`).
    pub fn with_unit(total: u64, unit: &str) -> Progress {
        use std::io::IsTerminal;
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{bar:40}} {{pos}}/{{len}} {unit}  {{elapsed}} elapsed, ETA {{eta}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let quiet = QUIET.with(|q| q.get());
        Progress {
            bar,
            started: Instant::now(),
            shown: false,
            enabled: std::io::stderr().is_terminal()
                && !quiet
                && !SILENT.load(std::sync::atomic::Ordering::Relaxed),
            unit: unit.to_string(),
            total,
            listener: if quiet { None } else { listener() },
        }
    }

    /// Sets the position. Call it every so often (per slice of steps, per window), not
    /// per step: each call reads the wall clock.
    pub fn tick(&mut self, pos: u64) {
        if let Some(l) = &self.listener {
            l(pos, self.total, &self.unit);
        }
        if !self.enabled {
            return;
        }
        if !self.shown && self.started.elapsed() > QUIET_FOR {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        self.bar.set_position(pos);
    }

    /// Sets the total (when it is known only once the work is planned).
    pub fn set_total(&mut self, total: u64) {
        self.total = total;
        self.bar.set_length(total);
    }

    /// Clears the bar.
    pub fn finish(&self) {
        if self.shown {
            self.bar.finish_and_clear();
        }
    }
}
