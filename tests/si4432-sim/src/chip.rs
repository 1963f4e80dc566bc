//! One virtual Si4432: register file, power and operating-mode state machine, interrupt
//! status, and what an SPI access does to each register.
//!
//! More `impl Chip` lives next door: SPI register semantics in `access.rs`, the TX packet
//! handler in `tx.rs`, frame acquisition in `acquire.rs` and reception in `rx.rs`.
//! Timing follows the datasheet's operating-mode response times (Table 11 / §3): crystal
//! start 600 µs (STANDBY → READY), PLL settle 200 µs (READY/TUNE → TX/RX), and a power-on
//! reset of about 15 ms after SDN is released.

use crate::air::Air;
use crate::fifo::Fifo;
use crate::registers::{self, addr, irq2, mode1};
use crate::rx::RxState;
use crate::tx::TxState;
use sim_rng::SplitMix64;

/// Crystal start-up, STANDBY → READY (datasheet: 600 µs typical).
pub const XTAL_START_NS: u64 = 600_000;
/// PLL settling before TX or RX (datasheet: 200 µs from READY or TUNE).
pub const PLL_SETTLE_NS: u64 = 200_000;
/// Power-on reset after SDN goes low until registers are usable (datasheet: ≈15 ms).
pub const POWER_ON_RESET_NS: u64 = 15_000_000;

/// A hardware fault injected into a chip.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fault {
    /// No fault.
    #[default]
    None,
    /// The module is not connected: MISO floats to `miso` (0xFF with a pull-up, 0x00 with a
    /// pull-down), writes go nowhere, nIRQ stays high.
    Unplugged {
        /// What every SPI read returns.
        miso: u8,
    },
    /// nIRQ reads low whatever the chip does (an unpowered or browned-out module, a
    /// shorted line); SPI works.
    NirqStuckLow,
    /// nIRQ never goes low (a broken trace: the open-drain line stays at its pull-up);
    /// SPI works.
    NirqStuckHigh,
}

/// The chip's operating state as a test sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChipState {
    /// SDN high: everything off, registers lost.
    Shutdown,
    /// Power-on reset in progress (SPI not yet usable).
    PowerOnReset,
    /// STANDBY or SLEEP: crystal off.
    Standby,
    /// READY: crystal on.
    Ready,
    /// TUNE: PLL on.
    Tune,
    /// Settling towards TX.
    SettlingTx,
    /// Settling towards RX.
    SettlingRx,
    /// Transmitting.
    Tx,
    /// Receiving (searching for or receiving a packet).
    Rx,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Power {
    Off,
    Resetting { ready_ns: u64 },
    On,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Target {
    Tx,
    Rx,
}

#[derive(Debug)]
pub(crate) enum Activity {
    Idle,
    Settling { until_ns: u64, target: Target },
    Tx(TxState),
    Rx(RxState),
}

/// Device status 0x02 bits this model latches.
pub(crate) const STATUS_FFOVFL: u8 = 1 << 7;
pub(crate) const STATUS_FFUNFL: u8 = 1 << 6;
pub(crate) const STATUS_HEADERR: u8 = 1 << 4;
/// EzMAC status 0x31 latched bits.
pub(crate) const EZMAC_PKVALID: u8 = 1 << 3;
pub(crate) const EZMAC_CRCERROR: u8 = 1 << 2;
pub(crate) const EZMAC_PKSENT: u8 = 1 << 0;

/// What the chip needs from the rest of the world while it changes state.
pub(crate) struct Ctx<'a> {
    pub air: &'a mut Air,
    pub rng: &'a mut SplitMix64,
    pub radio_count: usize,
}

/// Per-chip physical facts that registers do not hold.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Physical {
    pub crystal_error_ppm: f64,
    pub temperature_c: f64,
    pub supply_v: f64,
}

#[derive(Debug)]
pub(crate) struct Chip {
    pub me: usize,
    pub regs: [u8; 128],
    pub tx_fifo: Fifo,
    pub rx_fifo: Fifo,
    pub power: Power,
    pub activity: Activity,
    /// When the crystal is (or was) stable; `None` while it is off.
    pub xtal_ready_ns: Option<u64>,
    pub chip_ready_pending_ns: Option<u64>,
    pub status1: u8,
    pub status2: u8,
    pub device_flags: u8,
    pub ezmac_latched: u8,
    pub rssi_latch: Option<u8>,
    pub afc_raw: u16,
    pub fault: Fault,
    pub physical: Physical,
}

impl Chip {
    /// A chip that was powered long before the test starts: registers at reset values,
    /// READY, with `ipor` and `ichiprdy` latched (so nIRQ is low, as after a real boot).
    pub fn new(me: usize, physical: Physical) -> Self {
        Self {
            me,
            regs: registers::reset_file(),
            tx_fifo: Fifo::new(),
            rx_fifo: Fifo::new(),
            power: Power::On,
            activity: Activity::Idle,
            xtal_ready_ns: Some(0),
            chip_ready_pending_ns: None,
            status1: 0,
            status2: irq2::POWER_ON_RESET | irq2::CHIP_READY,
            device_flags: 0,
            ezmac_latched: 0,
            rssi_latch: None,
            afc_raw: 0,
            fault: Fault::None,
            physical,
        }
    }

    pub fn reg(&self, address: u8) -> u8 {
        self.regs
            .get(usize::from(address & 0x7F))
            .copied()
            .unwrap_or(0)
    }

    pub fn set_reg(&mut self, address: u8, value: u8) {
        if let Some(slot) = self.regs.get_mut(usize::from(address & 0x7F)) {
            *slot = value;
        }
    }

    /// The nIRQ pin: low while any enabled status bit is set.
    pub fn nirq_low(&self) -> bool {
        match self.fault {
            Fault::NirqStuckLow => return true,
            Fault::NirqStuckHigh | Fault::Unplugged { .. } => return false,
            Fault::None => {}
        }
        self.power == Power::On
            && ((self.status1 & self.reg(addr::INTERRUPT_ENABLE_1))
                | (self.status2 & self.reg(addr::INTERRUPT_ENABLE_2)))
                != 0
    }

    pub fn state(&self) -> ChipState {
        match (self.power, &self.activity) {
            (Power::Off, _) => ChipState::Shutdown,
            (Power::Resetting { .. }, _) => ChipState::PowerOnReset,
            (
                Power::On,
                Activity::Settling {
                    target: Target::Tx, ..
                },
            ) => ChipState::SettlingTx,
            (
                Power::On,
                Activity::Settling {
                    target: Target::Rx, ..
                },
            ) => ChipState::SettlingRx,
            (Power::On, Activity::Tx(_)) => ChipState::Tx,
            (Power::On, Activity::Rx(_)) => ChipState::Rx,
            (Power::On, Activity::Idle) => {
                let mode = self.reg(addr::OPERATING_MODE_1);
                if mode & mode1::PLLON != 0 {
                    ChipState::Tune
                } else if mode & mode1::XTON != 0 {
                    ChipState::Ready
                } else {
                    ChipState::Standby
                }
            }
        }
    }

    /// The next moment this chip changes by itself.
    pub fn next_event_ns(&self) -> Option<u64> {
        match self.power {
            Power::Off => return None,
            Power::Resetting { ready_ns } => return Some(ready_ns),
            Power::On => {}
        }
        let activity = match &self.activity {
            Activity::Idle => None,
            Activity::Settling { until_ns, .. } => Some(*until_ns),
            Activity::Tx(tx) => tx.next_event_ns(),
            Activity::Rx(rx) => rx.next_event_ns(),
        };
        match (activity, self.chip_ready_pending_ns) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Handle whatever is due at `now_ns` (one step; the world calls again while due).
    /// Returns the id of a transmission this step put on air.
    pub fn process(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) -> Option<u64> {
        if let Power::Resetting { ready_ns } = self.power {
            if ready_ns <= now_ns {
                self.power = Power::On;
                self.status2 |= irq2::POWER_ON_RESET;
                self.start_crystal(now_ns);
            }
            return None;
        }
        if self.chip_ready_pending_ns.is_some_and(|t| t <= now_ns) {
            self.chip_ready_pending_ns = None;
            self.status2 |= irq2::CHIP_READY;
            return None;
        }
        match self.activity {
            Activity::Settling { until_ns, target } if until_ns <= now_ns => match target {
                Target::Tx => return self.begin_tx(now_ns, ctx),
                Target::Rx => self.begin_rx(now_ns, ctx),
            },
            Activity::Tx(_) => self.tx_step(now_ns, ctx),
            Activity::Rx(_) => self.rx_step(now_ns, ctx),
            _ => {}
        }
        None
    }

    fn start_crystal(&mut self, now_ns: u64) {
        let ready = now_ns + XTAL_START_NS;
        self.xtal_ready_ns = Some(ready);
        self.chip_ready_pending_ns = Some(ready);
    }

    /// Stop TX/RX (aborting any frame) and go idle.
    pub fn stop_activity(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        match core::mem::replace(&mut self.activity, Activity::Idle) {
            Activity::Tx(tx) => ctx.air.abort(tx.id, now_ns),
            Activity::Rx(rx) => rx.abort(self.me, ctx),
            Activity::Idle | Activity::Settling { .. } => {}
        }
    }

    /// Registers, FIFOs and status back to reset values (swres, POR).
    fn reset_registers(&mut self) {
        self.regs = registers::reset_file();
        self.tx_fifo.clear();
        self.rx_fifo.clear();
        self.status1 = 0;
        self.status2 = 0;
        self.device_flags = 0;
        self.ezmac_latched = 0;
        self.rssi_latch = None;
        self.afc_raw = 0;
    }

    /// 0x07 swres: registers to defaults without a POR; the crystal restarts, then `ichiprdy`.
    pub fn software_reset(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        self.stop_activity(now_ns, ctx);
        self.reset_registers();
        self.start_crystal(now_ns);
    }

    /// Power-on reset (SDN released, or a brown-out injected by a test).
    pub fn power_on_reset(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        self.stop_activity(now_ns, ctx);
        self.reset_registers();
        self.xtal_ready_ns = None;
        self.chip_ready_pending_ns = None;
        self.power = Power::Resetting {
            ready_ns: now_ns + POWER_ON_RESET_NS,
        };
    }

    /// SDN driven high: shutdown, everything lost.
    pub fn shut_down(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        self.stop_activity(now_ns, ctx);
        self.reset_registers();
        self.xtal_ready_ns = None;
        self.chip_ready_pending_ns = None;
        self.power = Power::Off;
    }

    /// A write to 0x07: pick STANDBY/READY/TUNE/TX/RX (datasheet §3, Table 10).
    pub(crate) fn write_mode(&mut self, value: u8, now_ns: u64, ctx: &mut Ctx<'_>) {
        if value & mode1::SWRES != 0 {
            self.software_reset(now_ns, ctx);
            return;
        }
        self.set_reg(addr::OPERATING_MODE_1, value);
        let wants_crystal = value & (mode1::XTON | mode1::PLLON | mode1::TXON | mode1::RXON) != 0;
        match (wants_crystal, self.xtal_ready_ns) {
            (true, None) => self.start_crystal(now_ns),
            (false, Some(_)) => {
                self.xtal_ready_ns = None;
                self.chip_ready_pending_ns = None;
            }
            _ => {}
        }
        let target = if value & mode1::TXON != 0 {
            Some(Target::Tx)
        } else if value & mode1::RXON != 0 {
            Some(Target::Rx)
        } else {
            None
        };
        let current = match self.activity {
            Activity::Tx(_)
            | Activity::Settling {
                target: Target::Tx, ..
            } => Some(Target::Tx),
            Activity::Rx(_)
            | Activity::Settling {
                target: Target::Rx, ..
            } => Some(Target::Rx),
            Activity::Idle => None,
        };
        if target == current {
            return;
        }
        self.stop_activity(now_ns, ctx);
        if let Some(target) = target {
            let base = self.xtal_ready_ns.map_or(now_ns, |t| t.max(now_ns));
            self.activity = Activity::Settling {
                until_ns: base + PLL_SETTLE_NS,
                target,
            };
        }
    }
}
