//! The samples a run's plots are drawn from, in memory bounded by the scene rather than
//! the horizon.
//!
//! Every kept trace row is offered; a plotted point stands for a bucket of `stride`
//! consecutive rows. When the points reach `2 ·` [`MAX_PLOT_POINTS`] the buckets are
//! merged pairwise and the stride doubles, so a series never holds more than
//! `2 · MAX_PLOT_POINTS` values whatever the run's length and decimation. A point sits at
//! its bucket's first time; a *peak* series (constraint values) keeps the bucket's value
//! of largest magnitude, so a one-step spike is never dropped from a plot; a *first*
//! series (body coordinates, smooth) keeps the bucket's first value. Below
//! `2 · MAX_PLOT_POINTS` rows nothing is merged: every kept row is a point.

use serde::{Deserialize, Serialize};

/// Points per series after a merge (half the most a series holds).
pub const MAX_PLOT_POINTS: usize = 4096;

/// Bounded plot series sharing one time axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlotSamples {
    /// Rows per plotted point (a power of two).
    stride: u64,
    /// Rows offered so far.
    seen: u64,
    /// Time of each point [s].
    pub times: Vec<f64>,
    /// Series merged by largest magnitude.
    pub peaks: Vec<Vec<f64>>,
    /// Series merged by first value.
    pub firsts: Vec<Vec<f64>>,
}

impl PlotSamples {
    /// Empty samples for `peaks` and `firsts` series.
    pub fn new(peaks: usize, firsts: usize) -> PlotSamples {
        PlotSamples {
            stride: 1,
            seen: 0,
            times: Vec::new(),
            peaks: vec![Vec::new(); peaks],
            firsts: vec![Vec::new(); firsts],
        }
    }

    /// Offers one row: time `t`, then one value per peak and per first series.
    pub fn push(
        &mut self,
        t: f64,
        peaks: impl IntoIterator<Item = f64>,
        firsts: impl IntoIterator<Item = f64>,
    ) {
        if self.seen.is_multiple_of(self.stride) {
            self.times.push(t);
            for (s, v) in self.peaks.iter_mut().zip(peaks) {
                s.push(v);
            }
            for (s, v) in self.firsts.iter_mut().zip(firsts) {
                s.push(v);
            }
        } else {
            for (s, v) in self.peaks.iter_mut().zip(peaks) {
                if let Some(last) = s.last_mut() {
                    *last = larger(*last, v);
                }
            }
        }
        self.seen += 1;
        if self.times.len() >= 2 * MAX_PLOT_POINTS {
            self.halve();
        }
    }

    /// Merges the points pairwise and doubles the stride.
    fn halve(&mut self) {
        let n = self.times.len() / 2;
        for k in 0..n {
            self.times[k] = self.times[2 * k];
            for s in &mut self.peaks {
                s[k] = larger(s[2 * k], s[2 * k + 1]);
            }
            for s in &mut self.firsts {
                s[k] = s[2 * k];
            }
        }
        self.times.truncate(n);
        self.peaks.iter_mut().for_each(|s| s.truncate(n));
        self.firsts.iter_mut().for_each(|s| s.truncate(n));
        self.stride *= 2;
    }
}

/// The value of larger magnitude (the first on a tie; NaN wins, so it shows).
fn larger(a: f64, b: f64) -> f64 {
    if b.is_nan() || b.abs() > a.abs() {
        b
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_runs_keep_every_row() {
        let mut p = PlotSamples::new(1, 1);
        for i in 0..1000 {
            p.push(f64::from(i), [f64::from(i)], [f64::from(-i)]);
        }
        assert_eq!(p.times.len(), 1000);
        assert_eq!(p.peaks[0][999], 999.0);
        assert_eq!(p.firsts[0][999], -999.0);
    }

    #[test]
    fn long_runs_stay_bounded_and_keep_every_spike() {
        let mut p = PlotSamples::new(1, 1);
        let rows = 1_000_003u32;
        for i in 0..rows {
            let w = match i {
                123_457 => 5.0,
                777_777 => -7.0,
                _ => 1e-3 * f64::from(i % 7),
            };
            p.push(f64::from(i) * 1e-3, [w], [f64::from(i)]);
            assert!(p.times.len() < 2 * MAX_PLOT_POINTS);
        }
        assert!(p.times.len() >= MAX_PLOT_POINTS / 2);
        assert!(p.peaks[0].contains(&5.0) && p.peaks[0].contains(&-7.0));
        // Points are in time order, at their buckets' first rows.
        assert!(p.times.windows(2).all(|w| w[0] < w[1]));
        let stride = p.stride as f64;
        for (t, first) in p.times.iter().zip(&p.firsts[0]) {
            assert_eq!(*first, (t * 1e3).round());
            assert_eq!(first % stride, 0.0);
        }
    }
}
