//! The general-purpose and basic timers the images use (RM0090 §18 TIM2–5, §19 TIM9–14,
//! §20 TIM6/7), up-counting only: CR1 (CEN, UDIS, URS, OPM, ARPE), CR2.MMS (TRGO), DIER,
//! SR, EGR (UG, CCxG), CCMR output compare modes with preload, CCER (enable, polarity),
//! CNT, PSC and ARR with their shadow registers, CCR1–4.
//!
//! The counter is not ticked: it is computed from the time since the last tick boundary
//! it was rebased to, at the timer clock / (PSC + 1), exactly — the boundary is kept to a
//! fraction of a nanosecond, so neither events nor register writes that rebase it lose
//! time (a time driver's compare writes, hundreds a second, would otherwise slow the count
//! by up to a tick each). Events happen at the first nanosecond at or after their tick. Events are the update (overflow, UG) and compare matches; each
//! updates flags, output references and TRGO. Outputs: OCxREF per the OCxM mode, XOR CCxP,
//! driven when CCxE is set (the pin's drive goes to the board with the edge's time).
//! Not modelled, and recorded if set: down/centre-aligned counting, slave mode, input
//! capture, DMA requests, TIM1/8 break features.

use super::gpio::SignalDrive;

// Register offsets (RM0090 §18.4.21).
const CR1: u32 = 0x00;
const CR2: u32 = 0x04;
const SMCR: u32 = 0x08;
const DIER: u32 = 0x0C;
const SR: u32 = 0x10;
const EGR: u32 = 0x14;
const CCMR1: u32 = 0x18;
const CCMR2: u32 = 0x1C;
const CCER: u32 = 0x20;
const CNT: u32 = 0x24;
const PSC: u32 = 0x28;
const ARR: u32 = 0x2C;
const CCR1: u32 = 0x34;
const CCR4: u32 = 0x40;
const DCR: u32 = 0x48;
const OR: u32 = 0x50;

const CEN: u32 = 1 << 0;
const UDIS: u32 = 1 << 1;
const URS: u32 = 1 << 2;
const OPM: u32 = 1 << 3;
const DIR_CMS: u32 = 0x70;
const ARPE: u32 = 1 << 7;
const UIF: u32 = 1 << 0;
const UG: u32 = 1 << 0;

/// Which timer this is: its width, channels and registers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimerKind {
    /// TIMx number.
    pub number: u8,
    /// 32-bit counter (TIM2, TIM5).
    pub wide: bool,
    /// Capture/compare channels (0 for the basic timers).
    pub channels: u8,
    /// Has CR2 (MMS).
    pub has_cr2: bool,
}

/// TIM2: 32-bit, 4 channels.
pub const TIM2: TimerKind = TimerKind {
    number: 2,
    wide: true,
    channels: 4,
    has_cr2: true,
};
/// TIM3: 16-bit, 4 channels.
pub const TIM3: TimerKind = TimerKind {
    number: 3,
    wide: false,
    channels: 4,
    has_cr2: true,
};
/// TIM6: basic timer.
pub const TIM6: TimerKind = TimerKind {
    number: 6,
    wide: false,
    channels: 0,
    has_cr2: true,
};
/// TIM9: 16-bit, 2 channels, no CR2.
pub const TIM9: TimerKind = TimerKind {
    number: 9,
    wide: false,
    channels: 2,
    has_cr2: false,
};

/// An output's recent pulses, measured from its edges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PulseRecord {
    /// Time of the last rising edge.
    pub last_rise_ns: Option<u64>,
    /// Width of the last complete high pulse.
    pub last_high_ns: Option<u64>,
    /// Time between the last two rising edges.
    pub last_period_ns: Option<u64>,
    /// Time of the last falling edge (or release).
    pub last_fall_ns: Option<u64>,
}

/// What the registers say a channel outputs now (for the board's motor model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PwmSetting {
    /// Counter period, ns ((ARR + 1) ticks).
    pub period_ns: f64,
    /// High time per period for a PWM mode, after polarity, ns.
    pub high_ns: f64,
    /// One-pulse mode: a pulse per start, not a periodic output.
    pub one_pulse: bool,
    /// The counter runs.
    pub running: bool,
    /// The channel drives its pin.
    pub enabled: bool,
}

/// One timer.
pub struct Timer {
    kind: TimerKind,
    cr1: u32,
    cr2: u32,
    smcr: u32,
    dier: u32,
    sr: u32,
    ccmr: [u32; 2],
    ccer: u32,
    psc: u32,
    psc_active: u32,
    arr: u32,
    arr_active: u32,
    ccr: [u32; 4],
    ccr_active: [u32; 4],
    /// Timer kernel clock (0: not clocked).
    clock_hz: u32,
    /// The counter became `epoch_count` at the tick boundary `epoch_ns + epoch_rem / clock_hz`
    /// ns (`epoch_rem` < `clock_hz`: the boundary's fraction of a nanosecond).
    epoch_ns: u64,
    epoch_rem: u64,
    epoch_count: u64,
    refs: [bool; 4],
    outputs: [SignalDrive; 4],
    /// Output changes to forward to the pins: (channel 1–4, drive, time).
    pub changes: Vec<(u8, SignalDrive, u64)>,
    /// TRGO pulses since last taken (for the DAC trigger), with their times.
    pub trgo: Vec<u64>,
    pulses: [PulseRecord; 4],
    /// The next event's time, kept current by every change (it is asked for often).
    next: u64,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Timer {
    /// A timer in its reset state.
    pub fn new(kind: TimerKind) -> Self {
        let max = if kind.wide { u32::MAX } else { 0xFFFF };
        Self {
            kind,
            cr1: 0,
            cr2: 0,
            smcr: 0,
            dier: 0,
            sr: 0,
            ccmr: [0; 2],
            ccer: 0,
            psc: 0,
            psc_active: 0,
            arr: max,
            arr_active: max,
            ccr: [0; 4],
            ccr_active: [0; 4],
            clock_hz: 0,
            epoch_ns: 0,
            epoch_rem: 0,
            epoch_count: 0,
            refs: [false; 4],
            outputs: [SignalDrive::Off; 4],
            changes: Vec::new(),
            trgo: Vec::new(),
            pulses: [PulseRecord::default(); 4],
            next: u64::MAX,
            unmodelled: Vec::new(),
        }
    }

    /// Back to reset values (RCC reset or system reset); outputs released at `now`.
    pub fn reset(&mut self, now: u64) {
        let clock = self.clock_hz;
        let kind = self.kind;
        let outputs = self.outputs;
        *self = Self::new(kind);
        self.clock_hz = clock;
        self.epoch_ns = now;
        for (i, o) in outputs.iter().enumerate() {
            if *o != SignalDrive::Off {
                self.changes.push((i as u8 + 1, SignalDrive::Off, now));
            }
        }
        self.recompute_next();
    }

    /// This timer's identity.
    pub fn kind(&self) -> TimerKind {
        self.kind
    }

    fn running(&self) -> bool {
        self.cr1 & CEN != 0 && self.clock_hz > 0
    }

    fn count_mask(&self) -> u64 {
        if self.kind.wide { 0xFFFF_FFFF } else { 0xFFFF }
    }

    /// A tick in units of 1/clock_hz ns: (PSC + 1) · 1e9.
    fn tick_units(&self) -> u64 {
        (u64::from(self.psc_active) + 1) * 1_000_000_000
    }

    /// Whole ticks from the epoch's boundary to `now` (0 before it).
    fn ticks_to(&self, now: u64) -> u64 {
        let dt = now.saturating_sub(self.epoch_ns);
        let per = self.tick_units();
        match dt.checked_mul(u64::from(self.clock_hz)) {
            Some(units) => units.saturating_sub(self.epoch_rem) / per,
            None => {
                let units = u128::from(dt) * u128::from(self.clock_hz);
                u64::try_from(units.saturating_sub(u128::from(self.epoch_rem)) / u128::from(per))
                    .unwrap_or(u64::MAX)
            }
        }
    }

    /// Tick `n` from the epoch: its boundary as whole ns past `epoch_ns` and the fraction.
    fn boundary(&self, n: u64) -> (u64, u64) {
        let hz = u128::from(self.clock_hz.max(1));
        let units = u128::from(n) * u128::from(self.tick_units()) + u128::from(self.epoch_rem);
        (
            u64::try_from(units / hz).unwrap_or(u64::MAX),
            (units % hz) as u64,
        )
    }

    /// The first ns at or after tick `n` from the epoch.
    fn time_of(&self, n: u64) -> u64 {
        let (ns, rem) = self.boundary(n);
        self.epoch_ns
            .saturating_add(ns)
            .saturating_add(u64::from(rem > 0))
    }

    /// Moves the epoch `n` ticks on, to that tick's boundary (the count is the caller's).
    fn advance_epoch(&mut self, n: u64) {
        let (ns, rem) = self.boundary(n);
        self.epoch_ns = self.epoch_ns.saturating_add(ns);
        self.epoch_rem = rem;
    }

    /// Starts the tick boundaries afresh at `now` (prescaler counter cleared).
    fn restart_epoch(&mut self, count: u64, now: u64) {
        self.epoch_count = count;
        self.epoch_ns = now;
        self.epoch_rem = 0;
    }

    /// The counter value at `now` (between events).
    pub fn count(&self, now: u64) -> u64 {
        if !self.running() {
            return self.epoch_count;
        }
        self.epoch_count + self.ticks_to(now)
    }

    /// Changes the kernel clock at `now` (RCC reprogrammed or the enable bit changed).
    pub fn set_clock(&mut self, hz: u32, now: u64) {
        if hz == self.clock_hz {
            return;
        }
        self.rebase(now);
        // The boundary's fraction, in units of the new clock's 1/hz ns.
        self.epoch_rem =
            (u128::from(self.epoch_rem) * u128::from(hz) / u128::from(self.clock_hz.max(1))) as u64;
        self.clock_hz = hz;
        self.recompute_next();
    }

    /// Moves the epoch to the last tick boundary at or before `now` (to `now` when the
    /// counter is stopped: it starts counting from the moment it is enabled).
    fn rebase(&mut self, now: u64) {
        if !self.running() {
            self.restart_epoch(self.epoch_count, now);
            return;
        }
        let n = self.ticks_to(now);
        self.epoch_count += n;
        self.advance_epoch(n);
    }

    /// Ticks from the epoch to the next event (update or compare match).
    fn ticks_to_next(&self) -> Option<u64> {
        if !self.running() {
            return None;
        }
        let arr = u64::from(self.arr_active);
        if arr == 0 {
            // RM0090 §18.3.2: the counter is blocked while ARR is 0.
            return None;
        }
        let top = if self.epoch_count > arr {
            self.count_mask()
        } else {
            arr
        };
        let mut next = top + 1 - self.epoch_count;
        for c in 0..usize::from(self.kind.channels) {
            let ccr = u64::from(self.ccr_active.get(c).copied().unwrap_or(0));
            if ccr > self.epoch_count && ccr <= top {
                next = next.min(ccr - self.epoch_count);
            }
        }
        Some(next)
    }

    /// The next time this timer changes by itself.
    pub fn next_event(&self) -> u64 {
        self.next
    }

    fn recompute_next(&mut self) {
        self.next = self.ticks_to_next().map_or(u64::MAX, |n| self.time_of(n));
    }

    /// Whether its events can raise an interrupt or feed another block (`trgo_used`: the
    /// DAC listens to this timer's TRGO); other timers are processed lazily.
    pub fn visible(&self, trgo_used: bool) -> bool {
        self.dier & 0x5F != 0 || (trgo_used && self.cr2 & 0x70 != 0)
    }

    /// Processes every event due by `now`.
    pub fn process(&mut self, now: u64) {
        while let Some(n) = self.ticks_to_next() {
            let t = self.time_of(n);
            if t > now {
                break;
            }
            let top = if self.epoch_count > u64::from(self.arr_active) {
                self.count_mask()
            } else {
                u64::from(self.arr_active)
            };
            let count = self.epoch_count + n;
            self.advance_epoch(n);
            if count > top {
                self.epoch_count = 0;
                self.update_event(t, true);
            } else {
                self.epoch_count = count;
            }
            self.compare(t);
        }
        self.recompute_next();
    }

    /// The counter reached its current value at `t`: matches and PWM levels.
    fn compare(&mut self, t: u64) {
        let count = self.epoch_count;
        for c in 0..usize::from(self.kind.channels) {
            let ccr = u64::from(self.ccr_active.get(c).copied().unwrap_or(0));
            if ccr == count {
                self.sr |= 1 << (c + 1);
                self.match_output(c);
            }
        }
        self.levels(t);
    }

    fn mode(&self, c: usize) -> u32 {
        let reg = self.ccmr.get(c / 2).copied().unwrap_or(0);
        (reg >> (8 * (c % 2) + 4)) & 7
    }

    fn preload(&self, c: usize) -> bool {
        let reg = self.ccmr.get(c / 2).copied().unwrap_or(0);
        reg & (1 << (8 * (c % 2) + 3)) != 0
    }

    /// The "on match" output modes act at a match.
    fn match_output(&mut self, c: usize) {
        let mode = self.mode(c);
        if let Some(r) = self.refs.get_mut(c) {
            match mode {
                1 => *r = true,
                2 => *r = false,
                3 => *r = !*r,
                _ => {}
            }
        }
    }

    /// Level modes (forced, PWM) follow the counter; outputs follow the references.
    fn levels(&mut self, t: u64) {
        let count = self.epoch_count;
        for c in 0..usize::from(self.kind.channels) {
            let ccr = u64::from(self.ccr_active.get(c).copied().unwrap_or(0));
            let mode = self.mode(c);
            if let Some(r) = self.refs.get_mut(c) {
                match mode {
                    4 => *r = false,
                    5 => *r = true,
                    6 => *r = count < ccr,
                    7 => *r = count >= ccr,
                    _ => {}
                }
            }
            let enabled = self.ccer & (1 << (4 * c)) != 0;
            let inverted = self.ccer & (1 << (4 * c + 1)) != 0;
            let reference = self.refs.get(c).copied().unwrap_or(false);
            let drive = if enabled {
                SignalDrive::Level(reference ^ inverted)
            } else {
                SignalDrive::Off
            };
            if let Some(o) = self.outputs.get_mut(c)
                && *o != drive
            {
                *o = drive;
                self.changes.push((c as u8 + 1, drive, t));
                if let Some(p) = self.pulses.get_mut(c) {
                    record_pulse(p, drive, t);
                }
            }
        }
    }

    /// An update event at `t`: shadow registers, UIF, TRGO, one-pulse stop.
    fn update_event(&mut self, t: u64, overflow: bool) {
        if self.cr1 & UDIS != 0 {
            return;
        }
        self.psc_active = self.psc;
        self.arr_active = self.arr;
        for c in 0..4 {
            if self.preload(c)
                && let (Some(a), Some(&p)) = (self.ccr_active.get_mut(c), self.ccr.get(c))
            {
                *a = p;
            }
        }
        if overflow || self.cr1 & URS == 0 {
            self.sr |= UIF;
        }
        if (self.cr2 >> 4) & 7 == 2 {
            self.trgo.push(t);
        }
        if overflow && self.cr1 & OPM != 0 {
            self.cr1 &= !CEN;
        }
    }

    /// The timer's interrupt request.
    pub fn irq(&self) -> bool {
        self.sr & self.dier & 0x5F != 0
    }

    /// What channel `ch` (1–4) is set to output.
    pub fn pwm_setting(&self, ch: u8) -> Option<PwmSetting> {
        let c = usize::from(ch.checked_sub(1)?);
        if c >= usize::from(self.kind.channels) {
            return None;
        }
        let tick_ns = (f64::from(self.psc_active) + 1.0) * 1e9 / f64::from(self.clock_hz.max(1));
        let period_ticks = f64::from(self.arr_active) + 1.0;
        let ccr = f64::from(self.ccr_active.get(c).copied().unwrap_or(0)).min(period_ticks);
        let active = match self.mode(c) {
            6 => ccr,
            7 => period_ticks - ccr,
            5 => period_ticks,
            _ => 0.0,
        };
        let inverted = self.ccer & (1 << (4 * c + 1)) != 0;
        let high = if inverted {
            period_ticks - active
        } else {
            active
        };
        Some(PwmSetting {
            period_ns: period_ticks * tick_ns,
            high_ns: high * tick_ns,
            one_pulse: self.cr1 & OPM != 0,
            running: self.running(),
            enabled: self.ccer & (1 << (4 * c)) != 0,
        })
    }

    /// Channel `ch`'s (1–4) measured pulses.
    pub fn pulses(&self, ch: u8) -> Option<PulseRecord> {
        self.pulses.get(usize::from(ch.checked_sub(1)?)).copied()
    }

    /// Register read at `now`.
    pub fn read(&self, offset: u32, now: u64) -> Option<u32> {
        let ch = usize::from(self.kind.channels);
        Some(match offset {
            CR1 => self.cr1,
            CR2 if self.kind.has_cr2 => self.cr2,
            SMCR if self.kind.channels > 0 => self.smcr,
            DIER => self.dier,
            SR => self.sr,
            EGR => 0,
            CCMR1 if ch > 0 => self.ccmr[0],
            CCMR2 if ch > 2 => self.ccmr[1],
            CCER if ch > 0 => self.ccer,
            CNT => (self.count(now) & self.count_mask()) as u32,
            PSC => self.psc,
            ARR => self.arr,
            CCR1..=CCR4 => {
                let c = ((offset - CCR1) / 4) as usize;
                if c >= ch {
                    return None;
                }
                *self.ccr.get(c)?
            }
            DCR | OR if ch == 4 => 0,
            _ => return None,
        })
    }

    /// Register write at `now` (events due before `now` already processed).
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        let done = self.write_register(offset, value, now);
        self.recompute_next();
        done
    }

    fn write_register(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        let ch = usize::from(self.kind.channels);
        let mask = self.count_mask() as u32;
        match offset {
            CR1 => {
                self.rebase(now);
                let was_running = self.cr1 & CEN != 0;
                if value & DIR_CMS != 0 {
                    self.unmodelled.push("timer down/centre-aligned counting");
                }
                self.cr1 = value & 0x3FF;
                if self.cr1 & ARPE == 0 {
                    self.arr_active = self.arr;
                }
                if !was_running && self.cr1 & CEN != 0 && (self.cr2 >> 4) & 7 == 1 {
                    self.trgo.push(now);
                }
            }
            CR2 if self.kind.has_cr2 => {
                self.cr2 = value & 0xF8;
                if (value >> 4) & 7 > 2 {
                    self.unmodelled.push("timer TRGO from compare (MMS > 2)");
                }
            }
            SMCR if ch > 0 => {
                self.smcr = value;
                if value & 7 != 0 {
                    self.unmodelled.push("timer slave mode");
                }
            }
            DIER => {
                self.dier = value & 0x5F5F;
                if value & 0x5F00 != 0 {
                    self.unmodelled.push("timer DMA requests");
                }
            }
            SR => self.sr &= value,
            EGR => self.generate(value, now),
            CCMR1 if ch > 0 => self.write_ccmr(0, value, now),
            CCMR2 if ch > 2 => self.write_ccmr(1, value, now),
            CCER if ch > 0 => {
                self.ccer = value & 0xBBBB;
                self.levels(now);
            }
            CNT => {
                self.restart_epoch(u64::from(value & mask), now);
                self.levels(now);
            }
            PSC => self.psc = value & 0xFFFF,
            ARR => {
                self.arr = value & mask;
                if self.cr1 & ARPE == 0 {
                    self.rebase(now);
                    self.arr_active = self.arr;
                }
            }
            CCR1..=CCR4 => {
                let c = ((offset - CCR1) / 4) as usize;
                if c >= ch {
                    return None;
                }
                *self.ccr.get_mut(c)? = value & mask;
                if !self.preload(c) {
                    *self.ccr_active.get_mut(c)? = value & mask;
                    self.rebase(now);
                    self.levels(now);
                }
            }
            DCR | OR if ch == 4 => {
                if value != 0 {
                    self.unmodelled.push("timer DMA burst / option register");
                }
            }
            _ => return None,
        }
        Some(())
    }

    fn write_ccmr(&mut self, i: usize, value: u32, now: u64) {
        if value & 0x0303 != 0 {
            self.unmodelled.push("timer input capture");
        }
        if let Some(r) = self.ccmr.get_mut(i) {
            *r = value & 0xFFFF;
        }
        self.rebase(now);
        self.levels(now);
    }

    /// EGR: UG re-initialises the counter and prescaler and updates the shadows;
    /// CCxG sets the channel flags.
    fn generate(&mut self, value: u32, now: u64) {
        if value & UG != 0 {
            self.restart_epoch(0, now);
            if (self.cr2 >> 4) & 7 == 0 {
                self.trgo.push(now);
            }
            self.update_event(now, false);
            self.levels(now);
        }
        let ccg = value & 0x1E & ((1u32 << (u32::from(self.kind.channels) + 1)) - 2);
        self.sr |= ccg;
    }
}

/// Tracks rising/falling edges into a pulse record.
fn record_pulse(p: &mut PulseRecord, drive: SignalDrive, t: u64) {
    match drive {
        SignalDrive::Level(true) => {
            if let Some(prev) = p.last_rise_ns {
                p.last_period_ns = Some(t - prev);
            }
            p.last_rise_ns = Some(t);
        }
        SignalDrive::Level(false) | SignalDrive::Off => {
            if let Some(rise) = p.last_rise_ns
                && p.last_fall_ns.is_none_or(|f| f < rise)
            {
                p.last_high_ns = Some(t - rise);
            }
            p.last_fall_ns = Some(t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PSC_1MHZ: u32 = 83; // 84 MHz / 84

    /// embassy-stm32 time_driver (gp16.rs) init_timer + init on TIM2.
    fn time_driver(now: u64) -> Timer {
        let mut t = Timer::new(TIM2);
        t.set_clock(84_000_000, 0);
        t.write(CR1, 0, now);
        t.write(CNT, 0, now);
        t.write(PSC, PSC_1MHZ, now);
        t.write(ARR, 0xFFFF, now);
        t.write(CR1, URS, now);
        t.write(EGR, UG, now);
        t.write(CR1, 0, now);
        t.write(0x34, 0x8000, now);
        t.write(DIER, UIF | 1 << 1, now);
        t.write(CR1, CEN, now);
        t
    }

    #[test]
    fn embassy_time_driver_ticks_at_1_mhz_with_half_period_interrupts() {
        let mut t = time_driver(1_000);
        assert_eq!(t.read(SR, 1_000), Some(0), "UG with URS set raises no UIF");
        assert_eq!(t.read(CNT, 1_000 + 12_345_000), Some(12_345));
        // Half-overflow compare at 0x8000 µs, overflow at 0x10000 µs.
        assert_eq!(t.next_event(), 1_000 + 0x8000 * 1_000);
        t.process(1_000 + 0x8000 * 1_000);
        assert_eq!(t.read(SR, 0), Some(1 << 1));
        assert!(t.irq());
        t.write(SR, !(1 << 1), 0);
        assert!(!t.irq());
        assert_eq!(t.next_event(), 1_000 + 0x10000 * 1_000);
        t.process(1_000 + 0x10000 * 1_000);
        // CCR2–4 are 0: they match as the counter wraps to 0 too (flags without enables).
        assert_eq!(t.read(SR, 0).unwrap() & (UIF | 1 << 1), UIF);
        assert_eq!(t.read(CNT, 1_000 + 0x10000 * 1_000 + 999), Some(0));
        assert_eq!(t.read(CNT, 1_000 + 0x10000 * 1_000 + 1_000), Some(1));
    }

    /// The time driver rewrites the alarm's CCR2 at arbitrary instants, hundreds of times a
    /// second; none of those writes may move the count: after 10 s of them (and of the
    /// half-period and overflow events) the counter reads exactly 10 s of ticks.
    #[test]
    fn alarm_writes_between_ticks_keep_the_count_exact() {
        let mut t = time_driver(0);
        let mut now = 0;
        let mut seen = 0u64;
        while now + 1_234_567 < 10_000_000_000 {
            now += 1_234_567; // never on a tick boundary for long
            t.process(now);
            t.write(0x38, (now / 1_000 + 500) as u32 & 0xFFFF, now);
            t.write(SR, 0, now);
            seen += 1;
        }
        assert!(seen > 8_000);
        let at = 10_000_000_000 + 999;
        t.process(at);
        let periods = 10_000_000 / 0x10000;
        assert_eq!(t.read(CNT, at), Some(10_000_000 - periods * 0x10000));
    }

    /// The same on a tick that is no whole number of nanoseconds (84 MHz, PSC 0: 11.9 ns):
    /// the boundary's fraction is kept across every rebase.
    #[test]
    fn rebases_keep_fractional_tick_boundaries() {
        let mut t = Timer::new(TIM2);
        t.set_clock(84_000_000, 0);
        t.write(CR1, CEN, 0);
        let mut now = 0;
        while now + 777_777 < 1_000_000_000 {
            now += 777_777;
            t.write(0x34, 0, now);
        }
        assert_eq!(t.read(CNT, 1_000_000_000), Some(84_000_000));
        assert_eq!(t.read(CNT, 999_999_999), Some(83_999_999));
    }

    #[test]
    fn an_alarm_on_ccr2_fires_when_the_counter_gets_there() {
        let mut t = time_driver(0);
        t.write(0x38, 5_000, 100_000);
        t.write(DIER, UIF | 1 << 1 | 1 << 2, 100_000);
        assert_eq!(t.next_event(), 5_000_000);
        t.process(5_000_000);
        assert_eq!(t.read(SR, 5_000_000).unwrap() & 1 << 2, 1 << 2);
    }

    #[test]
    fn the_prescaler_takes_effect_at_the_next_update() {
        let mut t = Timer::new(TIM3);
        t.set_clock(84_000_000, 0);
        t.write(ARR, 999, 0);
        t.write(CR1, CEN, 0);
        // PSC 0: 84 MHz, a period of 1000 ticks = 11 905 ns (rounded up to the ns).
        t.write(PSC, 83, 100);
        assert_eq!(t.next_event(), 11_905);
        t.process(11_905);
        assert_eq!(t.read(SR, 0).unwrap() & UIF, UIF);
        assert_eq!(t.next_event(), 11_905 + 1_000_000, "now 1 µs ticks");
    }

    /// MotorTimer::new for PWM: PSC, ARR (UG), ARPE, PWM1 + preload, polarity, CCR, CCxE,
    /// UG, CEN.
    fn pwm(t: &mut Timer, psc: u32, arr: u32, ccr: u32, inverted: bool, opm: bool) {
        t.write(CR1, 0, 0);
        t.write(PSC, psc, 0);
        t.write(ARR, arr, 0);
        t.write(CR1, URS, 0);
        t.write(EGR, UG, 0);
        t.write(CR1, ARPE, 0);
        t.write(CCMR1, 0x6868, 0);
        t.write(CCER, if inverted { 0x33 } else { 0x11 }, 0);
        t.write(0x34, ccr, 0);
        t.write(0x38, ccr, 0);
        t.write(CR1, ARPE | if opm { OPM } else { 0 }, 0);
        t.write(CR1, ARPE | URS | if opm { OPM } else { 0 }, 0);
        t.write(EGR, UG, 0);
        t.write(CR1, ARPE | if opm { OPM } else { 0 }, 0);
        if !opm {
            t.write(CR1, ARPE | CEN, 0);
        }
    }

    #[test]
    fn pwm_mode_1_gives_edges_at_update_and_compare() {
        // TIM9 at 168 MHz, PSC 167 → 1 µs ticks, 2 ms period, 1.5 ms pulses.
        let mut t = Timer::new(TIM9);
        t.set_clock(168_000_000, 0);
        pwm(&mut t, 167, 1999, 1500, false, false);
        assert!(t.changes.contains(&(1, SignalDrive::Level(true), 0)));
        assert_eq!(t.changes.last(), Some(&(2, SignalDrive::Level(true), 0)));
        t.changes.clear();
        t.process(4_000_000);
        assert_eq!(
            t.changes,
            vec![
                (1, SignalDrive::Level(false), 1_500_000),
                (2, SignalDrive::Level(false), 1_500_000),
                (1, SignalDrive::Level(true), 2_000_000),
                (2, SignalDrive::Level(true), 2_000_000),
                (1, SignalDrive::Level(false), 3_500_000),
                (2, SignalDrive::Level(false), 3_500_000),
                (1, SignalDrive::Level(true), 4_000_000),
                (2, SignalDrive::Level(true), 4_000_000),
            ]
        );
        let s = t.pwm_setting(1).unwrap();
        assert_eq!((s.period_ns, s.high_ns), (2_000_000.0, 1_500_000.0));
        assert_eq!(t.pulses(2).unwrap().last_high_ns, Some(1_500_000));
        assert_eq!(t.pulses(2).unwrap().last_period_ns, Some(2_000_000));
        // Preloaded CCR: a new duty starts at the next period.
        t.write(0x34, 1000, 4_100_000);
        t.changes.clear();
        t.process(6_000_000);
        assert_eq!(t.changes[0], (1, SignalDrive::Level(false), 5_500_000));
        t.process(8_000_000);
        assert_eq!(t.pulses(1).unwrap().last_high_ns, Some(1_000_000));
    }

    #[test]
    fn oneshot125_fires_one_inverted_pulse_ending_at_arr_and_stops() {
        // TIM3 at 84 MHz, PSC 0: ARR 21 000 = 250 µs; pulse 187.5 µs → CCR = ARR − 15 750.
        let mut t = Timer::new(TIM3);
        t.set_clock(84_000_000, 0);
        pwm(&mut t, 0, 21_000, 21_000 - 15_750, true, true);
        assert_eq!(
            t.changes.last().map(|c| c.1),
            Some(SignalDrive::Level(false))
        );
        t.changes.clear();
        t.process(10_000_000);
        assert!(t.changes.is_empty(), "nothing until the loop fires it");
        // apply(): UG then CEN.
        t.write(EGR, UG, 10_000_000);
        t.write(CR1, ARPE | OPM | CEN, 10_000_000);
        t.process(20_000_000);
        let ch1: Vec<_> = t.changes.iter().filter(|c| c.0 == 1).collect();
        assert_eq!(ch1.len(), 2);
        assert_eq!(ch1[0].2, 10_000_000 + 62_500, "rises at CCR");
        assert_eq!(
            ch1[1].2,
            10_000_000 + 250_012,
            "falls at the update (ARR+1 ticks)"
        );
        assert_eq!(t.read(CR1, 20_000_000).unwrap() & CEN, 0, "OPM cleared CEN");
        assert_eq!(t.pulses(1).unwrap().last_high_ns, Some(187_512));
    }

    #[test]
    fn tim6_update_gives_trgo_with_mms_update() {
        let mut t = Timer::new(TIM6);
        t.set_clock(84_000_000, 0);
        t.write(CR2, 2 << 4, 0);
        t.write(ARR, 83, 0);
        t.write(CR1, CEN, 0);
        t.process(10_000);
        assert_eq!(
            t.trgo,
            vec![
                1_000, 2_000, 3_000, 4_000, 5_000, 6_000, 7_000, 8_000, 9_000, 10_000
            ]
        );
        t.trgo.clear();
        t.write(EGR, UG, 10_500);
        assert_eq!(t.trgo, vec![10_500], "UG is an update too");
        assert!(!t.visible(false));
        assert!(t.visible(true));
    }
}
