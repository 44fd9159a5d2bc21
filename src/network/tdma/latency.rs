//! Per-frame latency: transmission time + propagation + processing jitter (seeded,
//! one draw per frame from the sender's jitter stream).

use super::config::Jitter;
use super::random::{Source, Stream};
use crate::kernel::SimTime;

/// A frame's latency from the start of its transmission to its delivery.
pub fn latency(duration: SimTime, propagation: SimTime, jitter: SimTime) -> SimTime {
    SimTime(
        duration
            .0
            .saturating_add(propagation.0)
            .saturating_add(jitter.0),
    )
}

/// The processing jitter of every sender.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JitterSource {
    jitter: Jitter,
    /// One stream per node (empty when the jitter is not random).
    streams: Vec<Stream>,
}

impl JitterSource {
    /// The jitter of `nodes` senders for the scenario `seed`.
    pub fn new(jitter: Jitter, nodes: usize, seed: u64) -> JitterSource {
        let streams = if jitter.is_random() {
            (0..nodes)
                .map(|n| Stream::new(seed, Source::Jitter, n))
                .collect()
        } else {
            Vec::new()
        };
        JitterSource { jitter, streams }
    }

    /// The jitter of `sender`'s next frame (zero, without a draw, when there is none).
    pub fn draw(&mut self, sender: usize) -> SimTime {
        let Some(s) = self.streams.get_mut(sender) else {
            return SimTime::ZERO;
        };
        match self.jitter {
            Jitter::None => SimTime::ZERO,
            Jitter::Uniform { max } => SimTime(s.below_or_equal(max.0)),
            // `as` saturates: a draw beyond the range of time is the largest time.
            Jitter::Exponential { mean } => SimTime(s.exponential(mean.0 as f64).round() as u64),
        }
    }

    /// 32-bit words drawn so far.
    pub fn words_drawn(&self) -> u128 {
        self.streams.iter().map(Stream::words_drawn).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_jitter_draws_nothing() {
        for j in [
            Jitter::None,
            Jitter::Uniform { max: SimTime::ZERO },
            Jitter::Exponential {
                mean: SimTime::ZERO,
            },
        ] {
            let mut s = JitterSource::new(j, 4, 1);
            assert_eq!(s.draw(2), SimTime::ZERO);
            assert_eq!(s.words_drawn(), 0);
        }
        assert_eq!(latency(SimTime(8), SimTime(2), SimTime::ZERO), SimTime(10));
    }

    #[test]
    fn uniform_and_exponential_jitter_have_their_range_and_mean() {
        let mut u = JitterSource::new(Jitter::Uniform { max: SimTime(1000) }, 3, 5);
        let mut e = JitterSource::new(
            Jitter::Exponential {
                mean: SimTime(1000),
            },
            3,
            5,
        );
        let n = 20_000;
        let (mut su, mut se) = (0u64, 0u64);
        for _ in 0..n {
            let x = u.draw(1);
            assert!(x <= SimTime(1000));
            su += x.0;
            se += e.draw(1).0;
        }
        assert!((su as f64 / n as f64 - 500.0).abs() < 15.0);
        assert!((se as f64 / n as f64 - 1000.0).abs() < 40.0);
        // Each sender has its own stream: drawing for node 1 left node 2 untouched.
        let mut fresh = JitterSource::new(Jitter::Uniform { max: SimTime(1000) }, 3, 5);
        assert_eq!(u.draw(2), fresh.draw(2));
        assert_ne!(
            fresh.draw(2),
            JitterSource::new(Jitter::Uniform { max: SimTime(1000) }, 3, 6).draw(2)
        );
    }
}
