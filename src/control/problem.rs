//! From a controlled vector `x` to channel delays, and the objective of a window
//! (method §5).
//!
//! - CP: `x` holds the first n − 1 delays; the last channel takes the rest of the
//!   budget, `τ_n = k_n / (B − Σ_{i<n} k_i/x_i)`, raised to `τ_min` if the rest would
//!   allow a faster channel than the bounds do (that only lowers the bandwidth used).
//!   Objective: the window cost C.
//! - UP: `x` holds all n delays; objective `C + b Σ k_i/τ_i`.
//!
//! On ideal channels a requested delay runs to the nanosecond: the channel samples at
//! the first step at or after each multiple of it, so its average rate is `1/τ` and
//! the bandwidth used is the requested one. (It used to run at the next whole number
//! of steps, `ceil(τ/dt)·dt`: a request of 3.015 ms ran at 4 ms and a run at the budget
//! used 317 of its 400 Hz.) Requested and achieved delays are both reported.

use crate::control::dsm::{Feasible, SimplexError};
use crate::kernel::SimTime;
use crate::scenario::model::{ChannelSpec, ControllerSpec, Problem};

/// The delay space of a controlled scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Delays {
    problem: Problem,
    k: Vec<f64>,
    tau_min: f64,
    tau_max: f64,
    dt: SimTime,
}

impl Delays {
    /// The delay space of `spec` over `channels`, with step `dt`.
    pub fn new(spec: &ControllerSpec, channels: &[ChannelSpec], dt: SimTime) -> Delays {
        Delays {
            problem: spec.problem,
            k: channels.iter().map(|c| c.k).collect(),
            tau_min: spec.tau_min,
            tau_max: spec.tau_max,
            dt,
        }
    }

    /// Number of controlled coordinates.
    pub fn dim(&self) -> usize {
        match self.problem {
            Problem::Constrained { .. } => self.k.len() - 1,
            Problem::Unconstrained { .. } => self.k.len(),
        }
    }

    /// The requested delay of every channel [s] for `x`, or `None` if `x` is
    /// infeasible (outside the bounds, or over the budget).
    pub fn taus(&self, x: &[f64]) -> Option<Vec<f64>> {
        if x.len() != self.dim()
            || x.iter()
                .any(|&v| !(v.is_finite() && v >= self.tau_min && v <= self.tau_max))
        {
            return None;
        }
        match self.problem {
            Problem::Unconstrained { .. } => Some(x.to_vec()),
            Problem::Constrained { budget } => {
                let used: f64 = x.iter().zip(&self.k).map(|(x, k)| k / x).sum();
                let left = budget - used;
                let k_last = self.k[self.k.len() - 1];
                if left <= 0.0 || k_last / left > self.tau_max {
                    return None;
                }
                let mut taus = x.to_vec();
                taus.push((k_last / left).max(self.tau_min));
                Some(taus)
            }
        }
    }

    /// The period each ideal channel runs at: the requested delay to the nanosecond (at
    /// least one step). A channel samples at the first step at or after each multiple
    /// of its period, so its average rate is the requested one (a TDMA network replaces
    /// these by what its slot list achieves).
    pub fn achieved(&self, taus: &[f64]) -> Vec<SimTime> {
        taus.iter()
            .map(|&t| crate::network::channel::achieved_period(t, self.dt))
            .collect()
    }

    /// Bandwidth `Σ k/τ` [1/s] of delays `taus` [s].
    pub fn bandwidth(&self, taus: &[f64]) -> f64 {
        taus.iter().zip(&self.k).map(|(t, k)| k / t).sum()
    }

    /// The objective of a window with cost `cost` run at achieved periods `achieved`.
    pub fn objective(&self, cost: f64, achieved: &[SimTime]) -> f64 {
        match self.problem {
            Problem::Constrained { .. } => cost,
            Problem::Unconstrained { penalty } => {
                let secs: Vec<f64> = achieved.iter().map(|t| t.as_secs_f64()).collect();
                cost + penalty * self.bandwidth(&secs)
            }
        }
    }

    /// The feasible set for the simplex methods.
    pub fn feasible(&self) -> Result<Feasible, SimplexError> {
        let n = self.dim();
        let boxed = Feasible::boxed(vec![self.tau_min; n], vec![self.tau_max; n])?;
        match self.problem {
            Problem::Unconstrained { .. } => Ok(boxed),
            Problem::Constrained { budget } => {
                // τ_n ≤ τ_max  ⇔  Σ_{i<n} k_i/x_i ≤ B − k_n/τ_max.
                let k_last = self.k[self.k.len() - 1];
                boxed.with_budget(self.k[..n].to_vec(), budget - k_last / self.tau_max)
            }
        }
    }

    /// "No optimization": every channel at the same delay — at the budget for CP
    /// (`τ = Σk/B`), for UP at `fallback` (the initial delays' mean).
    pub fn equal(&self, fallback: &[f64]) -> Vec<f64> {
        match self.problem.equal_share(self.k.iter().copied()) {
            Some(tau) => vec![tau.clamp(self.tau_min, self.tau_max); self.dim()],
            None => {
                let mean = fallback.iter().sum::<f64>() / fallback.len() as f64;
                vec![mean; self.dim()]
            }
        }
    }

    /// The grid values of one delay: spacing `step` from `τ_min` up to `τ_max`.
    fn axis(&self, step: f64) -> Vec<f64> {
        let count = grid_count(self.tau_min, self.tau_max, step);
        (0..count)
            .map(|i| {
                let v = self.tau_min + i as f64 * step;
                // Snap to whole nanoseconds (0.001 + 6 × 0.001 = 0.007, not 0.0070000001).
                (v * 1e9).round() / 1e9
            })
            .collect()
    }

    /// Every feasible grid point with spacing `step` from `τ_min` (product over the
    /// controlled coordinates), in lexicographic order.
    pub fn grid(&self, step: f64) -> Vec<Vec<f64>> {
        let mut points = product(&self.axis(step), self.dim());
        points.retain(|x| self.taus(x).is_some());
        points
    }

    /// The landscape of a constrained problem over two channels: every pair of grid
    /// delays `(τ_1, τ_2)` (spacing `step`, both within the bounds), the budget ignored,
    /// in lexicographic order; empty for any other problem. The budget line runs
    /// through it, so it shows where the constrained optimum sits in the whole space.
    pub fn landscape(&self, step: f64) -> Vec<Vec<f64>> {
        match self.problem {
            Problem::Constrained { .. } if self.k.len() == 2 => product(&self.axis(step), 2),
            _ => Vec::new(),
        }
    }

    /// The budget line of a two-channel constrained problem: the delay [s] of the other
    /// channel when channel `i` (0 or 1) runs at `tau` [s] and the two use the whole
    /// budget (`None` where channel `i` alone uses it up, or for any other problem).
    pub fn budget_partner(&self, i: usize, tau: f64) -> Option<f64> {
        match self.problem {
            Problem::Constrained { budget } if self.k.len() == 2 && i < 2 => {
                let left = budget - self.k[i] / tau;
                (left > 0.0).then(|| self.k[1 - i] / left)
            }
            _ => None,
        }
    }
}

/// Number of grid values from `lo` to `hi` at spacing `step` (both ends included when
/// `hi − lo` is a whole number of steps).
pub fn grid_count(lo: f64, hi: f64, step: f64) -> usize {
    ((hi - lo) / step + 1e-9).floor() as usize + 1
}

/// Every vector of `dim` values from `axis`, in lexicographic order.
fn product(axis: &[f64], dim: usize) -> Vec<Vec<f64>> {
    let mut points: Vec<Vec<f64>> = vec![Vec::new()];
    for _ in 0..dim {
        points = points
            .into_iter()
            .flat_map(|p| {
                axis.iter().map(move |&v| {
                    let mut q = p.clone();
                    q.push(v);
                    q
                })
            })
            .collect();
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp() -> Delays {
        Delays {
            problem: Problem::Constrained { budget: 400.0 },
            k: vec![1.0, 1.0],
            tau_min: 0.001,
            tau_max: 0.05,
            dt: SimTime(1_000_000),
        }
    }

    #[test]
    fn the_budget_line_runs_both_ways() {
        let d = cp();
        let t2 = d.budget_partner(0, 0.003).unwrap();
        assert!((t2 - 0.015).abs() < 1e-12, "{t2}");
        assert!((d.budget_partner(1, t2).unwrap() - 0.003).abs() < 1e-12);
        assert_eq!(d.budget_partner(0, 0.0025), None, "τ1 alone uses 400 Hz");
        assert_eq!(d.budget_partner(2, 0.003), None);
    }

    #[test]
    fn cp_gives_the_last_channel_the_rest_of_the_budget() {
        let d = cp();
        let taus = d.taus(&[0.003]).unwrap();
        assert!((taus[1] - 0.015).abs() < 1e-12, "{taus:?}");
        assert!((d.bandwidth(&taus) - 400.0).abs() < 1e-9);
        // Over the budget: 1/0.002 = 500 > 400.
        assert!(d.taus(&[0.002]).is_none());
        // The rest would give τ2 above τ_max.
        assert!(d.taus(&[0.0026]).is_none());
    }

    #[test]
    fn achieved_delays_are_the_requested_ones_so_the_budget_is_used() {
        // τ1 = 3.4 ms leaves τ2 = 1/(400 − 1/0.0034) = 9.444… ms: both run to the
        // nanosecond, and together they use the budget to 1e-6 (rounded up to whole
        // steps they were 4 and 10 ms, 350 Hz of 400).
        let d = cp();
        let taus = d.taus(&[0.0034]).unwrap();
        let ach = d.achieved(&taus);
        assert_eq!(ach[0], SimTime(3_400_000));
        assert_eq!(ach[1], SimTime(9_444_444));
        let secs: Vec<f64> = ach.iter().map(|t| t.as_secs_f64()).collect();
        assert!(
            (d.bandwidth(&secs) - 400.0).abs() < 1e-3,
            "{}",
            d.bandwidth(&secs)
        );
        // Never below one step.
        assert_eq!(d.achieved(&[1e-5]), vec![SimTime(1_000_000)]);
    }

    #[test]
    fn no_optimization_is_equal_delays_at_the_budget() {
        let d = cp();
        assert_eq!(d.equal(&[0.004]), vec![0.005]);
    }

    #[test]
    fn grid_points_are_feasible_and_on_the_step() {
        let d = cp();
        let g = d.grid(0.001);
        assert_eq!(g.first().unwrap(), &vec![0.003]);
        assert!(g.iter().all(|x| d.taus(x).is_some()));
        assert_eq!(g.len(), 48); // 0.003 ..= 0.050
        let up = Delays {
            problem: Problem::Unconstrained { penalty: 5e-4 },
            ..cp()
        };
        assert_eq!(up.grid(0.01).len(), 25); // 0.001, 0.011, …, 0.041 per axis
    }

    #[test]
    fn the_simplex_feasible_set_matches_taus() {
        let d = cp();
        let f = d.feasible().unwrap();
        for x in [0.0026, 0.003, 0.01, 0.05, 0.06] {
            assert_eq!(f.contains(&[x]), d.taus(&[x]).is_some(), "x = {x}");
        }
    }
}
