//! Static Nelder–Mead baseline (method §5): the textbook simplex search, which treats
//! the cost as if it did not move with time. Same ask/tell interface and constraint
//! handling as the [`Dsm`](super::dsm::Dsm).
//!
//! One iteration, with vertices ranked `f_1 ≤ … ≤ f_{N+1}` and `c` the centroid of the
//! best `N` (coefficients: reflection 1, expansion 2, contraction ½, shrink ½; the step
//! structure of Lagarias et al. 1998):
//! ```text
//!  x_r = c + (c − x_{N+1})                       measure f_r
//!  f_r < f_1          → x_e = c + 2(c − x_{N+1}), accept x_e if f_e < f_r, else x_r
//!  f_1 ≤ f_r < f_N    → accept x_r
//!  f_N ≤ f_r < f_N+1  → x_c = c + ½(x_r − c),  accept if f_c ≤ f_r, else shrink
//!  f_r ≥ f_{N+1}      → x_cc = c − ½(c − x_{N+1}), accept if f_cc < f_{N+1}, else shrink
//!  shrink: x_i ← x_1 + ½(x_i − x_1) for i ≥ 2, measure each
//! ```
//! Rules fixed here:
//! - **Ties.** Vertices are ranked by `(infeasible, cost, age)`: an accepted point is
//!   younger than every vertex it joins, so among equal costs it ranks last (Lagarias'
//!   non-shrink rule); after a shrink `x_1` keeps its age and the shrunk vertices age in
//!   their previous rank order (Lagarias' shrink rule).
//! - **Infeasible points** (outside [`Feasible`]) are never asked: they get cost `+∞`
//!   without a measurement ([`NelderMead::skipped`] counts them). An infeasible reflection
//!   therefore leads to an inside contraction, an infeasible expansion to accepting `x_r`.
//!   Contraction and shrink points are convex combinations of vertices and the feasible
//!   set is convex, so they are infeasible only through rounding; a shrink point that is
//!   stays in the simplex with `+∞` and ranks last. An accepted point always had a finite
//!   cost below a vertex's, so it was measured; [`NelderMead::best`] is always feasible.
//! - **Stop.** At the start of an iteration the search stops ([`NelderMead::ask`] returns
//!   `None`) when `max_i ‖x_i − x_1‖_∞ ≤ x_tolerance` and `max_i |f_i − f_1| ≤
//!   f_tolerance`, or when the simplex has collapsed to one point.

use std::cmp::Ordering;

use super::dsm::{sanitize, Feasible, SimplexError};

/// Parameters of the Nelder–Mead search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NelderMeadConfig {
    /// Edge length of the initial regular simplex around `x0` [units of x].
    pub size: f64,
    /// Stop when every vertex is within this distance (max norm) of the best [units of x];
    /// 0 never stops on it alone.
    pub x_tolerance: f64,
    /// ... and every cost within this of the best cost [units of cost].
    pub f_tolerance: f64,
}

/// What the next [`NelderMead::ask`] is for. For traces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum NelderMeadPhase {
    /// Measuring vertex `vertex` (0-based) of the initial simplex.
    Initial {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// Measuring the reflected point.
    Reflect,
    /// Measuring the expanded point.
    Expand,
    /// Measuring the outside contraction.
    OutsideContraction,
    /// Measuring the inside contraction.
    InsideContraction,
    /// Measuring shrunk vertex `vertex` (0-based index in [`NelderMead::vertices`]).
    Shrink {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// Stopped: the tolerances are met or the simplex collapsed.
    Converged,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
enum Stage {
    Initial {
        next: usize,
    },
    Reflect {
        point: Vec<f64>,
    },
    Expand {
        reflected: Vec<f64>,
        f_reflected: f64,
        point: Vec<f64>,
    },
    OutsideContraction {
        f_reflected: f64,
        point: Vec<f64>,
    },
    InsideContraction {
        point: Vec<f64>,
    },
    Shrink {
        next: usize,
    },
    Converged,
}

/// Nelder–Mead as an ask/tell state machine. `Clone` for forks and checkpoints.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct NelderMead {
    config: NelderMeadConfig,
    feasible: Feasible,
    x: Vec<Vec<f64>>,
    f: Vec<f64>,
    infeasible: Vec<bool>,
    age: Vec<u64>,
    next_age: u64,
    /// Vertex indices best first, fixed at the start of the iteration.
    order: Vec<usize>,
    /// Centroid of all but the worst, fixed at the start of the iteration.
    centroid: Vec<f64>,
    stage: Stage,
    iterations: usize,
    measurements: usize,
    skipped: usize,
}

impl NelderMead {
    /// A search starting from the regular simplex of edge `config.size` centred on `x0`,
    /// moved into `feasible` if needed ([`Feasible::fit_simplex`]).
    pub fn new(
        config: NelderMeadConfig,
        x0: &[f64],
        feasible: Feasible,
    ) -> Result<NelderMead, SimplexError> {
        for tol in [config.x_tolerance, config.f_tolerance] {
            if tol.is_nan() || tol < 0.0 {
                return Err(SimplexError::BadTolerance(tol));
            }
        }
        let x = feasible.fit_simplex(x0, config.size)?;
        let m = x.len();
        Ok(NelderMead {
            config,
            feasible,
            x,
            f: vec![f64::INFINITY; m],
            infeasible: vec![false; m],
            age: (0..m as u64).collect(),
            next_age: m as u64,
            order: (0..m).collect(),
            centroid: Vec::new(),
            stage: Stage::Initial { next: 0 },
            iterations: 0,
            measurements: 0,
            skipped: 0,
        })
    }

    fn rank(&self, a: usize, b: usize) -> Ordering {
        self.infeasible[a]
            .cmp(&self.infeasible[b])
            .then(self.f[a].total_cmp(&self.f[b]))
            .then(self.age[a].cmp(&self.age[b]))
    }

    fn sorted(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.x.len()).collect();
        order.sort_by(|&a, &b| self.rank(a, b));
        order
    }

    /// The next point to measure (always inside [`Feasible`]), or `None` once stopped.
    /// Asking again without a [`tell`](NelderMead::tell) returns the same point.
    pub fn ask(&self) -> Option<Vec<f64>> {
        self.pending().map(<[f64]>::to_vec)
    }

    fn pending(&self) -> Option<&[f64]> {
        match &self.stage {
            Stage::Initial { next } => Some(&self.x[*next]),
            Stage::Reflect { point }
            | Stage::Expand { point, .. }
            | Stage::OutsideContraction { point, .. }
            | Stage::InsideContraction { point } => Some(point),
            Stage::Shrink { next } => Some(&self.x[self.order[*next]]),
            Stage::Converged => None,
        }
    }

    /// Reports the cost of the point [`ask`](NelderMead::ask) returns now (NaN is stored
    /// as `+∞`). Ignored once stopped.
    pub fn tell(&mut self, cost: f64) {
        if matches!(self.stage, Stage::Converged) {
            return;
        }
        self.measurements += 1;
        self.advance(sanitize(cost));
        self.settle();
    }

    /// Skips infeasible pending points (cost `+∞`, not measured).
    fn settle(&mut self) {
        while let Some(x) = self.pending() {
            if self.feasible.contains(x) {
                return;
            }
            self.skipped += 1;
            if let Stage::Shrink { next } = self.stage {
                self.infeasible[self.order[next]] = true;
            }
            self.advance(f64::INFINITY);
        }
    }

    fn advance(&mut self, cost: f64) {
        let stage = std::mem::replace(&mut self.stage, Stage::Converged);
        let n = self.x.len() - 1;
        let worst = self.order[n];
        match stage {
            Stage::Initial { next } => {
                self.f[next] = cost;
                if next < n {
                    self.stage = Stage::Initial { next: next + 1 };
                } else {
                    self.begin();
                }
            }
            Stage::Reflect { point } => {
                let (f1, fn_, fw) = (
                    self.f[self.order[0]],
                    self.f[self.order[n - 1]],
                    self.f[worst],
                );
                if cost < f1 {
                    self.stage = Stage::Expand {
                        point: self.along(2.0),
                        reflected: point,
                        f_reflected: cost,
                    };
                } else if cost < fn_ {
                    self.accept(point, cost);
                } else if cost < fw {
                    self.stage = Stage::OutsideContraction {
                        point: self.along(0.5),
                        f_reflected: cost,
                    };
                } else {
                    self.stage = Stage::InsideContraction {
                        point: self.along(-0.5),
                    };
                }
            }
            Stage::Expand {
                reflected,
                f_reflected,
                point,
            } => {
                if cost < f_reflected {
                    self.accept(point, cost);
                } else {
                    self.accept(reflected, f_reflected);
                }
            }
            Stage::OutsideContraction { f_reflected, point } => {
                if cost <= f_reflected {
                    self.accept(point, cost);
                } else {
                    self.shrink();
                }
            }
            Stage::InsideContraction { point } => {
                if cost < self.f[worst] {
                    self.accept(point, cost);
                } else {
                    self.shrink();
                }
            }
            Stage::Shrink { next } => {
                self.f[self.order[next]] = cost;
                if next < n {
                    self.stage = Stage::Shrink { next: next + 1 };
                } else {
                    self.iterations += 1;
                    self.begin();
                }
            }
            Stage::Converged => {}
        }
    }

    /// `c + s (c − x_worst)`.
    fn along(&self, s: f64) -> Vec<f64> {
        let w = &self.x[self.order[self.x.len() - 1]];
        self.centroid
            .iter()
            .zip(w)
            .map(|(c, w)| c + s * (c - w))
            .collect()
    }

    fn accept(&mut self, point: Vec<f64>, cost: f64) {
        let worst = self.order[self.x.len() - 1];
        self.x[worst] = point;
        self.f[worst] = cost;
        self.infeasible[worst] = false;
        self.age[worst] = self.next_age;
        self.next_age += 1;
        self.iterations += 1;
        self.begin();
    }

    fn shrink(&mut self) {
        let best = self.order[0];
        let x1 = self.x[best].clone();
        for &i in &self.order[1..] {
            for (v, b) in self.x[i].iter_mut().zip(&x1) {
                *v = b + 0.5 * (*v - b);
            }
            self.f[i] = f64::INFINITY;
            self.infeasible[i] = false;
            self.age[i] = self.next_age;
            self.next_age += 1;
        }
        self.stage = Stage::Shrink { next: 1 };
    }

    /// Starts an iteration: ranks, tests the stop rule, asks the reflection.
    fn begin(&mut self) {
        self.order = self.sorted();
        let n = self.x.len() - 1;
        let best = self.order[0];
        let spread_x = self
            .x
            .iter()
            .flat_map(|v| v.iter().zip(&self.x[best]).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        let spread_f = self
            .f
            .iter()
            .map(|f| (f - self.f[best]).abs())
            .fold(
                0.0,
                |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
            );
        let collapsed = spread_x == 0.0;
        if collapsed || (spread_x <= self.config.x_tolerance && spread_f <= self.config.f_tolerance)
        {
            self.stage = Stage::Converged;
            return;
        }
        let dim = self.x[0].len();
        self.centroid = (0..dim)
            .map(|d| self.order[..n].iter().map(|&i| self.x[i][d]).sum::<f64>() / n as f64)
            .collect();
        self.stage = Stage::Reflect {
            point: self.along(1.0),
        };
    }

    /// Asks and tells until stopped or `max_measurements` costs have been told in this
    /// call; returns how many were.
    pub fn minimize(
        &mut self,
        max_measurements: usize,
        mut measure: impl FnMut(&[f64]) -> f64,
    ) -> usize {
        let mut made = 0;
        while made < max_measurements {
            let Some(x) = self.pending() else { break };
            let cost = measure(x);
            self.tell(cost);
            made += 1;
        }
        made
    }

    /// The best vertex (lowest cost, ties to the older vertex). Always feasible.
    pub fn best(&self) -> &[f64] {
        &self.x[self.best_index()]
    }

    /// Stored cost of [`best`](NelderMead::best).
    pub fn best_cost(&self) -> f64 {
        self.f[self.best_index()]
    }

    fn best_index(&self) -> usize {
        (1..self.x.len()).fold(0, |b, i| {
            if self.rank(i, b) == Ordering::Less {
                i
            } else {
                b
            }
        })
    }

    /// Vertices of the simplex (storage order, not ranked).
    pub fn vertices(&self) -> &[Vec<f64>] {
        &self.x
    }

    /// Stored costs of [`vertices`](NelderMead::vertices) (`+∞` for unmeasured or
    /// infeasible).
    pub fn costs(&self) -> &[f64] {
        &self.f
    }

    /// Completed iterations (accepted points plus completed shrinks).
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Costs told so far.
    pub fn measurements(&self) -> usize {
        self.measurements
    }

    /// Points skipped as infeasible without a measurement.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// Whether the search has stopped.
    pub fn converged(&self) -> bool {
        matches!(self.stage, Stage::Converged)
    }

    /// What the next [`ask`](NelderMead::ask) is for.
    pub fn phase(&self) -> NelderMeadPhase {
        match &self.stage {
            Stage::Initial { next } => NelderMeadPhase::Initial { vertex: *next },
            Stage::Reflect { .. } => NelderMeadPhase::Reflect,
            Stage::Expand { .. } => NelderMeadPhase::Expand,
            Stage::OutsideContraction { .. } => NelderMeadPhase::OutsideContraction,
            Stage::InsideContraction { .. } => NelderMeadPhase::InsideContraction,
            Stage::Shrink { next } => NelderMeadPhase::Shrink {
                vertex: self.order[*next],
            },
            Stage::Converged => NelderMeadPhase::Converged,
        }
    }

    /// The parameters.
    pub fn config(&self) -> NelderMeadConfig {
        self.config
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::dsm::regular_simplex;

    fn rosenbrock(x: &[f64]) -> f64 {
        100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2)
    }

    fn config(size: f64, tol: f64) -> NelderMeadConfig {
        NelderMeadConfig {
            size,
            x_tolerance: tol,
            f_tolerance: tol,
        }
    }

    #[test]
    fn finds_the_rosenbrock_minimum() {
        let feasible = Feasible::boxed(vec![-2.0, -2.0], vec![2.0, 2.0]).unwrap();
        let mut nm = NelderMead::new(config(0.5, 1e-10), &[-1.2, 1.0], feasible.clone()).unwrap();
        let made = nm.minimize(2000, |x| {
            assert!(feasible.contains(x), "asked {x:?}");
            rosenbrock(x)
        });
        let b = nm.best();
        eprintln!("rosenbrock: {made} measurements, best {b:?}");
        assert!(nm.converged(), "stopped within 2000 measurements");
        assert!(
            (b[0] - 1.0).abs() < 1e-4 && (b[1] - 1.0).abs() < 1e-4,
            "best {b:?}"
        );
        assert!(nm.best_cost() < 1e-8);
    }

    #[test]
    fn finds_a_quadratic_minimum_in_3d() {
        let c = [0.3, -0.7, 1.1];
        let f = |x: &[f64]| -> f64 {
            x.iter()
                .zip(&c)
                .enumerate()
                .map(|(i, (x, c))| (i + 1) as f64 * (x - c).powi(2))
                .sum()
        };
        let mut nm =
            NelderMead::new(config(1.0, 1e-12), &[0.0; 3], Feasible::unbounded(3)).unwrap();
        let made = nm.minimize(1000, f);
        assert!(nm.converged(), "stopped after {made}");
        for (b, c) in nm.best().iter().zip(&c) {
            assert!((b - c).abs() < 1e-5, "best {:?}", nm.best());
        }
    }

    #[test]
    fn respects_a_box_with_the_optimum_outside() {
        // min |x − (2, 0.5)|² over [0, 1]²: the answer is (1, 0.5).
        let feasible = Feasible::boxed(vec![0.0, 0.0], vec![1.0, 1.0]).unwrap();
        let mut nm = NelderMead::new(config(0.2, 1e-10), &[0.2, 0.2], feasible.clone()).unwrap();
        nm.minimize(2000, |x| {
            assert!(feasible.contains(x), "asked {x:?}");
            (x[0] - 2.0).powi(2) + (x[1] - 0.5).powi(2)
        });
        let b = nm.best();
        assert!(feasible.contains(b));
        assert!(nm.skipped() > 0, "the wall was hit");
        assert!(
            (b[0] - 1.0).abs() < 1e-4 && (b[1] - 0.5).abs() < 1e-4,
            "best {b:?}"
        );
    }

    #[test]
    fn respects_a_budget() {
        // min τ1 + τ2 subject to 1/τ1 + 1/τ2 ≤ 400 Hz: τ1 = τ2 = 5 ms.
        let feasible = Feasible::boxed(vec![0.001; 2], vec![0.05; 2])
            .unwrap()
            .with_budget(vec![1.0, 1.0], 400.0)
            .unwrap();
        let mut nm =
            NelderMead::new(config(0.004, 1e-12), &[0.02, 0.03], feasible.clone()).unwrap();
        nm.minimize(5000, |x| {
            assert!(feasible.contains(x), "asked {x:?}");
            x[0] + x[1]
        });
        let b = nm.best();
        assert!(feasible.contains(b));
        assert!(
            (b[0] - 0.005).abs() < 2e-4 && (b[1] - 0.005).abs() < 2e-4,
            "best {b:?}"
        );
    }

    #[test]
    fn steps_follow_the_textbook_on_a_line() {
        // 1-D, f = x, start {−.5, .5}: reflect to −1.5 (< f_1) → expand to −2.5, accepted.
        let mut nm = NelderMead::new(config(1.0, 0.0), &[0.0], Feasible::unbounded(1)).unwrap();
        assert_eq!(regular_simplex(&[0.0], 1.0), nm.vertices());
        nm.tell(-0.5);
        nm.tell(0.5);
        assert_eq!(nm.phase(), NelderMeadPhase::Reflect);
        assert_eq!(nm.ask().unwrap(), vec![-1.5]);
        nm.tell(-1.5);
        assert_eq!(nm.phase(), NelderMeadPhase::Expand);
        assert_eq!(nm.ask().unwrap(), vec![-2.5]);
        nm.tell(-2.5);
        assert_eq!(nm.best(), &[-2.5]);
        assert_eq!(nm.vertices(), &[vec![-0.5], vec![-2.5]]);
        // A reflection worse than the worst contracts inside: c − ½(c − x_w).
        assert_eq!(nm.ask().unwrap(), vec![-4.5]);
        nm.tell(10.0);
        assert_eq!(nm.phase(), NelderMeadPhase::InsideContraction);
        assert_eq!(nm.ask().unwrap(), vec![-1.5]);
        nm.tell(10.0); // not better than the worst (−0.5): shrink towards −2.5
        assert_eq!(nm.phase(), NelderMeadPhase::Shrink { vertex: 0 });
        assert_eq!(nm.ask().unwrap(), vec![-1.5]);
    }

    #[test]
    fn equal_costs_rank_the_older_vertex_first() {
        let mut nm = NelderMead::new(config(1.0, 0.0), &[0.0], Feasible::unbounded(1)).unwrap();
        nm.tell(1.0);
        nm.tell(1.0);
        assert_eq!(nm.best(), nm.vertices()[0].as_slice(), "tie: lower age");
    }
}
