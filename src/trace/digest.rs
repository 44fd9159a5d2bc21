//! The run digest: BLAKE3 over the exact bytes of every recorded value, chained record
//! by record.
//!
//! A run's records come in two chains, each in the order the kernel produces its
//! records (at equal time: measurement < controller < TDMA cycle < slot < sample <
//! delivery < partition step, see [`crate::kernel::EventClass`]).
//!
//! The **dynamics chain** holds, interleaved in time order:
//!
//! 1. **Step** — for every step k = 0..=steps: the time `t_k` as a little-endian `u64`
//!    count of nanoseconds, then the `f64` bit patterns (little-endian) of every link's
//!    `w` then every link's `f` (link order), then every body's `p` then `v` (body
//!    order, x y z), then every traced FMU output value in its type's bytes (a Real's
//!    `f64` bits, an integer as a little-endian `i64` or `u64`, a Boolean as a `u64` 0
//!    or 1, a String's or a Binary's length as a `u64` then its bytes: see
//!    [`crate::fmu::value`]). These are trace.csv's values, for every step, whatever
//!    the decimation.
//! 2. **TDMA cycle** — on a TDMA scene, each cycle when it is computed (at its start):
//!    the cycle's start [ns], then per frame in slot order its slot, sender, actual start
//!    [ns] and delivery [ns] (`u64::MAX` if lost), each a little-endian `u64` — so the
//!    digest pins every frame's timing, which network.csv reports.
//!
//! The **epoch chain** holds, window after window:
//!
//! 3. **Epoch row, world columns** — when a measurement window closes (its
//!    `Measurement` event at `t_end`, before the step at `t_end`): `t_start` and `t_end`
//!    [ns] as `u64`, then per channel (channel order) the bits of `tau_<c>_requested`
//!    and `tau_<c>_achieved` [s], then `bandwidth` and `cost`.
//! 4. **Epoch row, controller columns** — on a controlled run, right after the live
//!    world closed the window and the controller recorded it: the bits of
//!    `objective_<method>`, then of each baseline's objective (column order), then the
//!    number of `grid_opt_tau_*` values as a `u64` (0 when the grid was not searched in
//!    this window) and their bits, then `measurements` as a `u64`.
//!
//! Each chain is `d_{k+1} = BLAKE3(d_k ‖ record_k)` from `d_0` = 32 zero bytes. The
//! run's `digest` (summary.json, 64 hex digits) is `BLAKE3(dynamics ‖ epochs)` of the two
//! final chain values, so a change in any value of trace.csv (at any step), network.csv
//! or epochs.csv changes it, while every step is hashed once. Chaining keeps each
//! chain's whole state in 32 bytes, so a checkpoint can store it and a resumed run
//! continues the very same chains.
//!
//! `dynamics_digest` in summary.json is the dynamics chain alone: the live dynamics,
//! which a controller's forks never touch, so it is equal for a controlled run and the
//! same run without baselines.
//!
//! Column names, decimation, traced-body selection and number formatting are not
//! hashed, so changing the output options never changes the digest; `-0.0` and `0.0`
//! hash differently, as they are different bits.

/// Incremental digest of a run.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Digest {
    chain: [u8; 32],
    record: Vec<u8>,
}

impl Digest {
    /// An empty digest.
    pub fn new() -> Digest {
        Digest::default()
    }

    /// Adds a time in nanoseconds to the current record.
    pub fn time(&mut self, ns: u64) {
        self.record.extend_from_slice(&ns.to_le_bytes());
    }

    /// Adds a count or index to the current record (little-endian `u64`).
    pub fn count(&mut self, n: u64) {
        self.record.extend_from_slice(&n.to_le_bytes());
    }

    /// Adds the bit patterns of `values` to the current record.
    pub fn values(&mut self, values: &[f64]) {
        for v in values {
            self.record.extend_from_slice(&v.to_bits().to_le_bytes());
        }
    }

    /// Adds FMU output values to the current record, each as
    /// [`crate::fmu::Value::digest_bytes`] gives it (a Real's `f64` bits, as
    /// [`Digest::values`] adds them).
    pub fn signals(&mut self, values: &[crate::fmu::Value]) {
        for v in values {
            v.digest_bytes(&mut self.record);
        }
    }

    /// Adds the bit patterns of one value to the current record.
    pub fn value(&mut self, v: f64) {
        self.record.extend_from_slice(&v.to_bits().to_le_bytes());
    }

    /// Closes the current record: folds it into the chain.
    pub fn end_step(&mut self) {
        self.chain = self.folded();
        self.record.clear();
    }

    /// The chain value (an open record counts as closed).
    pub fn bytes(&self) -> [u8; 32] {
        if self.record.is_empty() {
            self.chain
        } else {
            self.folded()
        }
    }

    /// `BLAKE3(a ‖ b)` of two chains' values, as 64 lowercase hex digits: the run digest
    /// of a dynamics chain `a` and an epoch chain `b`.
    pub fn combined_hex(a: &Digest, b: &Digest) -> String {
        let mut h = blake3::Hasher::new();
        h.update(&a.bytes());
        h.update(&b.bytes());
        hex(h.finalize().as_bytes())
    }

    fn folded(&self) -> [u8; 32] {
        let mut h = blake3::Hasher::new();
        h.update(&self.chain);
        h.update(&self.record);
        *h.finalize().as_bytes()
    }

    /// The digest as 64 lowercase hex digits (an open record counts as closed).
    pub fn hex(&self) -> String {
        hex(&self.bytes())
    }
}

fn hex(bytes: &[u8; 32]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h(steps: &[&[f64]]) -> String {
        let mut d = Digest::new();
        for s in steps {
            d.values(s);
            d.end_step();
        }
        d.hex()
    }

    #[test]
    fn distinguishes_bit_patterns_order_and_step_boundaries() {
        assert_ne!(h(&[&[0.0]]), h(&[&[-0.0]]));
        assert_ne!(h(&[&[1.0, 2.0]]), h(&[&[2.0, 1.0]]));
        assert_eq!(h(&[&[1.0, 2.0]]), h(&[&[1.0, 2.0]]));
        assert_ne!(h(&[&[1.0, 2.0]]), h(&[&[1.0], &[2.0]]));
        assert_eq!(h(&[]).len(), 64);
    }

    #[test]
    fn a_restored_digest_continues_the_same_chain() {
        let mut a = Digest::new();
        a.values(&[1.0, 2.0]);
        a.end_step();
        let json = serde_json::to_string(&a).unwrap();
        let mut b: Digest = serde_json::from_str(&json).unwrap();
        for d in [&mut a, &mut b] {
            d.values(&[3.0]);
            d.end_step();
        }
        assert_eq!(a.hex(), b.hex());
    }
}
