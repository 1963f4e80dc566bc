//! The independent watchdog (RM0090 §21): KR keys (0xCCCC start, 0xAAAA reload, 0x5555
//! register access), PR, RLR and SR (PVU, RVU). A 12-bit down-counter at LSI / (4 · 2^PR)
//! that starts at 0xFFF, reloads on 0xAAAA and resets the chip on the tick after it
//! reaches 0 — RLR + 1 ticks (DS8626's IWDG timeout table: RL = 0xFFF at ÷4 is 512 ms at
//! 32 kHz, 4096 ticks); once started nothing stops it but a reset.
//!
//! PR and RLR live in the core's domain; the counter in the LSI's. A write (after 0x5555)
//! takes five LSI cycles to cross (PVU/RVU set meanwhile, and a write while the flag is set
//! is ignored: RM0090 §21.4.3/§21.4.4); until then the counter runs with the old prescaler
//! and a reload loads the old reload value — so a firmware that writes RLR and reloads at
//! once gets its old timeout for that period.
//!
//! The LSI frequency is the runner's (17–47 kHz, DS8626): the same image times out up to
//! 88 % later (17 kHz) or 32 % sooner (47 kHz) than at the nominal 32 kHz.

const KR: u32 = 0x00;
const PR: u32 = 0x04;
const RLR: u32 = 0x08;
const SR: u32 = 0x0C;

const KEY_START: u32 = 0xCCCC;
const KEY_RELOAD: u32 = 0xAAAA;
const KEY_ACCESS: u32 = 0x5555;
const PVU: u32 = 1 << 0;
const RVU: u32 = 1 << 1;
/// Ticks from the start to the reset: the counter starts at 0xFFF.
const TICKS_FROM_START: u64 = 0x1000;
/// LSI cycles a PR/RLR update takes to reach the watchdog's clock domain.
const UPDATE_LSI_CYCLES: u64 = 5;

/// A register value on its way to the LSI domain.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    value: u32,
    lands_at: u64,
}

/// The watchdog.
pub struct Iwdg {
    /// PR and RLR as software wrote them.
    pr: u32,
    rlr: u32,
    /// The values the counter uses.
    pr_active: u32,
    rlr_active: u32,
    pr_crossing: Option<Crossing>,
    rlr_crossing: Option<Crossing>,
    access: bool,
    started: bool,
    lsi_hz: u32,
    /// `epoch_count` ticks were left until the reset at `epoch_ns` (the counter + 1).
    epoch_ns: u64,
    epoch_count: u64,
    /// When the counter reaches 0 as things stand (kept current on every change).
    expires: u64,
    /// Reloads (feeds) seen.
    pub reloads: u64,
    /// Shortest margin left at a reload, ns (how close the image came to a reset).
    pub min_margin_ns: Option<u64>,
}

impl Iwdg {
    /// Reset state at LSI frequency `lsi_hz`.
    pub fn new(lsi_hz: u32) -> Self {
        Self {
            pr: 0,
            rlr: 0xFFF,
            pr_active: 0,
            rlr_active: 0xFFF,
            pr_crossing: None,
            rlr_crossing: None,
            access: false,
            started: false,
            lsi_hz,
            epoch_ns: 0,
            epoch_count: TICKS_FROM_START,
            expires: u64::MAX,
            reloads: 0,
            min_margin_ns: None,
        }
    }

    /// A system reset stops it (software-started watchdog, option byte WDG_SW = 1).
    pub fn reset(&mut self) {
        let (lsi, reloads, margin) = (self.lsi_hz, self.reloads, self.min_margin_ns);
        *self = Self::new(lsi);
        self.reloads = reloads;
        self.min_margin_ns = margin;
    }

    /// Whether it runs (the RCC forces the LSI on then).
    pub fn started(&self) -> bool {
        self.started
    }

    /// Changes the LSI frequency at `now`.
    pub fn set_lsi_hz(&mut self, hz: u32, now: u64) {
        self.rebase(now);
        self.lsi_hz = hz;
        self.expires = self.compute_expiry();
    }

    fn tick_ns(&self) -> u128 {
        (4u128 << self.pr_active.min(6)) * 1_000_000_000
    }

    fn count(&self, now: u64) -> u64 {
        if !self.started || now <= self.epoch_ns {
            return self.epoch_count;
        }
        let ticks = u128::from(now - self.epoch_ns) * u128::from(self.lsi_hz) / self.tick_ns();
        self.epoch_count
            .saturating_sub(u64::try_from(ticks).unwrap_or(u64::MAX))
    }

    fn rebase(&mut self, now: u64) {
        self.epoch_count = self.count(now);
        self.epoch_ns = now;
        self.expires = self.compute_expiry();
    }

    /// When the counter reaches 0 (u64::MAX when stopped).
    pub fn expiry(&self) -> u64 {
        self.expires
    }

    fn compute_expiry(&self) -> u64 {
        if !self.started {
            return u64::MAX;
        }
        let ns = u128::from(self.epoch_count) * self.tick_ns() / u128::from(self.lsi_hz.max(1));
        self.epoch_ns
            .saturating_add(u64::try_from(ns).unwrap_or(u64::MAX))
    }

    /// The next time the watchdog changes by itself: a register landing in the LSI
    /// domain, or the reset.
    pub fn next_event(&self) -> u64 {
        let lands = |c: Option<Crossing>| c.map_or(u64::MAX, |c| c.lands_at);
        self.expires
            .min(lands(self.pr_crossing))
            .min(lands(self.rlr_crossing))
    }

    /// Processes due events; true when the counter reached 0 (reset).
    pub fn process(&mut self, now: u64) -> bool {
        if let Some(c) = self
            .pr_crossing
            .filter(|c| c.lands_at <= now && c.lands_at < self.expires)
        {
            self.rebase(c.lands_at);
            self.pr_active = c.value;
            self.pr_crossing = None;
            self.expires = self.compute_expiry();
        }
        if let Some(c) = self.rlr_crossing.filter(|c| c.lands_at <= now) {
            self.rlr_active = c.value;
            self.rlr_crossing = None;
        }
        self.started && now >= self.expires
    }

    /// Register read at `now`.
    pub fn read(&self, offset: u32, now: u64) -> Option<u32> {
        let busy = |c: Option<Crossing>| c.is_some_and(|c| now < c.lands_at);
        Some(match offset {
            KR => 0,
            PR => self.pr,
            RLR => self.rlr,
            SR => {
                let mut v = 0;
                if busy(self.pr_crossing) {
                    v |= PVU;
                }
                if busy(self.rlr_crossing) {
                    v |= RVU;
                }
                v
            }
            _ => return None,
        })
    }

    fn update_ns(&self) -> u64 {
        UPDATE_LSI_CYCLES * 1_000_000_000 / u64::from(self.lsi_hz.max(1))
    }

    /// Register write at `now` (events due before it already processed); true when the
    /// write started the watchdog.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<bool> {
        match offset {
            KR => match value & 0xFFFF {
                KEY_START => {
                    let was = self.started;
                    if !was {
                        self.started = true;
                        self.epoch_ns = now;
                        self.epoch_count = TICKS_FROM_START;
                        self.expires = self.compute_expiry();
                    }
                    self.access = false;
                    return Some(!was);
                }
                KEY_RELOAD => {
                    if self.started {
                        let margin = self.expires.saturating_sub(now);
                        self.min_margin_ns =
                            Some(self.min_margin_ns.map_or(margin, |m| m.min(margin)));
                        self.reloads += 1;
                        self.epoch_ns = now;
                        self.epoch_count = u64::from(self.rlr_active) + 1;
                        self.expires = self.compute_expiry();
                    }
                    self.access = false;
                }
                KEY_ACCESS => self.access = true,
                _ => self.access = false,
            },
            PR if self.access && self.pr_crossing.is_none() => {
                self.pr = value & 7;
                self.pr_crossing = Some(Crossing {
                    value: self.pr,
                    lands_at: now + self.update_ns(),
                });
            }
            RLR if self.access && self.rlr_crossing.is_none() => {
                self.rlr = value & 0xFFF;
                self.rlr_crossing = Some(Crossing {
                    value: self.rlr,
                    lands_at: now + self.update_ns(),
                });
            }
            PR | RLR | SR => {}
            _ => return None,
        }
        Some(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `IndependentWatchdog::new(250 ms)` as embassy computes it: the smallest prescaler
    /// whose longest period covers 250 ms — ÷4 — and RLR = 1999 (2000 ticks of 125 µs at
    /// its nominal 32 kHz).
    fn board_watchdog(lsi: u32) -> Iwdg {
        let mut w = Iwdg::new(lsi);
        w.write(KR, KEY_ACCESS, 0);
        w.write(PR, 0, 0);
        w.write(RLR, 1999, 0);
        w.process(1_000_000);
        w
    }

    /// `supervisor::set_timeout`: reload, 0x5555, PR, RLR, reload — at once.
    fn set_timeout(w: &mut Iwdg, pr: u32, rlr: u32, now: u64) {
        w.process(now);
        w.write(KR, KEY_RELOAD, now);
        w.write(KR, KEY_ACCESS, now);
        w.write(PR, pr, now);
        w.write(RLR, rlr, now);
        w.write(KR, KEY_RELOAD, now);
    }

    #[test]
    fn the_first_period_counts_from_0xfff_then_reloads_take_rlr_plus_one() {
        let mut w = board_watchdog(32_000);
        assert_eq!(w.next_event(), u64::MAX);
        assert_eq!(w.write(KR, KEY_START, 1_000_000), Some(true));
        // 4096 ticks of 125 µs: DS8626's 512 ms maximum at ÷4.
        assert_eq!(w.expiry(), 1_000_000 + 512_000_000);
        w.write(KR, KEY_RELOAD, 2_000_000);
        assert_eq!(w.expiry(), 2_000_000 + 250_000_000);
        assert!(!w.process(2_000_000 + 249_999_999));
        assert!(w.process(2_000_000 + 250_000_000));
    }

    #[test]
    fn the_timeout_scales_with_the_lsi_across_its_datasheet_range() {
        for (lsi, us) in [
            (17_000u32, 470_588u64),
            (32_000, 250_000),
            (47_000, 170_212),
        ] {
            let mut w = board_watchdog(lsi);
            w.write(KR, KEY_START, 1_000_000);
            w.write(KR, KEY_RELOAD, 1_000_000);
            assert_eq!((w.expiry() - 1_000_000) / 1_000, us, "LSI {lsi} Hz");
        }
    }

    #[test]
    fn registers_need_the_access_key_and_show_the_update() {
        let mut w = Iwdg::new(32_000);
        w.write(PR, 6, 0);
        assert_eq!(w.read(PR, 0), Some(0));
        w.write(KR, KEY_ACCESS, 0);
        w.write(RLR, 100, 0);
        assert_eq!(w.read(SR, 1), Some(RVU));
        w.write(RLR, 7, 10);
        assert_eq!(
            w.read(RLR, 10),
            Some(100),
            "a write while RVU is set is ignored"
        );
        assert_eq!(w.read(SR, 156_250), Some(0));
        w.write(KR, 0x1234, 200_000);
        w.write(RLR, 5, 200_000);
        assert_eq!(w.read(RLR, 200_000), Some(100));
    }

    /// The supervisor's `with_long_timeout` (÷64, RLR 2000: "4 s") and the restore (÷32,
    /// RLR 249). Each reload comes before RVU clears, so it loads the reload value already
    /// in the LSI domain, counted at the new prescaler once PR has crossed. The first
    /// stretch after a boot loads embassy's 1999 + 1 at ÷64: 4 s by luck. The restore loads
    /// 2000 at ÷32: 2 s until the next feed. Every later stretch loads 249 at ÷64: 500 ms.
    #[test]
    fn reloading_before_rvu_clears_keeps_the_old_reload_value() {
        let mut w = board_watchdog(32_000);
        w.write(KR, KEY_START, 1_000_000);
        let left = |w: &mut Iwdg, at: u64| {
            w.process(at + 1_000_000);
            assert_eq!(w.read(SR, at + 1_000_000), Some(0));
            (w.expiry() - at) / 1_000_000
        };
        set_timeout(&mut w, 4, 2000, 10_000_000);
        // 2000 ticks of 125 µs loaded, one gone before PR crosses, 1999 of 2 ms left.
        assert_eq!(left(&mut w, 10_000_000), 3998, "first stretch");
        set_timeout(&mut w, 3, 249, 100_000_000);
        assert_eq!(
            left(&mut w, 100_000_000),
            2001,
            "restore: 2001 ticks of 1 ms"
        );
        w.write(KR, KEY_RELOAD, 150_000_000);
        assert_eq!(left(&mut w, 150_000_000), 250, "the supervisor's next feed");
        set_timeout(&mut w, 4, 2000, 200_000_000);
        assert_eq!(
            left(&mut w, 200_000_000),
            500,
            "second stretch: 250 ticks of 2 ms"
        );
        w.write(KR, KEY_RELOAD, 300_000_000);
        assert_eq!(
            left(&mut w, 300_000_000),
            4002,
            "only a later reload gets 4 s"
        );
    }

    /// The second stretch on a fast-LSI part (47 kHz, DS8626's maximum): 340 ms.
    #[test]
    fn a_fast_lsi_shortens_the_stretch_further() {
        let mut w = board_watchdog(47_000);
        w.write(KR, KEY_START, 1_000_000);
        set_timeout(&mut w, 4, 2000, 10_000_000);
        set_timeout(&mut w, 3, 249, 100_000_000);
        set_timeout(&mut w, 4, 2000, 200_000_000);
        w.process(201_000_000);
        assert_eq!((w.expiry() - 200_000_000) / 1_000_000, 340);
    }
}
