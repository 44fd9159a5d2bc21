//! One plot axis: its range computed from the data, its ticks and their labels.
//!
//! We use our own [`Ranged`] coordinate instead of plotters' `f64` and log coordinates so
//! that one type serves both scales, ticks always exist (plotters' log axis has none on a
//! range narrower than a decade), labels are short and mapping never sees a NaN.

use std::ops::Range;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

use super::Scale;

/// Largest magnitude an axis end may have; keeps every span finite.
const LIMIT: f64 = 1e300;
/// Smallest positive value on a log axis.
const LOG_FLOOR: f64 = 1e-300;
/// Fraction of the data span added on each side.
const MARGIN: f64 = 0.05;
/// Smallest span relative to the magnitude of the ends, so ticks stay representable.
const MIN_REL_SPAN: f64 = 1e-9;

/// A finite, non-empty interval `lo < hi` on a linear or log scale (`lo > 0` for log).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Axis {
    scale: Scale,
    lo: f64,
    hi: f64,
}

/// True when `v` can be placed on an axis of this scale.
pub(crate) fn plottable(scale: Scale, v: f64) -> bool {
    v.is_finite() && (scale == Scale::Linear || v > 0.0)
}

impl Axis {
    /// The range of the plottable `values` plus a margin of 5 % of the span on each
    /// side (in log space for a log axis).
    ///
    /// No plottable value: `[0, 1]` (linear) or `[1, 10]` (log). All values equal to
    /// `v`: `v ± 10 %` (`±1` for 0), or half a decade either side on a log axis.
    pub(crate) fn fit(scale: Scale, values: impl IntoIterator<Item = f64>) -> Axis {
        let (min, max) = min_max(scale, values);
        Axis::around(scale, min, max, MARGIN)
    }

    /// The range `[min, max]` of the plottable `values` without a margin, with the
    /// same handling of no data and of equal values as [`Axis::fit`].
    pub(crate) fn exact(scale: Scale, values: impl IntoIterator<Item = f64>) -> Axis {
        let (min, max) = min_max(scale, values);
        Axis::around(scale, min, max, 0.0)
    }

    fn around(scale: Scale, min: Option<f64>, max: Option<f64>, margin: f64) -> Axis {
        let (lo, hi) = match (scale, min, max) {
            (Scale::Linear, Some(a), Some(b)) => {
                let (lo, hi) = widen(a, b, margin, |v| if v == 0.0 { 1.0 } else { v.abs() * 0.1 });
                (lo.max(-LIMIT), hi.min(LIMIT))
            }
            (Scale::Log, Some(a), Some(b)) => {
                let (lo, hi) = widen(a.log10(), b.log10(), margin, |_| 0.5);
                let (lo, hi) = (lo.max(LOG_FLOOR.log10()), hi.min(LIMIT.log10()));
                (10f64.powf(lo), 10f64.powf(hi))
            }
            (Scale::Linear, _, _) => (0.0, 1.0),
            (Scale::Log, _, _) => (1.0, 10.0),
        };
        Axis { scale, lo, hi }
    }

    /// The lower end.
    pub(crate) fn lo(&self) -> f64 {
        self.lo
    }

    /// The upper end.
    pub(crate) fn hi(&self) -> f64 {
        self.hi
    }

    /// The axis coordinate of `v`: `v` itself or `log10 v`.
    fn lin(&self, v: f64) -> f64 {
        match self.scale {
            Scale::Linear => v,
            Scale::Log => v.log10(),
        }
    }

    /// Position of `v` along the axis, 0 at `lo` and 1 at `hi`, clamped to `[0, 1]`
    /// (NaN maps to 0).
    pub(crate) fn fraction(&self, v: f64) -> f64 {
        let (a, b) = (self.lin(self.lo), self.lin(self.hi));
        let f = (self.lin(v) - a) / (b - a);
        if f.is_nan() {
            0.0
        } else {
            f.clamp(0.0, 1.0)
        }
    }

    /// At most `max` "nice" tick values inside the axis.
    pub(crate) fn ticks(&self, max: usize) -> Vec<f64> {
        if max == 0 {
            return Vec::new();
        }
        match self.scale {
            Scale::Linear => linear_ticks(self.lo, self.hi, max),
            Scale::Log => log_ticks(self.lo, self.hi, max),
        }
    }

    /// The tick label of `v`: as short as the axis's resolution allows.
    ///
    /// A linear axis uses one notation for all its labels, chosen by the larger end's
    /// magnitude; a log axis picks it per label.
    pub(crate) fn label(&self, v: f64) -> String {
        match self.scale {
            Scale::Linear => format_number(
                v,
                (self.hi - self.lo) / 1000.0,
                self.lo.abs().max(self.hi.abs()),
            ),
            Scale::Log => format_number(v, v.abs() / 1000.0, v.abs()),
        }
    }
}

/// Smallest and largest plottable value.
fn min_max(scale: Scale, values: impl IntoIterator<Item = f64>) -> (Option<f64>, Option<f64>) {
    values.into_iter().filter(|&v| plottable(scale, v)).fold(
        (None, None),
        |(lo, hi): (Option<f64>, Option<f64>), v| {
            (
                Some(lo.map_or(v, |l| l.min(v))),
                Some(hi.map_or(v, |h| h.max(v))),
            )
        },
    )
}

/// `[a, b]` grown by `margin` of its span on each side; a zero span becomes
/// `a ± flat(a)`, a span tinier than the magnitude allows is widened around its middle.
fn widen(a: f64, b: f64, margin: f64, flat: impl Fn(f64) -> f64) -> (f64, f64) {
    // Halves first so that `b - a` cannot overflow for ends near ±f64::MAX.
    let mid = a * 0.5 + b * 0.5;
    let mut half = b * 0.5 - a * 0.5;
    if half == 0.0 {
        half = flat(a);
    } else {
        half += half * (2.0 * margin);
    }
    half = half.max(mid.abs() * MIN_REL_SPAN).max(f64::MIN_POSITIVE);
    let (lo, hi) = (mid - half, mid + half);
    if lo.is_finite() && hi.is_finite() && lo < hi {
        (lo, hi)
    } else {
        (-LIMIT, LIMIT)
    }
}

/// Multiples of the largest 1-2-5 step that gives at most `max` ticks in `[lo, hi]`
/// (at least one tick where possible). Ticks are `i · step`, so they do not drift.
fn linear_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let span = hi - lo;
    if span.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !span.is_finite() {
        return Vec::new();
    }
    // Start one decade below the step that would give `max` ticks, go up until it fits.
    let mut exp = (span / max as f64).log10().floor() as i32 - 1;
    for _ in 0..8 {
        let decade = 10f64.powi(exp);
        for m in [1.0, 2.0, 5.0] {
            let step = m * decade;
            let (first, last) = ((lo / step).ceil(), (hi / step).floor());
            if !(first.is_finite() && last.is_finite()) {
                continue;
            }
            let count = last - first + 1.0;
            if count <= max as f64 {
                return (0..count.max(0.0) as i64)
                    .map(|i| (first + i as f64) * step)
                    .map(|v| if v == 0.0 { 0.0 } else { v })
                    .collect();
            }
        }
        exp += 1;
    }
    Vec::new()
}

/// Ticks for a log axis: `{1, 2, 5} · 10^k` when at least three fit, else every digit
/// `{1, …, 9} · 10^k` when that fits, else every n-th decade, else (a range within one
/// decade) linear ticks.
fn log_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let mut decades = Vec::new();
    let mut one_two_five = Vec::new();
    for k in k0..=k1 {
        let p = 10f64.powi(k);
        for (i, m) in [1.0, 2.0, 5.0].into_iter().enumerate() {
            let v = m * p;
            if v >= lo && v <= hi {
                one_two_five.push(v);
                if i == 0 {
                    decades.push(v);
                }
            }
        }
    }
    if one_two_five.len() >= 3 && one_two_five.len() <= max {
        return one_two_five;
    }
    // Within about a decade: every digit, `{1, …, 9} · 10^k`, if that gives more.
    let digits: Vec<f64> = (k0..=k1)
        .flat_map(|k| (1..10).map(move |m| f64::from(m) * 10f64.powi(k)))
        .filter(|&v| v >= lo && v <= hi)
        .take(max + 1)
        .collect();
    if digits.len() > one_two_five.len() && digits.len() <= max {
        return digits;
    }
    if one_two_five.len() == 2 && max >= 2 {
        return one_two_five;
    }
    if decades.len() >= 2 {
        let stride = decades.len().div_ceil(max);
        return decades.into_iter().step_by(stride).collect();
    }
    linear_ticks(lo, hi, max)
}

/// `v` with just enough digits to resolve `resolution`: fixed notation when `magnitude`
/// is in `[1e-3, 1e6)`, scientific (`2.5e-7`) outside; trailing zeros trimmed.
pub(crate) fn format_number(v: f64, resolution: f64, magnitude: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let resolution = if resolution > 0.0 && resolution.is_finite() {
        resolution
    } else {
        v.abs() * 1e-3
    };
    let text = if (1e-3..1e6).contains(&magnitude) {
        let decimals = (-resolution.log10()).ceil().clamp(0.0, 12.0) as usize;
        trim_zeros(format!("{v:.decimals$}"))
    } else {
        let digits = (v.abs() / resolution).log10().ceil().clamp(1.0, 12.0) as usize;
        let text = format!("{:.*e}", digits - 1, v);
        match text.split_once('e') {
            Some((mantissa, exp)) => format!("{}e{}", trim_zeros(mantissa.to_string()), exp),
            None => text,
        }
    };
    if text == "-0" {
        "0".to_string()
    } else {
        text
    }
}

/// Removes trailing zeros after a decimal point, and the point if nothing follows it.
fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

impl Ranged for Axis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let f = self.fraction(*value);
        limit.0 + (f * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        self.ticks(hint.max_num_points())
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for Axis {
    fn format_ext(&self, value: &f64) -> String {
        self.label(*value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_adds_margin() {
        let a = Axis::fit(Scale::Linear, [0.0, 10.0, f64::NAN, f64::INFINITY]);
        assert_eq!((a.lo(), a.hi()), (-0.5, 10.5));
    }

    #[test]
    fn degenerate_ranges() {
        let empty = Axis::fit(Scale::Linear, []);
        assert_eq!((empty.lo(), empty.hi()), (0.0, 1.0));
        let one = Axis::fit(Scale::Linear, [5.0]);
        assert_eq!((one.lo(), one.hi()), (4.5, 5.5));
        let zero = Axis::fit(Scale::Linear, [0.0, 0.0]);
        assert_eq!((zero.lo(), zero.hi()), (-1.0, 1.0));
        let log_empty = Axis::fit(Scale::Log, [0.0, -3.0, f64::NAN]);
        assert_eq!((log_empty.lo(), log_empty.hi()), (1.0, 10.0));
        let log_one = Axis::fit(Scale::Log, [100.0, -1.0]);
        assert!(log_one.lo() < 100.0 && log_one.hi() > 100.0);
        let huge = Axis::fit(Scale::Linear, [-f64::MAX, f64::MAX]);
        assert!(huge.lo() < huge.hi() && (huge.hi() - huge.lo()).is_finite());
        let tiny = Axis::fit(Scale::Linear, [1e15, 1e15 + 0.125]);
        assert!(tiny.lo() < tiny.hi());
        let sub = Axis::fit(Scale::Log, [f64::MIN_POSITIVE / 4.0, f64::MAX]);
        assert!(sub.lo() > 0.0 && sub.hi().is_finite());
        for a in [empty, one, zero, log_empty, log_one, huge, tiny, sub] {
            let ticks = a.ticks(10);
            assert!(!ticks.is_empty() && ticks.len() <= 10, "{a:?}: {ticks:?}");
            for t in ticks {
                assert!(t >= a.lo() && t <= a.hi(), "{a:?}: {t}");
                assert!(!a.label(t).is_empty());
            }
        }
    }

    #[test]
    fn linear_ticks_are_nice() {
        assert_eq!(
            linear_ticks(-0.5, 10.5, 10),
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
        );
        let t = linear_ticks(0.0, 1.0, 11);
        assert_eq!(t.len(), 11);
        let a = Axis::fit(Scale::Linear, [0.0, 1.0]);
        assert_eq!(a.label(t[3]), "0.3");
    }

    #[test]
    fn log_ticks_cover_decades() {
        assert_eq!(
            log_ticks(0.5, 30.0, 10),
            vec![0.5, 1.0, 2.0, 5.0, 10.0, 20.0]
        );
        assert_eq!(log_ticks(1e-6, 1e6, 5).len(), 5);
        assert!(!log_ticks(1.1, 1.9, 10).is_empty());
        assert_eq!(log_ticks(1.5, 6.5, 8), vec![2.0, 3.0, 4.0, 5.0, 6.0]);
    }

    #[test]
    fn number_format() {
        assert_eq!(format_number(0.30000000000000004, 1e-3, 1.0), "0.3");
        assert_eq!(format_number(-0.0, 1.0, 1.0), "0");
        assert_eq!(format_number(2.5e-7, 1e-9, 2.5e-7), "2.5e-7");
        assert_eq!(format_number(1e9 + 2.0, 0.01, 1e9), "1.000000002e9");
        assert_eq!(format_number(1500.0, 10.0, 1500.0), "1500");
        // One notation along a linear axis.
        let a = Axis::fit(Scale::Linear, [-1.2e-3, 1.2e-3]);
        assert_eq!(a.label(5e-4), "0.0005");
        assert_eq!(a.label(-1e-3), "-0.001");
    }

    #[test]
    fn mapping_clamps() {
        let a = Axis::fit(Scale::Log, [1.0, 100.0]);
        assert_eq!(a.map(&-5.0, (0, 100)), 0);
        assert_eq!(a.map(&f64::NAN, (0, 100)), 0);
        assert_eq!(a.map(&1e300, (0, 100)), 100);
        assert_eq!(a.map(&10.0, (100, 0)), 50);
    }
}
