//! What to simulate: one struct of knobs with the main job's defaults (the command line
//! that fills it is `cli.rs`).

use telemetry::channels::ChannelFormat;
use telemetry::link::{Band, LinkKey, RateMode};

/// What a third radio in the medium does to the link (`--attack`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attack {
    /// Knows the link's header and hop sequence (public), not its key: sends forged
    /// uplinks, downlinks and nonce frames on the link's channels.
    Forge,
    /// Follows the link's slots, records every frame it hears and sends each again in a
    /// later slot with the same on-air number (256·k slots on); the flight side is
    /// power-cycled twice meanwhile.
    Replay,
    /// Sends bind offers on the bind channel without pause while the flight side is
    /// power-cycled every 5 s.
    BindSpoof,
    /// Issue 30, finding 3: records the flight side's nonce frames, waits for it to be
    /// power-cycled and back, then again and again jams one downlink slot at the module and
    /// replays a recorded nonce frame in the next.
    NonceReplay,
    /// Issue 30, finding 1: records the bind and the link, then tries every offline check
    /// of a dictionary of phrases (the true one among them) against the recording.
    Guess,
}

impl Attack {
    /// The attack's command-line word.
    pub fn name(self) -> &'static str {
        match self {
            Attack::Forge => "forge",
            Attack::Replay => "replay",
            Attack::BindSpoof => "bind-spoof",
            Attack::NonceReplay => "nonce-replay",
            Attack::Guess => "guess",
        }
    }

    /// Where the attacking radio stands, as a fraction of the way from the module to the
    /// flight side: near the end whose receiver it targets — the module's for the nonce
    /// replay (it must beat the flight side's downlinks there), the flight side's for the
    /// others.
    pub fn position(self) -> f64 {
        match self {
            Attack::NonceReplay => 0.1,
            Attack::Forge | Attack::Replay | Attack::BindSpoof | Attack::Guess => 0.9,
        }
    }
}

use crate::handset::HandsetKind;

/// A simulation scenario.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Rate mode of the link.
    pub rate: RateMode,
    /// One slot in this many is a downlink slot.
    pub telemetry_ratio: u8,
    /// Uplink channel format.
    pub format: ChannelFormat,
    /// Band.
    pub band: Band,
    /// Distance between module and flight controller, metres.
    pub distance_m: f64,
    /// Extra random packet loss (0..1).
    pub loss: f64,
    /// Bit error rate on air.
    pub bit_error_rate: f64,
    /// Duty cycle (0..1) of a jammer hopping over the link's channel grid.
    pub interference: f64,
    /// Run a second, independently bound link in the same medium.
    pub foreign_link: bool,
    /// Seed of every random choice.
    pub seed: u64,
    /// Virtual duration, seconds.
    pub duration_s: f64,
    /// Follower failsafe delay, ms.
    pub failsafe_ms: u64,
    /// Cut the path between the two ends from..to (virtual seconds).
    pub cut_s: Option<(f64, f64)>,
    /// Over-the-air bind first (otherwise both ends start bound).
    pub bind: bool,
    /// Keep both telemetry streams saturated with test bytes.
    pub telemetry_load: bool,
    /// Chip header check on the receivers (off exposes foreign packets to the link CRC).
    pub header_check: bool,
    /// Chip CRC on the receivers (off exposes corrupted packets to the link CRC; packet
    /// level only).
    pub chip_crc: bool,
    /// What feeds the module's channel input.
    pub handset: HandsetKind,
    /// Run the real RFM22b driver on virtual Si4432s (`si4432-sim`); otherwise the
    /// packet-level mock radios (faster; supports `bit_error_rate` and `chip_crc`).
    pub chip_level: bool,
    /// Authenticate every link frame with this key (spec §12), on both ends: the random
    /// key the module hands over at bind (`--phrase` or `--keyed`).
    pub key: Option<LinkKey>,
    /// The binding phrase the bind's key agreement runs on (CPace; `None`: without one).
    pub phrase: Option<String>,
    /// A third radio attacking the link (chip level only).
    pub attack: Option<Attack>,
    /// The attacking radio stands where `attack` puts it and the flight side is
    /// power-cycled as under it, but the radio stays silent: the attack's clean run.
    pub silent_attacker: bool,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            rate: RateMode::F250,
            telemetry_ratio: 4,
            format: ChannelFormat::Full16,
            band: Band::Mhz433,
            distance_m: 500.0,
            loss: 0.0,
            bit_error_rate: 0.0,
            interference: 0.0,
            foreign_link: false,
            seed: 1,
            duration_s: 30.0,
            failsafe_ms: 250,
            cut_s: None,
            bind: true,
            telemetry_load: true,
            header_check: true,
            chip_crc: true,
            chip_level: true,
            key: None,
            phrase: None,
            attack: None,
            silent_attacker: false,
            handset: HandsetKind::CrsfSynced,
        }
    }
}

/// The link key the module of scenario seed `seed` draws (and hands over at bind): random
/// as the firmware's, from the seed so runs repeat.
pub fn link_key_of(seed: u64) -> LinkKey {
    let mut entropy = telemetry::link::Entropy::new(seed_bytes(seed, 0x006b_6579));
    let key = entropy.draw(b"module key");
    LinkKey::from_bytes(head(&key))
}

/// The first `N` bytes of a 32-byte value (a key or salt cut from a hash or a draw).
pub(crate) fn head<const N: usize>(bytes: &[u8; 32]) -> [u8; N] {
    bytes.first_chunk::<N>().copied().unwrap_or([0; N])
}

/// 32 bytes of the scenario's randomness for `what`.
pub fn seed_bytes(seed: u64, what: u64) -> [u8; 32] {
    let mut rng = telemetry::mock::SplitMix64::new(seed ^ what.rotate_left(17));
    let mut out = [0u8; 32];
    for chunk in out.chunks_exact_mut(8) {
        chunk.copy_from_slice(&rng.next_u64().to_le_bytes());
    }
    out
}

/// Parses a rate mode name (`L50`, `M100`, `F250`, `F500`, `F700`, case-insensitive).
pub fn parse_rate(s: &str) -> Option<RateMode> {
    RateMode::ALL
        .into_iter()
        .find(|m| format!("{m:?}").eq_ignore_ascii_case(s))
}
