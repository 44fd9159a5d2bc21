//! JSON text → [`ScenarioFile`] → [`Scenario`]: parsing, checking, defaults, id resolution.
//!
//! Every problem is reported once, as a one-line [`Error`] that names where it is:
//!
//! - malformed JSON (and numbers serde_json cannot hold, such as `1e999`) is an
//!   [`Error::Parse`] with line and column, plus the field being read when known;
//! - a wrong type, a missing required key, an unknown key or a `null` is an
//!   [`Error::Invalid`] whose path is the field (`model.bodies[2].mass`), with serde's
//!   message and the line and column;
//! - a bad value is an [`Error::Invalid`] whose path is the field as it appears in the
//!   file (0-based indices: `forces[2].until`, `model.links[0].b`, `stabilizer.mu`) and
//!   whose message names the value (`must be > 0 (got -1)`).
//!
//! Times are converted to integer nanoseconds ([`SimTime`]) here, once; `duration` must be
//! a whole number of `dt` steps in nanoseconds, so the step count is exact.
//!
//! The stages run in file-dependency order: the model (`bodies`), whose ids the later
//! sections name; then `partition`, which needs the bodies and links; then `network`
//! and `channels`, whose routes are the partition's borders.

mod bodies;
mod channels;
pub(super) mod checks;
mod controller;
mod fmus;
mod joints;
mod network;
mod partition;
mod schedule;
mod springs;

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Vector3;
use serde_json::error::Category;

use self::bodies::{model, Ids, Model};
use self::channels::channels;
use self::checks::{
    finite, foreign, magnitude, magnitude_vector, non_negative, num, positive, positive_magnitude,
    time, whole_nanos,
};
use self::joints::joint_rows;
pub use self::joints::MAX_JOINTS;
use self::network::{check_tdma, network};
use self::partition::partition;
pub use self::partition::{
    DEFAULT_EXTRAPOLATE, DEFAULT_LINES_ABOVE, DEFAULT_TANK, DEFAULT_TANK_SHARE, MAX_TANK_SHARE,
};
use super::file::{
    BodyModelFile, ForceFile, IntegratorFile, MeasurementFile, ModelFile, OutputFile, ScenarioFile,
    SolverFile, SolverKind, StabilizerFile, StabilizerKind, DEFAULT_BAUMGARTE_RATE,
    DEFAULT_CG_MAX_ITERATIONS, DEFAULT_CG_TOLERANCE, DEFAULT_MEASUREMENT_PERIOD,
    DEFAULT_PCG_MAX_ITERATIONS, DEFAULT_PCG_REFACTOR_EVERY, DEFAULT_PCG_TOLERANCE,
    DEFAULT_SMC_EPSILON, DEFAULT_SMC_K, DEFAULT_SMC_MU,
};
use super::model::{
    BodyModel, ForceSpec, GhostMode, Integrator, LoadAt, NetworkSpec, OutputSpec, Scenario, Solver,
    Stabilizer,
};
use crate::error::{Error, Result};
use crate::kernel::SimTime;

/// Reads, parses and validates a scenario file.
///
/// A file that cannot be read is an [`Error::Io`]; a file that is not UTF-8 is an
/// [`Error::Parse`] at the first bad byte; everything else is as [`parse_str`].
pub fn load(path: &Path) -> Result<Scenario> {
    let bytes = crate::input::read(path)?;
    let text = utf8(&bytes, &path.display().to_string())?;
    parse_at(text, &path.display().to_string(), Some(path))
}

/// Parses and validates the text of the scenario file at `path` (`None`: not from a
/// file): relative FMU paths are read from the file's directory.
pub fn parse_at(text: &str, label: &str, path: Option<&Path>) -> Result<Scenario> {
    let mut file = parse_file(text, label)?;
    file.base_dir = path.map(|p| {
        p.parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf()
    });
    validate(file)
}

/// Parses and validates the bytes of a scenario file; `label` names it in errors. Bytes
/// that are not UTF-8 are an [`Error::Parse`] at the first bad byte.
pub fn from_bytes(bytes: &[u8], label: &str) -> Result<Scenario> {
    parse_str(utf8(bytes, label)?, label)
}

/// The bytes of a scenario file as text, or an [`Error::Parse`] at the first bad byte.
fn utf8<'a>(bytes: &'a [u8], label: &str) -> Result<&'a str> {
    let label = label.to_string();
    std::str::from_utf8(bytes).map_err(|e| {
        let before = &bytes[..e.valid_up_to()];
        let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
        let column = 1 + before.iter().rev().take_while(|&&b| b != b'\n').count();
        Error::Parse {
            file: label.clone(),
            message: "invalid UTF-8".to_string(),
            line,
            column,
        }
    })
}

/// Parses and validates scenario JSON; `file_label` names the source in parse errors.
pub fn parse_str(text: &str, file_label: &str) -> Result<Scenario> {
    validate(parse_file(text, file_label)?)
}

/// Parses scenario JSON into the raw [`ScenarioFile`] without checking values.
///
/// A leading UTF-8 byte-order mark is skipped (some Windows editors write one).
pub fn parse_file(text: &str, file_label: &str) -> Result<ScenarioFile> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut de = serde_json::Deserializer::from_str(text);
    let file: ScenarioFile = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        match other_kind(text) {
            Some(kind) => Error::invalid(file_label, kind),
            _ => serde_error(e.inner(), &path, file_label, text),
        }
    })?;
    // Anything but whitespace after the top-level object is a syntax error.
    de.end()
        .map_err(|e| serde_error(&e, ".", file_label, text))?;
    Ok(file)
}

/// What a JSON file that is not a scenario but another of dsmcosim's files is, and what
/// to do with it, when its top-level keys say so: a sweep file, a run's `summary.json`, a
/// sweep point's `done.json`.
fn other_kind(text: &str) -> Option<&'static str> {
    let v: serde_json::Value = serde_json::from_str(text).ok()?;
    let has = |k: &str| v.get(k).is_some();
    if has("base") && (has("axes") || has("overrides")) {
        Some("is a sweep file (it has `base` and `axes`), not a scenario: run its points with `dsmcosim sweep FILE -o DIR`")
    } else if has("digest") && has("scenario") && has("status") {
        Some(
            "is a run's summary.json, not a scenario: the run's scenario is the \
             scenario.json beside it",
        )
    } else if has("scenario_digest") && has("base_digest") {
        Some(
            "is a sweep point's done.json, not a scenario: the point's scenario is the \
             scenario.json beside it",
        )
    } else {
        None
    }
}

/// Maps a serde_json error at field `path` (serde_path_to_error's form; `.` = the top
/// level) to a one-line [`Error`]; `text` is the parsed source, from which a syntax
/// error quotes the offending token (`NaN`, `Infinity`, `1e999`, …).
fn serde_error(err: &serde_json::Error, path: &str, file_label: &str, text: &str) -> Error {
    let (line, column) = (err.line(), err.column());
    // serde_json's Display appends " at line L column C"; keep only the message.
    let full = err.to_string();
    let message = full
        .strip_suffix(&format!(" at line {line} column {column}"))
        .unwrap_or(&full);
    let message = one_line(message);
    // `.` is the top level, `?` a position serde_path_to_error could not name.
    let path = (path != "." && path != "?").then(|| one_line(path));
    // serde_json reports column 0 for an error before the first character.
    let column = column.max(1);
    match err.classify() {
        Category::Data => Error::Invalid {
            path: path.unwrap_or_else(|| "top level".to_string()),
            message: format!(
                "{} (line {line}, column {column})",
                with_suggestion(&message)
            ),
        },
        Category::Syntax | Category::Eof | Category::Io => {
            let token = token_at(text, line, column);
            let message = match token.as_deref() {
                Some(t @ ("NaN" | "Infinity" | "-Infinity" | "inf" | "-inf" | "nan")) => {
                    format!("{message}: got `{t}`, and JSON numbers must be finite")
                }
                Some(t) if message.starts_with("number out of range") => {
                    format!("{message}: got `{t}`, beyond the largest finite f64")
                }
                Some(t) => format!("{message} (got `{t}`)"),
                None => message,
            };
            Error::Parse {
                file: one_line(file_label),
                message: match path {
                    Some(path) => format!("{message} (in `{path}`)"),
                    None => message,
                },
                line,
                column,
            }
        }
    }
}

/// serde's "unknown field `x`, expected one of `a`, `b`, …" (or "unknown variant")
/// with the listing replaced by the nearest name when one is close, as cargo does for a
/// mistyped subcommand: "unknown field `intergrator`; did you mean `integrator`?". A
/// name is close when at most a third of its letters (at least one) differ; with no
/// close name the full listing stays.
pub fn with_suggestion(message: &str) -> String {
    let unknown = ["unknown field `", "unknown variant `"]
        .iter()
        .find_map(|p| {
            message
                .strip_prefix(p)
                .map(|rest| (&p[..p.len() - 2], rest))
        });
    let Some((what, rest)) = unknown else {
        return message.to_string();
    };
    let Some((name, listing)) = rest.split_once('`') else {
        return message.to_string();
    };
    let candidates: Vec<&str> = listing.split('`').skip(1).step_by(2).collect();
    let nearest = candidates
        .iter()
        .map(|c| (strsim::damerau_levenshtein(name, c), *c))
        .min();
    match nearest {
        Some((d, c)) if d <= (c.chars().count() / 3).max(1) => {
            format!("{what} `{name}`; did you mean `{c}`?")
        }
        _ => message.to_string(),
    }
}

/// The word-like token (letters, digits, `+ - .`) around 1-based `line`/`column` of
/// `text`, where serde_json reports a syntax error (at its start or its end).
fn token_at(text: &str, line: usize, column: usize) -> Option<String> {
    let chars: Vec<char> = text.lines().nth(line.checked_sub(1)?)?.chars().collect();
    let word = |c: char| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.');
    let at = column.checked_sub(1)?.min(chars.len().checked_sub(1)?);
    if !word(chars[at]) {
        return None;
    }
    let start = (0..=at).rev().take_while(|&i| word(chars[i])).last()?;
    let end = (at..chars.len()).take_while(|&i| word(chars[i])).last()?;
    let token: String = chars[start..=end].iter().collect();
    (token.chars().count() <= 40).then_some(token)
}

/// Escapes control characters (a key may contain an escaped newline) so that every
/// error stays on one line.
fn one_line(s: &str) -> String {
    let mut out = String::with_capacity(s.len().min(4 * QUOTED_MAX));
    // A value quoted between backticks (serde's `unknown variant `…``) longer than
    // QUOTED_MAX characters is cut, so a 100 kB string in a file gives a short message.
    let mut quoted = None::<usize>;
    for c in s.chars() {
        if c == '`' {
            if let Some(n) = quoted.take() {
                if n > QUOTED_MAX {
                    out.push_str(&format!("… ({n} characters)"));
                }
            } else {
                quoted = Some(0);
            }
        } else if let Some(n) = quoted.as_mut() {
            *n += 1;
            if *n > QUOTED_MAX {
                continue;
            }
        }
        if c.is_control() {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    out
}

/// Longest value an error message quotes in full [characters].
const QUOTED_MAX: usize = 64;

/// Validates a parsed file and converts it into a [`Scenario`].
///
/// Defaults are applied as documented on [`ScenarioFile`]; body ids are resolved to
/// indices into [`Scenario::bodies`] (file order; a grid expands row by row).
pub fn validate(file: ScenarioFile) -> Result<Scenario> {
    if file.name.trim().is_empty() {
        return Err(Error::invalid("name", "must not be empty"));
    }
    if let Some(d) = &file.description {
        let chars = d.chars().count();
        if chars > crate::scenario::file::MAX_DESCRIPTION_CHARS {
            return Err(Error::invalid(
                "description",
                format!(
                    "has {chars} characters; at most {} are allowed",
                    crate::scenario::file::MAX_DESCRIPTION_CHARS
                ),
            ));
        }
    }
    let (dt, duration) = step_and_duration(file.dt, file.duration)?;
    let integrator = match file.integrator {
        IntegratorFile::Euler => Integrator::Euler,
        IntegratorFile::SymplecticEuler => Integrator::SymplecticEuler,
        IntegratorFile::Rk4 => Integrator::Rk4,
    };
    let stabilizer = match &file.stabilizer {
        Some(section) => stabilizer(section)?,
        None => default_stabilizer(&file.model),
    };
    let solver = solver(&file.solver)?;

    let Model {
        bodies,
        mut links,
        mut body_model,
        ids,
    } = model(
        &file.model,
        file.body_model,
        loads_needing_rotation(&file),
        !file.fmus.is_empty(),
    )?;
    if !file.model.joints.is_empty() {
        if file.body_model == BodyModelFile::PointMass {
            return Err(Error::invalid(
                "model.joints",
                "joints turn their bodies: they need body_model \"rigid\" or \"auto\" \
                 (got \"point_mass\")",
            ));
        }
        body_model = BodyModel::Rigid;
        links.extend(joint_rows(&file.model.joints, &ids, &bodies)?);
    }
    let springs = springs::springs(&file.model.springs, &ids, &bodies)?;
    if let Some(i) = springs.iter().position(|s| {
        s.anchor_a != Vector3::zeros() || (s.b.is_some() && s.anchor_b != Vector3::zeros())
    }) {
        if file.body_model == BodyModelFile::PointMass {
            return Err(Error::invalid(
                format!("model.springs[{i}]"),
                "an anchor off a body's centre turns the body: it needs body_model \
                 \"rigid\" or \"auto\" (got \"point_mass\")",
            ));
        }
        body_model = BodyModel::Rigid;
    }
    let mut forces = file
        .forces
        .iter()
        .enumerate()
        .map(|(i, f)| force(&format!("forces[{i}]"), f, &ids))
        .collect::<Result<Vec<_>>>()?;
    for (i, t) in file.torques.iter().enumerate() {
        forces.push(torque(&format!("torques[{i}]"), t, &ids)?);
    }
    let gravity = match file.model.gravity {
        Some(g) => Some(magnitude_vector("model.gravity", g)?),
        None => None,
    };
    let max_violation = positive("divergence.max_violation", file.divergence.max_violation)?;
    let measurement_period = measurement(&file.measurement, dt, duration)?;
    let output = output(&file.output, &ids, bodies.len())?;
    let partition = match &file.partition {
        Some(p) => Some(partition(
            p,
            file.model.grid.as_ref(),
            &ids,
            (&bodies, &links),
            !file.model.joints.is_empty(),
        )?),
        None => None,
    };
    // A spring's force needs both its ends' states every step: it lives on one node.
    if let Some(p) = &partition {
        for (i, s) in springs.iter().enumerate() {
            if let Some(b) = s.b.filter(|&b| p.node_of[b] != p.node_of[s.a]) {
                return Err(Error::invalid(
                    format!("model.springs[{i}]"),
                    format!(
                        "joins body {} on node {} to body {} on node {}: a spring across \
                         a partition border is not supported (put both bodies on one node, \
                         or join them by a link or joint)",
                        bodies[s.a].id,
                        p.node_of[s.a] + 1,
                        bodies[b].id,
                        p.node_of[b] + 1
                    ),
                ));
            }
        }
    }
    // Held ghosts cannot carry a border joint: a joint's rows pull its far body to the
    // near one every step, which a ghost frozen between arrivals cannot follow (the
    // shipped crane and hanging chain failed within 21 ms, the solve or the joint).
    if let Some(p) = partition.as_ref().filter(|p| p.ghosts == GhostMode::Hold) {
        let border = links
            .iter()
            .find(|l| l.joint.is_some() && !l.world && p.node_of[l.a] != p.node_of[l.b]);
        if let Some(l) = border {
            let j = l.joint.map_or(0, |(j, _)| j as usize);
            return Err(Error::invalid(
                "partition.ghosts",
                format!(
                    "\"hold\" freezes a ghost between arrivals, which a border joint cannot \
                     follow: model.joints[{j}] joins body {} on node {} to body {} on node {}; \
                     use \"integrate\" (the default), or keep the joint's bodies on one node",
                    bodies[l.a].id,
                    p.node_of[l.a] + 1,
                    bodies[l.b].id,
                    p.node_of[l.b] + 1
                ),
            ));
        }
    }
    let signal_channels: Vec<&str> = file
        .connections
        .iter()
        .map(|c| c.channel.as_str())
        .collect();
    let channels = channels(
        &file.channels,
        partition.as_ref(),
        &links,
        dt,
        &signal_channels,
    )?;
    let fmus::Fmus {
        specs: fmus,
        connections,
        cost_signals,
    } = fmus::fmus(
        &file.fmus,
        &file.connections,
        &fmus::ModelView {
            ids: &ids,
            partitioned: partition.is_some(),
        },
        file.measurement.signals.as_deref(),
        file.base_dir.as_deref(),
        (dt, duration),
        &channels,
    )?;
    let fmu_nodes = fmus.iter().map(|f| f.node + 1).max().unwrap_or(0);
    let network = network(&file.network, partition.as_ref(), fmu_nodes, &channels)?;
    if matches!(network, NetworkSpec::Tdma(_)) {
        if let Some(i) = file.channels.iter().position(|c| c.phase.is_some()) {
            return Err(Error::invalid(
                format!("channels[{i}].phase"),
                "is not used by a \"tdma\" network (the slot list places the samples)",
            ));
        }
    }
    let controller = match &file.controller {
        Some(c) => Some(controller::controller(
            c,
            &channels,
            dt,
            duration,
            measurement_period,
        )?),
        None => None,
    };
    let schedule = schedule::schedule(
        &file.schedule,
        &channels,
        controller.is_some(),
        (measurement_period, duration),
    )?;

    let scenario = Scenario {
        name: file.name,
        seed: file.seed,
        duration,
        dt,
        steps: duration.as_nanos() / dt.as_nanos(),
        integrator,
        stabilizer,
        solver,
        body_model,
        bodies: bodies.into(),
        links: links.into(),
        forces,
        gravity,
        springs,
        max_violation,
        measurement_period,
        output,
        partition,
        network,
        channels,
        controller,
        schedule,
        fmus,
        connections,
        cost_signals,
    };
    check_tdma(&scenario)?;
    fmus::forks_possible(&scenario)?;
    Ok(scenario)
}

/// `dt` and `duration` in nanoseconds: `dt` ≥ 1 ns and a whole number of nanoseconds,
/// `duration` a whole number of steps.
fn step_and_duration(dt_secs: f64, duration_secs: f64) -> Result<(SimTime, SimTime)> {
    positive("dt", dt_secs)?;
    let dt = time("dt", dt_secs)?;
    if dt == SimTime::ZERO {
        return Err(Error::invalid(
            "dt",
            format!("must be at least 1 ns (got {} s)", num(dt_secs)),
        ));
    }
    whole_nanos("dt", dt_secs)?;
    positive("duration", duration_secs)?;
    let duration = time("duration", duration_secs)?;
    if dt > duration {
        return Err(Error::invalid(
            "dt",
            format!(
                "must not exceed duration (got dt {} s > duration {} s)",
                num(dt_secs),
                num(duration_secs)
            ),
        ));
    }
    let rest = duration.as_nanos() % dt.as_nanos();
    if rest != 0 {
        return Err(Error::invalid(
            "duration",
            format!(
                "must be a whole number of dt steps (got {} s = {} steps of {} s + {})",
                num(duration_secs),
                duration.as_nanos() / dt.as_nanos(),
                num(dt_secs),
                SimTime(rest)
            ),
        ));
    }
    Ok((dt, duration))
}

/// The law of a scenario without a `stabilizer` section: the thesis's SMC on a scene
/// of distance links, Baumgarte's exact multipliers on a scene with joints.
///
/// Why by the model: on a joint the SMC law, which solves for `ż` and leaves the
/// turning of `J M⁻¹ Jᵀ` to its robustness term, does work. A ball joint held open by
/// the law's lag carries its reaction pair at two points, a couple that changes the
/// angular momentum; a heavy top's nutation grows, a conical pendulum diverges within
/// a second (docs/method.md §2.1 gives the measurements). The thesis's scenes have no
/// joints and keep its law and their digests.
fn default_stabilizer(model: &ModelFile) -> Stabilizer {
    if model.joints.is_empty() {
        Stabilizer::Smc {
            mu: DEFAULT_SMC_MU,
            k: DEFAULT_SMC_K,
            epsilon: DEFAULT_SMC_EPSILON,
        }
    } else {
        Stabilizer::Baumgarte {
            alpha: DEFAULT_BAUMGARTE_RATE,
            beta: DEFAULT_BAUMGARTE_RATE,
        }
    }
}

/// The `stabilizer` section, the thesis's SMC values or Baumgarte's defaults for any
/// omitted key.
fn stabilizer(s: &StabilizerFile) -> Result<Stabilizer> {
    match s.kind {
        StabilizerKind::Smc => {
            if s.alpha.is_some() {
                return Err(foreign("stabilizer.alpha", "smc"));
            }
            if s.beta.is_some() {
                return Err(foreign("stabilizer.beta", "smc"));
            }
            Ok(Stabilizer::Smc {
                mu: smc_mu(s.mu.unwrap_or(DEFAULT_SMC_MU))?,
                k: positive_magnitude("stabilizer.k", s.k.unwrap_or(DEFAULT_SMC_K))?,
                epsilon: positive_magnitude(
                    "stabilizer.epsilon",
                    s.epsilon.unwrap_or(DEFAULT_SMC_EPSILON),
                )?,
            })
        }
        StabilizerKind::Baumgarte => {
            for (key, value) in [("mu", s.mu), ("k", s.k), ("epsilon", s.epsilon)] {
                if value.is_some() {
                    return Err(foreign(&format!("stabilizer.{key}"), "baumgarte"));
                }
            }
            let alpha = s.alpha.unwrap_or(DEFAULT_BAUMGARTE_RATE);
            let beta = s.beta.unwrap_or(DEFAULT_BAUMGARTE_RATE);
            Ok(Stabilizer::Baumgarte {
                alpha: magnitude("stabilizer.alpha", non_negative("stabilizer.alpha", alpha)?)?,
                beta: magnitude("stabilizer.beta", non_negative("stabilizer.beta", beta)?)?,
            })
        }
    }
}

/// Shortest and longest SMC time constant μ [s]: from the nanosecond of the time grid
/// to about 30 years. The law divides by μ² and multiplies by it; at μ = 1e155 s, μ²
/// overflowed and the run stopped blaming a singular J M⁻¹ Jᵀ.
const SMC_MU_RANGE: (f64, f64) = (1e-9, 1e9);

/// `stabilizer.mu`, within [`SMC_MU_RANGE`].
fn smc_mu(mu: f64) -> Result<f64> {
    let mu = positive("stabilizer.mu", mu)?;
    let (lo, hi) = SMC_MU_RANGE;
    if !(lo..=hi).contains(&mu) {
        return Err(Error::invalid(
            "stabilizer.mu",
            format!(
                "must be from {} s to {} s (got {} s)",
                num(lo),
                num(hi),
                num(mu)
            ),
        ));
    }
    Ok(mu)
}

/// The `solver` section.
fn solver(s: &SolverFile) -> Result<Solver> {
    match s.kind {
        SolverKind::Cholesky | SolverKind::CholeskyAmd => {
            let name = if s.kind == SolverKind::Cholesky {
                "cholesky"
            } else {
                "cholesky_amd"
            };
            if s.max_iterations.is_some() {
                return Err(foreign("solver.max_iterations", name));
            }
            if s.tolerance.is_some() {
                return Err(foreign("solver.tolerance", name));
            }
            if s.refactor_every.is_some() {
                return Err(foreign("solver.refactor_every", name));
            }
            Ok(Solver::Cholesky)
        }
        SolverKind::CholeskyPcg => {
            let at_least_one = |field: &str, v: usize| {
                if v == 0 {
                    Err(Error::invalid(field, "must be ≥ 1 (got 0)"))
                } else {
                    Ok(v)
                }
            };
            let refactor_every = at_least_one(
                "solver.refactor_every",
                s.refactor_every.unwrap_or(DEFAULT_PCG_REFACTOR_EVERY),
            )?;
            let max_iterations = at_least_one(
                "solver.max_iterations",
                s.max_iterations.unwrap_or(DEFAULT_PCG_MAX_ITERATIONS),
            )?;
            let tolerance = s.tolerance.unwrap_or(DEFAULT_PCG_TOLERANCE);
            // A zero tolerance could never be met (round-off): every solve would
            // iterate to its budget and then factorize anyway.
            if !(tolerance > 0.0 && tolerance < 1.0) {
                return Err(Error::invalid(
                    "solver.tolerance",
                    format!("must be in (0, 1) for cholesky_pcg (got {tolerance})"),
                ));
            }
            Ok(Solver::CholeskyPcg {
                refactor_every,
                tolerance,
                max_iterations,
            })
        }
        SolverKind::Cg => {
            if s.refactor_every.is_some() {
                return Err(foreign("solver.refactor_every", "cg"));
            }
            let max_iterations = s.max_iterations.unwrap_or(DEFAULT_CG_MAX_ITERATIONS);
            if max_iterations == 0 {
                return Err(Error::invalid(
                    "solver.max_iterations",
                    "must be ≥ 1 (got 0)",
                ));
            }
            let tolerance = non_negative(
                "solver.tolerance",
                s.tolerance.unwrap_or(DEFAULT_CG_TOLERANCE),
            )?;
            Ok(Solver::ConjugateGradient {
                max_iterations,
                tolerance,
            })
        }
    }
}

/// The first load field that turns a body (a force off the centre, a torque), with its
/// value, for the body-model choice.
fn loads_needing_rotation(file: &ScenarioFile) -> Option<(String, Vec<f64>)> {
    let point = file.forces.iter().enumerate().find_map(|(i, f)| {
        f.point
            .filter(|p| *p != [0.0; 3])
            .map(|p| (format!("forces[{i}].point"), p.to_vec()))
    });
    // A zero torque turns nothing: point masses may carry one.
    point.or_else(|| {
        file.torques
            .iter()
            .enumerate()
            .find(|(_, t)| t.amplitude != [0.0; 3])
            .map(|(i, t)| (format!("torques[{i}].amplitude"), t.amplitude.to_vec()))
    })
}

/// One entry of `torques`: the time function of a force, applied as a pure torque.
fn torque(path: &str, t: &ForceFile, ids: &Ids) -> Result<ForceSpec> {
    if t.point.is_some() {
        return Err(Error::invalid(
            format!("{path}.point"),
            "a torque acts about the body's centre and has no point (a force at a point \
             gives its torque itself)",
        ));
    }
    let mut spec = force(path, t, ids)?;
    spec.applied = LoadAt::Torque;
    Ok(spec)
}

/// One entry of `forces`: body resolved, times in nanoseconds.
fn force(path: &str, f: &ForceFile, ids: &Ids) -> Result<ForceSpec> {
    let body = ids.index(&format!("{path}.body"), f.body)?;
    let amplitude = magnitude_vector(&format!("{path}.amplitude"), f.amplitude)?;
    let omega = finite(&format!("{path}.omega"), f.omega)?;
    let phase = finite(&format!("{path}.phase"), f.phase)?;
    let from = time(&format!("{path}.from"), f.from)?;
    let until = match f.until {
        None => None,
        Some(until) => {
            let until_path = format!("{path}.until");
            finite(&until_path, until)?;
            if until < f.from {
                return Err(Error::invalid(
                    until_path,
                    format!(
                        "must not be before from (got until {} s < from {} s)",
                        num(until),
                        num(f.from)
                    ),
                ));
            }
            Some(time(&until_path, until)?)
        }
    };
    let ramp = match &f.ramp {
        Some(r) => Some(controller::ramp(&format!("{path}.ramp"), r)?),
        None => None,
    };
    let applied = match f.point {
        Some(p) if p != [0.0; 3] => LoadAt::Point(magnitude_vector(&format!("{path}.point"), p)?),
        _ => LoadAt::Centre,
    };
    Ok(ForceSpec {
        body,
        amplitude,
        omega,
        phase,
        from,
        until,
        ramp,
        applied,
    })
}

/// The measurement period: explicit (checked), or the default rounded down to whole
/// steps (at least one) and capped at the duration.
fn measurement(m: &MeasurementFile, dt: SimTime, duration: SimTime) -> Result<SimTime> {
    let Some(secs) = m.period else {
        let default = SimTime::from_secs_f64(DEFAULT_MEASUREMENT_PERIOD).unwrap_or(duration);
        let whole_steps = (default.as_nanos() / dt.as_nanos()).max(1) * dt.as_nanos();
        return Ok(SimTime(whole_steps).min(duration));
    };
    let path = "measurement.period";
    positive(path, secs)?;
    let period = time(path, secs)?;
    if period < dt || period.as_nanos() % dt.as_nanos() != 0 {
        return Err(Error::invalid(
            path,
            format!(
                "must be a whole number of dt steps (got {} s with dt {} s)",
                num(secs),
                num(dt.as_secs_f64())
            ),
        ));
    }
    if period > duration {
        return Err(Error::invalid(
            path,
            format!(
                "must not exceed duration (got {} s > {} s)",
                num(secs),
                num(duration.as_secs_f64())
            ),
        ));
    }
    Ok(period)
}

/// The `output` section: ids resolved, defaults filled in.
fn output(o: &OutputFile, ids: &Ids, body_count: usize) -> Result<OutputSpec> {
    if o.decimation == 0 {
        return Err(Error::invalid("output.decimation", "must be ≥ 1 (got 0)"));
    }
    let list = |key: &str, list: &[u32]| -> Result<Vec<usize>> {
        let mut seen = BTreeMap::new();
        let mut indices = Vec::with_capacity(list.len());
        for (i, &id) in list.iter().enumerate() {
            let path = format!("output.{key}[{i}]");
            indices.push(ids.index(&path, id)?);
            if let Some(first) = seen.insert(id, i) {
                return Err(Error::invalid(
                    path,
                    format!("body {id} is listed twice (also output.{key}[{first}])"),
                ));
            }
        }
        Ok(indices)
    };
    let trace_bodies = match &o.trace_bodies {
        Some(ids) => list("trace_bodies", ids)?,
        None => (0..body_count).collect(),
    };
    let plot_bodies = match &o.plot_bodies {
        Some(ids) => list("plot_bodies", ids)?,
        None if body_count == 0 => Vec::new(),
        None if body_count == 1 => vec![0],
        None => vec![0, body_count - 1],
    };
    if o.network_decimation == 0 {
        return Err(Error::invalid(
            "output.network_decimation",
            "must be ≥ 1 (got 0)",
        ));
    }
    if o.timeline_cycles == 0 {
        return Err(Error::invalid(
            "output.timeline_cycles",
            "must be ≥ 1 (got 0)",
        ));
    }
    Ok(OutputSpec {
        decimation: o.decimation,
        trace_bodies,
        trace_rotation: o.trace_rotation,
        plot_bodies,
        network_decimation: o.network_decimation,
        timeline_cycles: o.timeline_cycles,
    })
}

#[cfg(test)]
mod tests {
    /// A mistyped key or variant names the nearest valid one instead of listing all;
    /// nothing close keeps the listing.
    #[test]
    fn a_mistyped_name_gets_the_nearest_valid_one() {
        let e = super::with_suggestion(
            "unknown field `intergrator`, expected one of `name`, `seed`, `integrator`, `dt`",
        );
        assert_eq!(e, "unknown field `intergrator`; did you mean `integrator`?");
        let e = super::with_suggestion(
            "unknown variant `rk5`, expected one of `euler`, `symplectic_euler`, `rk4`",
        );
        assert_eq!(e, "unknown variant `rk5`; did you mean `rk4`?");
        let far = "unknown field `zzzzzz`, expected one of `name`, `seed`";
        assert_eq!(super::with_suggestion(far), far);
        let other = "invalid type: string \"a\", expected f64";
        assert_eq!(super::with_suggestion(other), other);
    }

    use nalgebra::{UnitQuaternion, Vector3};

    use super::*;
    use crate::scenario::model::BodyModel;

    /// The thesis scene (method §3 and §7).
    const THESIS: &str = r#"{
        "name": "grid16_monolithic",
        "seed": 7,
        "duration": 30.0,
        "dt": 0.001,
        "integrator": "euler",
        "stabilizer": {"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1},
        "model": {
            "grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}
        },
        "forces": [
            {"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.0,
             "from": 0.0, "until": 12.0},
            {"body": 16, "amplitude": [0, 0, 20], "omega": 2.0, "from": 12.0, "until": 24.0}
        ]
    }"#;

    /// Two bodies 3 m apart on x, one link between them; `extra` keys are spliced in.
    fn pair(link: &str) -> String {
        format!(
            r#"{{"name": "pair", "seed": 1, "duration": 1.0, "dt": 0.01,
                "model": {{
                  "bodies": [{{"id": 10, "mass": 2.0, "size": 0.5, "position": [0, 0, 0]}},
                             {{"id": 20, "mass": 1.0, "size": 0.2, "position": [3, 0, 0]}}],
                  "links": [{link}]
                }}}}"#
        )
    }

    fn ok(text: &str) -> Scenario {
        match parse_str(text, "test.json") {
            Ok(s) => s,
            Err(e) => panic!("expected a valid scenario, got: {e}"),
        }
    }

    fn err(text: &str) -> String {
        match parse_str(text, "test.json") {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn thesis_scene_bodies_and_links() {
        let s = ok(THESIS);
        assert_eq!(s.name, "grid16_monolithic");
        assert_eq!(s.seed, 7);
        assert_eq!(s.bodies.len(), 16);
        assert_eq!(s.links.len(), 24);
        // Link 1 joins bodies 1–2, link 2 joins bodies 1–5 (0-based indices).
        assert_eq!((s.links[0].a, s.links[0].b), (0, 1));
        assert_eq!((s.links[1].a, s.links[1].b), (0, 4));
        assert!(s.links.iter().all(|l| l.length == 1.8));
        assert!(s.links.iter().all(|l| l.anchor_a == Vector3::zeros()));
        let last = &s.bodies[15];
        assert_eq!(last.id, 16);
        assert!((last.position - Vector3::new(5.4, 5.4, 0.0)).norm() < 1e-12);
        let cube = 0.2 * 0.2 / 6.0;
        assert!(s
            .bodies
            .iter()
            .all(|b| b.inertia == Vector3::repeat(cube) && b.mass == 1.0 && b.size == 0.2));
        assert!(s
            .bodies
            .iter()
            .all(|b| b.orientation == UnitQuaternion::identity()));
        assert_eq!(s.body_model, BodyModel::PointMass);
    }

    #[test]
    fn thesis_scene_times_and_defaults() {
        let s = ok(THESIS);
        assert_eq!(s.dt, SimTime(1_000_000));
        assert_eq!(s.duration, SimTime(30_000_000_000));
        assert_eq!(s.steps, 30_000);
        assert_eq!(s.integrator, Integrator::Euler);
        assert_eq!(
            s.stabilizer,
            Stabilizer::Smc {
                mu: 0.05,
                k: 10.0,
                epsilon: 0.1
            }
        );
        assert_eq!(s.solver, Solver::Cholesky);
        assert_eq!(s.max_violation, 1.0);
        assert_eq!(s.measurement_period, SimTime(1_000_000_000));
        assert_eq!(s.output.decimation, 10);
        assert_eq!(s.output.trace_bodies, (0..16).collect::<Vec<_>>());
        assert_eq!(s.output.plot_bodies, vec![0, 15]);
        assert_eq!(s.forces.len(), 2);
        assert_eq!(s.forces[1].body, 15);
        assert_eq!(s.forces[1].phase, 0.0);
        assert_eq!(s.forces[1].from, SimTime(12_000_000_000));
        assert_eq!(s.forces[1].until, Some(SimTime(24_000_000_000)));
        assert_eq!(s.forces[0].amplitude, Vector3::new(0.0, 0.0, 20.0));
    }

    #[test]
    fn stabilizer_section_defaults_each_missing_field() {
        let text = THESIS.replace(
            r#"{"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1}"#,
            r#"{"kind": "smc", "k": 3}"#,
        );
        let s = ok(&text);
        assert_eq!(
            s.stabilizer,
            Stabilizer::Smc {
                mu: 0.05,
                k: 3.0,
                epsilon: 0.1
            }
        );
        let text = THESIS.replace(
            r#"{"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1}"#,
            r#"{"kind": "baumgarte", "alpha": 5, "beta": 0}"#,
        );
        assert_eq!(
            ok(&text).stabilizer,
            Stabilizer::Baumgarte {
                alpha: 5.0,
                beta: 0.0
            }
        );
    }

    #[test]
    fn cg_solver_defaults() {
        let text = THESIS.replace(
            r#""integrator""#,
            r#""solver": {"kind": "cg"}, "integrator""#,
        );
        assert_eq!(
            ok(&text).solver,
            Solver::ConjugateGradient {
                max_iterations: 50,
                tolerance: 1e-10
            }
        );
    }

    #[test]
    fn centred_anchors_without_spin_give_point_masses() {
        let s = ok(&pair(r#"{"a": 10, "b": 20}"#));
        assert_eq!(s.body_model, BodyModel::PointMass);
        assert_eq!(s.links[0].length, 3.0);
        assert_eq!(s.output.plot_bodies, vec![0, 1]);
    }

    #[test]
    fn off_centre_anchor_gives_rigid_bodies() {
        let s = ok(&pair(r#"{"a": 10, "b": 20, "anchor_b": [-0.1, 0, 0]}"#));
        assert_eq!(s.body_model, BodyModel::Rigid);
        assert!((s.links[0].length - 2.9).abs() < 1e-15);
    }

    #[test]
    fn spinning_body_gives_rigid_bodies() {
        let text = pair(r#"{"a": 10, "b": 20}"#).replace(
            r#""position": [3, 0, 0]"#,
            r#""position": [3, 0, 0], "angular_velocity": [0, 0, 1]"#,
        );
        assert_eq!(ok(&text).body_model, BodyModel::Rigid);
        let rigid =
            pair(r#"{"a": 10, "b": 20}"#).replace(r#""seed""#, r#""body_model": "rigid", "seed""#);
        assert_eq!(ok(&rigid).body_model, BodyModel::Rigid);
    }

    #[test]
    fn explicit_point_mass_rejects_off_centre_anchor() {
        let text = pair(r#"{"a": 10, "b": 20, "anchor_a": [0.1, 0, 0]}"#)
            .replace(r#""seed""#, r#""body_model": "point_mass", "seed""#);
        assert_eq!(
            err(&text),
            "model.links[0].anchor_a: must be [0, 0, 0] with body_model \"point_mass\" \
             (got [0.1, 0, 0]); use \"rigid\" or \"auto\""
        );
    }

    #[test]
    fn defaulted_length_is_the_world_anchor_distance() {
        // Body 10 turned 90° about z: its anchor (1, 0, 0) sits at (0, 1, 0) in the world;
        // body 20's anchor (0, 0, 1) is unrotated, at (3, 0, 1).
        let half = std::f64::consts::FRAC_PI_4;
        let text = pair(r#"{"a": 10, "b": 20, "anchor_a": [1, 0, 0], "anchor_b": [0, 0, 1]}"#)
            .replace(
                r#""position": [0, 0, 0]"#,
                &format!(
                    r#""position": [0, 0, 0], "orientation": [{}, 0, 0, {}]"#,
                    half.cos(),
                    half.sin()
                ),
            );
        let s = ok(&text);
        let expected: f64 = (Vector3::new(0.0, 1.0, 0.0) - Vector3::new(3.0, 0.0, 1.0)).norm();
        assert!(
            (s.links[0].length - expected).abs() < 1e-12,
            "{}",
            s.links[0].length
        );
        assert_eq!(s.body_model, BodyModel::Rigid);
    }

    #[test]
    fn explicit_inertia_and_orientation_are_normalized() {
        let text = pair(r#"{"a": 10, "b": 20, "length": 2.5}"#).replace(
            r#""position": [0, 0, 0]"#,
            r#""position": [0, 0, 0], "inertia": [1, 2, 3], "orientation": [2, 0, 0, 0]"#,
        );
        let s = ok(&text);
        assert_eq!(s.bodies[0].inertia, Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(s.bodies[0].orientation, UnitQuaternion::identity());
        assert_eq!(s.bodies[1].inertia, Vector3::repeat(1.0 * 0.2 * 0.2 / 6.0));
        assert_eq!(s.links[0].length, 2.5);
    }

    #[test]
    fn measurement_default_is_rounded_to_steps_and_capped() {
        let short =
            pair(r#"{"a": 10, "b": 20}"#).replace(r#""duration": 1.0"#, r#""duration": 0.5"#);
        assert_eq!(ok(&short).measurement_period, SimTime(500_000_000));
        let odd = THESIS.replace(r#""dt": 0.001"#, r#""dt": 0.003"#);
        assert_eq!(ok(&odd).measurement_period, SimTime(999_000_000));
        let explicit = THESIS.replace(r#""seed""#, r#""measurement": {"period": 2.5}, "seed""#);
        assert_eq!(ok(&explicit).measurement_period, SimTime(2_500_000_000));
    }

    #[test]
    fn output_lists_resolve_ids_in_the_order_given() {
        let text = THESIS.replace(
            r#""seed""#,
            r#""output": {"decimation": 1, "trace_bodies": [16, 2], "plot_bodies": [5]}, "seed""#,
        );
        let out = ok(&text).output;
        assert_eq!(out.decimation, 1);
        assert_eq!(out.trace_bodies, vec![15, 1]);
        assert_eq!(out.plot_bodies, vec![4]);
    }

    #[test]
    fn serde_errors_name_the_field_and_stay_on_one_line() {
        let unknown = THESIS.replace(r#""rows": 4"#, r#""rows": 4, "colour": 1"#);
        let e = err(&unknown);
        assert!(e.starts_with("model.grid"), "{e}");
        assert!(e.contains("unknown field `colour`"), "{e}");
        let typed = THESIS.replace(r#""mass": 1.0"#, r#""mass": "heavy""#);
        let e = err(&typed);
        assert!(
            e.starts_with("model.grid.mass: invalid type: string"),
            "{e}"
        );
        let null = THESIS.replace(r#""until": 12.0"#, r#""until": null"#);
        assert!(err(&null).starts_with("forces[0].until: invalid type: null"));
        let syntax = THESIS.replace(r#""seed": 7,"#, r#""seed": 7"#);
        match parse_str(&syntax, "thesis.json") {
            Err(Error::Parse { line, column, .. }) => assert_eq!((line, column), (4, 9)),
            other => panic!("expected a parse error, got {other:?}"),
        }
        let key = THESIS.replace(r#""seed""#, r#""se\ned""#);
        let e = err(&key);
        assert!(!e.contains('\n') && e.contains(r"se\ned"), "{e}");
    }
}
