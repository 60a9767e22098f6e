//! Numbers of the output tables in their shortest round-trip decimal form, byte for byte as
//! Rust's `{}` writes an `f64` (positional notation, no exponent; `1` for `1.0`, `-0` for
//! `-0.0`), from the digits of the Ryū algorithm (the `ryu` crate, which `serde_json` uses
//! for the JSON files), several times faster than `{}`: the state files of a diagram hold
//! hundreds of thousands of numbers.
//!
//! Both find the shortest digits that read back to the same `f64` and, among those, the
//! closest to its exact value; they can differ only where two are equally close. That
//! needs the exact binary value to end one decimal digit after the `n ≤ 17` significant
//! digits written, so at most 18 significant digits in all; a value whose lowest set bit is
//! `2^e` with `e ≤ −25` has at least `0.69·25 + 1 > 18` (the odd `M` in `M·2^e` times
//! `5^{−e}`), so only values with `e > −25` (integers, and numbers like `0.375` with short
//! binary expansions) are written by `{}` itself.

use std::fmt::Write as _;

/// Append the finite `v` to `out` exactly as `write!(out, "{v}")` does.
pub fn push_f64(out: &mut String, v: f64) {
    if !v.is_finite() || lowest_bit_exponent(v) > -25 {
        let _ = write!(out, "{v}");
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(v);
    // Without an exponent Ryū writes what `{}` writes (the value has a fraction, so there
    // is no `.0` to drop).
    if !text.contains('e') {
        out.push_str(text);
        return;
    }
    let text = text.as_bytes();
    let (negative, text) = match text.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, text),
    };
    let (mantissa, exponent) = match text.iter().position(|&b| b == b'e') {
        Some(at) => (&text[..at], parse_exponent(&text[at + 1..])),
        None => (text, 0),
    };
    let (int, frac) = match mantissa.iter().position(|&b| b == b'.') {
        Some(at) => (&mantissa[..at], &mantissa[at + 1..]),
        None => (mantissa, &mantissa[mantissa.len()..]),
    };
    // The significant digits, and the decimal point after the first `point` of them.
    let mut digits = [0u8; 40];
    let mut len = 0;
    for &b in int.iter().chain(frac) {
        digits[len] = b;
        len += 1;
    }
    let lead = digits[..len].iter().take_while(|&&b| b == b'0').count();
    let trail = digits[lead..len]
        .iter()
        .rev()
        .take_while(|&&b| b == b'0')
        .count();
    let digits = &digits[lead..len - trail];
    let point = int.len() as i32 + exponent - lead as i32;
    if negative {
        out.push('-');
    }
    let push = |out: &mut String, d: &[u8]| out.extend(d.iter().map(|&b| b as char));
    if point <= 0 {
        out.push_str("0.");
        out.extend(std::iter::repeat_n('0', point.unsigned_abs() as usize));
        push(out, digits);
    } else if point as usize >= digits.len() {
        push(out, digits);
        out.extend(std::iter::repeat_n('0', point as usize - digits.len()));
    } else {
        let (a, b) = digits.split_at(point as usize);
        push(out, a);
        out.push('.');
        push(out, b);
    }
}

/// The exponent `e` of the lowest set bit `2^e` of the finite, nonzero `v` (`i32::MAX` for
/// zero, which `{}` writes as it is).
fn lowest_bit_exponent(v: f64) -> i32 {
    let bits = v.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    let (significand, exponent) = if biased == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1u64 << 52), biased - 1075)
    };
    if significand == 0 {
        return i32::MAX;
    }
    exponent + significand.trailing_zeros() as i32
}

/// The exponent Ryū writes after `e` (an optional `-`, then decimal digits).
fn parse_exponent(text: &[u8]) -> i32 {
    let (sign, digits) = match text.split_first() {
        Some((b'-', rest)) => (-1, rest),
        _ => (1, text),
    };
    sign * digits
        .iter()
        .fold(0i32, |acc, &b| acc * 10 + i32::from(b - b'0'))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(v: f64) {
        let mut ours = String::new();
        push_f64(&mut ours, v);
        assert_eq!(ours, format!("{v}"), "bits {:#018x}", v.to_bits());
    }

    /// Equal to `{}` on the edge cases of the layout (zeros of both signs, integers, powers
    /// of ten on both sides of each layout switch of Ryū, the extremes and subnormals of
    /// `f64`, values that tie between two shortest candidates) and on four million values:
    /// random bit patterns (every exponent) and random numbers of the sizes the tables hold.
    #[test]
    fn writes_what_display_writes() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.3,
            0.375,
            123456.0,
            1.5e-5,
            1e-7,
            1658206780088562.2,
            233115890514796.12,
            f64::MIN_POSITIVE,
            f64::from_bits(1),
            f64::from_bits(0x000f_ffff_ffff_ffff),
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            9007199254740993.0,
            std::f64::consts::PI,
        ] {
            check(v);
        }
        for e in -30..=30 {
            for m in [1.0, 1.5, 9.999999999999999, 123.456, 1.0 / 3.0] {
                check(m * 10f64.powi(e));
                check(-m * 10f64.powi(e));
            }
        }
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for _ in 0..2_000_000 {
            let v = f64::from_bits(next());
            if v.is_finite() {
                check(v);
            }
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
            check((u - 0.5) * 10f64.powi((next() % 13) as i32 - 6));
        }
    }

    /// The lowest set bit of values with known binary expansions.
    #[test]
    fn lowest_bit_of_known_values() {
        assert_eq!(lowest_bit_exponent(1.0), 0);
        assert_eq!(lowest_bit_exponent(0.375), -3);
        assert_eq!(lowest_bit_exponent(-6.0), 1);
        assert_eq!(lowest_bit_exponent(f64::from_bits(1)), -1074);
        assert_eq!(lowest_bit_exponent(1.0 + f64::EPSILON), -52);
        assert_eq!(lowest_bit_exponent(0.0), i32::MAX);
    }
}
