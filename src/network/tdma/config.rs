//! The TDMA configuration: slot geometry, link, clocks and processing jitter.

use super::error::TdmaError;
use crate::kernel::time::NANOS_PER_SEC;
use crate::kernel::SimTime;
pub use crate::scenario::model::tdma::{Jitter, TdmaConfig};

impl Jitter {
    /// Whether any random number is drawn.
    pub fn is_random(&self) -> bool {
        match *self {
            Jitter::None => false,
            Jitter::Uniform { max } => max > SimTime::ZERO,
            Jitter::Exponential { mean } => mean > SimTime::ZERO,
        }
    }
}

/// Most slots one cycle may hold (sync, static and dynamic): every cycle is computed
/// slot by slot, and the scheduler's placement search is quadratic in the slots of a
/// cycle (99 011 slots of 101 ns took 15.7 s to validate; 20 000 take well under a
/// second), so the slot grid bounds the work and memory of validation and of each cycle.
pub const MAX_SLOTS_PER_CYCLE: u64 = 20_000;

impl TdmaConfig {
    /// The geometry alone; every other field at its zero-effect value (see the type
    /// docs).
    pub fn new(clients: usize, slot: SimTime, cycle: SimTime) -> TdmaConfig {
        TdmaConfig {
            slot,
            guard: SimTime::ZERO,
            cycle,
            link_rate: f64::INFINITY,
            propagation: SimTime::ZERO,
            header_bytes: 0,
            clients,
            drift_ppm: 0.0,
            random_walk_ppm: 0.0,
            sync_error: SimTime::ZERO,
            jitter: Jitter::None,
        }
    }

    /// Number of nodes (server + clients).
    pub fn nodes(&self) -> usize {
        self.clients + 1
    }

    /// Usable part of a slot, `slot − guard`.
    pub fn usable(&self) -> SimTime {
        SimTime(self.slot.0.saturating_sub(self.guard.0))
    }

    /// Whether the clocks draw anything (drift, random walk or sync error configured).
    pub fn clocks_random(&self) -> bool {
        self.drift_ppm > 0.0 || self.random_walk_ppm > 0.0 || self.sync_error > SimTime::ZERO
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), TdmaError> {
        if self.clients == 0 {
            return Err(TdmaError::config(
                "clients",
                "a TDMA network needs at least one client, got 0",
            ));
        }
        if self.slot == SimTime::ZERO {
            return Err(TdmaError::config("slot", "must be > 0, got 0"));
        }
        if self.guard >= self.slot {
            return Err(TdmaError::config(
                "guard",
                format!(
                    "must be shorter than the slot ({}), got {}",
                    self.slot, self.guard
                ),
            ));
        }
        if self.link_rate.is_nan() || self.link_rate <= 0.0 {
            return Err(TdmaError::config(
                "link_rate",
                format!(
                    "must be > 0 bit/s (or infinite), got {}",
                    crate::error::num(self.link_rate)
                ),
            ));
        }
        let statics = self.clients as u64 + 2;
        let fixed = self.slot.0.checked_mul(statics);
        if fixed.is_none_or(|f| self.cycle.0 < f) {
            return Err(TdmaError::config(
                "cycle",
                format!(
                    "{} is shorter than the sync and static part ({} slots of {})",
                    self.cycle, statics, self.slot
                ),
            ));
        }
        let slots = self.cycle.0 / self.slot.0;
        if slots > MAX_SLOTS_PER_CYCLE {
            return Err(TdmaError::config(
                "cycle",
                format!(
                    "{} holds {slots} slots of {}; at most {MAX_SLOTS_PER_CYCLE} slots per \
                     cycle are modelled (lengthen the slot or shorten the cycle)",
                    self.cycle, self.slot
                ),
            ));
        }
        if !self.cycle.0.is_multiple_of(self.slot.0) {
            return Err(TdmaError::config(
                "cycle",
                format!(
                    "{} must be a whole number of slots of {}",
                    self.cycle, self.slot
                ),
            ));
        }
        check_ppm("drift_ppm", self.drift_ppm)?;
        check_ppm("random_walk_ppm", self.random_walk_ppm)?;
        let sync = transmission_time(self.header_bytes, self.link_rate);
        if sync > self.usable() {
            return Err(TdmaError::FrameTooLong {
                what: "sync frame (header only)".into(),
                bytes: self.header_bytes,
                needed: sync,
                slot: self.slot,
                guard: self.guard,
            });
        }
        Ok(())
    }
}

/// A ppm value must be finite, ≥ 0 and keep clock rates positive (< 10⁶).
fn check_ppm(field: &'static str, value: f64) -> Result<(), TdmaError> {
    if !value.is_finite() || value < 0.0 {
        return Err(TdmaError::config(
            field,
            format!(
                "must be a finite number ≥ 0 ppm, got {}",
                crate::error::num(value)
            ),
        ));
    }
    if value >= 1e6 {
        return Err(TdmaError::config(
            field,
            format!(
                "must be below 10⁶ ppm (a clock cannot stop), got {}",
                crate::error::num(value)
            ),
        ));
    }
    Ok(())
}

/// Time on the wire of `bytes` at `rate` [bit/s]: `bytes · 8 / rate`, rounded up to the
/// nanosecond (a frame never fits a slot by rounding); zero on an infinite rate.
pub fn transmission_time(bytes: u64, rate: f64) -> SimTime {
    if rate.is_infinite() || bytes == 0 {
        return SimTime::ZERO;
    }
    let bits = u128::from(bytes) * 8;
    if rate.fract() == 0.0 && rate <= (1u64 << 53) as f64 {
        // Exact integer arithmetic for the usual whole-number rates.
        let r = rate as u128;
        let ns = (bits * u128::from(NANOS_PER_SEC)).div_ceil(r);
        return SimTime(u64::try_from(ns).unwrap_or(u64::MAX));
    }
    let ns = (bits as f64 * NANOS_PER_SEC as f64 / rate).ceil();
    SimTime(if ns >= u64::MAX as f64 {
        u64::MAX
    } else {
        ns as u64
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmission_time_is_bits_over_rate_rounded_up() {
        assert_eq!(transmission_time(100, 1e6), SimTime(800_000));
        assert_eq!(transmission_time(1, 3e9), SimTime(3)); // 8/3 ns → 3
        assert_eq!(transmission_time(1, 3.5e9), SimTime(3)); // 2.29 ns → 3
        assert_eq!(transmission_time(1000, f64::INFINITY), SimTime::ZERO);
        assert_eq!(transmission_time(0, 1e6), SimTime::ZERO);
    }

    fn good() -> TdmaConfig {
        let mut c = TdmaConfig::new(3, SimTime(100_000), SimTime(10_000_000));
        c.guard = SimTime(10_000);
        c.link_rate = 10e6;
        c.header_bytes = 16;
        c
    }

    fn field_of(c: &TdmaConfig) -> String {
        c.validate().unwrap_err().to_string()
    }

    #[test]
    fn a_good_configuration_passes() {
        assert_eq!(good().validate(), Ok(()));
        assert!(!good().clocks_random());
    }

    #[test]
    fn each_bad_field_is_named() {
        type Breaks = Box<dyn Fn(&mut TdmaConfig)>;
        let cases: Vec<(&str, Breaks)> = vec![
            ("clients:", Box::new(|c| c.clients = 0)),
            ("slot:", Box::new(|c| c.slot = SimTime::ZERO)),
            ("guard:", Box::new(|c| c.guard = c.slot)),
            ("link_rate:", Box::new(|c| c.link_rate = f64::NAN)),
            ("link_rate:", Box::new(|c| c.link_rate = -1.0)),
            ("cycle:", Box::new(|c| c.cycle = SimTime(400_000))),
            ("cycle:", Box::new(|c| c.cycle = SimTime(10_050_000))),
            ("drift_ppm:", Box::new(|c| c.drift_ppm = -1.0)),
            ("drift_ppm:", Box::new(|c| c.drift_ppm = f64::NAN)),
            ("drift_ppm:", Box::new(|c| c.drift_ppm = 2e6)),
            (
                "random_walk_ppm:",
                Box::new(|c| c.random_walk_ppm = f64::NAN),
            ),
            ("random_walk_ppm:", Box::new(|c| c.random_walk_ppm = -0.5)),
            ("slot:", Box::new(|c| c.header_bytes = 1000)),
        ];
        for (field, bad) in cases {
            let mut c = good();
            bad(&mut c);
            let msg = field_of(&c);
            assert!(msg.starts_with(field), "expected {field} in {msg:?}");
        }
    }

    #[test]
    fn messages_carry_the_offending_value() {
        let mut c = good();
        c.drift_ppm = -3.5;
        assert_eq!(
            field_of(&c),
            "drift_ppm: must be a finite number ≥ 0 ppm, got -3.5"
        );
        let mut c = good();
        c.header_bytes = 1000;
        assert!(
            field_of(&c).contains("1000 bytes take 0.000800000 s"),
            "{}",
            field_of(&c)
        );
    }

    #[test]
    fn jitter_with_zero_width_is_not_random() {
        assert!(!Jitter::None.is_random());
        assert!(!Jitter::Uniform { max: SimTime::ZERO }.is_random());
        assert!(!Jitter::Exponential {
            mean: SimTime::ZERO
        }
        .is_random());
        assert!(Jitter::Exponential { mean: SimTime(5) }.is_random());
    }
}
