//! The independent watchdog (RM0090 §21): KR keys (0xCCCC start, 0xAAAA reload, 0x5555
//! register access), PR, RLR and SR (PVU, RVU). A 12-bit down-counter at LSI / (4 · 2^PR)
//! that starts at 0xFFF, reloads RLR on 0xAAAA and resets the chip when it reaches 0; once
//! started nothing stops it but a reset. PR/RLR writes need 0x5555 first and take five LSI
//! cycles to reach the LSI domain (PVU/RVU busy meanwhile). The LSI frequency is the
//! runner's (17–47 kHz, DS8626): the same image times out up to 88 % later (17 kHz) or
//! 32 % sooner (47 kHz) than at the nominal 32 kHz it was designed for.

const KR: u32 = 0x00;
const PR: u32 = 0x04;
const RLR: u32 = 0x08;
const SR: u32 = 0x0C;

const KEY_START: u32 = 0xCCCC;
const KEY_RELOAD: u32 = 0xAAAA;
const KEY_ACCESS: u32 = 0x5555;
const PVU: u32 = 1 << 0;
const RVU: u32 = 1 << 1;
/// LSI cycles a PR/RLR update takes to reach the watchdog's clock domain.
const UPDATE_LSI_CYCLES: u64 = 5;

/// The watchdog.
pub struct Iwdg {
    pr: u32,
    rlr: u32,
    access: bool,
    started: bool,
    lsi_hz: u32,
    /// The counter was `epoch_count` at `epoch_ns`.
    epoch_ns: u64,
    epoch_count: u64,
    /// The prescaler in effect (PR takes effect after its update).
    pr_active: u32,
    pvu_until: u64,
    rvu_until: u64,
    /// Reloads (feeds) seen.
    pub reloads: u64,
    /// Shortest margin left at a reload, ns (how close the image came to a reset).
    pub min_margin_ns: Option<u64>,
    /// When the counter reaches 0 as things stand (kept current on every change).
    expires: u64,
}

impl Iwdg {
    /// Reset state at LSI frequency `lsi_hz`.
    pub fn new(lsi_hz: u32) -> Self {
        Self {
            pr: 0,
            rlr: 0xFFF,
            access: false,
            started: false,
            lsi_hz,
            epoch_ns: 0,
            epoch_count: 0xFFF,
            pr_active: 0,
            pvu_until: 0,
            rvu_until: 0,
            reloads: 0,
            min_margin_ns: None,
            expires: u64::MAX,
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

    /// The next time the watchdog changes by itself: a prescaler update landing, or the
    /// reset.
    pub fn next_event(&self) -> u64 {
        if self.started && self.pvu_until > self.epoch_ns {
            self.pvu_until.min(self.expiry())
        } else {
            self.expiry()
        }
    }

    /// Processes due events; true when the counter reached 0 (reset).
    pub fn process(&mut self, now: u64) -> bool {
        if self.started
            && self.pvu_until > self.epoch_ns
            && now >= self.pvu_until
            && self.pvu_until < self.expiry()
        {
            let at = self.pvu_until;
            self.rebase(at);
            self.pr_active = self.pr;
            self.expires = self.compute_expiry();
        }
        self.started && now >= self.expiry()
    }

    /// Register read at `now`.
    pub fn read(&self, offset: u32, now: u64) -> Option<u32> {
        Some(match offset {
            KR => 0,
            PR => self.pr,
            RLR => self.rlr,
            SR => {
                let mut v = 0;
                if now < self.pvu_until {
                    v |= PVU;
                }
                if now < self.rvu_until {
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

    /// Register write at `now`; true when the write started the watchdog.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<bool> {
        match offset {
            KR => match value & 0xFFFF {
                KEY_START => {
                    let was = self.started;
                    if !was {
                        self.started = true;
                        self.epoch_ns = now;
                        self.epoch_count = 0xFFF;
                        self.expires = self.compute_expiry();
                    }
                    self.access = false;
                    return Some(!was);
                }
                KEY_RELOAD => {
                    if self.started {
                        let margin = self.expiry().saturating_sub(now);
                        self.min_margin_ns =
                            Some(self.min_margin_ns.map_or(margin, |m| m.min(margin)));
                        self.reloads += 1;
                        self.rebase(now);
                        self.epoch_count = u64::from(self.rlr);
                        self.expires = self.compute_expiry();
                    }
                    self.access = false;
                }
                KEY_ACCESS => self.access = true,
                _ => self.access = false,
            },
            PR if self.access => {
                self.pr = value & 7;
                self.pvu_until = now + self.update_ns();
                if !self.started {
                    self.pr_active = self.pr;
                }
            }
            RLR if self.access => {
                self.rlr = value & 0xFFF;
                self.rvu_until = now + self.update_ns();
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

    /// IndependentWatchdog::new(250 ms): PR = 3 (÷32), RLR = 249 at the HAL's 32 kHz.
    fn board_watchdog(lsi: u32) -> Iwdg {
        let mut w = Iwdg::new(lsi);
        w.write(KR, KEY_ACCESS, 0);
        w.write(PR, 3, 0);
        w.write(RLR, 249, 0);
        w
    }

    #[test]
    fn the_first_period_counts_from_0xfff_then_reloads_take_rlr() {
        let mut w = board_watchdog(32_000);
        assert_eq!(w.next_event(), u64::MAX);
        assert_eq!(w.write(KR, KEY_START, 1_000_000), Some(true));
        // 4096 ticks at 1 kHz.
        assert_eq!(w.expiry(), 1_000_000 + 4_095_000_000);
        w.write(KR, KEY_RELOAD, 2_000_000);
        assert_eq!(w.expiry(), 2_000_000 + 249_000_000);
        assert!(!w.process(2_000_000 + 248_999_999));
        assert!(w.process(2_000_000 + 249_000_000));
    }

    #[test]
    fn the_timeout_scales_with_the_lsi_across_its_datasheet_range() {
        for (lsi, ms) in [(17_000u32, 468u64), (32_000, 249), (47_000, 169)] {
            let mut w = board_watchdog(lsi);
            w.write(KR, KEY_START, 0);
            w.write(KR, KEY_RELOAD, 0);
            assert_eq!(w.expiry() / 1_000_000, ms, "LSI {lsi} Hz");
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
        assert_eq!(w.read(SR, 156_250), Some(0));
        w.write(KR, 0x1234, 0);
        w.write(RLR, 5, 0);
        assert_eq!(w.read(RLR, 0), Some(100));
    }

    #[test]
    fn the_supervisors_long_timeout_and_back() {
        // with_long_timeout: reload, access, PR ÷64, RLR, reload.
        let mut w = board_watchdog(32_000);
        w.write(KR, KEY_START, 0);
        w.write(KR, KEY_RELOAD, 10_000_000);
        w.write(KR, KEY_ACCESS, 10_000_000);
        w.write(PR, 4, 10_000_000);
        w.write(RLR, 2000, 10_000_000);
        w.write(KR, KEY_RELOAD, 10_000_000);
        w.process(20_000_000);
        assert_eq!(w.read(SR, 20_000_000), Some(0));
        // ÷64 at 32 kHz: 2 ms per tick, 2000 ticks ≈ 4 s from the reload.
        let left = w.expiry() - 20_000_000;
        assert!((3_980_000_000..=4_000_000_000).contains(&left), "{left}");
    }
}
