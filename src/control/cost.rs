//! The cost of a measurement window (method §5):
//! `C = Σ_l sqrt( (1/T) ∫_t^{t+T} w_l(u)² du )`, summed over every link of the model.
//!
//! The integral is the left Riemann sum over the integration steps whose start time lies
//! in `[t, t+T)`: `∫ w² du ≈ Σ_k w_l(t_k)² dt`. It is exact for the piecewise-constant
//! reading of the step values and converges at first order in `dt` otherwise. A final
//! window shorter than `T` (duration not a multiple of `T`) is measured over its own
//! length. The co-simulation closes windows with measurement events of the kernel.

use crate::kernel::SimTime;

/// One measurement window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Epoch {
    /// Window start.
    pub t_start: SimTime,
    /// Window end (exclusive).
    pub t_end: SimTime,
    /// Cost C over the window [m].
    pub cost: f64,
}

/// Accumulates `∫ w²` per link; the owner closes a window at its end time.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct CostMeter {
    dt: SimTime,
    start: SimTime,
    steps: u64,
    sum_sq: Vec<f64>,
    epochs: Vec<Epoch>,
}

impl CostMeter {
    /// A meter for `links` links with step `dt`, its first window starting at 0.
    pub fn new(links: usize, dt: SimTime) -> CostMeter {
        CostMeter {
            dt,
            start: SimTime::ZERO,
            steps: 0,
            sum_sq: vec![0.0; links],
            epochs: Vec::new(),
        }
    }

    /// Adds one step's constraint values `w` (or the measured signals' values).
    pub fn add(&mut self, w: impl IntoIterator<Item = f64>) {
        for (s, w) in self.sum_sq.iter_mut().zip(w) {
            *s += w * w;
        }
        self.steps += 1;
    }

    /// Closes the window `[start, end)` and starts the next at `end`; returns it.
    /// A window with no steps (zero length) costs 0.
    pub fn close(&mut self, end: SimTime) -> &Epoch {
        let dt = self.dt.as_secs_f64();
        let length = end.0.saturating_sub(self.start.0) as f64 * 1e-9;
        // No links (a scene of FMUs only, without `measurement.signals`): 0, not the
        // empty sum's -0.
        let cost = if self.steps == 0 || length <= 0.0 || self.sum_sq.is_empty() {
            0.0
        } else {
            self.sum_sq
                .iter()
                .map(|s| (s * dt / length).sqrt())
                .sum::<f64>()
        };
        self.epochs.push(Epoch {
            t_start: self.start,
            t_end: end,
            cost,
        });
        self.sum_sq.fill(0.0);
        self.steps = 0;
        self.start = end;
        &self.epochs[self.epochs.len() - 1]
    }

    /// The closed windows.
    pub fn epochs(&self) -> &[Epoch] {
        &self.epochs
    }

    /// Mean cost over the closed windows (0 when there are none).
    pub fn mean_cost(&self) -> f64 {
        if self.epochs.is_empty() {
            0.0
        } else {
            self.epochs.iter().map(|e| e.cost).sum::<f64>() / self.epochs.len() as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_violation_costs_its_magnitude_per_link() {
        // w = 0.01 m on 3 links for a whole window: C = 3 × 0.01.
        let dt = SimTime(1_000_000);
        let mut m = CostMeter::new(3, dt);
        for k in 0..2000 {
            m.add([0.01, -0.01, 0.01]);
            if k % 1000 == 999 {
                m.close(SimTime((k + 1) * dt.0));
            }
        }
        assert_eq!(m.epochs().len(), 2);
        for e in m.epochs() {
            assert!((e.cost - 0.03).abs() < 1e-12, "{}", e.cost);
        }
        assert_eq!(m.epochs()[1].t_start, SimTime(1_000_000_000));
    }

    #[test]
    fn sine_violation_costs_its_rms() {
        // w = A sin(2π t) over whole periods: RMS = A/√2.
        let dt = SimTime(100_000);
        let mut m = CostMeter::new(1, dt);
        for k in 0..10_000u64 {
            let t = k as f64 * 1e-4;
            m.add([0.5 * (2.0 * std::f64::consts::PI * t).sin()]);
        }
        m.close(SimTime(10_000 * dt.0));
        assert!((m.epochs()[0].cost - 0.5 / 2f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn partial_last_window_uses_its_own_length() {
        let dt = SimTime(1_000_000);
        let mut m = CostMeter::new(1, dt);
        for k in 0..1500 {
            m.add([0.2]);
            if k == 999 {
                m.close(SimTime(1_000_000_000));
            }
        }
        m.close(SimTime(1_500_000_000));
        assert_eq!(m.epochs().len(), 2);
        assert_eq!(m.epochs()[1].t_end, SimTime(1_500_000_000));
        assert!((m.epochs()[1].cost - 0.2).abs() < 1e-12);
    }
}
