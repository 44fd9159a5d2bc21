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
        r
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
            state.add_scaled_into(&k[1], 0.5 * h, &mut stage);
            self.rates(half, &stage, &mut k[2])?;
            state.add_scaled_into(&k[2], h, &mut stage);
            self.rates(full, &stage, &mut k[3])?;
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
