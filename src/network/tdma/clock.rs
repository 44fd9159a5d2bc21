//! Client clocks: a rate offset drawn once (within ±`drift_ppm`), an optional random
//! walk of that rate (one normal step per cycle), and a re-alignment at every received
//! sync frame with a seeded residual error. The server's clock is the reference
//! (global time).
//!
//! Between two cycle starts a client's clock is affine in global time `t`:
//! `local(t) = t + offset + round((t − anchor) · rate · 10⁻⁶)`, where `anchor` is the
//! start of the current cycle, `offset` the clock's error there (the sync error after
//! a received sync frame, the carried-over error after a lost one) and `rate` the rate
//! offset [ppm] during the cycle. A clock never reads below zero.

use super::config::TdmaConfig;
use super::random::{Source, Stream};
use crate::kernel::SimTime;

/// One client's clock.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClientClock {
    /// Global start of the current segment (the current cycle).
    anchor: SimTime,
    /// Local minus global time at `anchor` [ns].
    offset: i64,
    /// Rate offset during the segment [ppm].
    rate_ppm: f64,
}

impl ClientClock {
    /// A clock that reads global time.
    pub fn perfect() -> ClientClock {
        ClientClock {
            anchor: SimTime::ZERO,
            offset: 0,
            rate_ppm: 0.0,
        }
    }

    /// Rate offset [ppm].
    pub fn rate_ppm(&self) -> f64 {
        self.rate_ppm
    }

    /// Local minus global time at global time `t` [ns].
    pub fn offset_at(&self, t: SimTime) -> i64 {
        let elapsed = i128::from(t.0) - i128::from(self.anchor.0);
        let drift = if self.rate_ppm == 0.0 {
            0
        } else {
            (elapsed as f64 * self.rate_ppm * 1e-6).round() as i128
        };
        clamp_i64(i128::from(self.offset) + drift)
    }

    /// What the clock reads at global time `t`.
    pub fn local_time(&self, t: SimTime) -> SimTime {
        clamp_time(i128::from(t.0) + i128::from(self.offset_at(t)))
    }

    /// The global time at which the clock reads `local` (to the nearest ns).
    pub fn global_time_of_local(&self, local: SimTime) -> SimTime {
        let since = i128::from(local.0) - i128::from(self.anchor.0) - i128::from(self.offset);
        let elapsed = if self.rate_ppm == 0.0 {
            since
        } else {
            (since as f64 / (1.0 + self.rate_ppm * 1e-6)).round() as i128
        };
        clamp_time(i128::from(self.anchor.0) + elapsed)
    }
}

fn clamp_i64(x: i128) -> i64 {
    x.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
}

fn clamp_time(x: i128) -> SimTime {
    SimTime(x.clamp(0, i128::from(u64::MAX)) as u64)
}

/// Every client's clock and the streams that move them.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Clocks {
    /// Client `i`'s clock at index `i − 1`.
    clients: Vec<ClientClock>,
    /// Standard deviation of one cycle's random-walk step [ppm].
    walk_step_ppm: f64,
    /// Sync error bound [ns].
    sync_error: SimTime,
    /// Streams per client (empty when the source is off).
    drift: Vec<Stream>,
    walk: Vec<Stream>,
    sync: Vec<Stream>,
    /// Cycles begun so far.
    cycles: u64,
}

impl Clocks {
    /// The clients' clocks for `cfg` (validated) and the scenario `seed`: each rate
    /// offset drawn now (if `drift_ppm > 0`), clocks reading global time until the
    /// first [`Clocks::begin_cycle`].
    pub fn new(cfg: &TdmaConfig, seed: u64) -> Clocks {
        let streams = |on: bool, source| {
            let nodes = if on { cfg.clients } else { 0 };
            (1..=nodes)
                .map(|n| Stream::new(seed, source, n))
                .collect::<Vec<_>>()
        };
        let mut drift = streams(cfg.drift_ppm > 0.0, Source::Drift);
        let clients = (0..cfg.clients)
            .map(|i| ClientClock {
                rate_ppm: drift.get_mut(i).map_or(0.0, |s| s.symmetric(cfg.drift_ppm)),
                ..ClientClock::perfect()
            })
            .collect();
        Clocks {
            clients,
            walk_step_ppm: cfg.random_walk_ppm * cfg.cycle.as_secs_f64().sqrt(),
            sync_error: cfg.sync_error,
            drift,
            walk: streams(cfg.random_walk_ppm > 0.0, Source::RandomWalk),
            sync: streams(cfg.sync_error > SimTime::ZERO, Source::SyncError),
            cycles: 0,
        }
    }

    /// Client `node`'s clock (`None` for the server, whose clock is global time, and
    /// unknown nodes).
    pub fn client(&self, node: usize) -> Option<&ClientClock> {
        self.clients.get(node.checked_sub(1)?)
    }

    /// What `node`'s clock reads at global time `t`.
    pub fn local_time(&self, node: usize, t: SimTime) -> SimTime {
        self.client(node).map_or(t, |c| c.local_time(t))
    }

    /// The global time at which `node`'s clock reads `local`: when it starts a
    /// transmission scheduled at `local`.
    pub fn global_time_of_local(&self, node: usize, local: SimTime) -> SimTime {
        self.client(node)
            .map_or(local, |c| c.global_time_of_local(local))
    }

    /// Sets a client's rate offset [ppm] from now on (what-if studies and tests).
    pub fn set_rate_ppm(&mut self, node: usize, ppm: f64) {
        if let Some(c) = node.checked_sub(1).and_then(|i| self.clients.get_mut(i)) {
            c.rate_ppm = ppm;
        }
    }

    /// A new cycle starts at global time `start` (cycles in order): every clock carries
    /// its error over to `start`, takes one random-walk step (after the first cycle),
    /// and, if the cycle's sync frame was received (`synced`), re-aligns to the server
    /// with a fresh sync error.
    pub fn begin_cycle(&mut self, start: SimTime, synced: bool) {
        for (i, c) in self.clients.iter_mut().enumerate() {
            c.offset = c.offset_at(start);
            c.anchor = start;
            if self.cycles > 0 {
                if let Some(s) = self.walk.get_mut(i) {
                    c.rate_ppm += self.walk_step_ppm * s.normal();
                }
            }
            if synced {
                c.offset = self
                    .sync
                    .get_mut(i)
                    .map_or(0, |s| s.symmetric_int(self.sync_error.0));
            }
        }
        self.cycles += 1;
    }

    /// 32-bit words drawn from every clock stream so far.
    pub fn words_drawn(&self) -> u128 {
        let all = self.drift.iter().chain(&self.walk).chain(&self.sync);
        all.map(Stream::words_drawn).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn cfg() -> TdmaConfig {
        TdmaConfig::new(3, SimTime(100_000), SimTime(10 * MS))
    }

    #[test]
    fn perfect_clocks_read_global_time_and_draw_nothing() {
        let mut c = Clocks::new(&cfg(), 1);
        c.begin_cycle(SimTime::ZERO, true);
        c.begin_cycle(SimTime(10 * MS), false);
        for node in 0..=3 {
            assert_eq!(c.local_time(node, SimTime(12_345_678)), SimTime(12_345_678));
            assert_eq!(c.global_time_of_local(node, SimTime(7)), SimTime(7));
        }
        assert_eq!(c.words_drawn(), 0);
    }

    #[test]
    fn a_drifting_clock_gains_rate_times_elapsed_and_round_trips() {
        let mut c = Clocks::new(&cfg(), 1);
        c.set_rate_ppm(2, 100.0);
        c.begin_cycle(SimTime::ZERO, true);
        // 100 ppm over 10 ms = 1 µs ahead; it starts a 10 ms slot 1 µs early (≈).
        assert_eq!(c.local_time(2, SimTime(10 * MS)), SimTime(10 * MS + 1_000));
        assert_eq!(
            c.global_time_of_local(2, SimTime(10 * MS)),
            SimTime(10 * MS - 1_000)
        );
        for t in [0, 1, 999_999, 5 * MS + 3, 9 * MS] {
            let back = c.global_time_of_local(2, c.local_time(2, SimTime(t)));
            assert!(back.0.abs_diff(t) <= 1, "{t} → {back}");
        }
        // Without a sync the error carries over; with one it is gone.
        c.begin_cycle(SimTime(10 * MS), false);
        assert_eq!(c.local_time(2, SimTime(20 * MS)), SimTime(20 * MS + 2_000));
        c.begin_cycle(SimTime(20 * MS), true);
        assert_eq!(c.local_time(2, SimTime(20 * MS)), SimTime(20 * MS));
        assert_eq!(c.local_time(1, SimTime(20 * MS)), SimTime(20 * MS));
    }

    #[test]
    fn drift_is_drawn_once_within_the_bound_from_its_own_stream() {
        let mut with_drift = cfg();
        with_drift.drift_ppm = 50.0;
        let a = Clocks::new(&with_drift, 9);
        let rates: Vec<f64> = (1..=3).map(|n| a.client(n).unwrap().rate_ppm()).collect();
        assert!(
            rates.iter().all(|r| r.abs() <= 50.0 && *r != 0.0),
            "{rates:?}"
        );
        assert_eq!(a.words_drawn(), 3 * 2);
        // Turning other sources on does not move the drift draws.
        let mut more = with_drift.clone();
        more.sync_error = SimTime(200);
        more.random_walk_ppm = 1.0;
        let b = Clocks::new(&more, 9);
        let same: Vec<f64> = (1..=3).map(|n| b.client(n).unwrap().rate_ppm()).collect();
        assert_eq!(rates, same);
        // Another seed, other rates.
        let c = Clocks::new(&with_drift, 10);
        assert_ne!(rates[0], c.client(1).unwrap().rate_ppm());
    }

    #[test]
    fn sync_error_and_random_walk_stay_where_configured() {
        let mut conf = cfg();
        conf.sync_error = SimTime(300);
        let mut c = Clocks::new(&conf, 2);
        let mut seen = std::collections::BTreeSet::new();
        for k in 0..200 {
            let start = SimTime(k * 10 * MS);
            c.begin_cycle(start, true);
            let off = c.client(1).unwrap().offset_at(start);
            assert!(off.abs() <= 300);
            seen.insert(off);
            assert_eq!(c.client(1).unwrap().rate_ppm(), 0.0);
        }
        assert!(seen.len() > 100, "sync errors vary");
        let mut conf = cfg();
        conf.random_walk_ppm = 10.0;
        let mut c = Clocks::new(&conf, 2);
        c.begin_cycle(SimTime::ZERO, true);
        assert_eq!(c.words_drawn(), 0, "no step at the first cycle");
        c.begin_cycle(SimTime(10 * MS), true);
        let r = c.client(3).unwrap().rate_ppm();
        assert!(
            r != 0.0 && r.abs() < 10.0,
            "one step of σ = 10·√0.01 = 1 ppm: {r}"
        );
    }
}
