//! What the co-simulation needs of an emulated microcontroller (a SoC model with its
//! Cortex-M4F core, running an image): run it to an instant, hand it timestamped inputs,
//! read its UART rates, power it, and read its statistics. The STM32F405 and nRF52840
//! models implement it around `m4_sim`'s core; a test implements it with a scripted fake.

use crate::wire::{Outside, Pin};

/// Why a run stopped before its deadline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Halt {
    /// The core locked up (a fault in a fault handler): it stays stopped until a reset.
    Lockup(String),
    /// Anything else the core or SoC reports (an unrecoverable emulation error).
    Error(String),
}

/// A hardware fault the SoC model injects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Injection {
    /// A bus error during a DMA transfer on `controller`'s `stream` (DMA1 = 1, DMA2 = 2):
    /// the stream's transfer-error flag (RM0090 §10.3.15, TEIFx) — embassy-stm32's DMA
    /// interrupt handler panics on it.
    DmaTransferError {
        /// DMA controller.
        controller: u8,
        /// Stream.
        stream: u8,
    },
}

/// The figures of one emulated MCU since power-on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MachineStats {
    /// Instructions executed.
    pub instructions: u64,
    /// Virtual time the core ran (not asleep in WFI/WFE), ns.
    pub active_ns: u64,
    /// Virtual time the core slept, ns.
    pub asleep_ns: u64,
    /// The initial stack pointer of the image (the stack's top).
    pub stack_top: u32,
    /// The lowest stack pointer seen (None: not yet run).
    pub lowest_sp: Option<u32>,
    /// Resets by a watchdog.
    pub watchdog_resets: u32,
    /// Every reset after the first power-on (watchdog, software, lockup recovery, power).
    pub resets: u32,
    /// From power-on until the last of the image's tasks was first polled, ns (None: none
    /// yet).
    pub boot_ns: Option<u64>,
    /// The image's tasks polled at least once, of how many it holds (a task the image's
    /// configuration does not spawn is never polled: the module's receiver-only PPM output
    /// in the transmitter role).
    pub tasks_polled: u32,
    /// …
    pub tasks_total: u32,
    /// When the last task was first polled, ns since power-on.
    pub last_first_poll_ns: Option<u64>,
    /// Times the core locked up.
    pub lockups: u32,
}

impl MachineStats {
    /// The deepest stack use, bytes.
    pub fn max_stack_bytes(&self) -> Option<u32> {
        self.lowest_sp.map(|sp| self.stack_top.saturating_sub(sp))
    }

    /// Busy share of the time, % (active over active + asleep).
    pub fn cpu_load_pct(&self) -> Option<f64> {
        let total = self.active_ns + self.asleep_ns;
        (total > 0).then(|| 100.0 * self.active_ns as f64 / total as f64)
    }
}

/// An emulated microcontroller on its board `Self::Board`.
pub trait Machine {
    /// Its board.
    type Board: Outside;

    /// The board (the co-simulation feeds its chips between steps).
    fn board(&mut self) -> &mut Self::Board;

    /// The virtual time the machine has reached, ns.
    fn now_ns(&self) -> u64;

    /// Runs until `deadline_ns` (asleep, time jumps); `Err` when it stopped for good.
    fn run_until(&mut self, deadline_ns: u64) -> Result<(), Halt>;

    /// An input pin is at `level` from `at_ns` on.
    fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64);

    /// A byte arrives on UART `uart`, its stop bit ending at `at_ns`.
    fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64);

    /// The rate UART `uart` is set to now (None: not configured).
    fn uart_baud(&mut self, uart: u8) -> Option<u32>;

    /// Power off (`false`: everything stops, RAM is lost) or on (a power-on reset) at
    /// `now_ns`.
    fn set_powered(&mut self, on: bool, now_ns: u64);

    /// Whether it is powered.
    fn powered(&self) -> bool;

    /// Its figures so far.
    fn stats(&self) -> MachineStats;

    /// Injects a hardware fault now; false when the model cannot.
    fn inject(&mut self, injection: Injection) -> bool {
        let _ = injection;
        false
    }

    /// A USB host at the console port is plugged in (or pulled) now; false when the machine
    /// has no USB port modelled.
    fn usb_plug(&mut self, plugged: bool) -> bool {
        let _ = plugged;
        false
    }

    /// The USB host types `line` into the console now (sent once it has enumerated) and
    /// drops what the firmware answered since the last call; the answer's length.
    fn usb_type(&mut self, line: &[u8]) -> usize {
        let _ = line;
        0
    }

    /// `len` bytes of its memory at `addr` as a debug probe reads them (flash, RAM); None
    /// when unmapped or not supported.
    fn read_memory(&self, addr: u32, len: usize) -> Option<Vec<u8>> {
        let _ = (addr, len);
        None
    }
}

/// Hands `inputs` to `machine`'s queues.
pub fn deliver<Mc: Machine>(machine: &mut Mc, inputs: Vec<crate::board::Input>) {
    for i in inputs {
        match i {
            crate::board::Input::Pin { pin, level, at_ns } => {
                machine.drive_input(pin, level, at_ns)
            }
            crate::board::Input::Uart { uart, byte, at_ns } => {
                machine.uart_receive(uart, byte, at_ns);
            }
        }
    }
}

/// What a [`FakeMachine`] does at each step: acts on its board at the step's end with the
/// inputs that fell due.
pub type Behaviour<B> = Box<dyn FnMut(&mut B, u64, &[crate::board::Input])>;

/// A scripted stand-in for an emulated MCU, for testing the co-simulation: it keeps the
/// inputs it gets, and a `behaviour` function acts on the board at each step as firmware
/// would (drive pins, clock SPI bytes, send UART bytes), with the inputs due by then.
pub struct FakeMachine<B: Outside> {
    board: B,
    now_ns: u64,
    powered: bool,
    /// Inputs received and not yet due, in time order.
    pending: Vec<crate::board::Input>,
    /// The inputs that fell due, in time order (what the fake "saw").
    pub seen: Vec<crate::board::Input>,
    behaviour: Behaviour<B>,
    /// UART rates it reports.
    pub bauds: Vec<(u8, u32)>,
    stats: MachineStats,
    /// The deadlines it was run to.
    pub steps: u64,
}

impl<B: Outside> FakeMachine<B> {
    /// A powered fake on `board`, acting by `behaviour(board, now_ns, inputs due)` once per
    /// step.
    pub fn new(
        board: B,
        behaviour: impl FnMut(&mut B, u64, &[crate::board::Input]) + 'static,
    ) -> Self {
        Self {
            board,
            now_ns: 0,
            powered: true,
            pending: Vec::new(),
            seen: Vec::new(),
            behaviour: Box::new(behaviour),
            bauds: Vec::new(),
            stats: MachineStats {
                stack_top: 0x2002_0000,
                ..MachineStats::default()
            },
            steps: 0,
        }
    }

    /// The board, read-only.
    pub fn board_ref(&self) -> &B {
        &self.board
    }
}

impl<B: Outside> Machine for FakeMachine<B> {
    type Board = B;

    fn board(&mut self) -> &mut B {
        &mut self.board
    }

    fn now_ns(&self) -> u64 {
        self.now_ns
    }

    fn run_until(&mut self, deadline_ns: u64) -> Result<(), Halt> {
        self.steps += 1;
        if !self.powered {
            self.stats.asleep_ns += deadline_ns.saturating_sub(self.now_ns);
            self.now_ns = deadline_ns;
            return Ok(());
        }
        self.pending.sort_by_key(crate::board::Input::at_ns);
        let split = self.pending.partition_point(|i| i.at_ns() <= deadline_ns);
        let due: Vec<_> = self.pending.drain(..split).collect();
        (self.behaviour)(&mut self.board, deadline_ns, &due);
        self.seen.extend(due);
        self.stats.active_ns += deadline_ns.saturating_sub(self.now_ns);
        self.now_ns = deadline_ns;
        Ok(())
    }

    fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.pending
            .push(crate::board::Input::Pin { pin, level, at_ns });
    }

    fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64) {
        self.pending
            .push(crate::board::Input::Uart { uart, byte, at_ns });
    }

    fn uart_baud(&mut self, uart: u8) -> Option<u32> {
        self.bauds.iter().find(|(u, _)| *u == uart).map(|(_, b)| *b)
    }

    fn set_powered(&mut self, on: bool, _now_ns: u64) {
        if on && !self.powered {
            self.stats.resets += 1;
            self.pending.clear();
        }
        self.powered = on;
    }

    fn powered(&self) -> bool {
        self.powered
    }

    fn stats(&self) -> MachineStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stack_and_load_figures() {
        let s = MachineStats {
            active_ns: 250,
            asleep_ns: 750,
            stack_top: 0x2002_0000,
            lowest_sp: Some(0x2001_C000),
            ..MachineStats::default()
        };
        assert_eq!(s.max_stack_bytes(), Some(0x4000));
        assert_eq!(s.cpu_load_pct(), Some(25.0));
        assert_eq!(MachineStats::default().cpu_load_pct(), None);
    }
}
