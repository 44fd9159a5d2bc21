//! The TDMA model's random streams: one ChaCha8 stream per (source, node), all from the
//! scenario seed, told apart by a fixed stream id; so adding a source or a node never
//! shifts the numbers of another, and a source that is not configured has no stream
//! and draws nothing.

use rand_chacha::rand_core::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random source of the TDMA model.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum Source {
    /// A client's clock rate offset, drawn once.
    Drift,
    /// A client's rate random walk, one step per cycle.
    RandomWalk,
    /// A client's residual error at each sync.
    SyncError,
    /// A sender's processing jitter, one draw per frame.
    Jitter,
}

impl Source {
    fn code(self) -> u64 {
        match self {
            Source::Drift => 1,
            Source::RandomWalk => 2,
            Source::SyncError => 3,
            Source::Jitter => 4,
        }
    }
}

/// The high 32 bits of every TDMA stream id ("TDMA" in ASCII), keeping them apart from
/// the streams of other parts of the simulator.
pub const STREAM_NAMESPACE: u64 = 0x5444_4D41;

/// The stream id of `source` at `node`: namespace, source code (8 bits), node (24 bits).
pub fn stream_id(source: Source, node: usize) -> u64 {
    (STREAM_NAMESPACE << 32) | (source.code() << 24) | (node as u64 & 0xFF_FFFF)
}

/// One random stream.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(into = "StreamState", from = "StreamState")]
pub struct Stream {
    seed: u64,
    rng: ChaCha8Rng,
}

/// What a stream is saved as (checkpoints): seed, stream id and position.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
struct StreamState {
    seed: u64,
    stream: u64,
    word_pos: u128,
}

impl From<Stream> for StreamState {
    fn from(s: Stream) -> StreamState {
        StreamState {
            seed: s.seed,
            stream: s.rng.get_stream(),
            word_pos: s.rng.get_word_pos(),
        }
    }
}

impl From<StreamState> for Stream {
    fn from(s: StreamState) -> Stream {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
        rng.set_stream(s.stream);
        rng.set_word_pos(s.word_pos);
        Stream { seed: s.seed, rng }
    }
}

impl PartialEq for Stream {
    fn eq(&self, other: &Stream) -> bool {
        StreamState::from(self.clone()) == StreamState::from(other.clone())
    }
}

impl Stream {
    /// The stream of `source` at `node` for the scenario `seed`.
    pub fn new(seed: u64, source: Source, node: usize) -> Stream {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream_id(source, node));
        Stream { seed, rng }
    }

    /// 32-bit words drawn so far (0 for a stream never used).
    pub fn words_drawn(&self) -> u128 {
        self.rng.get_word_pos()
    }

    /// Uniform in `[0, 1)` (53 random bits).
    pub fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[−bound, bound]`.
    pub fn symmetric(&mut self, bound: f64) -> f64 {
        bound * (2.0 * self.uniform() - 1.0)
    }

    /// Uniform on the whole numbers `0..=max` (by a widening multiply; the bias is below
    /// 2⁻⁶⁴ per value).
    pub fn below_or_equal(&mut self, max: u64) -> u64 {
        let n = u128::from(max) + 1;
        ((u128::from(self.rng.next_u64()) * n) >> 64) as u64
    }

    /// Uniform on the whole numbers `−bound..=bound`.
    pub fn symmetric_int(&mut self, bound: u64) -> i64 {
        let bound = bound.min(i64::MAX as u64 / 2);
        self.below_or_equal(2 * bound) as i64 - bound as i64
    }

    /// Standard normal (Box–Muller, one value per two uniforms).
    ///
    /// Kept hand-written rather than `rand_distr::StandardNormal` (measured, rand_distr
    /// 0.6 on this ChaCha8 stream, 100 000 draws): rand_distr's normal uses the Ziggurat
    /// method, which draws a different number of words per sample (204 406 words against
    /// our 400 000) and gave 0 of 100 000 values bit-equal to these, so every stored TDMA
    /// digest would change.
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]: the logarithm stays finite
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Exponential with the given mean (inversion of one uniform).
    ///
    /// Kept hand-written rather than `rand_distr::Exp` (measured as for
    /// [`Stream::normal`]): rand_distr's exponential is a Ziggurat sampler too (206 634
    /// words for 100 000 draws against our 200 000, 0 of 100 000 values bit-equal), so
    /// every stored TDMA digest would change.
    pub fn exponential(&mut self, mean: f64) -> f64 {
        -mean * (1.0 - self.uniform()).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_differ_by_source_and_node_and_repeat_by_seed() {
        let first = |seed, source, node| Stream::new(seed, source, node).uniform();
        let a = first(7, Source::Drift, 1);
        assert_eq!(a, first(7, Source::Drift, 1));
        assert_ne!(a, first(8, Source::Drift, 1));
        assert_ne!(a, first(7, Source::Drift, 2));
        assert_ne!(a, first(7, Source::Jitter, 1));
    }

    #[test]
    fn a_fresh_stream_has_drawn_nothing() {
        let mut s = Stream::new(1, Source::Jitter, 3);
        assert_eq!(s.words_drawn(), 0);
        s.uniform();
        assert_eq!(s.words_drawn(), 2);
    }

    #[test]
    fn a_saved_stream_resumes_where_it_was() {
        let mut s = Stream::new(5, Source::SyncError, 2);
        for _ in 0..37 {
            s.normal();
        }
        let saved = serde_json::to_string(&s).unwrap();
        let mut back: Stream = serde_json::from_str(&saved).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.uniform().to_bits(), s.uniform().to_bits());
    }

    #[test]
    fn draws_stay_in_range_with_the_right_means() {
        let mut s = Stream::new(3, Source::Jitter, 0);
        let n = 20_000;
        let (mut sum_e, mut sum_n, mut sum_n2) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let u = s.below_or_equal(4);
            assert!(u <= 4);
            let k = s.symmetric_int(3);
            assert!((-3..=3).contains(&k));
            let x = s.symmetric(2.0);
            assert!((-2.0..=2.0).contains(&x));
            sum_e += s.exponential(10.0);
            let z = s.normal();
            sum_n += z;
            sum_n2 += z * z;
        }
        let n = n as f64;
        assert!(
            (sum_e / n - 10.0).abs() < 0.5,
            "exponential mean {}",
            sum_e / n
        );
        assert!((sum_n / n).abs() < 0.05, "normal mean {}", sum_n / n);
        assert!(
            (sum_n2 / n - 1.0).abs() < 0.05,
            "normal variance {}",
            sum_n2 / n
        );
    }
}
