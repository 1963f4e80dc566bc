//! The binding phrase (spec §12.5): the rules every path applies to a phrase a person typed
//! (both firmwares and the ground station call [`check_phrase`]), and its slow, salted
//! derivation into the password-related string CPace runs on ([`PhraseSecret`]).
//!
//! **Strength.** A phrase is at least [`PHRASE_MIN_CHARS`] characters with at least
//! [`PHRASE_MIN_DISTINCT`] different ones, and not one of the examples every dictionary
//! starts with. Nothing on air or on BLE lets a guesser test a phrase offline (CPace), so the
//! rule is not what keeps a radio attacker out — one guess per bind window does that; it
//! bounds what the module's stored derivation gives someone who reads its flash (spec
//! §12.1, "What a stored value gives away").
//!
//! **Derivation.** PBKDF2-HMAC-SHA-512 (RFC 8018) of the phrase's UTF-8 bytes with the salt
//! `"TauLink/2 phrase" ‖ salt₆₄` and [`PHRASE_ITERATIONS`] iterations, 32 bytes: the salt is
//! drawn per module and travels in its bind offers and phone answers, so no table serves two
//! modules, and each guess at a stored value costs the iterations. [`Derivation`] runs it in
//! steps, so a firmware task can yield between them.

use hmac::Mac;

use super::sha512::{HmacSha512, hmac};

/// Fewest characters (Unicode scalar values) a phrase has, white space at the ends dropped.
pub const PHRASE_MIN_CHARS: usize = 12;
/// Fewest different characters in a phrase (no `aaaaaaaaaaaa`).
pub const PHRASE_MIN_DISTINCT: usize = 6;
/// Longest binding phrase, bytes of UTF-8.
pub const PHRASE_MAX_BYTES: usize = 64;
/// PBKDF2 iterations of the phrase's derivation.
pub const PHRASE_ITERATIONS: u32 = 4096;
/// Bytes of the salt each module draws for its phrase.
pub const SALT_BYTES: usize = 8;
/// Bytes of the derived password-related string.
pub const PRS_BYTES: usize = 32;

/// Examples every dictionary starts with, refused whatever their length (compared with
/// ASCII case folded and runs of spaces as one).
const FAMOUS: [&str; 3] = [
    "correct horse battery staple",
    "the quick brown fox jumps over the lazy dog",
    "password password",
];
/// The salt's domain prefix.
const SALT_PREFIX: &[u8] = b"TauLink/2 phrase";

/// Why a binding phrase was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PhraseError {
    /// Fewer than [`PHRASE_MIN_CHARS`] characters.
    TooShort,
    /// Longer than [`PHRASE_MAX_BYTES`] bytes.
    TooLong,
    /// Holds a control character (a phrase must be typeable the same on every end).
    NotPrintable,
    /// Fewer than [`PHRASE_MIN_DISTINCT`] different characters.
    TooSimple,
    /// A famous example: the first entry of any dictionary.
    Famous,
}

impl core::fmt::Display for PhraseError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            PhraseError::TooShort => "binding phrase shorter than 12 characters",
            PhraseError::TooLong => "binding phrase longer than 64 bytes",
            PhraseError::NotPrintable => "binding phrase holds a control character",
            PhraseError::TooSimple => "binding phrase has fewer than 6 different characters",
            PhraseError::Famous => "binding phrase is a famous example",
        })
    }
}

impl core::error::Error for PhraseError {}

/// The phrase in `text` as every end takes it: white space at the ends dropped; `Ok(None)`
/// when nothing is left (no phrase); else it must meet the strength rule (module doc).
pub fn check_phrase(text: &str) -> Result<Option<&str>, PhraseError> {
    let phrase = text.trim();
    if phrase.is_empty() {
        return Ok(None);
    }
    if phrase.len() > PHRASE_MAX_BYTES {
        return Err(PhraseError::TooLong);
    }
    if phrase.chars().any(char::is_control) {
        return Err(PhraseError::NotPrintable);
    }
    if phrase.chars().count() < PHRASE_MIN_CHARS {
        return Err(PhraseError::TooShort);
    }
    if distinct_chars(phrase) < PHRASE_MIN_DISTINCT {
        return Err(PhraseError::TooSimple);
    }
    if FAMOUS.iter().any(|famous| same_words(phrase, famous)) {
        return Err(PhraseError::Famous);
    }
    Ok(Some(phrase))
}

/// Different characters in `text`, counted up to [`PHRASE_MIN_DISTINCT`] (no allocation).
fn distinct_chars(text: &str) -> usize {
    let mut seen = [None::<char>; PHRASE_MIN_DISTINCT];
    let mut n = 0;
    for c in text.chars() {
        if n == PHRASE_MIN_DISTINCT {
            break;
        }
        if !seen.contains(&Some(c))
            && let Some(slot) = seen.get_mut(n)
        {
            *slot = Some(c);
            n += 1;
        }
    }
    n
}

/// Whether `a` and `b` are the same words, ASCII case folded, white space runs as one.
fn same_words(a: &str, b: &str) -> bool {
    let mut a = a.split_whitespace();
    let mut b = b.split_whitespace();
    loop {
        match (a.next(), b.next()) {
            (None, None) => return true,
            (Some(x), Some(y)) if x.eq_ignore_ascii_case(y) => {}
            _ => return false,
        }
    }
}

/// A phrase's slow derivation with its salt: what a module stores instead of the phrase, and
/// the password-related string of CPace. `Debug` does not print it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct PhraseSecret {
    /// The salt (public: it travels in bind offers).
    pub salt: [u8; SALT_BYTES],
    /// PBKDF2-HMAC-SHA-512 of the phrase under the salt.
    pub prs: [u8; PRS_BYTES],
}

impl core::fmt::Debug for PhraseSecret {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "PhraseSecret {{ salt: {:02x?}, .. }}", self.salt)
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for PhraseSecret {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "PhraseSecret {{ salt: {=[u8]:x}, .. }}", self.salt);
    }
}

impl PhraseSecret {
    /// The derivation of `phrase` (already checked) under `salt`, all at once.
    pub fn derive(phrase: &str, salt: [u8; SALT_BYTES]) -> Self {
        let mut derivation = Derivation::new(phrase, salt);
        loop {
            if let Some(secret) = derivation.step(PHRASE_ITERATIONS) {
                return secret;
            }
        }
    }
}

/// PBKDF2-HMAC-SHA-512 of one phrase, run a number of iterations at a time.
#[derive(Clone)]
pub struct Derivation {
    mac: HmacSha512,
    salt: [u8; SALT_BYTES],
    u: [u8; 64],
    t: [u8; 64],
    done: u32,
    iterations: u32,
}

impl core::fmt::Debug for Derivation {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Derivation({}/{})", self.done, self.iterations)
    }
}

impl Derivation {
    /// The derivation of `phrase` under `salt`, not yet started.
    pub fn new(phrase: &str, salt: [u8; SALT_BYTES]) -> Self {
        Self::with_iterations(phrase, salt, PHRASE_ITERATIONS)
    }

    fn with_iterations(phrase: &str, salt: [u8; SALT_BYTES], iterations: u32) -> Self {
        // HMAC takes keys of any length: this cannot fail.
        let mac = HmacSha512::new_from_slice(phrase.as_bytes())
            .unwrap_or_else(|_| HmacSha512::new(&Default::default()));
        Self {
            mac,
            salt,
            u: [0; 64],
            t: [0; 64],
            done: 0,
            iterations,
        }
    }

    /// Runs up to `n` more iterations; the secret once all are done.
    pub fn step(&mut self, n: u32) -> Option<PhraseSecret> {
        for _ in 0..n {
            if self.done == self.iterations {
                break;
            }
            self.u = if self.done == 0 {
                hmac(&self.mac, &[SALT_PREFIX, &self.salt, &1u32.to_be_bytes()])
            } else {
                hmac(&self.mac, &[&self.u])
            };
            for (t, u) in self.t.iter_mut().zip(self.u) {
                *t ^= u;
            }
            self.done += 1;
        }
        (self.done == self.iterations).then(|| {
            let mut prs = [0u8; PRS_BYTES];
            prs.copy_from_slice(self.t.get(..PRS_BYTES).unwrap_or(&[0; PRS_BYTES]));
            PhraseSecret {
                salt: self.salt,
                prs,
            }
        })
    }

    /// Iterations done and to do.
    pub fn progress(&self) -> (u32, u32) {
        (self.done, self.iterations)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(text: &str) -> [u8; 32] {
        core::array::from_fn(|i| u8::from_str_radix(&text[2 * i..2 * i + 2], 16).unwrap())
    }

    #[test]
    fn the_derivation_is_pbkdf2_hmac_sha512_of_the_spec() {
        // Known answers from Python, not from this code:
        // hashlib.pbkdf2_hmac('sha512', phrase, b"TauLink/2 phrase" + salt, n)[:32]
        let salt: [u8; 8] = core::array::from_fn(|i| i as u8);
        assert_eq!(
            PhraseSecret::derive("amber kettle under the oak", salt).prs,
            hex("94fe1e1c5e41e1ed2856b7e7e7ff8e78bdb3f5098842f37824e3e664a76d75ce")
        );
        assert_eq!(
            PhraseSecret::derive("twelve chars", [0xFF; 8]).prs,
            hex("632b21d45a592a97b8281f632b40960bf4b4d634353759657b301329768649ce")
        );
        let mut one = Derivation::with_iterations("amber kettle under the oak", salt, 1);
        assert_eq!(
            one.step(5).map(|s| s.prs),
            Some(hex(
                "6479cc2b9d1c4aa9ac9251c3820d6f33612740d1e59a039d3eb4df219c16fd73"
            ))
        );
    }

    #[test]
    fn the_derivation_in_steps_is_the_derivation_at_once() {
        let mut steps = Derivation::new("amber kettle under the oak", [3; 8]);
        let mut calls = 0;
        let secret = loop {
            calls += 1;
            if let Some(secret) = steps.step(1000) {
                break secret;
            }
        };
        assert_eq!(calls, 5);
        assert_eq!(steps.progress(), (4096, 4096));
        assert_eq!(
            secret,
            PhraseSecret::derive("amber kettle under the oak", [3; 8])
        );
        assert_ne!(
            secret,
            PhraseSecret::derive("amber kettle under the oak", [4; 8]),
            "another salt"
        );
        let shown = format!("{secret:?}");
        assert!(shown.contains("salt") && !shown.contains("prs"), "{shown}");
    }

    #[test]
    fn phrases_meet_the_strength_rule_or_are_refused() {
        assert_eq!(check_phrase(""), Ok(None));
        assert_eq!(check_phrase("   \t"), Ok(None));
        assert_eq!(
            check_phrase("  amber kettle under the oak\t"),
            Ok(Some("amber kettle under the oak"))
        );
        assert_eq!(check_phrase("short one"), Err(PhraseError::TooShort));
        assert_eq!(
            check_phrase("ääääbbbbcccc").map(|p| p.is_some()),
            Err(PhraseError::TooSimple)
        );
        assert_eq!(
            check_phrase("abababababababab"),
            Err(PhraseError::TooSimple)
        );
        assert!(check_phrase("Grüezi Säntis 2026").unwrap().is_some());
        let longest = "abcdefghij".repeat(6) + "abcd";
        assert_eq!(
            check_phrase(&longest),
            Ok(Some(longest.as_str())),
            "64 bytes"
        );
        assert_eq!(check_phrase(&(longest + "e")), Err(PhraseError::TooLong));
        assert_eq!(
            check_phrase("bell\u{7}ringing loud"),
            Err(PhraseError::NotPrintable)
        );
        for famous in [
            "correct horse battery staple",
            "Correct  Horse Battery STAPLE",
            "the quick brown fox jumps over the lazy dog",
        ] {
            assert_eq!(check_phrase(famous), Err(PhraseError::Famous), "{famous}");
        }
        assert!(
            check_phrase("correct horse battery stapler")
                .unwrap()
                .is_some()
        );
    }
}
