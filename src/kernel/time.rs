//! Integer simulated time.
//!
//! Simulated time is a count of nanoseconds in a `u64` (about 584 years of range).
//! Nothing in the simulator keeps an `f64` clock: seconds are converted to
//! nanoseconds once, at validation, and every comparison of times is exact.

use std::fmt;

/// A point in (or a span of) simulated time [ns].
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Default,
    serde::Serialize,
    serde::Deserialize,
)]
#[repr(transparent)]
pub struct SimTime(pub u64);

/// Nanoseconds per second.
pub const NANOS_PER_SEC: u64 = 1_000_000_000;

impl SimTime {
    /// Time zero.
    pub const ZERO: SimTime = SimTime(0);

    /// Converts seconds to the nearest nanosecond; `None` for negative, non-finite or
    /// out-of-range values.
    pub fn from_secs_f64(seconds: f64) -> Option<SimTime> {
        if !seconds.is_finite() || seconds < 0.0 {
            return None;
        }
        let ns = (seconds * NANOS_PER_SEC as f64).round();
        if ns >= u64::MAX as f64 {
            return None;
        }
        Some(SimTime(ns as u64))
    }

    /// The time in seconds (exact for any time below 2^53 ns ≈ 104 days).
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 / NANOS_PER_SEC as f64
    }

    /// Nanoseconds.
    pub fn as_nanos(self) -> u64 {
        self.0
    }

    /// `self + other`, or `None` on overflow.
    pub fn checked_add(self, other: SimTime) -> Option<SimTime> {
        self.0.checked_add(other.0).map(SimTime)
    }

    /// `self - other`, or `None` if `other > self`.
    pub fn checked_sub(self, other: SimTime) -> Option<SimTime> {
        self.0.checked_sub(other.0).map(SimTime)
    }

    /// `self * k`, or `None` on overflow.
    pub fn checked_mul(self, k: u64) -> Option<SimTime> {
        self.0.checked_mul(k).map(SimTime)
    }
}

impl fmt::Display for SimTime {
    /// Seconds with nanosecond precision, e.g. `12.000000000 s`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}.{:09} s",
            self.0 / NANOS_PER_SEC,
            self.0 % NANOS_PER_SEC
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_round_trip_to_the_nanosecond() {
        let t = SimTime::from_secs_f64(0.001).unwrap();
        assert_eq!(t, SimTime(1_000_000));
        assert_eq!(SimTime::from_secs_f64(30.0).unwrap().0, 30 * NANOS_PER_SEC);
        assert_eq!(t.as_secs_f64(), 0.001);
    }

    #[test]
    fn rejects_negative_and_non_finite() {
        assert!(SimTime::from_secs_f64(-1.0).is_none());
        assert!(SimTime::from_secs_f64(f64::NAN).is_none());
        assert!(SimTime::from_secs_f64(f64::INFINITY).is_none());
        assert!(SimTime::from_secs_f64(1e30).is_none());
    }

    #[test]
    fn display_is_exact() {
        assert_eq!(SimTime(12_000_000_001).to_string(), "12.000000001 s");
    }
}
