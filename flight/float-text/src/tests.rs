//! This crate's text against `core`'s, which it replaces in an image: the same shortest text
//! for every `f32` tried, the same value read back, the same rounding.

use super::*;

fn shortest(v: f32) -> String {
    format!("{}", Shortest(v))
}

/// Every `stride`-th bit pattern of the positive finite floats, and both signs of each.
fn sampled(stride: u32) -> impl Iterator<Item = f32> {
    (0..f32::INFINITY.to_bits())
        .step_by(stride as usize)
        .flat_map(|b| [f32::from_bits(b), -f32::from_bits(b)])
}

/// The floats next to powers of two and to the subnormal/normal border, where the
/// rounding interval is lopsided.
fn edges() -> Vec<f32> {
    let mut v = vec![
        0.0,
        -0.0,
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::from_bits(1),
        f32::from_bits(0x007F_FFFF),
    ];
    for field in 0..255u32 {
        for frac in [0u32, 1, 2, 0x7F_FFFF, 0x40_0000] {
            v.push(f32::from_bits(field << 23 | frac));
        }
    }
    v
}

#[test]
fn shortest_text_is_cores_over_the_whole_range() {
    let mut n = 0;
    for v in sampled(1021).chain(edges()) {
        let text = shortest(v);
        assert_eq!(text, format!("{v}"), "bits {:#010x}", v.to_bits());
        assert_eq!(
            parse(&text).map(f32::to_bits),
            Some(v.to_bits()),
            "{text} reads back"
        );
        n += 1;
    }
    assert!(n > 4_000_000, "{n} values");
    assert_eq!(shortest(f32::NAN), "NaN");
    assert_eq!(shortest(f32::NEG_INFINITY), "-inf");
    assert_eq!(shortest(1e-45), format!("{}", 1e-45f32));
}

#[test]
fn reading_agrees_with_core() {
    let texts = [
        "0",
        "-0",
        "+0",
        "0.0",
        "00012",
        "1.",
        ".5",
        "-.5",
        "1e3",
        "1E3",
        "1e+3",
        "1e-3",
        "2.5e-1",
        "0.004",
        "0.00004",
        "480000",
        "1e9",
        "1e-9",
        "1e-6",
        "1e6",
        "3.4028235e38",
        "3.4028236e38",
        "3.40282357e38",
        "3.4028235677973366e38",
        "1e39",
        "1e-45",
        "1.4e-45",
        "7e-46",
        "7.006e-46",
        "7.1e-46",
        "1.1754942e-38",
        "1.17549435e-38",
        "16777217",
        "16777219",
        "33554434",
        "0.1",
        "0.2",
        "0.30000001",
        "123456789",
        "9999999999999999999",
        "9999999999999999999e-19",
        "1e1000000",
        "1e-1000000",
        "0e999999999",
        "inf",
        "-Infinity",
        "NaN",
        "nan",
        "INF",
        "+inf",
    ];
    for text in texts {
        let expect: f32 = text.parse().unwrap();
        let got = parse(text).unwrap_or_else(|| panic!("{text} refused"));
        assert!(
            got.to_bits() == expect.to_bits() || got.is_nan() && expect.is_nan(),
            "{text}: {got} vs {expect}"
        );
    }
    for bad in [
        "", ".", "-", "+", "e5", "1e", "1e+", "1e-", "1_0", " 1", "1 ", "0x10", "1.2.3", "infinit",
        "nana", "--1", "1e5.0", "١",
    ] {
        assert!(
            bad.parse::<f32>().is_err(),
            "{bad} is no number for core either"
        );
        assert_eq!(parse(bad), None, "{bad}");
    }
    // More than MAX_DIGITS significant digits: refused, not rounded twice; zeros are free.
    assert_eq!(parse("12345678901234567891"), None);
    assert_eq!(parse("12345678901234567890"), Some(1.2345679e19));
    assert_eq!(parse("0.00000000000000000000000012345"), Some(1.2345e-25));
    assert_eq!(parse("100000000000000000000000000"), Some(1e26));
}

#[test]
fn reading_random_decimals_agrees_with_core() {
    // SplitMix64, inline: the test needs no other crate.
    let mut state = 0x5EED_u64;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    for _ in 0..300_000 {
        let digits = 1 + next() % 19;
        let mantissa = next() % 10u64.pow(digits as u32);
        let exponent = (next() % 110) as i32 - 70;
        let point = (next() % (digits + 1)) as usize;
        let mut text = mantissa.to_string();
        if point < text.len() {
            text.insert(point, '.');
        }
        let text = format!("{text}e{exponent}");
        let expect: f32 = text.parse().unwrap();
        assert_eq!(
            parse(&text).map(f32::to_bits),
            Some(expect.to_bits()),
            "{text}"
        );
    }
}

#[test]
fn halfway_cases_round_to_even() {
    // Integers exactly halfway between two neighbouring floats (few enough digits to be
    // typed whole): the even neighbour wins; one more unit tips it up.
    for k in 24..=62u32 {
        for j in [0u64, 1, 2, 7, 1000] {
            let unit = 1u64 << (k - 24);
            let half = (1u64 << k) + unit * (2 * j + 1);
            let text = half.to_string();
            let expect: f32 = text.parse().unwrap();
            assert_eq!(parse(&text), Some(expect), "{text}");
            let lo = (1u64 << k) + unit * 2 * j;
            assert_eq!(expect.to_bits() % 2, 0, "{text} goes to the even neighbour");
            assert!(
                expect == lo as f32 || expect == (lo + 2 * unit) as f32,
                "{text}"
            );
            let above = (half + 1).to_string();
            assert_eq!(parse(&above), Some(above.parse().unwrap()), "{above}");
        }
    }
}

#[test]
fn fixed_decimals_round_as_core() {
    for v in sampled(65_521).chain(edges()) {
        if v.abs() >= 1e15 {
            continue;
        }
        for d in 0..=3u8 {
            let expect = format!("{v:.*}", usize::from(d));
            assert_eq!(format!("{}", Fixed(v, d)), expect, "{v:e} .{d}");
        }
    }
    assert_eq!(format!("{}", Fixed(0.125, 2)), format!("{:.2}", 0.125f32));
    assert_eq!(format!("{}", Fixed(-0.001, 2)), format!("{:.2}", -0.001f32));
    assert_eq!(format!("{}", Fixed(2.5, 0)), format!("{:.0}", 2.5f32));
    assert_eq!(format!("{}", Fixed(1e20, 1)), "100000000000000000000");
}
