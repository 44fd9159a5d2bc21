//! The run digest: BLAKE3 over the exact bytes of every recorded value.
//!
//! Order (SPEC section 6): for every step k = 0..=steps, in step order, the time `t_k`
//! as a little-endian `u64` count of nanoseconds, then the `f64` bit patterns
//! (little-endian) of every link's `w` then every link's `f` (link order), then every
//! body's `p` then `v` (body order, x y z). Every step is hashed, whatever the trace
//! decimation or the traced-body selection, so changing the output options never
//! changes the digest; `-0.0` and `0.0` hash differently, as they are different bits.

/// Incremental digest of a run.
#[derive(Debug, Clone, Default)]
pub struct Digest {
    hasher: blake3::Hasher,
}

impl Digest {
    /// An empty digest.
    pub fn new() -> Digest {
        Digest::default()
    }

    /// Adds a time in nanoseconds.
    pub fn time(&mut self, ns: u64) {
        self.hasher.update(&ns.to_le_bytes());
    }

    /// Adds the bit patterns of `values`.
    pub fn values(&mut self, values: &[f64]) {
        for v in values {
            self.hasher.update(&v.to_bits().to_le_bytes());
        }
    }

    /// Adds the bit patterns of one value.
    pub fn value(&mut self, v: f64) {
        self.hasher.update(&v.to_bits().to_le_bytes());
    }

    /// The digest as 64 lowercase hex digits.
    pub fn hex(&self) -> String {
        self.hasher.finalize().to_hex().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distinguishes_bit_patterns_and_order() {
        let h = |vals: &[f64]| {
            let mut d = Digest::new();
            d.values(vals);
            d.hex()
        };
        assert_ne!(h(&[0.0]), h(&[-0.0]));
        assert_ne!(h(&[1.0, 2.0]), h(&[2.0, 1.0]));
        assert_eq!(h(&[1.0, 2.0]), h(&[1.0, 2.0]));
        assert_eq!(h(&[]).len(), 64);
    }
}
