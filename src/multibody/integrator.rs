//! One integration step `t_k → t_{k+1} = t_k + dt`, split in two so that the caller can
//! record the values at `t_k` (which the first rate evaluation computes) in between:
//!
//! ```text
//! system.begin_step(t_k, &state)?;   // rates at (t_k, x_k): w_k, ẇ_k, Baumgarte z_k
//! record(t_k, &state, &system);      // trace / digest / divergence check
//! system.finish_step(t_k, &mut state)?;
//! ```
//!
//! - `euler`: `x_{k+1} = x_k + dt f(t_k, x_k)` over the whole `(x, v, z)` state, every
//!   rate (and every force) evaluated at the start of the step (the thesis's scheme).
//! - `symplectic_euler`: `v, ω, z` first with the rates at `t_k`, then `p, q` with the
//!   new velocities.
//! - `rk4`: classical Runge–Kutta; stage times `t_k + dt/2` are rounded down to whole
//!   nanoseconds (exact for any even `dt` in ns).
//!
//! Quaternions are re-normalized after every step (all three schemes).

use nalgebra::Quaternion;

use super::dynamics::EvalError;
use super::solver::{dense_cholesky_solve_batch, DenseProblem, SolveError, BATCH};
use super::state::State;
use super::system::System;
use crate::kernel::SimTime;
use crate::scenario::model::Integrator;

impl System {
    /// Evaluates the rates at the start of the step (stage 1 of every scheme).
    pub fn begin_step(&mut self, t: SimTime, state: &State) -> Result<(), EvalError> {
        let mut k1 = std::mem::replace(&mut self.k[0], empty_rates());
        let r = self.rates(t, state, &mut k1);
        self.k[0] = k1;
        if r.is_ok() {
            self.note_step_multipliers();
            self.book_row_forces(self.first_stage_weight(), true);
        }
        r
    }

    /// The weight [s] of the first stage's rates in the step: `h`, or `h/6` under RK4.
    fn first_stage_weight(&self) -> f64 {
        let h = self.dt.as_secs_f64();
        if self.integrator == Integrator::Rk4 {
            h / 6.0
        } else {
            h
        }
    }

    /// [`begin_step`](Self::begin_step) of several independent systems (the nodes of a
    /// partitioned run), with the same results and the same first error (index into
    /// `systems`) as calling it on each in order: the small dense multiplier solves of up
    /// to `BATCH` systems run interleaved (`dense_cholesky_solve_batch`).
    pub fn begin_steps<'a>(
        t: SimTime,
        systems: impl IntoIterator<Item = (&'a mut System, &'a State)>,
    ) -> Result<(), (usize, EvalError)> {
        let mut systems = systems.into_iter();
        let mut base = 0;
        loop {
            let mut chunk: [Option<(&mut System, &State)>; BATCH] =
                std::array::from_fn(|_| systems.next());
            match &mut chunk {
                [None, ..] => return Ok(()),
                // A lone system (a monolithic run, or the last of several): nothing to
                // interleave, so the plain evaluation, without the batch bookkeeping.
                [Some((sys, state)), None, ..] => {
                    return sys.begin_step(t, state).map_err(|e| (base, e));
                }
                _ => {}
            }
            // Up to the right-hand sides; a failure ends the chunk there (the systems
            // after it would not have been evaluated).
            let mut prepared = 0;
            let mut failed = None;
            for (sys, state) in chunk.iter_mut().flatten() {
                if let Err(e) = sys.rates_to_rhs(t, state) {
                    failed = Some((prepared, e));
                    break;
                }
                prepared += 1;
            }
            let mut solve_errors: [Option<SolveError>; BATCH] = Default::default();
            let mut problems: [Option<DenseProblem>; BATCH] = Default::default();
            for ((entry, problem), error) in chunk
                .iter_mut()
                .take(prepared)
                .zip(problems.iter_mut())
                .zip(solve_errors.iter_mut())
            {
                let Some((sys, _)) = entry else { continue };
                let sys: &mut System = sys;
                if sys.solver.is_dense() {
                    if let Some(a) = sys.solver.assemble_dense(&sys.geo, &sys.mass) {
                        *problem = Some(DenseProblem {
                            a,
                            b: &sys.ws.rhs,
                            x: &mut sys.ws.sol,
                            result: Ok(()),
                        });
                    }
                } else {
                    *error = sys
                        .solver
                        .solve(&sys.geo, &sys.mass, &sys.ws.rhs, &mut sys.ws.sol)
                        .and_then(|()| sys.check_cg_budget())
                        .err();
                }
            }
            dense_cholesky_solve_batch(&mut problems);
            for (problem, error) in problems.iter().zip(solve_errors.iter_mut()) {
                if let Some(p) = problem {
                    *error = p.result.clone().err();
                }
            }
            // The first failure in system order, as sequential calls would report it.
            let first_solve_error = solve_errors
                .iter_mut()
                .enumerate()
                .find_map(|(i, e)| e.take().map(|e| (i, e)));
            let done = first_solve_error.as_ref().map_or(prepared, |&(i, _)| i);
            for (sys, state) in chunk.iter_mut().take(done).flatten() {
                let mut k1 = std::mem::replace(&mut sys.k[0], empty_rates());
                sys.rates_from_solution(state, &mut k1);
                sys.k[0] = k1;
                sys.note_step_multipliers();
                let weight = sys.first_stage_weight();
                sys.book_row_forces(weight, true);
            }
            if let Some((i, e)) = first_solve_error {
                let failure = match &chunk[i] {
                    Some((sys, _)) => sys.solve_failure(e),
                    None => EvalError::Solve(e),
                };
                return Err((base + i, failure));
            }
            if let Some((i, e)) = failed {
                return Err((base + i, e));
            }
            base += BATCH;
        }
    }

    /// Completes the step begun by [`begin_step`](Self::begin_step) at the same `t`.
    pub fn finish_step(&mut self, t: SimTime, state: &mut State) -> Result<(), EvalError> {
        let h = self.dt.as_secs_f64();
        match self.integrator {
            Integrator::Euler => {
                state.add_scaled(&self.k[0], h);
            }
            Integrator::SymplecticEuler => {
                let k1 = &self.k[0];
                for (v, a) in state.v.iter_mut().zip(&k1.v) {
                    *v += a * h;
                }
                for (w, a) in state.omega.iter_mut().zip(&k1.omega) {
                    *w += a * h;
                }
                for (z, dz) in state.z.iter_mut().zip(&k1.z) {
                    *z += dz * h;
                }
                for (p, v) in state.p.iter_mut().zip(&state.v) {
                    *p += v * h;
                }
                for (q, w) in state.q.iter_mut().zip(&state.omega) {
                    *q += Quaternion::from_imag(*w) * *q * (0.5 * h);
                }
            }
            Integrator::Rk4 => self.rk4(t, state, h)?,
        }
        state.normalize_orientations();
        Ok(())
    }

    /// Begins and finishes one step (when nothing needs recording at `t_k`).
    pub fn step(&mut self, t: SimTime, state: &mut State) -> Result<(), EvalError> {
        self.begin_step(t, state)?;
        self.finish_step(t, state)
    }

    fn rk4(&mut self, t: SimTime, state: &mut State, h: f64) -> Result<(), EvalError> {
        let half = SimTime(t.0 + self.dt.0 / 2);
        let full = SimTime(t.0 + self.dt.0);
        let mut stage = std::mem::replace(&mut self.stage, State::empty());
        let mut k = std::mem::replace(&mut self.k, std::array::from_fn(|_| empty_rates()));
        let result = (|| {
            state.add_scaled_into(&k[0], 0.5 * h, &mut stage);
            self.rates(half, &stage, &mut k[1])?;
            self.book_row_forces(h / 3.0, false);
            state.add_scaled_into(&k[1], 0.5 * h, &mut stage);
            self.rates(half, &stage, &mut k[2])?;
            self.book_row_forces(h / 3.0, false);
            state.add_scaled_into(&k[2], h, &mut stage);
            self.rates(full, &stage, &mut k[3])?;
            self.book_row_forces(h / 6.0, false);
            // k1 + 2 k2 + 2 k3 + k4, accumulated into k[1].
            let (k0, rest) = k.split_at_mut(1);
            let (k1, rest) = rest.split_at_mut(1);
            let (k2, k3) = rest.split_at_mut(1);
            k1[0].combine(2.0, &k0[0], 1.0);
            k1[0].combine(1.0, &k2[0], 2.0);
            k1[0].combine(1.0, &k3[0], 1.0);
            stage.clone_from(state);
            stage.add_scaled_into(&k1[0], h / 6.0, state);
            Ok(())
        })();
        self.stage = stage;
        self.k = k;
        result
    }
}

fn empty_rates() -> super::state::Rates {
    super::state::Rates::zeros_like(&State::empty())
}
