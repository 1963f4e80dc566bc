//! ARM semihosting through `BKPT 0xAB` (the operation in R0, its parameter in R1, the
//! result in R0): console output (SYS_WRITEC, SYS_WRITE0, SYS_WRITE to the `:tt` handles
//! SYS_OPEN gives out) and exit (SYS_EXIT, SYS_EXIT_EXTENDED). Other operations answer -1,
//! "unsupported". Output collects in the core for [`crate::Cpu::take_semihost_output`].

use crate::bus::{Bus, Width};
use crate::cpu::Cpu;
use crate::fault::Fault;

const SYS_OPEN: u32 = 0x01;
const SYS_CLOSE: u32 = 0x02;
const SYS_WRITEC: u32 = 0x03;
const SYS_WRITE0: u32 = 0x04;
const SYS_WRITE: u32 = 0x05;
const SYS_ISTTY: u32 = 0x09;
const SYS_EXIT: u32 = 0x18;
const SYS_EXIT_EXTENDED: u32 = 0x20;
/// `ADP_Stopped_ApplicationExit`: a normal exit.
const APPLICATION_EXIT: u32 = 0x2_0026;
/// The handles SYS_OPEN gives for `:tt` (stdout for reading/writing modes, stderr for
/// append modes, as the semihosting specification suggests).
const STDOUT: u32 = 1;
const STDERR: u32 = 2;
/// Longest string SYS_WRITE0 follows before giving up (a missing terminator).
const MAX_STRING: u32 = 1 << 16;

impl Cpu {
    /// Performs the semihosting call in R0/R1. Returns the exit code when the program
    /// exits.
    pub(crate) fn semihost<B: Bus>(&mut self, bus: &mut B) -> Result<Option<u32>, Fault> {
        let op = self.r[0];
        let arg = self.r[1];
        let result = match op {
            SYS_OPEN => {
                let name = self.load(bus, arg, Width::Word, false)?;
                let mode = self.load(bus, arg.wrapping_add(4), Width::Word, false)?;
                let tt = self.read_string(bus, name, 4)? == b":tt";
                match (tt, mode) {
                    (true, 8..=11) => STDERR,
                    (true, _) => STDOUT,
                    (false, _) => u32::MAX,
                }
            }
            SYS_CLOSE => 0,
            SYS_ISTTY => 1,
            SYS_WRITEC => {
                let c = self.load(bus, arg, Width::Byte, false)?;
                self.semihost_out.push(c as u8);
                self.r[0]
            }
            SYS_WRITE0 => {
                let s = self.read_string(bus, arg, MAX_STRING)?;
                self.semihost_out.extend_from_slice(&s);
                self.r[0]
            }
            SYS_WRITE => {
                let handle = self.load(bus, arg, Width::Word, false)?;
                let data = self.load(bus, arg.wrapping_add(4), Width::Word, false)?;
                let len = self.load(bus, arg.wrapping_add(8), Width::Word, false)?;
                if handle == STDOUT || handle == STDERR {
                    for i in 0..len.min(MAX_STRING) {
                        let b = self.load(bus, data.wrapping_add(i), Width::Byte, false)?;
                        self.semihost_out.push(b as u8);
                    }
                    0
                } else {
                    len
                }
            }
            SYS_EXIT => return Ok(Some(exit_code(arg, 0))),
            SYS_EXIT_EXTENDED => {
                let reason = self.load(bus, arg, Width::Word, false)?;
                let sub = self.load(bus, arg.wrapping_add(4), Width::Word, false)?;
                return Ok(Some(exit_code(reason, sub)));
            }
            _ => u32::MAX,
        };
        self.r[0] = result;
        Ok(None)
    }

    /// A NUL-terminated string of at most `max` bytes.
    fn read_string<B: Bus>(&mut self, bus: &mut B, addr: u32, max: u32) -> Result<Vec<u8>, Fault> {
        let mut out = Vec::new();
        for i in 0..max {
            let b = self.load(bus, addr.wrapping_add(i), Width::Byte, false)? as u8;
            if b == 0 {
                break;
            }
            out.push(b);
        }
        Ok(out)
    }
}

/// The exit status of SYS_EXIT (`reason`, 0 for the subcode) or SYS_EXIT_EXTENDED, as
/// QEMU reports it: the subcode for a normal exit, 1 for any other reason.
fn exit_code(reason: u32, subcode: u32) -> u32 {
    if reason == APPLICATION_EXIT {
        subcode
    } else {
        1
    }
}
