//! A test rig: a flat bus with a vector table, hand-assembled code at [`CODE`] ending in
//! `BKPT #0`, and helpers to set registers, run to the breakpoint and read the results.
#![allow(dead_code, clippy::unwrap_used, clippy::indexing_slicing)]

use m4_sim::{Config, Cpu, FlatBus, Reg, Stop};

/// Where the code under test starts.
pub const CODE: u32 = 0x100;
/// Initial main stack pointer.
pub const STACK: u32 = 0x2000_8000;
/// Scratch RAM for data.
pub const DATA: u32 = 0x2000_1000;
/// `BKPT #0`, appended to every program.
pub const BKPT: u16 = 0xBE00;

/// The vector table's handler for exception `n` when a test does not place one: a BKPT
/// with the exception number as immediate, at 0x800 + 4n.
pub fn default_handler(n: u32) -> u32 {
    0x800 + 4 * n
}

pub struct Rig {
    pub cpu: Cpu,
    pub bus: FlatBus,
}

impl Rig {
    pub fn new(code: &[u16]) -> Rig {
        Self::with_config(Config::default(), code)
    }

    pub fn with_config(cfg: Config, code: &[u16]) -> Rig {
        let mut bus = FlatBus::mps2_an386();
        bus.load(0, &STACK.to_le_bytes());
        for n in 1..64u32 {
            let handler = if n == 1 { CODE } else { default_handler(n) };
            bus.load(4 * n, &(handler | 1).to_le_bytes());
            // BKPT #n at each default handler.
            bus.load(default_handler(n), &(0xBE00u16 | n as u16).to_le_bytes());
        }
        let mut rig = Rig {
            cpu: Cpu::new(cfg),
            bus,
        };
        rig.place(CODE, code);
        rig.place(CODE + 2 * code.len() as u32, &[BKPT]);
        rig.cpu.reset(&mut rig.bus);
        rig
    }

    /// Loads halfwords at `addr`.
    pub fn place(&mut self, addr: u32, code: &[u16]) {
        let bytes: Vec<u8> = code.iter().flat_map(|h| h.to_le_bytes()).collect();
        assert!(self.bus.load(addr, &bytes));
    }

    /// Points exception `n`'s vector at `addr`.
    pub fn vector(&mut self, n: u32, addr: u32) {
        self.bus.load(4 * n, &(addr | 1).to_le_bytes());
    }

    pub fn set(&mut self, r: u8, v: u32) {
        self.cpu.write_reg(Reg::R(r), v);
    }

    pub fn r(&self, r: u8) -> u32 {
        self.cpu.read_reg(Reg::R(r))
    }

    pub fn s(&self, n: u8) -> u32 {
        self.cpu.read_reg(Reg::S(n))
    }

    pub fn set_s(&mut self, n: u8, v: u32) {
        self.cpu.write_reg(Reg::S(n), v);
    }

    pub fn set_f(&mut self, n: u8, v: f32) {
        self.set_s(n, v.to_bits());
    }

    pub fn f(&self, n: u8) -> f32 {
        f32::from_bits(self.s(n))
    }

    /// N, Z, C, V.
    pub fn nzcv(&self) -> (bool, bool, bool, bool) {
        let x = self.cpu.read_reg(Reg::Xpsr);
        (
            x >> 31 & 1 == 1,
            x >> 30 & 1 == 1,
            x >> 29 & 1 == 1,
            x >> 28 & 1 == 1,
        )
    }

    pub fn q(&self) -> bool {
        self.cpu.read_reg(Reg::Xpsr) >> 27 & 1 == 1
    }

    pub fn ge(&self) -> u32 {
        self.cpu.read_reg(Reg::Xpsr) >> 16 & 0xF
    }

    /// Sets N, Z, C, V (and clears Q and GE).
    pub fn set_nzcv(&mut self, n: bool, z: bool, c: bool, v: bool) {
        let x = u32::from(n) << 31 | u32::from(z) << 30 | u32::from(c) << 29 | u32::from(v) << 28;
        self.cpu.write_reg(Reg::Xpsr, x | 1 << 24);
    }

    pub fn word(&self, addr: u32) -> u32 {
        let b = self.bus.peek(addr, 4).unwrap();
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }

    pub fn poke(&mut self, addr: u32, v: u32) {
        assert!(self.bus.load(addr, &v.to_le_bytes()));
    }

    /// Runs up to one second of virtual time.
    pub fn run(&mut self) -> Stop {
        let deadline = self.cpu.now_ns() + 1_000_000_000;
        self.cpu.run_until(&mut self.bus, deadline)
    }

    /// Runs to the BKPT that ends the program and checks it is that one.
    pub fn run_to_end(&mut self, code_len: usize) {
        let end = CODE + 2 * code_len as u32;
        assert_eq!(self.run(), Stop::Breakpoint { pc: end, imm: 0 });
    }

    /// Runs and expects the default handler of exception `n` to be entered.
    pub fn run_to_handler(&mut self, n: u32) {
        assert_eq!(
            self.run(),
            Stop::Breakpoint {
                pc: default_handler(n),
                imm: n as u8
            }
        );
    }

    /// Writes a system register through the core's own view of the SCS (as a debugger
    /// would, with the core's privileged access).
    pub fn scs_write(&mut self, addr: u32, v: u32) {
        // movw/movt r11, addr; movw/movt r12, v; str r12, [r11]; bkpt — run at 0x600.
        let mut code = Vec::new();
        code.extend(mov32(11, addr));
        code.extend(mov32(12, v));
        code.extend([0xF8CB, 0xC000, 0xBE00]); // str.w r12, [r11]; bkpt #0
        self.call(&code);
    }

    /// Reads a system register through the core.
    pub fn scs_read(&mut self, addr: u32) -> u32 {
        let mut code = Vec::new();
        code.extend(mov32(11, addr));
        code.extend([0xF8DB, 0xC000, 0xBE00]); // ldr.w r12, [r11]; bkpt #0
        self.call(&code);
        self.r(12)
    }

    /// Runs a snippet at 0x600 and returns to where the core was.
    fn call(&mut self, code: &[u16]) {
        let pc = self.cpu.read_reg(Reg::R(15));
        let (r11, r12) = (self.r(11), self.r(12));
        self.place(0x600, code);
        self.cpu.write_reg(Reg::R(15), 0x600);
        let stop = self.run();
        assert!(matches!(stop, Stop::Breakpoint { .. }), "{stop:?}");
        self.cpu.write_reg(Reg::R(15), pc);
        let got = self.r(12);
        self.set(11, r11);
        self.set(12, r12);
        // Keep the value read visible in R12 for scs_read.
        self.set(12, got);
    }
}

/// MOVW/MOVT of a 32-bit constant into `rd`.
pub fn mov32(rd: u16, v: u32) -> [u16; 4] {
    let enc = |top: bool, imm: u32| -> [u16; 2] {
        let imm4 = (imm >> 12) & 0xF;
        let i = (imm >> 11) & 1;
        let imm3 = (imm >> 8) & 7;
        let imm8 = imm & 0xFF;
        let op = if top { 0xF2C0 } else { 0xF240 };
        [
            (op | i << 10 | imm4) as u16,
            (imm3 << 12 | u32::from(rd) << 8 | imm8) as u16,
        ]
    };
    let lo = enc(false, v & 0xFFFF);
    let hi = enc(true, v >> 16);
    [lo[0], lo[1], hi[0], hi[1]]
}
