//! Value checks and number formatting shared by the validation stages.
//!
//! Every check takes the field path it reports (`model.bodies[0].mass`) and returns the
//! value on success, so a stage reads `let mass = positive(&path, b.mass)?;`.

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::kernel::SimTime;

pub(in crate::scenario) use crate::error::num;

/// Formats a vector for an error message: `[0.1, 0, 0]`.
pub(super) fn vec_str(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|&x| num(x)).collect();
    format!("[{}]", parts.join(", "))
}

/// `x` if it is finite.
pub(super) fn finite(path: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::invalid(
            path,
            format!("must be a finite number (got {})", num(x)),
        ))
    }
}

/// `x` if it is finite and > 0.
pub(in crate::scenario) fn positive(path: &str, x: f64) -> Result<f64> {
    if finite(path, x)? > 0.0 {
        Ok(x)
    } else {
        Err(Error::invalid(
            path,
            format!("must be > 0 (got {})", num(x)),
        ))
    }
}

/// `x` if it is finite and ≥ 0.
pub(super) fn non_negative(path: &str, x: f64) -> Result<f64> {
    if finite(path, x)? >= 0.0 {
        Ok(x)
    } else {
        Err(Error::invalid(
            path,
            format!("must be ≥ 0 (got {})", num(x)),
        ))
    }
}

/// Largest magnitude of a mass, moment of inertia, force amplitude, gain or scale
/// factor, and the inverse of the smallest nonzero one. Within it, the products and
/// quotients of the step (`M⁻¹`, `J M⁻¹ Jᵀ`, `F/m`, `K/μ²`) stay far inside the range
/// of `f64`; beyond it a finite value gave non-finite accelerations, which the solve
/// then reported as a singular `J M⁻¹ Jᵀ` (the wrong cause).
pub(in crate::scenario) const MAGNITUDE: f64 = 1e100;

/// `x` if it is finite and 0 or of magnitude in [1/[`MAGNITUDE`], [`MAGNITUDE`]].
pub(in crate::scenario) fn magnitude(path: &str, x: f64) -> Result<f64> {
    let a = finite(path, x)?.abs();
    if x == 0.0 || (1.0 / MAGNITUDE..=MAGNITUDE).contains(&a) {
        Ok(x)
    } else {
        Err(Error::invalid(
            path,
            format!(
                "must have a magnitude from 1e-100 to 1e100 (or be 0) (got {}; the step's \
                 products would leave the range of floating point)",
                num(x)
            ),
        ))
    }
}

/// `x` if it is > 0 and within [`magnitude`]'s range.
pub(in crate::scenario) fn positive_magnitude(path: &str, x: f64) -> Result<f64> {
    magnitude(path, positive(path, x)?)
}

/// A vector whose components are within [`magnitude`]'s range (an error names the
/// component: `[1]`).
pub(super) fn magnitude_vector(path: &str, v: [f64; 3]) -> Result<Vector3<f64>> {
    for (i, &x) in v.iter().enumerate() {
        magnitude(&format!("{path}[{i}]"), x)?;
    }
    Ok(Vector3::from(v))
}

/// A vector whose components are all finite (an error names the component: `[1]`).
pub(super) fn vector(path: &str, v: [f64; 3]) -> Result<Vector3<f64>> {
    for (i, &x) in v.iter().enumerate() {
        finite(&format!("{path}[{i}]"), x)?;
    }
    Ok(Vector3::from(v))
}

/// Seconds ≥ 0 to the nearest nanosecond.
pub(super) fn time(path: &str, secs: f64) -> Result<SimTime> {
    non_negative(path, secs)?;
    SimTime::from_secs_f64(secs).ok_or_else(|| {
        Error::invalid(
            path,
            format!(
                "is beyond the range of simulated time (got {} s, limit about 1.8e10 s)",
                num(secs)
            ),
        )
    })
}

/// Seconds ≥ 0 as a whole number of nanoseconds. Rounding to the nanosecond must not
/// change the value noticeably (1.5 ns → 2 ns would be a silent 33 % change); 1 ppb
/// leaves room for decimal round-off only.
pub(super) fn whole_nanos(path: &str, secs: f64) -> Result<SimTime> {
    let t = time(path, secs)?;
    let exact_ns = secs * 1e9;
    if (exact_ns - t.as_nanos() as f64).abs() > 1e-9 * exact_ns {
        return Err(Error::invalid(
            path,
            format!(
                "must be a whole number of nanoseconds (got {} s)",
                num(secs)
            ),
        ));
    }
    Ok(t)
}

/// A required key of one kind of a section, absent from the file.
pub(super) fn required(path: &str, kind: &str) -> Error {
    Error::invalid(path, format!("is required for kind \"{kind}\""))
}

/// A key of a section that belongs to another kind than the one chosen.
pub(super) fn foreign(path: &str, kind: &str) -> Error {
    Error::invalid(path, format!("is not a key of kind \"{kind}\""))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_readable() {
        assert_eq!(num(-1.0), "-1");
        assert_eq!(num(0.05), "0.05");
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(f64::NAN), "NaN");
        assert_eq!(num(f64::INFINITY), "inf");
        assert_eq!(vec_str(&[0.1, 0.0, -2.0]), "[0.1, 0, -2]");
    }

    #[test]
    fn checks_name_the_path_and_the_value() {
        let e = |r: Result<f64>| r.unwrap_err().to_string();
        assert_eq!(e(positive("a.b", -1.0)), "a.b: must be > 0 (got -1)");
        assert_eq!(e(non_negative("c", -0.5)), "c: must be ≥ 0 (got -0.5)");
        assert_eq!(
            e(finite("d", f64::NAN)),
            "d: must be a finite number (got NaN)"
        );
        assert_eq!(
            vector("v", [0.0, f64::INFINITY, 0.0])
                .unwrap_err()
                .to_string(),
            "v[1]: must be a finite number (got inf)"
        );
        assert_eq!(time("t", 0.001).unwrap(), SimTime(1_000_000));
        assert!(time("t", 1e11).is_err());
        assert_eq!(whole_nanos("l", 0.0).unwrap(), SimTime::ZERO);
        assert_eq!(whole_nanos("l", 0.005).unwrap(), SimTime(5_000_000));
        assert_eq!(
            whole_nanos("l", 1.5e-9).unwrap_err().to_string(),
            "l: must be a whole number of nanoseconds (got 1.5e-9 s)"
        );
    }
}
