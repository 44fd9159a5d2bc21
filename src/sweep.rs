//! What-if parameter sweeps: `dsmcosim sweep SWEEP.json --out DIR` runs a base scenario
//! with fields replaced by the values of one or more axes, and `dsmcosim sweep-merge`
//! joins sweeps split into shards.
//!
//! # Sweep file
//!
//! ```json
//! { "name": "tdma4_drift", "base": "../scenarios/tdma4_space_fixed.json",
//!   "combine": "factorial",
//!   "axes": [ {"name": "drift", "pointer": "/network/drift_ppm", "values": [0, 50, 200]},
//!             {"name": "tau1", "pointer": "/channels/0/tau",
//!              "range": {"from": 0.002, "to": 0.008, "steps": 4}} ],
//!   "overrides": {"/duration": 5.0} }
//! ```
//!
//! - `base`: the base scenario, relative to the sweep file's directory.
//! - `combine`: `factorial` (default; every combination, the last axis varying
//!   fastest) or `zip` (the i-th values of all axes; equal lengths).
//! - `axes[]`: `name` (`[A-Za-z0-9_.-]`, a column of `sweep.csv`), `pointer` (RFC 6901
//!   into the scenario JSON) and either `values` (any JSON: numbers, strings, whole
//!   slot lists) or `range` (`steps` numbers `from + i·(to − from)/(steps − 1)`, the
//!   last exactly `to`; always JSON floats, so an integer field takes `values`).
//! - `overrides`: pointer → value set on every point before the axes.
//!
//! Unknown keys are errors. A pointer's parent must exist in the base; its last key may
//! be new on an object (the scenario's own validation then names an unknown key).
//!
//! # Points, keys and seeds
//!
//! Point `i`'s scenario is the base with, in order: the overrides, `seed` =
//! `splitmix64(base_seed ^ splitmix64(key))` ([`derive_seed`]; `base_seed` is the base's
//! `seed` after the overrides; `key` is [`points::Plan::seed_key`], BLAKE3 of the
//! point's configuration and repetition, never its index), the axis values, and `name`
//! = `<sweep name>_<key as 16 hex digits>`. An axis on `/seed` sets the seed itself.
//! `repeat: n` runs every configuration `n` times (a `rep` column). `sweep` builds and
//! validates every point before any runs (`validate` a bounded set of them:
//! [`points::checked_points`]); a bad sweep file or point is an
//! [`Error::Invalid`](crate::Error::Invalid) (exit code 2) naming the axis
//! (`axes[1].pointer: …`) or the point with its axis values (`point p3 (drift = 50,
//! tau1 = 0.004): dt: …`), and nothing is written.
//!
//! # Output (`DIR`)
//!
//! - `sweep.json`: a copy of the sweep file.
//! - `points/<key>/`: `scenario.json` (runs alone with `dsmcosim run`), the run's
//!   outputs (what [`Keep`] keeps), and last `done.json` (written atomically: the
//!   point's index, axis values, seed, BLAKE3 of its scenario text and of the base
//!   file, its row, its wall time).
//! - `sweep.csv`: one row per point in index order ([`table`] lists the columns); no
//!   wall time, so the file is the same for any thread count, shard split or resume.
//! - `timing.csv`: `index,wall_seconds`.
//! - `cost_vs_<axis>.svg` and, with two or more axes, `cost_heatmap.svg` ([`plots`]).
//!
//! A point that diverges is a row with status `diverged` and where it failed, not a
//! failure; the plots leave it out of their means and mark it. Points run in
//! parallel on rayon's pool and the tables are written from the `done.json` records
//! read back in index order, so the output does not depend on the thread count.
//!
//! # Resume, shards, merge
//!
//! Without `--resume`, a `DIR` that holds a sweep (`sweep.json` or `points/`) is an
//! error. With it, a point whose `done.json` records the same axis values, seed and
//! scenario text is skipped; any other is rerun. `--shard i/n` runs the points
//! `k` with `k mod n = i − 1` and writes the tables of those rows only;
//! `sweep-merge --out OUT DIR...` checks that the shard directories hold the same sweep
//! definition and base, and every point exactly once, then writes `OUT/sweep.csv`,
//! `timing.csv` and the plots with the same function as an unsharded run.

pub mod exec;
pub mod file;
pub mod merge;
pub mod plots;
/// JSON pointers live with the input files they address ([`crate::input::pointer`]);
/// re-exported under their old path.
pub use crate::input::pointer;
pub mod points;
pub mod record;
pub mod table;

use std::path::Path;

pub use exec::{
    check, check_with, finish, pending, run, run_one, Checked, Keep, Options, Report, Shard,
};
pub use merge::{merge, MergeReport};
pub use points::{derive_seed, splitmix64};

use crate::error::Result;
use crate::output::write_atomic;

/// Whether `name` is an entry `sweep` or `sweep-merge` writes at the top of its output
/// directory (beside `sweep.json`, which claims it): the tables, the plots, `points/`.
pub(crate) fn writes(name: &str) -> bool {
    matches!(
        name,
        "sweep.csv" | "timing.csv" | "points" | "cost_heatmap.svg"
    ) || (name.starts_with("cost_vs_") && name.ends_with(".svg"))
}

/// Writes `sweep.csv`, `timing.csv` and the plots of `records` (sorted by index) into
/// `out`; the one writer of both `sweep` and `sweep-merge`.
fn write_outputs(out: &Path, plan: &points::Plan, records: &[record::Record]) -> Result<()> {
    write_atomic(
        &out.join("sweep.csv"),
        table::sweep_csv(plan, records).as_bytes(),
    )?;
    write_atomic(
        &out.join("timing.csv"),
        table::timing_csv(records).as_bytes(),
    )?;
    plots::write(out, plan, records)
}
