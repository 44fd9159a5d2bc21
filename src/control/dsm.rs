//! Dynamic Simplex Method (Xiong & Jutan 2003), method §5: tracks a moving optimum
//! with a simplex of fixed size, as a pure function of the costs it is told.
//!
//! The optimizer never runs anything itself. It is an ask/tell state machine: [`Dsm::ask`]
//! names the next point to measure, the caller measures it however it likes (a lookahead
//! fork of the co-simulation, or the live plant) and reports the cost with [`Dsm::tell`].
//! [`Dsm::iterate`] wraps one complete iteration around a measuring closure.
//!
//! ```text
//!  start: regular simplex S, edge D_s, centred on x0 ──▶ measure its N+1 vertices
//!  ┌──────────────────────────── one iteration: m_r + 1 measurements ─────────────┐
//!  │ W ← S                                                                         │
//!  │ for p = 1..m_r:  r ← worst vertex of W, skipping the one reflection p−1 made   │
//!  │                  W[r] ← 2·centroid(W without r) − W[r]   (measure it)          │
//!  │                  S_p ← W                                                      │
//!  │ S ← the S_p with the lowest mean vertex cost (S_0 is not a candidate)          │
//!  │ re-measure the best vertex of S and store the new cost                         │
//!  └───────────────────────────────────────────────────────────────────────────────┘
//!  the plant runs at the best vertex of S ([`Dsm::best`]); there is no convergence test
//! ```
//!
//! Rules this implementation fixes (the method leaves them open):
//! - **Ranking.** Vertices are ordered by the key `(infeasible, cost, index)`: feasible
//!   before infeasible, then lower cost, then lower vertex index. The best vertex is the
//!   first in that order, the worst the last. Costs are compared with
//!   [`f64::total_cmp`]; a told NaN is stored as `+∞`.
//! - **Candidates.** Only `S_1 ..= S_m_r` compete (method §5: "continue from the `S_q`"); the starting
//!   simplex `S_0` does not. They are ordered by `(number of infeasible vertices, mean
//!   vertex cost, p)`, the lowest wins, so ties go to the earliest reflection. When every
//!   vertex is feasible this is exactly "the lowest mean vertex cost".
//! - **Infeasible reflections.** A reflected point outside [`Feasible`] is never handed to
//!   the caller: it enters the working simplex at once with cost `+∞`, flagged infeasible,
//!   and counts as reflection `p` (so `S_p` holds it and has an infinite mean). Reflection
//!   `p + 1` then reflects the worst vertex other than that one, as after any reflection.
//!   An iteration therefore asks `1 + (m_r − skipped)` points, see
//!   [`Dsm::skipped_last_iteration`]. Reflections are prepared eagerly, so the skips that
//!   open an iteration happen inside the `tell` that ends the previous one.
//! - **Best is always feasible.** Reflection 1 always reflects the worst vertex, which is
//!   the infeasible one if there is any, so the current simplex never holds more than one
//!   infeasible vertex and (N ≥ 1) always a measured one; infeasible vertices rank last.
//! - **Size.** Reflection is an isometry: edges keep the length `D_s` up to rounding
//!   (relative drift of order `1e−16 · √(reflections)`; nothing re-normalizes it).
//!
//! Limits, seen in the tests of this module:
//! - **Speed.** Unconstrained, on a static bowl far away, the 2-D simplex travels exactly
//!   `m_r · D_s / 2` per iteration. On a bowl moving at `v`, stored costs go stale, and in
//!   our runs (m_r = 5, 1000 iterations) tracking held up to `(m_r + 1) v T = 0.9 D_s`
//!   per iteration without noise and `0.8 D_s` with noise of ±0.5 D_s², and broke down
//!   from `0.95 D_s` without noise and at `1.0 D_s`, i.e. at `D_s = D_smin`, with and
//!   without noise: a kept vertex's cost, up to one iteration stale, then outranks a
//!   fresh vertex one edge nearer the optimum (tests
//!   `tracks_an_optimum_with_a_simplex_a_quarter_above_d_smin`,
//!   `loses_the_optimum_at_the_boundary_d_s_equal_to_d_smin`). So `D_s ≥ D_smin` is
//!   necessary but not sufficient here; `D_s = 1.25 D_smin` tracked. The thesis's
//!   `D_s = 2 D_smin` tracks within 2 D_s. Faster optima are lost entirely: once costs
//!   are dominated by time rather than position, the simplex stops following.
//! - **Walls.** Pure reflections keep the vertices on one triangular lattice of spacing
//!   `D_s`. At a wall not aligned with it, a static cost can trap the simplex at a lattice
//!   point whose neighbours towards the optimum are infeasible: the best ends within
//!   `D_s` of the wall but may sit several `D_s` along it from the nearest point to the
//!   optimum. In one dimension (CP with the last delay eliminated) this cannot happen.
//!
//! Everything is deterministic: no randomness, no hash maps.

mod feasible;
mod simplex;

pub use feasible::{DsmError, Feasible, SimplexError};
pub(crate) use simplex::sanitize;
use simplex::Simplex;
pub use simplex::{d_s_min, regular_simplex};

/// Parameters of the DSM.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DsmConfig {
    /// Edge length `D_s` of the simplex [units of x]; thesis 0.012 s. Should be at least
    /// [`d_s_min`] for the speed of the optimum.
    pub size: f64,
    /// Reflections per iteration `m_r` (≥ 1); thesis 5.
    pub reflections: usize,
}

/// Where the DSM stands: what the next [`Dsm::ask`] is for. For traces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum DsmPhase {
    /// Measuring vertex `vertex` (0-based) of the starting simplex of `of` vertices.
    Initial {
        /// 0-based vertex index.
        vertex: usize,
        /// N + 1.
        of: usize,
    },
    /// Measuring the point made by reflection `p` (1-based) of `of` (= m_r).
    Reflecting {
        /// 1-based reflection number.
        p: usize,
        /// m_r.
        of: usize,
    },
    /// Re-measuring vertex `vertex`, the best of the chosen simplex `S_q`.
    Remeasuring {
        /// 0-based vertex index in [`Dsm::vertices`].
        vertex: usize,
        /// q, the reflection whose simplex was chosen (1-based).
        chosen: usize,
    },
}

/// Reflection `p` to prepare, with the working simplex, the best candidate so far and
/// the vertex the previous reflection made.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Pass {
    p: usize,
    work: Simplex,
    chosen: Option<(usize, Simplex)>,
    last_created: Option<usize>,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
enum Stage {
    Initial {
        next: usize,
    },
    Reflecting {
        p: usize,
        work: Simplex,
        chosen: Option<(usize, Simplex)>,
        target: usize,
        point: Vec<f64>,
    },
    Remeasuring {
        vertex: usize,
        chosen: usize,
    },
}

/// The Dynamic Simplex optimizer: an ask/tell state machine (see the module docs for the
/// rules). `Clone` so that the simulator can fork and checkpoint it.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Dsm {
    config: DsmConfig,
    feasible: Feasible,
    current: Simplex,
    stage: Stage,
    iterations: usize,
    measurements: usize,
    skipped: usize,
    /// Skips in the iteration under way (reflections are prepared eagerly, so the first
    /// skips of an iteration happen inside the `tell` that ends the previous one).
    skipped_now: usize,
    /// Skips in the last completed iteration.
    skipped_last: usize,
}

impl Dsm {
    /// A DSM starting from the regular simplex of edge `config.size` centred on `x0`,
    /// moved into `feasible` if needed ([`Feasible::fit_simplex`]). Errors on bad
    /// parameters or when no placement of the simplex is feasible.
    pub fn new(config: DsmConfig, x0: &[f64], feasible: Feasible) -> Result<Dsm, DsmError> {
        if config.reflections == 0 {
            return Err(SimplexError::NoReflections);
        }
        let vertices = feasible.fit_simplex(x0, config.size)?;
        Ok(Dsm {
            config,
            feasible,
            current: Simplex::unmeasured(vertices),
            stage: Stage::Initial { next: 0 },
            iterations: 0,
            measurements: 0,
            skipped: 0,
            skipped_now: 0,
            skipped_last: 0,
        })
    }

    /// The next point to measure; always inside [`Feasible`]. Asking again without a
    /// [`tell`](Dsm::tell) returns the same point. The DSM never stops, so this is always
    /// `Some`; the `Option` matches [`NelderMead::ask`](super::nelder_mead::NelderMead::ask).
    pub fn ask(&self) -> Option<Vec<f64>> {
        Some(self.pending().to_vec())
    }

    fn pending(&self) -> &[f64] {
        match &self.stage {
            Stage::Initial { next } => &self.current.x[*next],
            Stage::Reflecting { point, .. } => point,
            Stage::Remeasuring { vertex, .. } => &self.current.x[*vertex],
        }
    }

    /// Reports the cost of the point [`ask`](Dsm::ask) returns now (NaN is stored as
    /// `+∞`) and moves on.
    pub fn tell(&mut self, cost: f64) {
        let cost = sanitize(cost);
        self.measurements += 1;
        let stage = std::mem::replace(&mut self.stage, Stage::Initial { next: 0 });
        match stage {
            Stage::Initial { next } => {
                self.current.cost[next] = cost;
                if next + 1 < self.current.x.len() {
                    self.stage = Stage::Initial { next: next + 1 };
                } else {
                    self.begin_iteration();
                }
            }
            Stage::Reflecting {
                p,
                mut work,
                chosen,
                target,
                point,
            } => {
                work.x[target] = point;
                work.cost[target] = cost;
                work.infeasible[target] = false;
                if let Some(next) = self.after_reflection(p, work, chosen, target) {
                    self.reflect(next);
                }
            }
            Stage::Remeasuring { vertex, .. } => {
                self.current.cost[vertex] = cost;
                self.iterations += 1;
                self.skipped_last = self.skipped_now;
                self.begin_iteration();
            }
        }
    }

    fn begin_iteration(&mut self) {
        self.skipped_now = 0;
        let pass = Pass {
            p: 1,
            work: self.current.clone(),
            chosen: None,
            last_created: None,
        };
        self.reflect(pass);
    }

    /// Prepares reflection `pass.p` of `pass.work`, skipping (cost `+∞`, unmeasured)
    /// every infeasible reflected point. A loop, not recursion: `m_r` is user input.
    fn reflect(&mut self, mut pass: Pass) {
        loop {
            let target = pass.work.worst_except(pass.last_created);
            let point = pass.work.reflect(target);
            if self.feasible.contains(&point) {
                self.stage = Stage::Reflecting {
                    p: pass.p,
                    work: pass.work,
                    chosen: pass.chosen,
                    target,
                    point,
                };
                return;
            }
            self.skipped += 1;
            self.skipped_now += 1;
            let mut work = pass.work;
            work.x[target] = point;
            work.cost[target] = f64::INFINITY;
            work.infeasible[target] = true;
            match self.after_reflection(pass.p, work, pass.chosen, target) {
                Some(next) => pass = next,
                None => return,
            }
        }
    }

    /// `work` is now `S_p`, its vertex `created` the one reflection `p` made. Returns the
    /// next reflection to prepare, or `None` once `S_q` is chosen.
    fn after_reflection(
        &mut self,
        p: usize,
        work: Simplex,
        chosen: Option<(usize, Simplex)>,
        created: usize,
    ) -> Option<Pass> {
        // Strictly better replaces, so ties go to the earliest reflection.
        let chosen = match chosen {
            Some(c) if !work.beats(&c.1) => c,
            _ => (p, work.clone()),
        };
        if p < self.config.reflections {
            Some(Pass {
                p: p + 1,
                work,
                chosen: Some(chosen),
                last_created: Some(created),
            })
        } else {
            let (q, simplex) = chosen;
            self.current = simplex;
            self.stage = Stage::Remeasuring {
                vertex: self.current.best(),
                chosen: q,
            };
            None
        }
    }

    /// Runs one complete iteration (or, first, the initial measurement of the N + 1
    /// vertices), calling `measure` on every asked point. Returns the number of
    /// measurements made: `m_r + 1 − skipped` per iteration.
    pub fn iterate(&mut self, mut measure: impl FnMut(&[f64]) -> f64) -> usize {
        let initial = matches!(self.stage, Stage::Initial { .. });
        let start = self.iterations;
        let mut made = 0;
        loop {
            let cost = measure(self.pending());
            self.tell(cost);
            made += 1;
            let done = if initial {
                !matches!(self.stage, Stage::Initial { .. })
            } else {
                self.iterations > start
            };
            if done {
                return made;
            }
        }
    }

    /// Where the plant should run now: the best vertex (lowest stored cost, ties to the
    /// lower index) of the current simplex. Always feasible. While the initial vertices are
    /// being measured, unmeasured ones count as `+∞` (so before any, it is vertex 0).
    pub fn best(&self) -> &[f64] {
        &self.current.x[self.current.best()]
    }

    /// Index of [`best`](Dsm::best) in [`vertices`](Dsm::vertices).
    pub fn best_index(&self) -> usize {
        self.current.best()
    }

    /// Vertices of the current simplex (`S_0` of the iteration under way; `S_q` once
    /// chosen).
    pub fn vertices(&self) -> &[Vec<f64>] {
        &self.current.x
    }

    /// Stored costs of [`vertices`](Dsm::vertices) (`+∞` for unmeasured or infeasible).
    pub fn costs(&self) -> &[f64] {
        &self.current.cost
    }

    /// Whether vertex `i` of the current simplex is an infeasible (never measured) point.
    pub fn is_infeasible(&self, i: usize) -> bool {
        self.current.infeasible.get(i).copied().unwrap_or(false)
    }

    /// Completed iterations (the initial measurement is not one).
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Costs told so far.
    pub fn measurements(&self) -> usize {
        self.measurements
    }

    /// Reflections that fell outside [`Feasible`] and were skipped without a measurement.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// Reflections skipped as infeasible in the last completed iteration, which therefore
    /// asked `m_r + 1 −` this many points.
    pub fn skipped_last_iteration(&self) -> usize {
        self.skipped_last
    }

    /// What the next [`ask`](Dsm::ask) is for.
    pub fn phase(&self) -> DsmPhase {
        match &self.stage {
            Stage::Initial { next } => DsmPhase::Initial {
                vertex: *next,
                of: self.current.x.len(),
            },
            Stage::Reflecting { p, .. } => DsmPhase::Reflecting {
                p: *p,
                of: self.config.reflections,
            },
            Stage::Remeasuring { vertex, chosen } => DsmPhase::Remeasuring {
                vertex: *vertex,
                chosen: *chosen,
            },
        }
    }

    /// The parameters.
    pub fn config(&self) -> DsmConfig {
        self.config
    }

    /// The feasible set.
    pub fn feasible(&self) -> &Feasible {
        &self.feasible
    }
}

#[cfg(test)]
mod tests;
