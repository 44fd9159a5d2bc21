//! Running one variant: body positions sampled on the common time grid, the run's
//! violation and cost, and its wall time (fastest of round-robin repetitions).

use std::time::Instant;

use nalgebra::Vector3;

use crate::cosim::{CoSim, Observer, StepValues};
use crate::error::Error;
use crate::kernel::SimTime;
use crate::progress::Progress;
use crate::scenario::Scenario;

/// Repetitions of a variant continue until their total wall time reaches this [s].
pub const MIN_TIMED_SECONDS: f64 = 1.0;

/// At most this many timed repetitions per variant.
pub const MAX_REPEATS: u32 = 25;

/// How a variant ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// Ran to the horizon.
    Ok,
    /// Stopped with an error (divergence or numerical failure); the error text.
    Diverged(String),
    /// The scenario format refused the variant; the validation error.
    Invalid(String),
}

impl Status {
    /// `ok`, `diverged` or `invalid`.
    pub fn name(&self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Diverged(_) => "diverged",
            Status::Invalid(_) => "invalid",
        }
    }

    /// The error text (empty when ok).
    pub fn error(&self) -> &str {
        match self {
            Status::Ok => "",
            Status::Diverged(e) | Status::Invalid(e) => e,
        }
    }
}

/// What one run measured.
#[derive(Debug, Clone)]
pub struct Measured {
    /// How it ended.
    pub status: Status,
    /// Body positions at every multiple of the comparison period, time-major.
    pub samples: Vec<Vector3<f64>>,
    /// Bodies per sample.
    pub bodies: usize,
    /// Largest `|w|` over the steps run [m].
    pub max_violation: f64,
    /// Mean window cost [m].
    pub mean_cost: f64,
    /// Fastest wall time of the simulation [s].
    pub wall_seconds: f64,
    /// Timed repetitions.
    pub repeats: u32,
    /// Steps run (the divergence step excluded).
    pub steps: u64,
    /// Simulated time of the failure, if the run failed.
    pub failed_at: Option<SimTime>,
}

impl Measured {
    /// A variant that was never run.
    pub fn invalid(error: String) -> Measured {
        Measured {
            status: Status::Invalid(error),
            samples: Vec::new(),
            bodies: 0,
            max_violation: f64::NAN,
            mean_cost: f64::NAN,
            wall_seconds: f64::NAN,
            repeats: 0,
            steps: 0,
            failed_at: None,
        }
    }
}

/// Counts steps across all runs of a study for the terminal progress bar.
pub struct Counter {
    progress: Progress,
    done: u64,
}

impl Counter {
    /// A counter over `total` steps.
    pub fn new(total: u64) -> Counter {
        Counter {
            progress: Progress::new(total),
            done: 0,
        }
    }

    pub(crate) fn add(&mut self, steps: u64) {
        // `Progress::tick` looks at positions that are multiples of 1024.
        let before = self.done / 1024;
        self.done += steps;
        if self.done / 1024 != before {
            self.progress.tick(self.done / 1024 * 1024);
        }
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.progress.finish();
    }
}

/// Samples positions on the comparison grid and counts steps.
struct Sampler<'a> {
    every: u64,
    samples: Vec<Vector3<f64>>,
    counter: &'a mut Counter,
}

impl Observer for Sampler<'_> {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        if s.time.as_nanos().is_multiple_of(self.every) {
            self.samples.extend_from_slice(s.p);
        }
        self.counter.add(1);
        Ok(())
    }
}

/// Runs `scenario` to its end, sampling body positions every `every`; the wall time
/// of this (observed) run is the first timing, refined by [`time_once`].
pub fn measure(scenario: &Scenario, every: SimTime, counter: &mut Counter) -> Measured {
    let mut world = CoSim::new(scenario);
    let mut sampler = Sampler {
        every: every.as_nanos().max(1),
        samples: Vec::new(),
        counter,
    };
    let started = Instant::now();
    let result = world.run_to_end(&mut sampler);
    let wall = started.elapsed().as_secs_f64();
    let failed_at = match &result {
        Ok(()) => None,
        Err(Error::Diverged(d)) => Some(d.time),
        Err(Error::Numerical { time, .. }) => Some(*time),
        Err(_) => Some(world.now()),
    };
    Measured {
        status: match result {
            Ok(()) => Status::Ok,
            Err(e) => Status::Diverged(e.to_string()),
        },
        samples: sampler.samples,
        bodies: scenario.bodies.len(),
        max_violation: world.max_violation(),
        mean_cost: world.mean_cost(),
        wall_seconds: wall,
        repeats: 1,
        steps: world.steps_done().saturating_sub(1),
        failed_at,
    }
}

/// Wall time [s] of one unobserved run of `scenario` (world building excluded).
pub fn time_once(scenario: &Scenario) -> f64 {
    let mut world = CoSim::new(scenario);
    let started = Instant::now();
    // The same scenario already ran to its end once; only the time matters here.
    let _ = world.run_to_end(&mut ());
    started.elapsed().as_secs_f64()
}

/// Refines the wall times of the finished runs among `runs`: round-robin repetitions
/// (so a change of machine load hits every variant alike), each run repeated until its
/// repetitions total [`MIN_TIMED_SECONDS`] or [`MAX_REPEATS`]; keeps the fastest.
pub fn refine_timings(runs: &mut [(&Scenario, &mut Measured)]) {
    let wanted: Vec<u32> = runs
        .iter()
        .map(|(_, m)| {
            let r = (MIN_TIMED_SECONDS / m.wall_seconds.max(1e-9)).ceil();
            if m.status == Status::Ok {
                (r.min(f64::from(MAX_REPEATS)) as u32).max(1)
            } else {
                1
            }
        })
        .collect();
    let rounds = wanted.iter().copied().max().unwrap_or(1);
    for round in 1..rounds {
        for ((s, m), &w) in runs.iter_mut().zip(&wanted) {
            if round < w {
                m.wall_seconds = m.wall_seconds.min(time_once(s));
                m.repeats += 1;
            }
        }
    }
}

/// Max and RMS distance between the body positions of `run` and `reference` over their
/// common samples [m]. NaN if there is none.
pub fn position_errors(run: &Measured, reference: &Measured) -> (f64, f64) {
    let n = run.samples.len().min(reference.samples.len());
    if n == 0 || run.bodies != reference.bodies {
        return (f64::NAN, f64::NAN);
    }
    let (mut max, mut sum) = (0.0_f64, 0.0);
    for (a, b) in run.samples[..n].iter().zip(&reference.samples[..n]) {
        let d = (a - b).norm();
        max = max.max(d);
        sum += d * d;
    }
    (max, (sum / n as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measured(samples: Vec<Vector3<f64>>, bodies: usize) -> Measured {
        Measured {
            samples,
            bodies,
            ..Measured::invalid(String::new())
        }
    }

    #[test]
    fn errors_are_max_and_rms_over_common_samples() {
        let z = Vector3::zeros();
        let r = measured(vec![z; 4], 2);
        let a = measured(
            vec![
                z,
                Vector3::new(3.0, 4.0, 0.0),
                Vector3::new(0.0, 0.0, 1.0),
                z,
            ],
            2,
        );
        let (max, rms) = position_errors(&a, &r);
        assert_eq!(max, 5.0);
        assert!((rms - (26.0_f64 / 4.0).sqrt()).abs() < 1e-15);
        // A shorter run compares over its own samples only.
        let short = measured(vec![z, Vector3::new(1.0, 0.0, 0.0)], 2);
        assert_eq!(position_errors(&short, &r).0, 1.0);
        assert!(position_errors(&measured(vec![], 2), &r).0.is_nan());
    }
}
