//! What a run will cost before it starts: steps, trace rows and bytes, checkpoints —
//! estimated from the scenario alone and checked against limits that a flag lifts.
//!
//! The estimates are upper bounds: a trace value is at most [`BYTES_PER_VALUE`] bytes of
//! text (Rust's shortest round-trip form of an `f64` with its comma), a header name at
//! most [`BYTES_PER_HEADER`], a row holds `t`,
//! `w` and `f` of every link, six values per traced body, the net's seven invariants
//! and, with `output.trace_rotation`, seven more per traced body.

use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::scenario::Scenario;
use crate::trace::recorder::{INVARIANT_COLUMNS, ROTATION_COLUMNS};

/// Largest text of one trace value with its separator [bytes] (`-1.2345678901234567e-308,`).
pub const BYTES_PER_VALUE: u64 = 25;
/// Largest header name of one trace column with its separator [bytes]: a name of at
/// most 3 characters and an index (`w_L`, `vz_B`, …, then up to 20 digits).
pub const BYTES_PER_HEADER: u64 = 26;
/// Default bound on the integration steps of one run (`--max-steps` lifts it): 10¹⁰
/// steps, hours of wall time even on the smallest scene.
pub const DEFAULT_MAX_STEPS: u64 = 10_000_000_000;
/// Default bound on the estimated trace.csv size [bytes] (`--max-output` lifts it):
/// 10 GB.
pub const DEFAULT_MAX_OUTPUT_BYTES: u64 = 10_000_000_000;
/// Default bound on the checkpoints one run writes (`--max-checkpoints` lifts it).
pub const DEFAULT_MAX_CHECKPOINTS: u64 = 1_000;
/// Default bound on the estimated peak memory [bytes] (`--max-memory` lifts it): 16 GB,
/// or less where the process may have less ([`default_max_memory`]). Defined with the
/// input limits, since it also bounds the checkpoint a resume reads.
pub use crate::input::DEFAULT_MAX_MEMORY_BYTES;
/// Peak resident memory of a run before any body [bytes] (measured: 6.3 MB for a 16×16
/// grid), with room for the allocator's rounding on small scenes.
pub const MEMORY_BASE: u64 = 10_000_000;
/// Peak resident memory per body [bytes], state, workspaces, the model and the CG
/// solve: measured peaks (`/usr/bin/time -f %M`, monolithic point-mass grids, CG 10,
/// 10 steps; the table in docs/reference.md) less [`MEMORY_BASE`] are 1.8 kB per body
/// at 64×64, 2.2 kB at 128×128, 2.4 kB at 256×256 and 512×512, 2.2 kB at 1000×1000;
/// rounded up.
pub const MEMORY_PER_BODY: u64 = 2_500;
/// Memory per constraint row beyond two per body [bytes]: [`MEMORY_PER_BODY`] was
/// measured on grids, about two links per body, so a scene of joints (a weld adds six
/// rows, a hinge five) holds rows it does not cover: each row's specification, its
/// kinematics and multiplier workspaces, its pattern entries in the solve and its two
/// trace columns. Measured peaks (`/usr/bin/time -v`, 10 steps, the exact solve) above
/// the estimate without this term, per such row: 2.04 kB on a chain of 5000 welds,
/// 2.13 kB on 20 000 welds, 2.42 kB on 50 000 ball joints; rounded up with a margin.
pub const MEMORY_PER_EXTRA_ROW: u64 = 3_000;
/// Memory per spring [bytes]: its specification (about 120 bytes) held by the
/// scenario, the monolithic system and a partitioned run's node and its copy of the
/// scenario, rounded up. Not measured as the per-body figure is: it is the size of what
/// is held, not a peak (a spring adds no workspace).
pub const MEMORY_PER_SPRING: u64 = 512;
/// Memory per entry of the exact solve's factor [bytes] (the AMD-ordered sparse
/// Cholesky's, as its symbolic analysis counts them). Measured peaks above the CG
/// path's (same grids and command), per factor entry: 17.4 (64×64), 17.0 (128×128),
/// 15.7 (256×256), 12.9 (512×512), 12.8 (1000×1000); the small grids' excess is covered
/// by the margin of [`MEMORY_BASE`] and [`MEMORY_PER_BODY`] (each size's total is
/// bounded: `estimate_bounds_the_measured_peak` in tests/memory_peak.rs).
pub const BYTES_PER_FACTOR_ENTRY: u64 = 16;

/// Where a run's memory bound comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MemoryLimitFrom {
    /// [`DEFAULT_MAX_MEMORY_BYTES`].
    Default,
    /// `--max-memory`.
    Flag,
    /// The process's address-space limit (`RLIMIT_AS`, `ulimit -v`).
    AddressSpace,
    /// The memory limit of the process's cgroup (`memory.max`, v1
    /// `memory.limit_in_bytes`).
    Cgroup,
}

impl MemoryLimitFrom {
    /// Words for the error message.
    fn describe(self) -> &'static str {
        match self {
            MemoryLimitFrom::Default => "the default limit",
            MemoryLimitFrom::Flag => "the limit",
            MemoryLimitFrom::AddressSpace => {
                "this process's address-space limit (RLIMIT_AS, `ulimit -v`)"
            }
            MemoryLimitFrom::Cgroup => "this process's cgroup memory limit",
        }
    }
}

/// A cgroup memory limit file's value [bytes]: `None` for `max` (v2) or a value of
/// 2⁶² or more (v1's "unlimited" is 2⁶³ − 4096), or anything unreadable.
pub fn parse_cgroup_limit(text: &str) -> Option<u64> {
    text.trim().parse::<u64>().ok().filter(|&b| b < 1 << 62)
}

/// The process's address-space limit [bytes] (`RLIMIT_AS`), if any.
pub fn address_space_limit() -> Option<u64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one `rlimit` through a valid, exclusive pointer.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } == 0;
    // `rlim_t` is `u64` on 64-bit Linux but not on every target.
    #[allow(clippy::unnecessary_cast)]
    let bytes = r.rlim_cur as u64;
    (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(bytes)
}

/// The memory limit of the cgroup the process runs in [bytes], if any: cgroup v2's
/// `/sys/fs/cgroup/memory.max`, else v1's `/sys/fs/cgroup/memory/memory.limit_in_bytes`
/// (the files of the cgroup namespace's root, which a container or a batch job sees as
/// its own).
pub fn cgroup_limit() -> Option<u64> {
    [
        "/sys/fs/cgroup/memory.max",
        "/sys/fs/cgroup/memory/memory.limit_in_bytes",
    ]
    .iter()
    .find_map(|f| parse_cgroup_limit(&std::fs::read_to_string(f).ok()?))
}

/// The default memory bound: the smallest of [`DEFAULT_MAX_MEMORY_BYTES`], the
/// address-space limit and the cgroup limit, and where it comes from. A job on a node
/// (or in a container) with less memory than a run needs is refused before it starts,
/// naming the estimate and `--max-memory`, instead of being killed half-way.
pub fn default_max_memory() -> (u64, MemoryLimitFrom) {
    let mut best = (DEFAULT_MAX_MEMORY_BYTES, MemoryLimitFrom::Default);
    for (limit, from) in [
        (address_space_limit(), MemoryLimitFrom::AddressSpace),
        (cgroup_limit(), MemoryLimitFrom::Cgroup),
    ] {
        if let Some(b) = limit.filter(|&b| b < best.0) {
            best = (b, from);
        }
    }
    best
}

/// Limits a run is checked against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Most integration steps.
    pub max_steps: u64,
    /// Most estimated trace.csv bytes.
    pub max_output_bytes: u64,
    /// Most checkpoints written.
    pub max_checkpoints: u64,
    /// Most estimated peak memory [bytes].
    pub max_memory_bytes: u64,
    /// Where `max_memory_bytes` comes from (for the message).
    pub max_memory_from: MemoryLimitFrom,
}

impl Default for Limits {
    /// The default limits; the memory bound is [`default_max_memory`], so it depends on
    /// the process's address-space and cgroup limits.
    fn default() -> Limits {
        let (max_memory_bytes, max_memory_from) = default_max_memory();
        Limits {
            max_steps: DEFAULT_MAX_STEPS,
            max_output_bytes: DEFAULT_MAX_OUTPUT_BYTES,
            max_checkpoints: DEFAULT_MAX_CHECKPOINTS,
            max_memory_bytes,
            max_memory_from,
        }
    }
}

/// What a run of a scenario will do and write, estimated before it starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Integration steps.
    pub steps: u64,
    /// FMU communication steps (`doStep` calls) over the run, all FMUs together, and
    /// the FMU with the most (its index): an FMU stepping faster than `dt` takes
    /// `dt / step` of them per integration step, each counted against `--max-steps`.
    pub fmu_steps: (u64, Option<usize>),
    /// Rows of trace.csv (header excluded), exactly.
    pub trace_rows: u64,
    /// Values per trace row.
    pub trace_columns: u64,
    /// Upper bound on trace.csv [bytes].
    pub trace_bytes: u64,
    /// Checkpoints written (with `--checkpoint-every`).
    pub checkpoints: u64,
    /// Entries of the exact solve's factor bound (0 on the CG path and for small
    /// systems, which use a dense factor).
    pub factor_entries: u64,
    /// [`Estimate::memory_bytes`] without the factor: what the CG path needs [bytes].
    pub memory_without_factor: u64,
    /// Estimated peak memory [bytes]: [`MEMORY_BASE`], [`MEMORY_PER_BODY`] per body,
    /// [`MEMORY_PER_EXTRA_ROW`] per row beyond two per body, [`MEMORY_PER_SPRING`] per
    /// spring and [`BYTES_PER_FACTOR_ENTRY`] per factor entry.
    pub memory_bytes: u64,
}

/// Entries of the exact solve's factor of the whole scene, from the same symbolic
/// analysis a monolithic run does (its pattern is bounded by the scene's links, which
/// are bounded before this is called). A partitioned run's nodes factorize parts of the
/// scene, with a few ghost links each.
fn factor_entries(scenario: &Scenario) -> u64 {
    // As the solver sees the rows: one held to the world ends on one more body.
    let nb = scenario.bodies.len();
    let world = scenario.links.iter().any(|l| l.world);
    let ends: Vec<(usize, usize)> = scenario
        .links
        .iter()
        .map(|l| (l.a, if l.world { nb } else { l.b }))
        .collect();
    crate::multibody::solver::exact_factor_entries(nb + usize::from(world), &ends)
        .unwrap_or(u64::MAX)
}

impl Estimate {
    /// The estimate for `scenario`, with checkpoints every `checkpoint_every`.
    pub fn of(scenario: &Scenario, checkpoint_every: Option<SimTime>) -> Estimate {
        let steps = scenario.steps;
        let mut fmu_steps = (0u64, None);
        let mut most = 0;
        for (i, f) in scenario.fmus.iter().enumerate() {
            let n = scenario.duration.0 / f.step.0.max(1);
            fmu_steps.0 = fmu_steps.0.saturating_add(n);
            if n > most {
                (most, fmu_steps.1) = (n, Some(i));
            }
        }
        let decimation = scenario.output.decimation.max(1);
        // Every decimation-th step from step 0, and the last step always.
        let trace_rows = steps / decimation + 1 + u64::from(!steps.is_multiple_of(decimation));
        let per_body = if scenario.output.trace_rotation {
            6 + ROTATION_COLUMNS.len()
        } else {
            6
        } as u64;
        let trace_columns = 1
            + 2 * scenario.links.len() as u64
            + per_body * scenario.output.trace_bodies.len() as u64
            + INVARIANT_COLUMNS.len() as u64;
        // The header row, then the values (the bound left the header out: 17.9 MB "at
        // most" for a 300×300 grid whose trace.csv is 21.1 MB).
        let trace_bytes = trace_rows
            .saturating_mul(trace_columns)
            .saturating_mul(BYTES_PER_VALUE)
            .saturating_add(trace_columns.saturating_mul(BYTES_PER_HEADER));
        let checkpoints = checkpoint_every
            .filter(|e| e.0 > 0)
            .map_or(0, |e| scenario.duration.0 / e.0);
        // `cholesky_pcg` keeps a simplicial factor, whose entries are the pattern's
        // true fill: at most the supernodal layout's (which stores its blocks dense)
        // that `factor_entries` counts above 1000 links, so the estimate bounds it.
        let exact = matches!(
            scenario.solver,
            crate::scenario::model::Solver::Cholesky
                | crate::scenario::model::Solver::CholeskyPcg { .. }
        );
        let factor_entries =
            if exact && scenario.links.len() > crate::multibody::solver::DENSE_MAX_LINKS {
                factor_entries(scenario)
            } else {
                0
            };
        let extra_rows =
            (scenario.links.len() as u64).saturating_sub(2 * scenario.bodies.len() as u64);
        let memory_without_factor = MEMORY_BASE
            .saturating_add(MEMORY_PER_BODY.saturating_mul(scenario.bodies.len() as u64))
            .saturating_add(MEMORY_PER_EXTRA_ROW.saturating_mul(extra_rows))
            .saturating_add(MEMORY_PER_SPRING.saturating_mul(scenario.springs.len() as u64));
        let memory_bytes = memory_without_factor
            .saturating_add(BYTES_PER_FACTOR_ENTRY.saturating_mul(factor_entries));
        Estimate {
            steps,
            fmu_steps,
            trace_rows,
            trace_columns,
            trace_bytes,
            checkpoints,
            factor_entries,
            memory_without_factor,
            memory_bytes,
        }
    }

    /// Checks the estimate against `limits`; the error names the fields and the flag.
    pub fn check(&self, limits: &Limits) -> Result<()> {
        if self.steps > limits.max_steps {
            return Err(Error::invalid(
                "duration",
                format!(
                    "duration / dt gives {} steps, above the limit of {} (raise it with \
                     --max-steps, or shorten the run)",
                    self.steps, limits.max_steps
                ),
            ));
        }
        if let (fmu, Some(i)) = self.fmu_steps {
            let total = self.steps.saturating_add(fmu);
            if total > limits.max_steps {
                return Err(Error::invalid(
                    format!("fmus[{i}].step"),
                    format!(
                        "the run takes {} integration steps and {fmu} FMU steps, {total} \
                         together, above the limit of {} (a longer FMU step, a shorter run, \
                         or --max-steps)",
                        self.steps, limits.max_steps
                    ),
                ));
            }
        }
        if self.trace_bytes > limits.max_output_bytes {
            return Err(Error::invalid(
                "output.decimation",
                format!(
                    "trace.csv would hold up to {} bytes ({} rows × {} values), above the \
                     limit of {} bytes (raise output.decimation, trace fewer bodies, or \
                     --max-output)",
                    self.trace_bytes, self.trace_rows, self.trace_columns, limits.max_output_bytes
                ),
            ));
        }
        if self.memory_bytes > limits.max_memory_bytes && self.factor_entries == u64::MAX {
            // The factor's size is unknown: its symbolic analysis could not be allocated
            // (under an address-space limit) or its pattern is beyond faer's indices.
            return Err(Error::invalid(
                "solver",
                format!(
                    "the exact solve's factor could not be sized: its symbolic analysis \
                     itself could not be allocated in this process (an address-space limit, \
                     `ulimit -v`, below what it needs) — `\"solver\": {{\"kind\": \"cg\"}}` \
                     needs about {} MB",
                    self.memory_without_factor.div_ceil(1_000_000)
                ),
            ));
        }
        if self.memory_bytes > limits.max_memory_bytes {
            let cg = self.memory_without_factor;
            let hint = if self.factor_entries > 0 {
                format!(
                    "; the exact solve's factor alone is up to {} entries — `\"solver\": \
                     {{\"kind\": \"cg\"}}` needs about {} MB",
                    self.factor_entries,
                    cg.div_ceil(1_000_000)
                )
            } else {
                String::new()
            };
            return Err(Error::invalid(
                if self.factor_entries > 0 {
                    "solver"
                } else {
                    "model"
                },
                format!(
                    "a run needs about {} MB of memory, above {} of {} MB{hint} (or \
                     raise --max-memory where the memory is there)",
                    self.memory_bytes.div_ceil(1_000_000),
                    limits.max_memory_from.describe(),
                    limits.max_memory_bytes / 1_000_000
                ),
            ));
        }
        if self.checkpoints > limits.max_checkpoints {
            return Err(Error::invalid(
                "--checkpoint-every",
                format!(
                    "gives {} checkpoints, above the limit of {} (checkpoint less often, or \
                     --max-checkpoints)",
                    self.checkpoints, limits.max_checkpoints
                ),
            ));
        }
        Ok(())
    }
}

/// Checks the integration steps a study (`tradeoff`, `stability-map`) takes over all its
/// runs, `total`, against [`DEFAULT_MAX_STEPS`]: what `run` refuses for one run, a study
/// refuses for the sum of its runs, before any of them starts. Its horizon is the one
/// time a user gives a study, so the error names `flag` (`--duration`).
pub fn check_study_steps(total: u64, flag: &str) -> Result<()> {
    if total > DEFAULT_MAX_STEPS {
        return Err(Error::invalid(
            flag,
            format!(
                "the study would integrate {total} steps over its runs, above the limit of \
                 {DEFAULT_MAX_STEPS} (shorten the horizon)"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(duration: f64, decimation: u64) -> Scenario {
        let text = format!(
            r#"{{"name": "b", "seed": 1, "duration": {duration}, "dt": 0.001,
                "model": {{"grid": {{"rows": 2, "cols": 3, "spacing": 1.0, "mass": 1.0, "size": 0.1}}}},
                "output": {{"decimation": {decimation}}}}}"#
        );
        crate::scenario::parse_str(&text, "b").expect("valid")
    }

    #[test]
    fn rows_and_columns_are_those_a_run_writes() {
        // 1.234 s = 1234 steps; every 100th from 0 (13 rows) and the last one.
        let e = Estimate::of(&scene(1.234, 100), None);
        assert_eq!((e.steps, e.trace_rows), (1234, 14));
        // t, w and f of 7 links, 6 values of each of 6 bodies, 7 invariants.
        assert_eq!(e.trace_columns, 1 + 14 + 36 + 7);
        let dir = std::env::temp_dir().join(format!("dsmcosim-budget-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        crate::run::run(&scene(1.234, 100), &dir).expect("runs");
        let trace = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
        assert_eq!(
            trace.lines().count() as u64,
            e.trace_rows + 1,
            "plus the header"
        );
        let values = trace.lines().nth(1).unwrap().split(',').count() as u64;
        assert_eq!(values, e.trace_columns);
        assert!(
            trace.len() as u64 <= e.trace_bytes,
            "the bound holds, header included"
        );
        let _ = std::fs::remove_dir_all(&dir);
        // A multiple of the decimation has no extra last row.
        assert_eq!(Estimate::of(&scene(1.2, 100), None).trace_rows, 13);
        // With each traced body's rotation: 7 more values per body.
        let mut rotating = scene(1.234, 100);
        rotating.output.trace_rotation = true;
        assert_eq!(
            Estimate::of(&rotating, None).trace_columns,
            e.trace_columns + 7 * 6
        );
    }

    /// The profile of `J M⁻¹ Jᵀ` in link order (row `k` from the lowest link sharing a
    /// body with link `k` to the diagonal): what a factorization in link order fills.
    fn profile(scenario: &Scenario) -> u64 {
        let mut lowest = vec![usize::MAX; scenario.bodies.len()];
        for (k, l) in scenario.links.iter().enumerate() {
            for b in [l.a, l.b] {
                lowest[b] = lowest[b].min(k);
            }
        }
        let rows = scenario.links.iter().enumerate();
        rows.map(|(k, l)| (k - lowest[l.a].min(lowest[l.b]) + 1) as u64)
            .sum()
    }

    /// The ordered factor of a 24×24 grid (1104 links) holds at least `A`'s own lower
    /// triangle and well under what the link order fills (the reason for ordering).
    #[test]
    fn the_ordered_factor_is_far_below_the_link_order_profile() {
        let s = crate::scenario::parse_str(
            r#"{"name": "g", "seed": 1, "duration": 0.01, "dt": 0.001,
                "model": {"grid": {"rows": 24, "cols": 24, "spacing": 1, "mass": 1, "size": 0.1}}}"#,
            "g",
        )
        .unwrap();
        let e = Estimate::of(&s, None);
        // Each link shares a body with at most 6 others; A's lower triangle holds each
        // pair once, plus the diagonal.
        let lower: u64 = {
            let mut per_body = vec![0u64; s.bodies.len()];
            for l in s.links.iter() {
                per_body[l.a] += 1;
                per_body[l.b] += 1;
            }
            s.links.len() as u64 + per_body.iter().map(|d| d * (d - 1) / 2).sum::<u64>()
        };
        assert!(e.factor_entries >= lower, "{} < {lower}", e.factor_entries);
        let profile = profile(&s);
        assert!(
            e.factor_entries * 2 < profile,
            "ordered {} vs profile {profile}",
            e.factor_entries
        );
        // Too few links for the sparse path: no factor entries.
        assert_eq!(Estimate::of(&scene(1.0, 1), None).factor_entries, 0);
    }

    #[test]
    fn each_limit_names_its_field_and_flag() {
        let e = Estimate::of(&scene(1.0, 1), SimTime::from_secs_f64(0.001));
        let tight = |f: fn(&mut Limits)| {
            let mut l = Limits::default();
            f(&mut l);
            e.check(&l).unwrap_err().to_string()
        };
        assert!(e.check(&Limits::default()).is_ok());
        let m = tight(|l| l.max_steps = 999);
        assert!(m.contains("duration") && m.contains("--max-steps"), "{m}");
        let m = tight(|l| l.max_output_bytes = 1000);
        assert!(
            m.contains("output.decimation") && m.contains("--max-output"),
            "{m}"
        );
        let m = tight(|l| l.max_memory_bytes = 1_000_000);
        assert!(m.contains("model") && m.contains("--max-memory"), "{m}");
        let m = tight(|l| {
            l.max_memory_bytes = 1_000_000;
            l.max_memory_from = MemoryLimitFrom::AddressSpace;
        });
        assert!(m.contains("RLIMIT_AS") && m.contains("--max-memory"), "{m}");
        let m = check_study_steps(DEFAULT_MAX_STEPS + 1, "--duration")
            .unwrap_err()
            .to_string();
        assert!(
            m.starts_with("--duration: ") && m.contains("10000000001 steps"),
            "{m}"
        );
        assert!(check_study_steps(DEFAULT_MAX_STEPS, "--duration").is_ok());
        let m = tight(|l| l.max_checkpoints = 10);
        assert!(
            m.contains("--checkpoint-every") && m.contains("1000 checkpoints"),
            "{m}"
        );
    }

    #[test]
    fn cgroup_limits_parse_and_unlimited_is_none() {
        assert_eq!(parse_cgroup_limit("4294967296\n"), Some(4_294_967_296));
        assert_eq!(parse_cgroup_limit("max\n"), None);
        assert_eq!(parse_cgroup_limit("9223372036854771712\n"), None);
        assert_eq!(parse_cgroup_limit(""), None);
        let (bound, _) = default_max_memory();
        assert!(bound <= DEFAULT_MAX_MEMORY_BYTES);
    }
}
