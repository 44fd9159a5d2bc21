//! Byte sizes on the command line (`--max-memory 16G`, `--max-output 500MB`).
//!
//! A size is a number (whole or with a fraction: `1.5G`) and an optional unit, as GNU
//! coreutils reads them (`sort -S`, `du -B`): `K`, `M`, `G`, `T` and `KiB`, `MiB`,
//! `GiB`, `TiB` are powers of 1024; `KB`, `MB`, `GB`, `TB` are powers of 1000; `B` or
//! no unit is bytes. Units are case-insensitive (`16g` = `16G`). A fraction of a byte
//! is rounded down.
//!
//! Written here rather than taken from `parse-size` or `bytesize`: both read `K`, `M`,
//! `G` as one reading for every unit of a kind (all decimal, or all binary with their
//! binary switch), while a memory bound wants coreutils' mix (`16G` binary, `16GB`
//! decimal), and the whole rule is the table below.

/// Parses a size in bytes (for clap's `value_parser`; clap names the flag and exits
/// with code 2 on an error).
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let unit = unit.trim();
    let bad_number = || {
        format!(
            "must be a number of bytes, optionally with a unit, e.g. 16G, 512M, 1.5GiB or \
             2000000000 (got {text:?})"
        )
    };
    if number.is_empty() || number == "." {
        return Err(bad_number());
    }
    let scale: u64 = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "k" | "kib" => 1 << 10,
        "m" | "mib" => 1 << 20,
        "g" | "gib" => 1 << 30,
        "t" | "tib" => 1 << 40,
        "kb" => 1_000,
        "mb" => 1_000_000,
        "gb" => 1_000_000_000,
        "tb" => 1_000_000_000_000,
        _ => {
            return Err(format!(
                "unknown unit {unit:?}: give bytes (2000000000) or a number with K, M, G, T \
                 (powers of 1024; also KiB … TiB) or KB, MB, GB, TB (powers of 1000), e.g. 16G"
            ))
        }
    };
    let too_big = || format!("is more than 2^64 - 1 bytes (got {text:?})");
    match number.split_once('.') {
        None => number
            .parse::<u64>()
            .map_err(|_| too_big())?
            .checked_mul(scale)
            .ok_or_else(too_big),
        Some((whole, fraction)) => {
            if fraction.contains('.') {
                return Err(bad_number());
            }
            let whole: u64 = if whole.is_empty() {
                0
            } else {
                whole.parse().map_err(|_| too_big())?
            };
            // Exactly, in integers: fraction digits d over 10^len, times the scale.
            let digits = fraction.trim_end_matches('0');
            if digits.len() > 18 {
                return Err(bad_number());
            }
            let numerator: u128 = if digits.is_empty() {
                0
            } else {
                digits.parse().map_err(|_| bad_number())?
            };
            let part = numerator * u128::from(scale) / 10u128.pow(digits.len() as u32);
            let total = u128::from(whole) * u128::from(scale) + part;
            u64::try_from(total).map_err(|_| too_big())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::parse_bytes;

    #[test]
    fn units_are_binary_unless_they_say_b_for_decimal() {
        for (text, bytes) in [
            ("2000000000", 2_000_000_000),
            ("16G", 16 << 30),
            ("16g", 16 << 30),
            ("16GiB", 16 << 30),
            ("16GB", 16_000_000_000),
            ("512M", 512 << 20),
            ("512 MiB", 512 << 20),
            ("1.5GiB", 3 << 29),
            ("1.5K", 1536),
            ("0.5T", 1 << 39),
            ("100B", 100),
            ("3.0", 3),
            ("1.0001K", 1024),
        ] {
            assert_eq!(parse_bytes(text), Ok(bytes), "{text}");
        }
    }

    #[test]
    fn bad_sizes_say_what_is_expected() {
        for (text, want) in [
            ("16X", "unknown unit \"X\""),
            ("G", "must be a number of bytes"),
            ("", "must be a number of bytes"),
            (".", "must be a number of bytes"),
            ("1.2.3G", "must be a number of bytes"),
            ("-1G", "must be a number of bytes"),
            ("20000000000T", "more than 2^64"),
            ("99999999999999999999", "more than 2^64"),
        ] {
            let e = parse_bytes(text).unwrap_err();
            assert!(e.contains(want), "{text}: {e}");
        }
    }
}
