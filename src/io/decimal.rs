//! Decimal text to f64, bit for bit what std's `str::parse::<f64>` returns, faster on
//! the numbers logs are made of.
//!
//! A field of at most 19 digits whose value is w · 10^e with w ≤ 2^53 and |e| ≤ 22
//! (every value a logger prints with up to 15 significant digits and a modest
//! exponent) is converted as one IEEE multiplication or division of two exactly
//! representable numbers, w and 10^|e|. That single operation is correctly rounded,
//! and so is std's parser, so both give the nearest f64 to the decimal value: the same
//! bits (Clinger's fast path, which std also takes first, after a general-purpose
//! scan). Any other text, including every text std rejects, goes to std itself.

/// 10^0 … 10^22: the powers of ten an f64 holds exactly.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses `text` (no surrounding spaces) as std's `str::parse::<f64>` does, with the
/// same result bit for bit and the same acceptance.
pub fn parse_f64(text: &str) -> Result<f64, std::num::ParseFloatError> {
    match fast_path_in(text.as_bytes(), 0..text.len()) {
        Some(v) => Ok(v),
        None => text.parse::<f64>(),
    }
}

/// [`parse_f64`]'s fast path for the field `row[field]`, which it reads eight bytes at
/// a time (bytes of `row` past the field are read but never used): `None` where std
/// must decide. A field of up to 7 digits before and after an optional point takes no
/// branch per digit; one with 8 or more on either side is left to std at once, and one
/// with an exponent to `exact_fast_path`.
pub fn fast_path_in(row: &[u8], field: std::ops::Range<usize>) -> Option<f64> {
    let end = field.end.min(row.len());
    let start = field.start.min(end);
    // The sign without a branch: signs of logged values are as good as random.
    let first = if start < end { row[start] } else { 0 };
    let negative = first == b'-';
    let mut i = start + usize::from(negative | (first == b'+'));
    let word = load8(row, i);
    let int_digits = leading_digits(word).min(end - i);
    if int_digits == 8 {
        // Eight digits or more: rarely exact here (a full-precision value needs std's
        // Eisel–Lemire path), so no second look.
        return None;
    }
    let mut w = digits_value(word, int_digits);
    i += int_digits;
    let mut fraction = 0;
    if i < end && row[i] == b'.' {
        i += 1;
        let word = load8(row, i);
        fraction = leading_digits(word).min(end - i);
        if fraction == 8 {
            return None;
        }
        w = w * POW10_U64[fraction] + digits_value(word, fraction);
        i += fraction;
    }
    if i != end {
        // An exponent, or not a number.
        return exact_fast_path(&row[start..end]);
    }
    if int_digits + fraction == 0 {
        return None;
    }
    // At most 14 digits: w < 2^53, and 10^fraction is exact.
    let magnitude = w as f64 / POW10[fraction];
    Some(f64::from_bits(
        magnitude.to_bits() | (u64::from(negative) << 63),
    ))
}

/// 10^0 … 10^7 as integers.
const POW10_U64: [u64; 8] = [1, 10, 100, 1000, 10_000, 100_000, 1_000_000, 10_000_000];

/// The eight bytes of `row` from `at`, little-endian (first byte lowest); zero bytes
/// (not digits) past its end.
fn load8(row: &[u8], at: usize) -> u64 {
    match row.get(at..at + 8) {
        Some(w) => u64::from_le_bytes(w.try_into().unwrap_or_default()),
        None => row
            .get(at..)
            .unwrap_or_default()
            .iter()
            .enumerate()
            .fold(0, |w, (k, &c)| w | (u64::from(c) << (8 * k))),
    }
}

/// How many of the bytes of `word`, from the lowest, are ASCII digits before the first
/// that is not (8 when all are). Exact: a carry or borrow between bytes starts only at a
/// byte that is not a digit and moves only to higher bytes.
fn leading_digits(word: u64) -> usize {
    let not_digit = (word.wrapping_add(0x4646_4646_4646_4646)
        | word.wrapping_sub(0x3030_3030_3030_3030))
        & 0x8080_8080_8080_8080;
    not_digit.trailing_zeros() as usize / 8
}

/// The value of the first `n` (≤ 8) bytes of `word`, ASCII digits, most significant
/// first: three multiplications for all eight.
fn digits_value(word: u64, n: usize) -> u64 {
    if n == 0 {
        return 0;
    }
    // The n digits to the top bytes, zeros (leading zeros) below; borrows of the bytes
    // beyond the digits go out at the top.
    let v = word.wrapping_sub(0x3030_3030_3030_3030) << (8 * (8 - n));
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    let pairs = v & 0x0000_00ff_0000_00ff;
    let next = (v >> 16) & 0x0000_00ff_0000_00ff;
    (pairs
        .wrapping_mul(100 + (1_000_000 << 32))
        .wrapping_add(next.wrapping_mul(1 + (10_000 << 32))))
        >> 32
}

/// The value of `s` when it is `[+-]digits[.digits][(e|E)[+-]digits]` with 1–19 digits
/// before the exponent, at most 4 exponent digits, and a value w · 10^e that
/// [`POW10`] converts exactly (w ≤ 2^53, |e| ≤ 22); otherwise `None`.
fn exact_fast_path(s: &[u8]) -> Option<f64> {
    let (negative, mut i) = match s.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let mut w: u64 = 0;
    let int_start = i;
    while let Some(d) = digit(s, i) {
        w = w.wrapping_mul(10).wrapping_add(d);
        i += 1;
    }
    let mut digits = i - int_start;
    let mut fraction = 0;
    if s.get(i) == Some(&b'.') {
        i += 1;
        let frac_start = i;
        while let Some(d) = digit(s, i) {
            w = w.wrapping_mul(10).wrapping_add(d);
            i += 1;
        }
        fraction = i - frac_start;
        digits += fraction;
    }
    // Below 10^19 < 2^64 nothing wrapped.
    if digits == 0 || digits > 19 {
        return None;
    }
    let mut exponent: i64 = 0;
    if s.get(i).is_some_and(|&c| c | 0x20 == b'e') {
        i += 1;
        let exp_negative = match s.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let exp_start = i;
        while let Some(d) = digit(s, i) {
            exponent = exponent * 10 + d as i64;
            i += 1;
            if i - exp_start > 4 {
                return None;
            }
        }
        if i == exp_start {
            return None;
        }
        if exp_negative {
            exponent = -exponent;
        }
    }
    if i != s.len() || w > 1 << 53 {
        return None;
    }
    let e = exponent - fraction as i64;
    let power = *POW10.get(e.unsigned_abs() as usize)?;
    let magnitude = if e >= 0 {
        w as f64 * power
    } else {
        w as f64 / power
    };
    Some(if negative { -magnitude } else { magnitude })
}

/// The decimal digit at `s[i]`, if it is one.
fn digit(s: &[u8], i: usize) -> Option<u64> {
    s.get(i)
        .filter(|c| c.is_ascii_digit())
        .map(|&c| u64::from(c - b'0'))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// `parse_f64` and std agree on `text`: the same bits, or both reject it.
    fn agrees(text: &str) {
        match (parse_f64(text), text.parse::<f64>()) {
            (Ok(a), Ok(b)) => assert_eq!(a.to_bits(), b.to_bits(), "{text:?}: {a:e} vs {b:e}"),
            (Err(_), Err(_)) => {}
            (a, b) => panic!("{text:?}: {a:?} vs std {b:?}"),
        }
    }

    /// Edge cases of the grammar and of the exactness bounds (2^53, 10^±22, 19 digits,
    /// 4 exponent digits, signed zeros), and texts std rejects or reads specially.
    #[test]
    fn adversarial_texts_match_std() {
        let texts = [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.0",
            "-0e0",
            "0e-400",
            "1",
            "-1",
            "+1",
            ".5",
            "5.",
            "-.5",
            "+5.",
            "1e5",
            "1E5",
            "1e+5",
            "1e-5",
            "1.e5",
            ".1e1",
            "1e22",
            "1e23",
            "1e-22",
            "1e-23",
            "123456789e-30",
            "9007199254740992",
            "9007199254740993",
            "9007199254740991.0",
            "900719925474099.3",
            "9007199254740992e22",
            "9007199254740992e-22",
            "9007199254740993e-22",
            "1234567890123456789",
            "12345678901234567890",
            "0.1234567890123456789",
            "0.12345678901234567890",
            "0000000000000000001",
            "00000000000000000001",
            "1e0000",
            "1e00001",
            "1e99999",
            "1e-99999",
            "0.1",
            "0.2",
            "0.3",
            "2.2250738585072014e-308",
            "4.9e-324",
            "1.7976931348623157e308",
            "1e308",
            "1e309",
            "",
            ".",
            "-",
            "+",
            "e5",
            ".e5",
            "1e",
            "1e+",
            "1e-",
            "--1",
            "+-1",
            "1..2",
            "1.2.3",
            "1e5e5",
            "1e5.5",
            " 1",
            "1 ",
            "1,5",
            "0x10",
            "1_000",
            "inf",
            "-inf",
            "+inf",
            "infinity",
            "Infinity",
            "nan",
            "NaN",
            "-nan",
            "1f",
            "1d",
            "١",
            "1\u{0}",
            "5.45416",
            "-0.385299",
            "2577.91",
            "-14.4542",
            "-0.0288174",
            "11105",
            "-9878.38",
            "1.5e-7",
            "6.02214076e23",
            "-3.14159265358979",
        ];
        for text in texts {
            agrees(text);
        }
    }

    /// The eight-byte reader gives std's bits for every field of random rows (digits,
    /// points, signs, exponents, junk, empty fields), reading past each field into the
    /// rest of the row, and for every digit count 0–8 before and after the point.
    #[test]
    fn fields_read_in_words_match_std() {
        let mut rng = StdRng::seed_from_u64(14);
        let alphabet = b"0123456789012345678901234567890123456789..--+eE x,";
        for _ in 0..200_000 {
            let len = rng.random_range(0..40);
            let row: Vec<u8> = (0..len)
                .map(|_| alphabet[rng.random_range(0..alphabet.len())])
                .collect();
            let mut start = 0;
            for end in (0..=row.len()).filter(|&i| i == row.len() || row[i] == b',') {
                let text = std::str::from_utf8(&row[start..end]).unwrap_or_default();
                if let Some(v) = fast_path_in(&row, start..end) {
                    let std = text.parse::<f64>().map(f64::to_bits);
                    assert_eq!(Ok(v.to_bits()), std, "{text:?} in {row:?}");
                }
                start = end + 1;
            }
        }
        for int in 0..=8 {
            for frac in 0..=8 {
                let digits = |n: usize| "987654321".get(..n).unwrap_or_default().to_string();
                let text = format!("-{}.{},123", digits(int), digits(frac));
                let field = 0..text.find(',').unwrap_or_default();
                let got = fast_path_in(text.as_bytes(), field.clone());
                let std = text[field].parse::<f64>().ok();
                if int + frac > 0 && int < 8 && frac < 8 {
                    assert!(got.is_some(), "{text}: fast path not taken");
                }
                if got.is_some() {
                    assert_eq!(got.map(f64::to_bits), std.map(f64::to_bits), "{text}");
                }
            }
        }
    }

    /// The fast path is taken where it is exact, and only there.
    #[test]
    fn fast_path_covers_logged_values_only_where_exact() {
        for text in [
            "5.45416",
            "-0.385299",
            "11105",
            "1e22",
            "-1.5e-7",
            "9007199254740992",
        ] {
            assert!(exact_fast_path(text.as_bytes()).is_some(), "{text}");
        }
        for text in [
            "1e23",
            "1e-23",
            "9007199254740993",
            "12345678901234567890",
            "inf",
            "1e",
        ] {
            assert!(exact_fast_path(text.as_bytes()).is_none(), "{text}");
        }
        // A field range past the row reads nothing (and does not panic).
        assert_eq!(
            fast_path_in(b"12", std::ops::Range { start: 5, end: 3 }),
            None
        );
        assert_eq!(fast_path_in(b"12,5", 3..9), Some(5.0));
    }

    /// Random decimal texts in and around the fast path: every part optional, lengths
    /// across the 19-digit bound, exponents across ±22 and beyond, with an occasional
    /// stray character. 200 000 texts (seeded, so a failure reproduces).
    #[test]
    fn random_texts_match_std() {
        let mut rng = StdRng::seed_from_u64(12);
        let mut text = String::new();
        let digits = |rng: &mut StdRng, text: &mut String, max: usize| {
            let zeros = if rng.random_bool(0.2) {
                rng.random_range(0..4)
            } else {
                0
            };
            text.extend(std::iter::repeat_n('0', zeros));
            for _ in 0..rng.random_range(0..=max) {
                text.push(char::from(b'0' + rng.random_range(0..10u8)));
            }
        };
        for _ in 0..200_000 {
            text.clear();
            match rng.random_range(0..4) {
                0 => text.push('-'),
                1 => text.push('+'),
                _ => {}
            }
            digits(&mut rng, &mut text, 12);
            if rng.random_bool(0.7) {
                text.push('.');
                digits(&mut rng, &mut text, 12);
            }
            if rng.random_bool(0.3) {
                text.push(if rng.random_bool(0.5) { 'e' } else { 'E' });
                match rng.random_range(0..3) {
                    0 => text.push('-'),
                    1 => text.push('+'),
                    _ => {}
                }
                let e: u32 = rng.random_range(0..40);
                text.push_str(&e.to_string());
            }
            if rng.random_bool(0.02) {
                let at = rng.random_range(0..=text.len());
                let stray = ['.', 'e', '-', ' ', 'x', '5'][rng.random_range(0..6)];
                text.insert(at, stray);
            }
            agrees(&text);
        }
    }

    /// Every f64 printed the way loggers print them (shortest round trip, and fixed
    /// precisions) reads back as std reads it.
    #[test]
    fn printed_floats_match_std() {
        let mut rng = StdRng::seed_from_u64(13);
        for _ in 0..100_000 {
            let x = f64::from_bits(rng.random::<u64>());
            let scale = 10f64.powi(rng.random_range(-8..8));
            let y = rng.random_range(-1.0..1.0) * scale;
            for v in [x, y] {
                agrees(&format!("{v}"));
                agrees(&format!("{v:e}"));
                agrees(&format!("{v:.6}"));
                agrees(&format!("{:.6}", v as f32));
            }
        }
    }
}
