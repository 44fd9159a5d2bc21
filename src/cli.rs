//! The command line: `dsmcosim validate FILE`, `dsmcosim run FILE --out DIR`,
//! `dsmcosim check FILE… --against DIR`, `dsmcosim sweep SWEEP --out DIR`, ….
//!
//! Exit codes: 0 success, 1 I/O failure, 2 bad input (scenario or arguments),
//! 3 a run that diverged or failed numerically, 4 `check` found a difference.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::scenario;

mod size;

use crate::console::say;

macro_rules! say {
    ($($arg:tt)*) => {
        say(format_args!($($arg)*))
    };
}

/// The version line: the crate's version, the commit the binary was built from
/// (`-dirty` when the checkout had changes) and the compiler, as `summary.json` records
/// them.
pub static VERSION: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    let commit = env!("DSMCOSIM_GIT_COMMIT");
    let commit = match commit.split_once('-') {
        Some((hash, rest)) => format!("{}-{rest}", &hash[..hash.len().min(12)]),
        None if commit.is_empty() => "unknown".to_string(),
        None => commit[..commit.len().min(12)].to_string(),
    };
    let rustc = env!("DSMCOSIM_RUSTC");
    let rustc = if rustc.is_empty() {
        "rustc unknown"
    } else {
        rustc
    };
    format!("{} (commit {commit}, {rustc})", env!("CARGO_PKG_VERSION"))
});

/// Deterministic co-simulator of distributed multi-body simulations with SMC
/// stabilization and delay optimization.
#[derive(Debug, Parser)]
#[command(
    name = "dsmcosim",
    version = VERSION.as_str(),
    about = "Deterministic co-simulation of distributed multi-body simulations over modelled networks",
    long_about = None
)]
#[command(after_help = "Example: dsmcosim run scenarios/grid16_space_fixed.json -o runs/first")]
pub struct Cli {
    /// Worker threads for the parallel parts (sweep points, `check` reruns, the nodes of
    /// a partitioned run); default: one per core, or RAYON_NUM_THREADS. Results do not
    /// depend on it.
    #[arg(short = 'j', long, global = true, value_name = "N")]
    pub jobs: Option<std::num::NonZeroUsize>,
    /// Print errors and warnings only: no progress bars, no summary lines.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
    /// `run`: also print the run's plan (what `validate` prints) before it starts.
    #[arg(short, long, global = true)]
    pub verbose: bool,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check a scenario file and print its plan, writing nothing.
    ///
    /// Example: `dsmcosim validate scenarios/tdma4_space_fixed.json`
    ///
    /// The plan: bodies and links, each node's bodies, ghosts and links, each channel's
    /// requested and achieved τ, latency, bandwidth and routes, the TDMA cycle with its
    /// slot list, the controller, and what a run will cost (steps, messages, kernel
    /// events, trace rows and bytes). Writes nothing but the --json file. Refuses (exit
    /// 2) what `run` would refuse, the limits included.
    Validate {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Also write the plan as JSON into FILE (nodes, channels, the TDMA slot list,
        /// the controller, the estimated cost).
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
        /// Change a value of the scenario: a JSON pointer and a JSON value
        /// (`--set /channels/0/tau=0.004`; text that is not JSON is a string:
        /// `--set /integrator=rk4`). Repeatable, applied in order, validated like the file.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
        /// Limits checked before the run starts.
        #[command(flatten)]
        limits: LimitArgs,
    },
    /// Run a scenario into a directory.
    ///
    /// Writes summary.json, trace.csv, epochs.csv, SVG plots and a copy of the scenario
    /// file (scenario.json).
    ///
    /// Example: `dsmcosim run scenarios/grid16_space_fixed.json -o runs/first --set
    /// /channels/0/tau=0.004`
    ///
    /// One run per output directory: a second run into a directory in use exits 1
    /// naming the holder; a directory holding another scenario's run is refused (exit 2)
    /// unless --force; the previous run's outputs are replaced, and those this run does
    /// not write again removed once its summary.json is written; a directory holding no
    /// run where a file has a run's name is refused, and nothing is written through a
    /// symlink or onto a non-regular file (docs/reference.md, "What dsmcosim deletes or
    /// replaces").
    Run {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Change a value of the scenario: a JSON pointer and a JSON value
        /// (`--set /channels/0/tau=0.004`; text that is not JSON is a string:
        /// `--set /integrator=rk4`). Repeatable, applied in order, validated like the file.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
        /// Output directory (created if missing; files in it are replaced atomically).
        #[arg(short, long)]
        out: PathBuf,
        /// Replace another scenario's run in --out.
        #[arg(long)]
        force: bool,
        /// Limits checked before the run starts.
        #[command(flatten)]
        limits: LimitArgs,
        /// Write the complete run state into OUT/checkpoints/ every S seconds of
        /// simulated time (at the next window boundary for controlled runs).
        #[arg(long, value_name = "S")]
        checkpoint_every: Option<f64>,
    },
    /// Finish a run from one of its checkpoints.
    ///
    /// The same digest as an uninterrupted run; writes every output (the trace from t =
    /// 0) into --out.
    ///
    /// Example: `dsmcosim resume runs/first/checkpoints/t_000010.000000000.ckpt -o
    /// runs/first` (after `dsmcosim run … --checkpoint-every 5`)
    Resume {
        /// A checkpoint file written by `run --checkpoint-every`.
        checkpoint: PathBuf,
        /// Output directory (claimed as by `run`).
        #[arg(short, long)]
        out: PathBuf,
        /// Replace another scenario's run in --out.
        #[arg(long)]
        force: bool,
        /// Limits checked before the run starts.
        #[command(flatten)]
        limits: LimitArgs,
        /// Keep writing checkpoints every S seconds of simulated time.
        #[arg(long, value_name = "S")]
        checkpoint_every: Option<f64>,
    },
    /// Rerun scenarios and compare each with its stored run.
    ///
    /// Bit for bit by default.
    ///
    /// Example: `dsmcosim check scenarios/*.json --against results/ --work /tmp/reruns`
    ///
    /// One scenario with a DIR that holds a summary.json: DIR is its stored run. Else
    /// (several scenarios, or a DIR without summary.json) each scenario's stored run is
    /// DIR/NAME/, NAME being the scenario's `name` key (or DIR/STEM/, STEM the file's
    /// stem, if only that holds a run): `dsmcosim check scenarios/*.json --against
    /// results/`.
    /// Scenarios are rerun in parallel and reported in argument order; a missing stored
    /// run or a bad scenario does not stop the others.
    ///
    /// Each rerun goes beside its stored run, into STORED.new (previous outputs there
    /// are replaced), or into WORK/NAME/ with --work, and stays for inspection. The
    /// digests in both summary.json files are compared, then trace.csv, epochs.csv and
    /// any other CSV both runs have, record by record: exactly (equal text, i.e. equal
    /// bits) unless --tolerance is given. A mismatch prints the first differing record:
    /// file, time, column, stored and new value, absolute and relative difference.
    ///
    /// Exit codes: 0 every scenario matches (or is within the tolerance); else, by
    /// precedence, 4 any mismatch, 1 any stored run missing or unreadable (DIR,
    /// summary.json, a CSV) or an I/O failure (a report file included), 2 any bad
    /// scenario, a summary.json that is not a run summary, two scenarios rerunning into
    /// one directory, or a bad --tolerance (then nothing runs).
    Check {
        /// Scenario files (JSON).
        #[arg(required = true, value_name = "SCENARIO")]
        scenarios: Vec<PathBuf>,
        /// A stored run (one scenario) or the directory of stored runs, one per scenario
        /// name (as written by `dsmcosim run --out DIR/NAME`).
        #[arg(long, value_name = "DIR")]
        against: PathBuf,
        /// Compare numbers relatively: |a − b| ≤ X·max(|a|, |b|). A run whose values all
        /// agree within X passes even if its digest differs.
        #[arg(long, value_name = "X", allow_negative_numbers = true)]
        tolerance: Option<f64>,
        /// Rerun into WORK/NAME/ instead of beside the stored runs.
        #[arg(long, value_name = "WORK")]
        work: Option<PathBuf>,
        /// Write the verdict as JUnit XML (one testcase per scenario; a failure naming
        /// the first differing record, an error for a missing run or a bad scenario).
        #[arg(long, value_name = "FILE")]
        junit: Option<PathBuf>,
        /// Write the verdict as JSON (per scenario: status match|mismatch|missing|error,
        /// digests, first difference, wall seconds; and totals).
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
        /// Change a value of every scenario before its rerun (`POINTER=VALUE`, as for
        /// `run`); repeatable.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
    },
    /// Study speed against accuracy, one setting at a time.
    ///
    /// Turns dt, integrator, J_s solve, stabilizer (and ghosts, network on partitioned
    /// scenes) one at a time and measures each variant against a monolithic RK4
    /// reference at dt/20.
    ///
    /// Example: `dsmcosim tradeoff scenarios/grid16_monolithic.json -o runs/tradeoff
    /// --duration 3`
    ///
    /// Writes tradeoff.csv, tradeoff.md, work_precision.svg and pareto.svg into DIR.
    /// Exit codes: 0 done (diverged variants are rows, not failures), 1 I/O failure,
    /// 2 bad scenario or --duration, 3 the reference itself failed.
    Tradeoff {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Change a value of the scenario before the study (`POINTER=VALUE`, as for
        /// `run`); repeatable, applied in order.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Horizon [s] instead of the scenario's duration (rounded down to a whole
        /// number of the sweep's largest dt). Chaotic scenes need a short one.
        #[arg(long, value_name = "S")]
        duration: Option<f64>,
    },
    /// Map stability over SMC μ × dt.
    ///
    /// Runs the scenario over SMC μ (1 ms … 1 s) × dt (0.1 … 10 ms) and classifies each
    /// cell: 0 max|w| ≤ ε, 1 ran with max|w| > ε, 2 diverged.
    ///
    /// Example: `dsmcosim stability-map scenarios/grid16_monolithic.json -o runs/map
    /// --duration 12`
    ///
    /// Writes stability_map.csv, stability_map.md, stability_map.svg and
    /// stability_max_w.svg into DIR.
    StabilityMap {
        /// Scenario file (JSON) with an SMC stabilizer.
        scenario: PathBuf,
        /// Change a value of the scenario before the study (`POINTER=VALUE`, as for
        /// `run`); repeatable, applied in order.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Horizon [s] instead of the scenario's duration (rounded down to 10 ms).
        #[arg(long, value_name = "S")]
        duration: Option<f64>,
    },
    /// Study the coupling schemes over delay on a partitioned scenario.
    ///
    /// Every coupling scheme (reset, predict, passive) × delay τ (3, 5, 8, 10, 15, 20,
    /// 30, 50 ms, latency = τ) × distribution (space, time), on ideal channels without
    /// the scenario's controller.
    ///
    /// Example: `dsmcosim coupling scenarios/mechanisms/ring12.json -o runs/ring`
    ///
    /// Per cell: bounded or not, max |w|, RMS position error of the first and last body
    /// over 0–3 s vs the monolithic run and vs the same scheme at τ = dt, kinetic-energy
    /// drift over the undriven tail, wall time per step relative to reset. Writes
    /// coupling.csv, coupling.md, error_vs_tau.svg and max_w_vs_tau.svg into DIR.
    /// Exit codes: 0 done (diverged cells are rows), 1 I/O failure, 2 bad scenario
    /// (or not partitioned) or --duration.
    Coupling {
        /// Scenario file (JSON) with a partition.
        scenario: PathBuf,
        /// Change a value of the scenario before the study (`POINTER=VALUE`, as for
        /// `run`); repeatable, applied in order.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Horizon [s] instead of the scenario's duration.
        #[arg(long, value_name = "S")]
        duration: Option<f64>,
    },
    /// Measure how far runs' bodies move from a reference run.
    ///
    /// Distance of body positions from a reference run: how long runs of a chaotic scene
    /// stay comparable.
    ///
    /// Example: `dsmcosim distance results/grid16_monolithic results/grid16_space_fixed
    /// --bodies 1,16 -o runs/distance`
    ///
    /// Reads trace.csv of REFERENCE and of each RUN directory (traced at the same
    /// times) and writes DIR/distance.csv (t, then |p_run − p_ref| [m] per run and body)
    /// and DIR/distance.svg (log scale). At most 12 runs × bodies. Exit codes: 0 done,
    /// 1 unreadable trace, 2 a trace of other times, a missing body or too many curves.
    Distance {
        /// Reference run directory (holding trace.csv).
        reference: PathBuf,
        /// Compared run directories.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Body ids to compare, comma-separated.
        #[arg(long, value_delimiter = ',', required = true)]
        bodies: Vec<u32>,
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
    },
    /// Run a what-if sweep, one run per point, in parallel.
    ///
    /// Runs a base scenario with fields set from the axes of a sweep file.
    ///
    /// Example: `dsmcosim sweep scenarios/sweeps/tdma4_slot_layouts.json -o runs/sweep -j 2`
    ///
    /// Writes DIR/sweep.json (a copy of the sweep file), DIR/points/KEY/ for each point (its
    /// scenario.json, run outputs and done.json), DIR/sweep.csv (one row per point),
    /// DIR/timing.csv (wall time per point), cost_vs_AXIS.svg and cost_heatmap.svg.
    /// Every point is validated before any runs. Exit codes: 0 done (diverged points
    /// are rows), 1 unreadable file or I/O failure, 2 bad sweep file, point, --shard, or
    /// a DIR that already holds a sweep without --resume (nothing written).
    Sweep {
        /// Sweep file (JSON).
        sweep: PathBuf,
        /// Change a value of the sweep's base scenario (`POINTER=VALUE`, as for `run`);
        /// repeatable, applied in order before the sweep's own overrides and axes.
        #[arg(long = "set", value_name = "POINTER=VALUE")]
        sets: Vec<String>,
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Continue the sweep in DIR: skip points whose done.json records the same point
        /// (axis values, seed, scenario), rerun the rest.
        #[arg(long)]
        resume: bool,
        /// Run only the points k with k mod n = i − 1 (1 ≤ i ≤ n); join the shards'
        /// directories with `dsmcosim sweep-merge`.
        #[arg(long, value_name = "i/n")]
        shard: Option<String>,
        /// What each point keeps of its run: `summary` (scenario.json, summary.json,
        /// epochs.csv, done.json), `trace` (also every CSV: trace.csv, network.csv, …) or
        /// `all` (also the plots).
        #[arg(long, value_enum, default_value = "all")]
        keep: crate::sweep::Keep,
    },
    /// Join the output directories of a sharded sweep.
    ///
    /// Checks that they hold the same sweep and every point exactly once, then writes
    /// sweep.csv, timing.csv and the plots into --out as an unsharded run does.
    ///
    /// Exit codes: 0 done, 1 I/O failure, 2 different sweeps, a point missing or done
    /// twice, or a directory that is not a sweep's.
    SweepMerge {
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// The shards' output directories (`dsmcosim sweep --shard i/n --out DIR`).
        #[arg(required = true, value_name = "SHARD_DIR")]
        shards: Vec<PathBuf>,
    },
    /// Write the JSON Schemas of scenario and sweep files.
    ///
    /// scenario.schema.json and sweep.schema.json into DIR, generated from the types that
    /// read them; the committed copies are in docs/schema/. A file may name its schema in
    /// a "$schema" key for editors' completion.
    Schema {
        /// Output directory (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
    },
    /// Print a shell completion script.
    ///
    /// For SHELL, on standard output, generated from this command line's definition.
    ///
    /// Example: `dsmcosim completions bash > ~/.local/share/bash-completion/completions/dsmcosim`
    /// (zsh: into a directory of $fpath as `_dsmcosim`; fish:
    /// `~/.config/fish/completions/dsmcosim.fish`).
    Completions {
        /// bash, zsh, fish, elvish or powershell.
        shell: clap_complete::Shell,
    },
    /// Write the manual pages.
    ///
    /// dsmcosim.1 and one dsmcosim-COMMAND.1 per subcommand, generated from this
    /// command line's definition, into DIR.
    ///
    /// Example: `dsmcosim man -o ~/.local/share/man/man1 && man dsmcosim-run`, or one
    /// page on standard output: `dsmcosim man run | man -l -`.
    Man {
        /// Output directory (created if missing) for every page; without it, the page
        /// of COMMAND (or the top page) goes to standard output.
        #[arg(short, long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// The subcommand whose page to print (without -o); default the top page.
        #[arg(value_name = "COMMAND", conflicts_with = "out")]
        page: Option<String>,
    },
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    if cli.quiet {
        crate::console::hush();
        crate::progress::silence();
    }
    if let Some(n) = cli.jobs {
        // The global pool is built once, before any parallel work; it cannot already
        // exist here, and if it did the runs would still be the same bits.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n.get())
            .build_global();
    }
    VERBOSE.store(cli.verbose, std::sync::atomic::Ordering::Relaxed);
    let result = execute(cli.command);
    // Output lost on stdout fails a command that otherwise succeeded (exit 1, as any
    // I/O failure); a failed command keeps its own exit code.
    let stdout = crate::console::take_failure();
    match (result, stdout) {
        (Ok(()), None) => ExitCode::SUCCESS,
        (Ok(()), Some(e)) => {
            eprintln!("error: writing to standard output: {e}");
            ExitCode::from(1)
        }
        (Err(e), _) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Writes `dsmcosim.1` and one `dsmcosim-COMMAND.1` per subcommand into `out`
/// (created if missing), each replaced atomically; returns the paths written.
fn write_man_pages(out: &std::path::Path) -> crate::Result<Vec<PathBuf>> {
    crate::output::create_out_dir(out)?;
    let mut written = Vec::new();
    for (name, page) in man_pages() {
        let path = out.join(format!("{name}.1"));
        let mut roff = Vec::new();
        clap_mangen::Man::new(page)
            .render(&mut roff)
            .map_err(|e| crate::Error::io(&path, e))?;
        crate::output::write_atomic(&path, &roff)?;
        written.push(path);
    }
    Ok(written)
}

/// The manual pages by name: `dsmcosim`, then one `dsmcosim-COMMAND` per subcommand.
fn man_pages() -> Vec<(String, clap::Command)> {
    let mut command = <Cli as clap::CommandFactory>::command();
    // Built, the global options (-j, -q, -v) are propagated into every subcommand.
    command.build();
    let mut pages = vec![("dsmcosim".to_string(), command.clone())];
    for sub in command.get_subcommands().filter(|s| s.get_name() != "help") {
        let name = format!("dsmcosim-{}", sub.get_name());
        // The page is dsmcosim-run(1); its synopsis reads `dsmcosim run …`.
        let synopsis = format!("dsmcosim {}", sub.get_name());
        pages.push((name.clone(), sub.clone().name(name).bin_name(synopsis)));
    }
    pages
}

/// `--verbose` (read by `run`).
static VERBOSE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Limits a run is checked against before it starts (`crate::run::budget`).
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct LimitArgs {
    /// Most integration steps of the run.
    #[arg(long, value_name = "N", default_value_t = crate::run::budget::DEFAULT_MAX_STEPS)]
    max_steps: u64,
    /// Most bytes trace.csv may take (estimated before the run); a size as for
    /// --max-memory.
    #[arg(long, value_name = "SIZE", value_parser = size::parse_bytes,
          default_value_t = crate::run::budget::DEFAULT_MAX_OUTPUT_BYTES)]
    max_output: u64,
    /// Most checkpoints the run may write.
    #[arg(long, value_name = "N", default_value_t = crate::run::budget::DEFAULT_MAX_CHECKPOINTS)]
    max_checkpoints: u64,
    /// Most memory the run may need (estimated before the run): bytes, or a number with
    /// K, M, G, T (powers of 1024, also written KiB … TiB) or KB, MB, GB, TB (powers of
    /// 1000), e.g. 16G, 512M, 1.5GiB [default: the smallest of 16GB, the address-space
    /// limit (ulimit -v) and the cgroup's memory limit].
    #[arg(long, value_name = "SIZE", value_parser = size::parse_bytes)]
    max_memory: Option<u64>,
}

impl LimitArgs {
    fn limits(&self) -> crate::run::budget::Limits {
        let limits = crate::run::budget::Limits {
            max_steps: self.max_steps,
            max_output_bytes: self.max_output,
            max_checkpoints: self.max_checkpoints,
            ..crate::run::budget::Limits::default()
        };
        match self.max_memory {
            Some(bytes) => crate::run::budget::Limits {
                max_memory_bytes: bytes,
                max_memory_from: crate::run::budget::MemoryLimitFrom::Flag,
                ..limits
            },
            None => limits,
        }
    }
}

/// The run options from the command line.
fn run_options(
    checkpoint_every: Option<f64>,
    force: bool,
    limits: LimitArgs,
) -> crate::Result<crate::run::RunOptions> {
    let checkpoint_every = match checkpoint_every {
        None => None,
        Some(secs) => match crate::kernel::SimTime::from_secs_f64(secs) {
            Some(t) if t.0 > 0 => Some(t),
            Some(_) if secs > 0.0 => {
                return Err(crate::Error::invalid(
                    "--checkpoint-every",
                    format!(
                        "must be at least 1 ns, a whole number of nanoseconds (got {} s)",
                        crate::error::num(secs)
                    ),
                ))
            }
            None if secs.is_finite() && secs > 0.0 => {
                return Err(crate::Error::invalid(
                    "--checkpoint-every",
                    format!(
                        "is beyond the range of simulated time (got {} s, limit about \
                         1.8e10 s)",
                        crate::error::num(secs)
                    ),
                ))
            }
            _ => {
                return Err(crate::Error::invalid(
                    "--checkpoint-every",
                    format!(
                        "must be a positive number of seconds (got {})",
                        crate::error::num(secs)
                    ),
                ))
            }
        },
    };
    Ok(crate::run::RunOptions {
        checkpoint_every,
        force,
        limits: limits.limits(),
        ..Default::default()
    })
}

fn report(name: &str, outcome: &crate::run::Outcome, out: &std::path::Path) {
    // Only what the scene has: no |w| without constraints, the cost in its own unit.
    let w = if outcome.rows > 0 {
        format!("max |w| = {:.3e} m; ", outcome.max_constraint_violation)
    } else {
        String::new()
    };
    let cost = if outcome.signal_cost {
        format!(
            "mean cost = {:.3e} (RMS of measurement.signals); ",
            outcome.mean_cost
        )
    } else if outcome.rows > 0 {
        format!("mean cost = {:.3e} m; ", outcome.mean_cost)
    } else {
        String::new() // no links and no signals: nothing is measured as a cost
    };
    say!(
        "{}: {} steps in {:.3} s wall; {w}{cost}digest {}",
        name,
        outcome.steps,
        outcome.wall_seconds,
        outcome.digest
    );
    if let Some(stopped) = &outcome.stopped {
        say!("{name}: {stopped}");
    }
    say!("wrote {}", out.display());
    for w in outcome.warnings() {
        eprintln!("warning: {w}");
    }
}

/// Whether `path` holds a sweep file (a JSON object with `axes` and `base`) rather than
/// a scenario; anything unreadable is left to the scenario loader to report.
fn is_sweep(path: &std::path::Path) -> bool {
    file_kind(path) == Some(FileKind::Sweep)
}

/// Which kind of file a JSON object is, by its required keys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FileKind {
    /// `base` and `axes`.
    Sweep,
    /// `model` and `duration`.
    Scenario,
}

/// The kind of the JSON file at `path`, if it is readable JSON of either kind.
fn file_kind(path: &std::path::Path) -> Option<FileKind> {
    let v = crate::input::read_text(path)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())?;
    if v.get("axes").is_some() && v.get("base").is_some() {
        Some(FileKind::Sweep)
    } else if v.get("model").is_some() && v.get("duration").is_some() {
        Some(FileKind::Scenario)
    } else {
        None
    }
}

/// Refuses a file of the other kind than `command` reads, saying which command reads it.
fn expect_kind(path: &std::path::Path, wanted: FileKind, command: &str) -> crate::Result<()> {
    let found = file_kind(path);
    let hint = match (wanted, found) {
        (FileKind::Scenario, Some(FileKind::Sweep)) => format!(
            "is a sweep file (it has `base` and `axes`), not a scenario: run its points with \
             `dsmcosim sweep {} -o DIR`",
            path.display()
        ),
        (FileKind::Sweep, Some(FileKind::Scenario)) => format!(
            "is a scenario file (it has `model` and `duration`), not a sweep: run it with \
             `dsmcosim run {} -o DIR`",
            path.display()
        ),
        _ => return Ok(()),
    };
    Err(crate::Error::invalid(
        path.display().to_string(),
        format!("{hint} (`{command}` reads the other kind)"),
    ))
}

/// Writes a report file atomically, creating its directory.
fn write_report(path: &std::path::Path, text: &str) -> crate::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::output::create_dir_all(dir)?;
    }
    crate::output::write_atomic(path, text.as_bytes())
}

/// Runs one subcommand.
pub fn execute(command: Command) -> crate::Result<()> {
    match command {
        Command::Validate {
            scenario,
            sets,
            json,
            limits,
        } => {
            if is_sweep(&scenario) {
                if json.is_some() {
                    return Err(crate::Error::invalid(
                        "--json",
                        "writes a scenario's plan; a sweep file has one per point \
                         (`dsmcosim sweep` writes each point's scenario.json)",
                    ));
                }
                let c = crate::sweep::check_with(&scenario, &sets)?;
                for w in &c.warnings {
                    eprintln!("warning: {w}");
                }
                say!(
                    "{}: ok — sweep {} of {} points, {} of them validated (each axis value, \
                     the extreme combinations; `sweep` checks every point before it runs); \
                     {} with a channel never served",
                    scenario.display(),
                    c.name,
                    c.points,
                    c.checked,
                    c.warnings.len()
                );
                return Ok(());
            }
            if let Some(path) = &json {
                crate::output::check_report_target(path, "--json", &[&scenario])?;
            }
            let (s, _) = scenario::load_with(&scenario, &sets)?;
            let options = run_options(None, false, limits)?;
            crate::run::preflight(&s, &options)?;
            let plan = crate::run::plan::plan(&s)?;
            if let Some(path) = json {
                let mut text = serde_json::to_string_pretty(&plan)
                    .map_err(|e| crate::Error::io(&path, std::io::Error::other(e)))?;
                text.push('\n');
                crate::output::write_atomic(&path, text.as_bytes())?;
            }
            say!("{}: ok — {}", scenario.display(), plan.text());
            Ok(())
        }
        Command::Run {
            scenario,
            sets,
            out,
            force,
            limits,
            checkpoint_every,
        } => {
            let options = run_options(checkpoint_every, force, limits)?;
            expect_kind(&scenario, FileKind::Scenario, "run")?;
            crate::interrupt::install();
            let (s, text) = scenario::load_with(&scenario, &sets)?;
            if VERBOSE.load(std::sync::atomic::Ordering::Relaxed) {
                let plan = crate::run::plan::plan(&s)?;
                say!("{}: {}", scenario.display(), plan.text());
            }
            let name = s.name.clone();
            let outcome =
                crate::run::run_keeping_scenario_of(s, &text, Some(&scenario), &out, options)?;
            report(&name, &outcome, &out);
            Ok(())
        }
        Command::Resume {
            checkpoint,
            out,
            force,
            limits,
            checkpoint_every,
        } => {
            let options = run_options(checkpoint_every, force, limits)?;
            crate::interrupt::install();
            let outcome = crate::run::resume(&checkpoint, &out, options)?;
            report(&checkpoint.display().to_string(), &outcome, &out);
            Ok(())
        }
        Command::Check {
            scenarios,
            against,
            tolerance,
            work,
            junit,
            json,
            sets,
        } => {
            // Before anything runs: a report never replaces an input, a stored run's
            // file or anything but a regular file.
            let inputs: Vec<&std::path::Path> = scenarios.iter().map(PathBuf::as_path).collect();
            for (path, flag) in [(&junit, "--junit"), (&json, "--json")] {
                if let Some(path) = path {
                    crate::output::check_report_target(path, flag, &inputs)?;
                }
            }
            if let (Some(a), Some(b)) = (&junit, &json) {
                if a == b {
                    return Err(crate::Error::invalid(
                        "--json",
                        format!(
                            "{} is the --junit file too; give each report its own",
                            b.display()
                        ),
                    ));
                }
            }
            let options = crate::check::batch::Options {
                against,
                tolerance,
                work,
                sets,
            };
            let batch = crate::check::batch::run(&scenarios, &options)?;
            let mut reports = Vec::new();
            if let Some(path) = junit {
                reports.push((path, crate::check::junit::render(&batch)));
            }
            if let Some(path) = json {
                reports.push((path, crate::check::json::render(&batch)));
            }
            let (lines, result) = batch.conclude();
            for line in lines {
                say!("{line}");
            }
            // A report that cannot be written fails the command (exit 1) unless the check
            // itself failed, whose exit code outranks it; the error is printed either way.
            let mut written = Ok(());
            for (path, text) in reports {
                if let Err(e) = write_report(&path, &text) {
                    if result.is_err() || written.is_err() {
                        eprintln!("error: {e}");
                    } else {
                        written = Err(e);
                    }
                }
            }
            result.and(written)
        }
        Command::Schema { out } => {
            for path in crate::schema::write(&out)? {
                say!("wrote {}", path.display());
            }
            Ok(())
        }
        Command::Completions { shell } => {
            let mut command = <Cli as clap::CommandFactory>::command();
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut command, "dsmcosim", &mut script);
            say!("{}", String::from_utf8_lossy(&script).trim_end());
            Ok(())
        }
        Command::Man {
            out: Some(out),
            page: _,
        } => {
            for path in write_man_pages(&out)? {
                say!("wrote {}", path.display());
            }
            Ok(())
        }
        Command::Man { out: None, page } => {
            let want = page.map_or("dsmcosim".to_string(), |p| format!("dsmcosim-{p}"));
            let pages = man_pages();
            let Some((_, command)) = pages.into_iter().find(|(name, _)| *name == want) else {
                return Err(crate::Error::invalid(
                    "COMMAND",
                    format!(
                        "no subcommand `{}` (dsmcosim --help lists them)",
                        want.trim_start_matches("dsmcosim-")
                    ),
                ));
            };
            let mut roff = Vec::new();
            clap_mangen::Man::new(command)
                .render(&mut roff)
                .map_err(|e| crate::Error::io("<stdout>", e))?;
            use std::io::Write as _;
            std::io::stdout()
                .write_all(&roff)
                .map_err(|e| crate::Error::io("<stdout>", e))
        }
        Command::Tradeoff {
            scenario,
            sets,
            out,
            duration,
        } => crate::tradeoff::command_tradeoff(&scenario, &sets, &out, duration),
        Command::StabilityMap {
            scenario,
            sets,
            out,
            duration,
        } => crate::tradeoff::command_stability_map(&scenario, &sets, &out, duration),
        Command::Coupling {
            scenario,
            sets,
            out,
            duration,
        } => {
            let mut bar = crate::progress::Progress::with_unit(0, "runs");
            let cells =
                crate::coupling_study::study(&scenario, &sets, &out, duration, &mut |k, n| {
                    bar.set_total(n as u64);
                    bar.tick(k as u64);
                })?;
            bar.finish();
            let bounded = cells.iter().filter(|c| c.bounded()).count();
            say!("{} cells, {} bounded", cells.len(), bounded);
            say!("wrote {}", out.join("coupling.csv").display());
            Ok(())
        }
        Command::Distance {
            reference,
            runs,
            bodies,
            out,
        } => {
            crate::distance::command(&reference, &runs, &bodies, &out)?;
            say!("wrote {}", out.join("distance.csv").display());
            Ok(())
        }
        Command::Sweep {
            sweep,
            sets,
            out,
            resume,
            shard,
            keep,
        } => {
            expect_kind(&sweep, FileKind::Sweep, "sweep")?;
            crate::interrupt::install();
            let shard = shard
                .as_deref()
                .map(crate::sweep::Shard::parse)
                .transpose()?;
            let options = crate::sweep::Options {
                keep,
                resume,
                shard,
                sets,
            };
            let r = crate::sweep::run(&sweep, &out, &options)?;
            say!(
                "{}: {} of {} points ({} run, {} already done), {} diverged",
                r.name,
                r.selected,
                r.points,
                r.ran,
                r.skipped,
                r.diverged
            );
            say!("wrote {}", out.join("sweep.csv").display());
            Ok(())
        }
        Command::SweepMerge { out, shards } => {
            let r = crate::sweep::merge(&out, &shards)?;
            say!(
                "{}: merged {} points from {} directories, {} diverged",
                r.name,
                r.points,
                shards.len(),
                r.diverged
            );
            say!("wrote {}", out.join("sweep.csv").display());
            Ok(())
        }
    }
}
