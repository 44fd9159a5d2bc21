//! From a sweep file to its points: checking the definition ([`plan`], which needs no
//! base scenario, so `sweep-merge` can use it), then building and validating every
//! point's scenario ([`expand`]).

use rayon::prelude::*;
use serde_json::Value;

use super::file::{AxisFile, Combine, SweepFile};
use super::pointer::Pointer;
use crate::error::{Error, Result};

/// `sweep.csv`'s fixed columns, in the groups it writes them ([`super::table`]): before
/// the axes; after them (and `rep`); after `unpaired_mean_cost_<method>`; last. With `rep` and
/// the `unpaired_mean_cost_`, `paired_` and `tau_` prefixes they are the names an axis may
/// not take.
pub const LEADING_COLUMNS: [&str; 2] = ["index", "point"];
/// See [`LEADING_COLUMNS`].
pub const STATUS_COLUMNS: [&str; 6] = [
    "seed",
    "status",
    "diverged_at",
    "diverged_node",
    "diverged_where",
    "mean_cost",
];
/// See [`LEADING_COLUMNS`].
pub const LOSS_COLUMN: &str = "lost_frames";
/// The columns of each paired comparison, `paired_<column>_<baseline>`, in order
/// (summary.json → `paired`, method §5): ratio of the means, windows, wins, losses,
/// mean difference, the 95 % paired-t interval's ends (secondary), the sign test's p
/// and the verdict by that sign test (5 %, uncorrected).
pub const PAIRED_COLUMNS: [&str; 9] = [
    "ratio", "n", "wins", "losses", "diff", "ci_low", "ci_high", "p", "verdict",
];
/// See [`LEADING_COLUMNS`].
pub const TRAILING_COLUMNS: [&str; 2] = ["bandwidth", "digest"];

/// Whether `name` is a column `sweep.csv` already has.
fn reserved(name: &str) -> bool {
    LEADING_COLUMNS
        .iter()
        .chain(&STATUS_COLUMNS)
        .chain(&TRAILING_COLUMNS)
        .chain(&["rep", LOSS_COLUMN])
        .any(|&c| c == name)
        || name.starts_with("unpaired_mean_cost_")
        || name.starts_with("paired_")
        || name.starts_with("tau_")
}

/// One checked axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Column name.
    pub name: String,
    /// Where its values go.
    pub pointer: Pointer,
    /// Its values, in file order (a range already expanded).
    pub values: Vec<Value>,
    /// Short names of the values for `sweep.csv` and plot legends, one per value; `None`
    /// when the file gives none (then every value is a number or a string).
    pub labels: Option<Vec<String>>,
}

impl Axis {
    /// The name of value `v` in `sweep.csv` and plots: its `labels` entry, else a
    /// number as it is, else a string's text.
    pub fn label(&self, v: usize) -> String {
        if let Some(labels) = &self.labels {
            return labels[v].clone();
        }
        match &self.values[v] {
            Value::String(s) => s.clone(),
            other => other.to_string(),
        }
    }

    /// The values as numbers, if every one is a number.
    pub fn numbers(&self) -> Option<Vec<f64>> {
        self.values.iter().map(Value::as_f64).collect()
    }
}

/// A checked sweep definition: the axes and, per point, which value of each axis it
/// takes.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Sweep name.
    pub name: String,
    /// How the axes combine.
    pub combine: Combine,
    /// The axes, in file order.
    pub axes: Vec<Axis>,
    /// Fixed values, in the pointers' sorted order.
    pub overrides: Vec<(Pointer, Value)>,
    /// Runs of each configuration (`repeat`, ≥ 1): point `i` is repetition
    /// `i mod repeat` of configuration `i / repeat`.
    pub repeat: usize,
    /// `points[i][k]`: index into `axes[k].values` of point `i`.
    pub points: Vec<Vec<usize>>,
}

impl Plan {
    /// The axis values of point `i`, in axis order.
    pub fn values(&self, i: usize) -> Vec<Value> {
        self.points[i]
            .iter()
            .zip(&self.axes)
            .map(|(&v, a)| a.values[v].clone())
            .collect()
    }

    /// Repetition of point `i` (0-based; 0 without `repeat`).
    pub fn rep(&self, i: usize) -> usize {
        i % self.repeat
    }

    /// `name = label, …` of point `i`, for messages.
    pub fn describe(&self, i: usize) -> String {
        let mut parts: Vec<String> = self
            .axes
            .iter()
            .zip(&self.points[i])
            .map(|(a, &v)| format!("{} = {}", a.name, a.label(v)))
            .collect();
        if self.repeat > 1 {
            parts.push(format!("rep = {}", self.rep(i)));
        }
        parts.join(", ")
    }

    /// The key point `i`'s seed derives from: BLAKE3 of its configuration — each
    /// axis's pointer and value (compact JSON), in pointer order — and its repetition,
    /// first 8 bytes little-endian. It does not depend on the point's index, so adding
    /// a value to an axis leaves every other point's seed (and its `--resume` entry)
    /// unchanged.
    pub fn seed_key(&self, i: usize) -> u64 {
        let mut parts: Vec<(String, String)> = self
            .axes
            .iter()
            .zip(&self.points[i])
            .map(|(a, &v)| (a.pointer.to_string(), a.values[v].to_string()))
            .collect();
        parts.sort();
        let mut text = String::new();
        for (pointer, value) in parts {
            text.push_str(&format!("{pointer}={value}\n"));
        }
        text.push_str(&format!("rep={}", self.rep(i)));
        let hash = blake3::hash(text.as_bytes());
        let mut bytes = [0u8; 8];
        bytes.copy_from_slice(&hash.as_bytes()[..8]);
        u64::from_le_bytes(bytes)
    }

    /// The name of point `i`'s directory (`points/<key>/`) and the suffix of its
    /// scenario's name: [`Plan::seed_key`] in 16 hex digits, so a point keeps its
    /// directory, its files' bytes and its `--resume` entry when other points are added.
    pub fn key(&self, i: usize) -> String {
        format!("{:016x}", self.seed_key(i))
    }
}

/// SplitMix64's output function (Steele, Lea, Flood 2014): a bijection of `u64` whose
/// outputs for consecutive inputs are statistically independent.
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of a point with configuration key `key` ([`Plan::seed_key`]) of a sweep over a
/// base scenario with seed `base`: `splitmix64(base ^ splitmix64(key))`.
pub fn derive_seed(base: u64, key: u64) -> u64 {
    splitmix64(base ^ splitmix64(key))
}

/// The values of a range: `from + i·(to − from)/(steps − 1)` for `i < steps − 1`, and
/// `to` itself last, so both ends are exact.
fn range_values(from: f64, to: f64, steps: usize) -> Vec<f64> {
    if steps == 1 {
        return vec![from];
    }
    let last = steps - 1;
    (0..steps)
        .map(|i| {
            if i == last {
                to
            } else {
                from + i as f64 * (to - from) / last as f64
            }
        })
        .collect()
}

/// Checks axis `k` and expands its values.
fn axis(k: usize, a: &AxisFile, earlier: &[Axis]) -> Result<Axis> {
    let at = |field: &str| format!("axes[{k}].{field}");
    let ok_name = !a.name.is_empty()
        && a.name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-'));
    if !ok_name {
        return Err(Error::invalid(
            at("name"),
            format!("must be non-empty [A-Za-z0-9_.-] (got {:?})", a.name),
        ));
    }
    if reserved(&a.name) {
        return Err(Error::invalid(
            at("name"),
            format!("`{}` is a column sweep.csv already has", a.name),
        ));
    }
    if let Some(j) = earlier.iter().position(|b| b.name == a.name) {
        return Err(Error::invalid(
            at("name"),
            format!("`{}` is already the name of axes[{j}]", a.name),
        ));
    }
    let pointer = Pointer::parse(&a.pointer).map_err(|m| Error::invalid(at("pointer"), m))?;
    if pointer.tokens()[0] == "name" {
        return Err(Error::invalid(
            at("pointer"),
            format!("{pointer}: the sweep sets /name itself (to <sweep name>_p<index>)"),
        ));
    }
    if let Some(j) = earlier.iter().position(|b| b.pointer == pointer) {
        return Err(Error::invalid(
            at("pointer"),
            format!(
                "{pointer} is already swept by axes[{j}] ({})",
                earlier[j].name
            ),
        ));
    }
    let values = match (&a.values, &a.range) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                format!("axes[{k}]"),
                "give either values or range, not both",
            ))
        }
        (None, None) => {
            return Err(Error::invalid(
                format!("axes[{k}]"),
                "needs values or range",
            ))
        }
        (Some(v), None) if v.is_empty() => {
            return Err(Error::invalid(
                at("values"),
                format!("axis `{}` is empty (no values)", a.name),
            ))
        }
        (Some(v), None) => v.clone(),
        (None, Some(r)) => {
            if r.steps < 1 {
                return Err(Error::invalid(
                    at("range.steps"),
                    format!("axis `{}` needs steps ≥ 1 (got {})", a.name, r.steps),
                ));
            }
            let steps = usize::try_from(r.steps)
                .ok()
                .filter(|&n| n <= MAX_SWEEP_POINTS)
                .ok_or_else(|| {
                    Error::invalid(
                        at("range.steps"),
                        format!(
                            "axis `{}` has {} steps; a sweep runs at most {MAX_SWEEP_POINTS} points",
                            a.name, r.steps
                        ),
                    )
                })?;
            range_values(r.from, r.to, steps)
                .into_iter()
                .map(|x| {
                    serde_json::Number::from_f64(x)
                        .map(Value::Number)
                        .ok_or_else(|| {
                            Error::invalid(
                                at("range"),
                                format!("axis `{}` gives a non-finite value", a.name),
                            )
                        })
                })
                .collect::<Result<_>>()?
        }
    };
    if let Some(labels) = &a.labels {
        if labels.len() != values.len() {
            return Err(Error::invalid(
                at("labels"),
                format!(
                    "axis `{}` has {} values but {} labels",
                    a.name,
                    values.len(),
                    labels.len()
                ),
            ));
        }
        if let Some(i) = labels
            .iter()
            .position(|l| l.trim().is_empty() || l.chars().any(char::is_control))
        {
            return Err(Error::invalid(
                format!("axes[{k}].labels[{i}]"),
                format!("must be a non-empty line of text (got {:?})", labels[i]),
            ));
        }
        // Labels name the rows of sweep.csv and the plots' ticks: two equal ones would
        // make two points indistinguishable there.
        let mut seen = std::collections::BTreeMap::new();
        for (i, l) in labels.iter().enumerate() {
            if let Some(first) = seen.insert(l.trim(), i) {
                return Err(Error::invalid(
                    format!("axes[{k}].labels[{i}]"),
                    format!(
                        "repeats labels[{first}] ({:?}); each value of axis `{}` needs its own \
                         label",
                        l, a.name
                    ),
                ));
            }
        }
    }
    if a.labels.is_none() {
        if let Some(i) = values
            .iter()
            .position(|v| !(v.is_number() || v.is_string()))
        {
            return Err(Error::invalid(
                at("labels"),
                format!(
                    "axis `{}`: values[{i}] is {}; an axis whose values are not all numbers or \
                     strings needs `labels` (one short name per value, for sweep.csv and the plots)",
                    a.name,
                    if values[i].is_array() { "an array" } else { "not a number or string" }
                ),
            ));
        }
    }
    Ok(Axis {
        name: a.name.clone(),
        pointer,
        values,
        labels: a.labels.clone(),
    })
}

/// Most points one sweep file may define (each is a whole run with its own output
/// directory).
pub const MAX_SWEEP_POINTS: usize = 100_000;

/// Checks a sweep file and lists its points, without reading the base scenario.
///
/// Errors name the field: `name`, `axes[1].pointer`, `axes[0].values` (empty axis),
/// `axes[2].range.steps`, `axes` (zero points; unequal lengths under `zip`),
/// `overrides./x`.
pub fn plan(file: &SweepFile) -> Result<Plan> {
    if file.name.trim().is_empty() || file.name.chars().any(char::is_control) {
        return Err(Error::invalid(
            "name",
            format!("must be a non-empty line of text (got {:?})", file.name),
        ));
    }
    if file.base.is_empty() {
        return Err(Error::invalid("base", "must name the base scenario file"));
    }
    let mut axes: Vec<Axis> = Vec::with_capacity(file.axes.len());
    for (k, a) in file.axes.iter().enumerate() {
        let checked = axis(k, a, &axes)?;
        axes.push(checked);
    }
    if axes.is_empty() {
        return Err(Error::invalid(
            "axes",
            "the sweep has zero points: it needs at least one axis",
        ));
    }
    let mut overrides = Vec::with_capacity(file.overrides.len());
    for (text, value) in &file.overrides {
        let at = format!("overrides.{text}");
        let pointer = Pointer::parse(text).map_err(|m| Error::invalid(&at, m))?;
        if pointer.tokens()[0] == "name" {
            return Err(Error::invalid(
                at,
                "the sweep sets /name itself (to <sweep name>_p<index>)",
            ));
        }
        overrides.push((pointer, value.clone()));
    }
    let repeat = usize::try_from(file.repeat)
        .ok()
        .filter(|&r| (1..=MAX_SWEEP_POINTS).contains(&r))
        .ok_or_else(|| {
            Error::invalid(
                "repeat",
                format!(
                    "must be a whole number from 1 to {MAX_SWEEP_POINTS} (got {})",
                    file.repeat
                ),
            )
        })?;
    if repeat > 1 {
        if let Some(k) = axes.iter().position(|a| a.pointer.tokens() == ["seed"]) {
            return Err(Error::invalid(
                format!("axes[{k}].pointer"),
                "an axis on /seed and `repeat` both draw seeds: use one of them",
            ));
        }
    }
    let lens: Vec<usize> = axes.iter().map(|a| a.values.len()).collect();
    let configurations = match file.combine {
        Combine::Zip => lens[0],
        Combine::Factorial => lens
            .iter()
            .try_fold(1usize, |n, &m| n.checked_mul(m))
            .unwrap_or(usize::MAX),
    };
    let count = configurations.saturating_mul(repeat);
    if count > MAX_SWEEP_POINTS {
        return Err(Error::invalid(
            "axes",
            format!(
                "give {count} points; a sweep runs at most {MAX_SWEEP_POINTS} (split it into \
                 several sweeps, or with --shard)"
            ),
        ));
    }
    let points: Vec<Vec<usize>> = match file.combine {
        Combine::Zip => {
            if let Some(k) = lens.iter().position(|&n| n != lens[0]) {
                return Err(Error::invalid(
                    format!("axes[{k}]"),
                    format!(
                        "zip needs axes of equal length: axes[0] ({}) has {} values, axes[{k}] ({}) has {}",
                        axes[0].name, lens[0], axes[k].name, lens[k]
                    ),
                ));
            }
            (0..lens[0]).map(|i| vec![i; axes.len()]).collect()
        }
        Combine::Factorial => {
            let total = lens
                .iter()
                .try_fold(1usize, |n, &m| n.checked_mul(m))
                .ok_or_else(|| Error::invalid("axes", "too many points (overflow)"))?;
            (0..total)
                .map(|mut i| {
                    let mut idx = vec![0; lens.len()];
                    for (k, &n) in lens.iter().enumerate().rev() {
                        idx[k] = i % n;
                        i /= n;
                    }
                    idx
                })
                .collect()
        }
    };
    let points = points
        .into_iter()
        .flat_map(|p| std::iter::repeat_n(p, repeat))
        .collect();
    let plan = Plan {
        name: file.name.clone(),
        combine: file.combine,
        axes,
        overrides,
        repeat,
        points,
    };
    // Two points of one configuration would share a directory and a seed.
    let mut seen = std::collections::BTreeMap::new();
    for i in 0..plan.points.len() {
        if let Some(j) = seen.insert(plan.seed_key(i), i) {
            return Err(Error::invalid(
                "axes",
                format!(
                    "points p{j} and p{i} are the same configuration ({}); give each value once \
                     (use `repeat` for more runs of one configuration)",
                    plan.describe(i)
                ),
            ));
        }
    }
    Ok(plan)
}

/// One point, checked: its scenario text parses and validates.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Index in the sweep.
    pub index: usize,
    /// Its directory's name ([`Plan::key`]).
    pub key: String,
    /// Axis values, in axis order.
    pub values: Vec<Value>,
    /// The seed of its scenario.
    pub seed: u64,
    /// The scenario as JSON text (pretty, keys in the base's order).
    pub text: String,
    /// BLAKE3 of `text` (hex).
    pub digest: String,
}

/// Builds the scenario of point `i` as JSON: the base, the overrides, `/seed`, the axes,
/// `/name`. Returns it with the axes that created a key the base does not have.
fn build(
    plan: &Plan,
    base: &Value,
    base_seed: Option<u64>,
    i: usize,
) -> Result<(Value, Vec<usize>)> {
    let mut doc = base.clone();
    for (pointer, value) in &plan.overrides {
        pointer
            .set(&mut doc, value.clone())
            .map_err(|m| Error::invalid(format!("overrides.{pointer}"), m))?;
    }
    if let Some(base_seed) = base_seed {
        doc["seed"] = Value::from(derive_seed(base_seed, plan.seed_key(i)));
    }
    let mut created = Vec::new();
    for (k, (axis, value)) in plan.axes.iter().zip(plan.values(i)).enumerate() {
        let added = axis.pointer.set(&mut doc, value).map_err(|m| {
            let at = if i == 0 {
                String::new()
            } else {
                format!(" (at point p{i}: {})", plan.describe(i))
            };
            Error::invalid(format!("axes[{k}].pointer"), format!("{m}{at}"))
        })?;
        if added {
            created.push(k);
        }
    }
    doc["name"] = Value::from(format!("{}_{}", plan.name, plan.key(i)));
    Ok((doc, created))
}

/// Values of one axis that [`checked_points`] takes at most (all of an axis with no more).
pub const CHECKED_VALUES_PER_AXIS: usize = 1_000;

/// The values of axis `a` that `validate` checks: all of them up to
/// [`CHECKED_VALUES_PER_AXIS`], else that many evenly spaced with both ends, and the
/// smallest and largest value of a numeric axis wherever they are. Sorted, distinct.
fn checked_values(a: &Axis) -> Vec<usize> {
    let n = a.values.len();
    let mut picks: Vec<usize> = if n <= CHECKED_VALUES_PER_AXIS {
        (0..n).collect()
    } else {
        let last = CHECKED_VALUES_PER_AXIS - 1;
        (0..CHECKED_VALUES_PER_AXIS)
            .map(|j| j * (n - 1) / last)
            .collect()
    };
    picks.extend(extremes(a));
    picks.sort_unstable();
    picks.dedup();
    picks
}

/// The values of axis `a` that the extreme combinations take: the first smallest and
/// first largest of a numeric axis (a range's ends), else every checked value.
fn extremes(a: &Axis) -> Vec<usize> {
    match a.numbers() {
        Some(x) => {
            let (mut lo, mut hi) = (0, 0);
            for (i, &v) in x.iter().enumerate() {
                if v < x[lo] {
                    lo = i;
                }
                if v > x[hi] {
                    hi = i;
                }
            }
            if lo == hi {
                vec![lo]
            } else {
                vec![lo.min(hi), lo.max(hi)]
            }
        }
        None if a.values.len() <= CHECKED_VALUES_PER_AXIS => (0..a.values.len()).collect(),
        None => checked_values(a),
    }
}

/// The points `validate` builds and checks of a sweep (indices, ascending), a bounded
/// set instead of all of them:
///
/// - every axis's checked values ([`CHECKED_VALUES_PER_AXIS`]: every value of an axis
///   of up to 1 000, else 1 000 evenly spaced with both ends and its smallest and
///   largest), each with the other axes at their first value (`zip`: the point of that
///   index);
/// - the extreme combinations: every combination of each axis's smallest and largest
///   value (a range's ends; all checked values of an axis that is not all numbers), where
///   derived sizes (steps, trace rows, memory) that grow or shrink with each field
///   peak;
/// - of each configuration only its first repetition (repetitions differ only in their
///   derived seed).
///
/// A sweep whose axes have at most 1 000 values each and no more than two numbers or a
/// few non-numbers per axis is checked whole; a 100 000-step range alone is 1 000 points.
/// The set is at most `Σ min(values, 1 000) + Π extremes` configurations and never more
/// than the sweep's points. `sweep` itself still builds and checks every point before
/// it runs any ([`expand`]).
pub fn checked_points(plan: &Plan) -> Vec<usize> {
    let lens: Vec<usize> = plan.axes.iter().map(|a| a.values.len()).collect();
    let configurations = plan.points.len() / plan.repeat;
    let mut set = std::collections::BTreeSet::new();
    match plan.combine {
        Combine::Zip => {
            for a in &plan.axes {
                set.extend(checked_values(a));
                set.extend(extremes(a));
            }
        }
        Combine::Factorial => {
            // Configuration of value indices `idx`: the last axis varies fastest.
            let config =
                |idx: &[usize]| idx.iter().zip(&lens).fold(0usize, |c, (&v, &n)| c * n + v);
            let mut idx = vec![0; lens.len()];
            for (k, a) in plan.axes.iter().enumerate() {
                for v in checked_values(a) {
                    idx[k] = v;
                    set.insert(config(&idx));
                }
                idx[k] = 0;
            }
            // Every combination of the axes' extremes, as an odometer.
            let ext: Vec<Vec<usize>> = plan.axes.iter().map(extremes).collect();
            let mut at = vec![0usize; ext.len()];
            loop {
                let idx: Vec<usize> = at.iter().zip(&ext).map(|(&j, e)| e[j]).collect();
                set.insert(config(&idx));
                let mut k = ext.len();
                loop {
                    if k == 0 {
                        break;
                    }
                    k -= 1;
                    at[k] += 1;
                    if at[k] < ext[k].len() {
                        break;
                    }
                    at[k] = 0;
                }
                if at.iter().all(|&j| j == 0) {
                    break;
                }
            }
        }
    }
    set.into_iter()
        .filter(|&c| c < configurations)
        .map(|c| c * plan.repeat)
        .collect()
}

/// Builds and validates every point's scenario from `base` (the base scenario's JSON,
/// the command line's `--set` overrides `sets` applied; `base_label` names it in
/// messages; `base_path` is its file, from whose directory relative paths in it, an
/// FMU's, are read as from the base itself).
///
/// Every point is checked before any is returned; the first failure (in index order) is
/// the error, naming the axis (`axes[1].pointer: …`) or the point and its axis values
/// (`point p3 (drift = 50, T = 0.5): dt: …`).
pub fn expand(
    plan: &Plan,
    base: &Value,
    (base_label, base_path): (&str, &std::path::Path),
    sets: &[String],
) -> Result<Vec<Point>> {
    let all: Vec<usize> = (0..plan.points.len()).collect();
    expand_points(plan, base, (base_label, base_path), &all, sets)
}

/// [`expand`] of the points `indices` (ascending) only: the first failure in their order
/// is the error.
pub fn expand_points(
    plan: &Plan,
    base: &Value,
    (base_label, base_path): (&str, &std::path::Path),
    indices: &[usize],
    sets: &[String],
) -> Result<Vec<Point>> {
    if !base.is_object() {
        return Err(Error::invalid(
            "base",
            format!("{base_label} is not a JSON object"),
        ));
    }
    let seed_swept = plan.axes.iter().any(|a| a.pointer.tokens() == ["seed"]);
    let mut with_overrides = base.clone();
    for (pointer, value) in &plan.overrides {
        pointer
            .set(&mut with_overrides, value.clone())
            .map_err(|m| Error::invalid(format!("overrides.{pointer}"), m))?;
    }
    let base_seed = if seed_swept {
        None
    } else {
        let seed = with_overrides.get("seed").and_then(Value::as_u64);
        Some(seed.ok_or_else(|| {
            Error::invalid(
                "base",
                format!(
                    "{base_label}: seed must be an unsigned integer to derive the points' seeds (got {})",
                    with_overrides.get("seed").map_or("nothing".to_string(), Value::to_string)
                ),
            )
        })?)
    };
    let results: Vec<Result<Point>> = indices
        .par_iter()
        .map(|&i| point(plan, (base, base_path), base_seed, i, sets))
        .collect();
    results.into_iter().collect()
}

/// Builds and validates point `i`, with the checks `run` makes before it starts.
fn point(
    plan: &Plan,
    (base, base_path): (&Value, &std::path::Path),
    base_seed: Option<u64>,
    i: usize,
    sets: &[String],
) -> Result<Point> {
    let (doc, created) = build(plan, base, base_seed, i)?;
    let mut text = serde_json::to_string_pretty(&doc)
        .map_err(|e| Error::invalid(format!("point p{i}"), e.to_string()))?;
    text.push('\n');
    let label = format!("{}_{}", plan.name, plan.key(i));
    let scenario = crate::scenario::parse_at(&text, &label, Some(base_path)).map_err(|e| {
        // A field a `--set` gave names that override, unless the sweep set it later.
        let later: Vec<String> = plan
            .overrides
            .iter()
            .map(|(p, _)| p.to_string())
            .chain(plan.axes.iter().map(|a| a.pointer.to_string()))
            .collect();
        let e = crate::scenario::overrides::name_override(e, sets, &later);
        let note: String = created
            .iter()
            .map(|&k| {
                format!(
                    "; axes[{k}].pointer {} adds a key the base scenario does not have",
                    plan.axes[k].pointer
                )
            })
            .collect();
        Error::invalid(
            format!("point p{i} ({})", plan.describe(i)),
            format!("{e}{note}"),
        )
    })?;
    // What `run` would still refuse (limits, a simplex that does not fit), before any
    // point runs.
    crate::run::preflight(&scenario, &crate::run::RunOptions::default())
        .map_err(|e| Error::invalid(format!("point p{i} ({})", plan.describe(i)), e.to_string()))?;
    Ok(Point {
        index: i,
        key: plan.key(i),
        values: plan.values(i),
        seed: scenario.seed,
        digest: blake3::hash(text.as_bytes()).to_hex().to_string(),
        text,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::file::parse;

    fn plan_of(json: &str) -> Result<Plan> {
        plan(&parse(json, "s.json").unwrap())
    }

    #[test]
    fn factorial_varies_the_last_axis_fastest() {
        let p = plan_of(
            r#"{"name": "s", "base": "b", "axes": [
                {"name": "a", "pointer": "/a", "values": [1, 2]},
                {"name": "b", "pointer": "/b", "values": ["x", "y", "z"]}]}"#,
        )
        .unwrap();
        assert_eq!(p.points.len(), 6);
        assert_eq!(p.points[1], vec![0, 1]);
        assert_eq!(p.points[3], vec![1, 0]);
        assert_eq!(p.describe(5), "a = 2, b = z");
    }

    #[test]
    fn zip_pairs_values_and_needs_equal_lengths() {
        let p = plan_of(
            r#"{"name": "s", "base": "b", "combine": "zip", "axes": [
                {"name": "a", "pointer": "/a", "values": [1, 2]},
                {"name": "b", "pointer": "/b", "range": {"from": 0, "to": 1, "steps": 2}}]}"#,
        )
        .unwrap();
        assert_eq!(p.points, vec![vec![0, 0], vec![1, 1]]);
        let e = plan_of(
            r#"{"name": "s", "base": "b", "combine": "zip", "axes": [
                {"name": "a", "pointer": "/a", "values": [1, 2]},
                {"name": "b", "pointer": "/b", "values": [1, 2, 3]}]}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("axes[1]: zip needs axes of equal length"),
            "{e}"
        );
    }

    #[test]
    fn ranges_are_evenly_spaced_with_exact_ends() {
        assert_eq!(range_values(0.5, 2.0, 4), vec![0.5, 1.0, 1.5, 2.0]);
        assert_eq!(range_values(3.0, 9.0, 1), vec![3.0]);
        let v = range_values(0.001, 0.007, 7);
        assert_eq!((v[0], v[6]), (0.001, 0.007));
        assert_eq!(v[3], 0.001 + 3.0 * (0.007 - 0.001) / 6.0);
    }

    #[test]
    fn bad_axes_are_named() {
        let cases = [
            (
                r#"{"name": "a", "pointer": "/a", "values": []}"#,
                "axes[0].values: axis `a` is empty",
            ),
            (
                r#"{"name": "a", "pointer": "/a", "range": {"from": 0, "to": 1, "steps": 0}}"#,
                "axes[0].range.steps:",
            ),
            (
                r#"{"name": "a", "pointer": "a", "values": [1]}"#,
                "axes[0].pointer:",
            ),
            (
                r#"{"name": "a", "pointer": "/name", "values": [1]}"#,
                "axes[0].pointer:",
            ),
            (
                r#"{"name": "seed", "pointer": "/a", "values": [1]}"#,
                "axes[0].name:",
            ),
            (
                r#"{"name": "a b", "pointer": "/a", "values": [1]}"#,
                "axes[0].name:",
            ),
            (
                r#"{"name": "a", "pointer": "/a"}"#,
                "axes[0]: needs values or range",
            ),
        ];
        for (axis, want) in cases {
            let e = plan_of(&format!(
                r#"{{"name": "s", "base": "b", "axes": [{axis}]}}"#
            ))
            .unwrap_err()
            .to_string();
            assert!(e.starts_with(want), "{axis}: {e}");
        }
        let e = plan_of(r#"{"name": "s", "base": "b", "axes": []}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("zero points"), "{e}");
    }

    #[test]
    fn seeds_are_distinct_and_fixed() {
        // Reference values of SplitMix64 seeded with 0: its first output is
        // splitmix64(0) = 0xE220A8397B1DCDAF.
        assert_eq!(splitmix64(0), 0xE220_A839_7B1D_CDAF);
        let seeds: std::collections::BTreeSet<u64> = (0..1000).map(|i| derive_seed(7, i)).collect();
        assert_eq!(seeds.len(), 1000);
    }

    #[test]
    fn a_seed_follows_the_configuration_not_the_index() {
        let small = plan_of(
            r#"{"name": "s", "base": "b", "repeat": 2, "axes": [
                {"name": "a", "pointer": "/a", "values": [1, 3]}]}"#,
        )
        .unwrap();
        let grown = plan_of(
            r#"{"name": "s", "base": "b", "repeat": 2, "axes": [
                {"name": "a", "pointer": "/a", "values": [1, 2, 3]}]}"#,
        )
        .unwrap();
        assert_eq!(small.points.len(), 4);
        assert_eq!(grown.points.len(), 6);
        // a = 3, rep 1 is point 3 of the first sweep and point 5 of the second.
        assert_eq!((small.rep(3), grown.rep(5)), (1, 1));
        assert_eq!(small.seed_key(3), grown.seed_key(5));
        assert_eq!(small.seed_key(0), grown.seed_key(0));
        assert_ne!(small.seed_key(0), small.seed_key(1), "repetitions differ");
        assert_eq!(small.describe(3), "a = 3, rep = 1");
    }

    #[test]
    fn structured_values_need_labels_and_repeat_excludes_a_seed_axis() {
        let e = plan_of(
            r#"{"name": "s", "base": "b", "axes": [
                {"name": "a", "pointer": "/a", "values": [[1, 2], [3]]}]}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("axes[0].labels: axis `a`: values[0] is an array"),
            "{e}"
        );
        let e = plan_of(
            r#"{"name": "s", "base": "b", "repeat": 3, "axes": [
                {"name": "d", "pointer": "/seed", "values": [1, 2]}]}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("axes[0].pointer: an axis on /seed and `repeat`"),
            "{e}"
        );
        for bad in ["0", "-1", "100001"] {
            let e = plan_of(&format!(
                r#"{{"name": "s", "base": "b", "repeat": {bad}, "axes": [
                {{"name": "a", "pointer": "/a", "values": [1]}}]}}"#
            ))
            .unwrap_err()
            .to_string();
            assert!(
                e.starts_with("repeat: must be a whole number"),
                "{bad}: {e}"
            );
        }
    }
}
