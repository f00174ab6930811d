//! Numbers in the CSV and markdown outputs: the shortest text that reads back to the same f64,
//! written as std's `{x}` (plain decimal) for 1e-4 ≤ |x| < 1e15 and 0, `{x:e}` (scientific)
//! otherwise, byte for byte.
//!
//! ```text
//! digits   zmij (Schubfach, the shortest round-trip digits; the crate serde_json formats
//!          with): d₁d₂…dₙ and E with |x| = d₁.d₂…dₙ × 10^E
//! {x}      E ≥ 0: d₁…d_{E+1} (zeros appended when n ≤ E) [. the rest]     1234.5, 100
//!          E < 0: 0.000…d₁…dₙ                                            0.00012
//! {x:e}    d₁[.d₂…dₙ]e E                                                 1.5e-7, 1e15
//! NaN, ±∞  std's own text
//! ```
//!
//! Why: std's shortest formatting (Grisu with a Dragon fallback) was 37 % of a 300-link
//! chain's `lash run` (4 001 rows × 1 800 columns); zmij takes a fraction of that. Both give
//! the shortest digits that read back, the closest to the exact value among them; they differ
//! only on an exact tie between two n-digit candidates (std rounds it up, zmij to even), which
//! needs an exact value of n + 1 significant digits: those few (`tie_free` false) are written by
//! std. The test module checks the text against std's on special values, ties and
//! two million random doubles.

use std::fmt::Write as _;

/// Appends `x` in the shortest form that reads back to the same f64 (module doc).
pub(crate) fn push_num(out: &mut String, x: f64) {
    let a = x.abs();
    let plain = x == 0.0 || (1e-4..1e15).contains(&a);
    if x == 0.0 || !x.is_finite() || !tie_free(a) {
        // Zero, NaN, ±∞ and the rare values whose digits may come from a tie (module doc).
        let _ = if plain {
            write!(out, "{x}")
        } else {
            write!(out, "{x:e}")
        };
        return;
    }
    let mut buf = zmij::Buffer::new();
    let s = buf.format_finite(a);
    if x < 0.0 {
        out.push('-');
    }
    // zmij writes 1e-5 ≤ |x| < 1e16 as a decimal ("123.0", "0.00012") and the rest as
    // "1.5e-7", "1e+16": std's text but for the ".0" and the "+".
    match (plain, s.find('e')) {
        (true, None) => out.push_str(s.strip_suffix(".0").unwrap_or(s)),
        (false, Some(k)) => {
            out.push_str(&s[..=k]);
            out.push_str(s[k + 1..].trim_start_matches('+'));
        }
        _ => rebuild(out, s, plain),
    }
}

/// Appends std's text of the positive number zmij wrote as `s` in the other notation
/// (1e-5 ≤ |x| < 1e-4 and 1e15 ≤ |x| < 1e16).
fn rebuild(out: &mut String, s: &str, plain: bool) {
    let (digits, n, e) = decompose(s);
    let d = &digits[..n];
    if !plain {
        out.push(char::from(d[0]));
        if n > 1 {
            out.push('.');
            push_ascii(out, &d[1..]);
        }
        let _ = write!(out, "e{e}");
    } else if e >= 0 {
        let int = e as usize + 1;
        if n <= int {
            push_ascii(out, d);
            (n..int).for_each(|_| out.push('0'));
        } else {
            push_ascii(out, &d[..int]);
            out.push('.');
            push_ascii(out, &d[int..]);
        }
    } else {
        out.push_str("0.");
        (0..(-e - 1)).for_each(|_| out.push('0'));
        push_ascii(out, d);
    }
}

/// Whether the shortest digits of a positive finite `a` cannot come from a tie. A tie (std
/// rounds it up, zmij to even) needs an exact value halfway between two n-digit decimals,
/// n ≤ 17: an exact expansion of n + 1 ≤ 18 significant digits. With a = m·2^k, m odd: for
/// k < 0 the expansion ends −k digits after the point, so it has E + 1 − k significant digits
/// (E = ⌊log₁₀ a⌋, bounded below from the binary exponent, one digit of margin); for k ≥ 0, a
/// is an integer, exact in 17 digits below 1e16. Computed values have 30 or more digits, so
/// only short binary fractions and large integers go to std.
fn tie_free(a: f64) -> bool {
    let bits = a.to_bits();
    let (mut m, mut k) = match (bits >> 52) & 0x7ff {
        0 => (bits & ((1 << 52) - 1), -1074),
        b => ((bits & ((1 << 52) - 1)) | (1 << 52), b as i32 - 1075),
    };
    if m == 0 {
        return false;
    }
    let tz = m.trailing_zeros();
    m >>= tz;
    k += tz as i32;
    if k >= 0 {
        return a < 1e16;
    }
    let log2_low = k + 63 - m.leading_zeros() as i32;
    let e_low = (f64::from(log2_low) * std::f64::consts::LOG10_2).floor() as i32 - 1;
    e_low + 1 - k > 19
}

/// Appends ASCII digits.
fn push_ascii(out: &mut String, d: &[u8]) {
    d.iter().for_each(|&c| out.push(char::from(c)));
}

/// The significant digits (no leading or trailing zeros), their count and the decimal exponent
/// E of a positive number's text in any of zmij's forms ("123.45", "0.00012", "1.5e-7",
/// "1e+16"): |x| = d₁.d₂…dₙ × 10^E.
fn decompose(s: &str) -> ([u8; 32], usize, i32) {
    let (mant, exp) = match s.find(['e', 'E']) {
        Some(k) => (&s[..k], s[k + 1..].parse::<i32>().unwrap_or(0)),
        None => (s, 0),
    };
    let mut digits = [b'0'; 32];
    let mut n = 0;
    // Digits before the point, counted among the significant ones once the first nonzero
    // digit is seen: `point` ends as the position of the point relative to d₁.
    let mut point: i32 = 0;
    let mut after_point = false;
    for c in mant.bytes() {
        match c {
            b'.' => after_point = true,
            b'0'..=b'9' => {
                if n == 0 && c == b'0' {
                    if after_point {
                        point -= 1;
                    }
                    continue;
                }
                if !after_point {
                    point += 1;
                }
                if n < digits.len() {
                    digits[n] = c;
                    n += 1;
                }
            }
            _ => {}
        }
    }
    while n > 1 && digits[n - 1] == b'0' {
        n -= 1;
    }
    (digits, n.max(1), point - 1 + exp)
}

#[cfg(test)]
mod tests {
    use super::push_num;

    /// std's text, the form the outputs had before (module doc).
    fn std_text(x: f64) -> String {
        let a = x.abs();
        if x == 0.0 || (1e-4..1e15).contains(&a) {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    }

    fn ours(x: f64) -> String {
        let mut s = String::new();
        push_num(&mut s, x);
        s
    }

    /// Special values, the plain/scientific boundaries, subnormals, powers of ten and the
    /// extremes: the same text as std.
    #[test]
    fn special_values_and_boundaries_match_std() {
        let mut xs = vec![
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            5e-324,
            1e-4,
            1e15,
            9.999999999999999e14,
            1e-4f64.next_up(),
            0.1,
            0.3,
            1.0 / 3.0,
            123456.789,
            1e14,
            100.0,
            1.5e-7,
            5e-5,
            -3.3e15,
            1.2345678901234567e-5,
            2.0f64.powi(60),
            -f64::from_bits(0x4314_db7d_95c6_adb1), // -1467707991108460.25: a tie
            1e21,
            1e22,
            1e23,
        ];
        for k in -320..=308 {
            let p = 10f64.powi(k);
            xs.extend([p, -p, p * 1.5, p.next_up(), p.next_down()]);
        }
        for x in xs {
            assert_eq!(ours(x), std_text(x), "{x:?}");
        }
    }

    /// A million each of random bit patterns (SplitMix64, fixed seed), random numbers in the
    /// plain range and large numbers with few fractional bits (ties): the same text as std.
    #[test]
    fn random_doubles_match_std() {
        let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        for _ in 0..1_000_000 {
            let x = f64::from_bits(next());
            assert_eq!(ours(x), std_text(x), "{:#x}", x.to_bits());
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
            let y = 10f64.powf(-6.0 + 22.0 * u) * if next() & 1 == 0 { 1.0 } else { -1.0 };
            assert_eq!(ours(y), std_text(y), "{:#x}", y.to_bits());
            // 53-bit integers scaled by 2^-8 … 2^11: exact expansions of 16–19 digits, where
            // the 17-digit ties live.
            let z = (next() >> 11) as f64 * 2f64.powi((next() % 20) as i32 - 8);
            assert_eq!(ours(z), std_text(z), "{:#x}", z.to_bits());
        }
    }
}
