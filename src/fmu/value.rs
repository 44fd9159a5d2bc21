//! A value of any FMI type, as dsmcosim reads, holds, traces and carries it.
//!
//! Every FMI 2.0 type (Real, Integer, Boolean, String, Enumeration) and every FMI 3.0
//! type but Clock (Float64, Float32, Int8 … UInt64, Boolean, String, Binary, Enumeration)
//! has one form here, without loss: signed integers as `i64`, unsigned ones as `u64` (so
//! an Int64 or a UInt64 never passes through an `f64`), Float32 as `f32`.
//!
//! | form | FMI types | trace.csv | digest bytes |
//! |---|---|---|---|
//! | [`Value::Float`] | Real, Float64 | Rust's shortest round-trip `f64` text | the `f64` bits |
//! | [`Value::Float32`] | Float32 | shortest round-trip `f32` text | the bits of the `f64` it widens to |
//! | [`Value::Int`] | Integer, Int8 … Int64, Enumeration | decimal | `i64` |
//! | [`Value::UInt`] | UInt8 … UInt64 | decimal | `u64` |
//! | [`Value::Bool`] | Boolean | `0` / `1` | `u64` 0 / 1 |
//! | [`Value::Text`] | String | the text, CSV-quoted where needed | `u64` length, UTF-8 bytes |
//! | [`Value::Bytes`] | Binary | lower-case hex | `u64` length, the bytes |
//!
//! (All little-endian.) A column's type is fixed by the scenario, so each column's
//! bytes decode one way only; a Real column hashes exactly as before other types were
//! traced.

use super::description::VarKind;

/// Largest String or Binary value read from an FMU [bytes]: 1 MiB. A longer one is
/// refused ([`super::FmuError::CapExceeded`]) rather than copied into every trace row.
pub const MAX_VALUE_BYTES: usize = 1 << 20;

/// One value of an FMI variable (or of one element of an array variable).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Value {
    /// Real (FMI 2.0), Float64 (FMI 3.0).
    Float(f64),
    /// Float32.
    Float32(f32),
    /// Integer, Enumeration (FMI 2.0); Int8, Int16, Int32, Int64, Enumeration (FMI 3.0).
    Int(i64),
    /// UInt8, UInt16, UInt32, UInt64.
    UInt(u64),
    /// Boolean.
    Bool(bool),
    /// String (UTF-8; an FMU's other bytes replaced by U+FFFD).
    Text(String),
    /// Binary.
    Bytes(Vec<u8>),
}

impl Value {
    /// The value a variable of `kind` holds before anything is read or delivered: zero,
    /// false, the empty string or no bytes.
    pub fn zero(kind: VarKind) -> Value {
        match kind {
            VarKind::Real => Value::Float(0.0),
            VarKind::Float32 => Value::Float32(0.0),
            VarKind::UInt8 | VarKind::UInt16 | VarKind::UInt32 | VarKind::UInt64 => Value::UInt(0),
            VarKind::Boolean => Value::Bool(false),
            VarKind::String => Value::Text(String::new()),
            VarKind::Binary => Value::Bytes(Vec::new()),
            VarKind::Integer
            | VarKind::Enumeration
            | VarKind::Int8
            | VarKind::Int16
            | VarKind::Int64
            | VarKind::Clock => Value::Int(0),
        }
    }

    /// The value as a number, for a cost or a plot: floats and integers as the nearest
    /// `f64`, a Boolean as 0 or 1; `None` for String and Binary.
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Value::Float(x) => Some(x),
            Value::Float32(x) => Some(f64::from(x)),
            Value::Int(i) => Some(i as f64),
            Value::UInt(u) => Some(u as f64),
            Value::Bool(b) => Some(f64::from(u8::from(b))),
            Value::Text(_) | Value::Bytes(_) => None,
        }
    }

    /// Whether the value is a NaN or an infinity (a float's; other values never are).
    pub fn is_non_finite(&self) -> bool {
        match *self {
            Value::Float(x) => !x.is_finite(),
            Value::Float32(x) => !x.is_finite(),
            _ => false,
        }
    }

    /// Appends the value's trace.csv field to `out` (see the module's table).
    pub fn write_csv(&self, out: &mut String) {
        use std::fmt::Write as _;
        match self {
            Value::Float(x) => {
                let _ = write!(out, "{x}");
            }
            Value::Float32(x) => {
                let _ = write!(out, "{x}");
            }
            Value::Int(i) => {
                let _ = write!(out, "{i}");
            }
            Value::UInt(u) => {
                let _ = write!(out, "{u}");
            }
            Value::Bool(b) => out.push(if *b { '1' } else { '0' }),
            Value::Text(s) => out.push_str(&crate::output::csv_field(s)),
            Value::Bytes(b) => {
                for byte in b {
                    let _ = write!(out, "{byte:02x}");
                }
            }
        }
    }

    /// The value's bytes in the run digest (see the module's table): `f64` bits for the
    /// floats, so a Real output hashes as it always has.
    pub fn digest_bytes(&self, out: &mut Vec<u8>) {
        match self {
            Value::Float(x) => out.extend_from_slice(&x.to_bits().to_le_bytes()),
            Value::Float32(x) => out.extend_from_slice(&f64::from(*x).to_bits().to_le_bytes()),
            Value::Int(i) => out.extend_from_slice(&i.to_le_bytes()),
            Value::UInt(u) => out.extend_from_slice(&u.to_le_bytes()),
            Value::Bool(b) => out.extend_from_slice(&u64::from(*b).to_le_bytes()),
            Value::Text(s) => {
                out.extend_from_slice(&(s.len() as u64).to_le_bytes());
                out.extend_from_slice(s.as_bytes());
            }
            Value::Bytes(b) => {
                out.extend_from_slice(&(b.len() as u64).to_le_bytes());
                out.extend_from_slice(b);
            }
        }
    }

    /// The `f64` a connection's message carries for this value, from which
    /// [`Value::from_carrier`] gives it back exactly for the same type: a float as
    /// itself (Float32 widened), a Boolean as 0 or 1, an integer of up to 32 bits as its
    /// exact `f64`, an Int64 or UInt64 as its 64 bits reinterpreted (the network copies
    /// a signal's value and never computes with it). `None` for String and Binary, which
    /// connections do not carry.
    pub fn to_carrier(&self, kind: VarKind) -> Option<f64> {
        Some(match *self {
            Value::Float(x) => x,
            Value::Float32(x) => f64::from(x),
            Value::Bool(b) => f64::from(u8::from(b)),
            Value::Int(i) if kind == VarKind::Int64 => f64::from_bits(i as u64),
            Value::UInt(u) if kind == VarKind::UInt64 => f64::from_bits(u),
            Value::Int(i) => i as f64,
            Value::UInt(u) => u as f64,
            Value::Text(_) | Value::Bytes(_) => return None,
        })
    }

    /// The value of type `kind` that [`Value::to_carrier`] made `x` from.
    pub fn from_carrier(kind: VarKind, x: f64) -> Value {
        match kind {
            VarKind::Real => Value::Float(x),
            VarKind::Float32 => Value::Float32(x as f32),
            VarKind::Boolean => Value::Bool(x != 0.0),
            VarKind::Int64 => Value::Int(x.to_bits() as i64),
            VarKind::UInt64 => Value::UInt(x.to_bits()),
            VarKind::UInt8 | VarKind::UInt16 | VarKind::UInt32 => Value::UInt(x as u64),
            VarKind::Integer
            | VarKind::Enumeration
            | VarKind::Int8
            | VarKind::Int16
            | VarKind::Clock => Value::Int(x as i64),
            VarKind::String | VarKind::Binary => Value::zero(kind),
        }
    }
}

impl std::fmt::Display for Value {
    /// As in trace.csv, but a String unquoted.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Text(s) => f.write_str(s),
            other => {
                let mut s = String::new();
                other.write_csv(&mut s);
                f.write_str(&s)
            }
        }
    }
}

/// Lower-case or upper-case hex digits (an even number, whitespace around them ignored)
/// as bytes: an FMI 3.0 Binary start value (`xs:hexBinary`) or a scenario's.
pub fn parse_hex(text: &str) -> Result<Vec<u8>, String> {
    let t = text.trim();
    if !t.len().is_multiple_of(2) {
        return Err(format!(
            "{text:?} is not hex bytes (an odd number of digits)"
        ));
    }
    (0..t.len())
        .step_by(2)
        .map(|i| {
            t.get(i..i + 2)
                .and_then(|d| u8::from_str_radix(d, 16).ok())
                .ok_or_else(|| format!("{text:?} is not hex bytes (0-9, a-f, two per byte)"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixty_four_bit_integers_cross_the_carrier_exactly() {
        for i in [i64::MIN, -1, 0, (1 << 53) + 1, i64::MAX] {
            let x = Value::Int(i).to_carrier(VarKind::Int64);
            assert_eq!(
                x.map(|x| Value::from_carrier(VarKind::Int64, x)),
                Some(Value::Int(i))
            );
        }
        for u in [0, (1 << 53) + 1, u64::MAX] {
            let x = Value::UInt(u).to_carrier(VarKind::UInt64);
            assert_eq!(
                x.map(|x| Value::from_carrier(VarKind::UInt64, x)),
                Some(Value::UInt(u))
            );
        }
        let x = Value::Int(i64::from(i32::MIN)).to_carrier(VarKind::Integer);
        assert_eq!(x, Some(-2147483648.0));
    }

    #[test]
    fn csv_fields_are_exact_and_quoted_where_needed() {
        let field = |v: Value| {
            let mut s = String::new();
            v.write_csv(&mut s);
            s
        };
        assert_eq!(field(Value::UInt(u64::MAX)), "18446744073709551615");
        assert_eq!(field(Value::Int((1 << 53) + 1)), "9007199254740993");
        assert_eq!(field(Value::Float32(0.1)), "0.1");
        assert_eq!(field(Value::Bool(true)), "1");
        assert_eq!(field(Value::Text("a, \"b\"".into())), "\"a, \"\"b\"\"\"");
        assert_eq!(field(Value::Bytes(vec![0, 0xab, 0xff])), "00abff");
        assert_eq!(parse_hex("00aBff"), Ok(vec![0, 0xab, 0xff]));
        assert!(parse_hex("0g").is_err() && parse_hex("abc").is_err());
    }
}
