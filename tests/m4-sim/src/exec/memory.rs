//! Loads and stores: single, dual, multiple and exclusive, with writeback, loads into the
//! PC (interworking, exception return) and load pipelining in the cycle model.

use super::Trap;
use crate::bus::{Bus, Width};
use crate::cpu::Cpu;
use crate::fault::Fault;
use crate::insn::{Index, MemOp};

/// Access width of a single load or store.
fn width(op: MemOp) -> Width {
    match op {
        MemOp::Ldr | MemOp::Str => Width::Word,
        MemOp::Ldrh | MemOp::Ldrsh | MemOp::Strh => Width::Half,
        MemOp::Ldrb | MemOp::Ldrsb | MemOp::Strb => Width::Byte,
    }
}

impl Cpu {
    /// LDR/STR (immediate), all index forms.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn exec_mem_imm<B: Bus>(
        &mut self,
        bus: &mut B,
        op: MemOp,
        rt: u8,
        rn: u8,
        index: Index,
        add: bool,
        _user: bool,
        imm: u16,
    ) -> Result<(), Trap> {
        let base = self.reg(rn);
        let offset_addr = if add {
            base.wrapping_add(u32::from(imm))
        } else {
            base.wrapping_sub(u32::from(imm))
        };
        let addr = if index == Index::Post {
            base
        } else {
            offset_addr
        };
        if index == Index::Offset {
            return self.exec_mem_at(bus, op, rt, addr, rn, rn);
        }
        if op.is_store() {
            self.store(bus, addr, width(op), self.reg(rt), false)?;
            self.set_reg(rn, offset_addr);
            self.last_load.0 = u64::MAX;
        } else {
            let v = self.load_value(bus, op, addr)?;
            self.set_reg(rn, offset_addr);
            self.write_loaded(bus, rt, v)?;
        }
        Ok(())
    }

    /// A single load or store at `addr` without writeback; `rn`/`rm` are the registers the
    /// address came from (for the pipelining rule).
    #[inline(always)]
    pub(crate) fn exec_mem_at<B: Bus>(
        &mut self,
        bus: &mut B,
        op: MemOp,
        rt: u8,
        addr: u32,
        rn: u8,
        rm: u8,
    ) -> Result<(), Trap> {
        if op.is_store() {
            self.store(bus, addr, width(op), self.reg(rt), false)?;
            return Ok(());
        }
        // A load right behind a load whose result does not form this address pipelines:
        // one cycle instead of two.
        let (at, prev_rt) = self.last_load;
        if at == self.stats.instructions.wrapping_sub(1) && prev_rt != rn && prev_rt != rm {
            self.clock.cycles -= 1;
        }
        let v = self.load_value(bus, op, addr)?;
        self.last_load = (self.stats.instructions, rt);
        self.write_loaded(bus, rt, v)
    }

    /// A load with its extension.
    #[inline(always)]
    fn load_value<B: Bus>(&mut self, bus: &mut B, op: MemOp, addr: u32) -> Result<u32, Fault> {
        let v = self.load(bus, addr, width(op), false)?;
        Ok(match op {
            MemOp::Ldrsh => v as u16 as i16 as i32 as u32,
            MemOp::Ldrsb => v as u8 as i8 as i32 as u32,
            _ => v,
        })
    }

    /// Writes a loaded value: into the PC it is `LoadWritePC` (interworking, exception
    /// return).
    #[inline(always)]
    fn write_loaded<B: Bus>(&mut self, bus: &mut B, rt: u8, v: u32) -> Result<(), Trap> {
        if rt == 15 {
            self.bx_write_pc(bus, v)?;
        } else {
            self.set_reg(rt, v);
        }
        Ok(())
    }

    /// LDM/STM/PUSH/POP.
    pub(crate) fn exec_multi<B: Bus>(
        &mut self,
        bus: &mut B,
        load: bool,
        rn: u8,
        regs: u16,
        wback: bool,
        db: bool,
    ) -> Result<(), Trap> {
        let base = self.reg(rn);
        let size = 4 * regs.count_ones();
        let start = if db { base.wrapping_sub(size) } else { base };
        let end = if db {
            base.wrapping_sub(size)
        } else {
            base.wrapping_add(size)
        };
        let mut addr = start;
        if load {
            let mut pc = None;
            for r in 0..16u8 {
                if regs >> r & 1 == 0 {
                    continue;
                }
                let v = self.load(bus, addr, Width::Word, true)?;
                if r == 15 {
                    pc = Some(v);
                } else if !(wback && r == rn) {
                    self.set_reg(r, v);
                }
                addr = addr.wrapping_add(4);
            }
            if wback {
                self.set_reg(rn, end);
            }
            if let Some(v) = pc {
                self.bx_write_pc(bus, v)?;
            }
        } else {
            // Check the whole range before storing anything, so a fault leaves memory as it
            // was (the frame a PUSH builds is written in one go).
            if start & 3 != 0 {
                return Err(Fault::Unaligned.into());
            }
            for r in 0..16u8 {
                if regs >> r & 1 == 0 {
                    continue;
                }
                let v = self.reg(r);
                self.store(bus, addr, Width::Word, v, true)?;
                addr = addr.wrapping_add(4);
            }
            if wback {
                self.set_reg(rn, end);
            }
        }
        Ok(())
    }

    /// LDRD/STRD (immediate).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn exec_dual<B: Bus>(
        &mut self,
        bus: &mut B,
        load: bool,
        rt: u8,
        rt2: u8,
        rn: u8,
        index: Index,
        add: bool,
        imm: u16,
    ) -> Result<(), Trap> {
        let base = if rn == 15 {
            self.r[15] & !3
        } else {
            self.reg(rn)
        };
        let offset_addr = if add {
            base.wrapping_add(u32::from(imm))
        } else {
            base.wrapping_sub(u32::from(imm))
        };
        let addr = if index == Index::Post {
            base
        } else {
            offset_addr
        };
        if load {
            let lo = self.load(bus, addr, Width::Word, true)?;
            let hi = self.load(bus, addr.wrapping_add(4), Width::Word, true)?;
            self.set_reg(rt, lo);
            self.set_reg(rt2, hi);
        } else {
            let (lo, hi) = (self.reg(rt), self.reg(rt2));
            self.store(bus, addr, Width::Word, lo, true)?;
            self.store(bus, addr.wrapping_add(4), Width::Word, hi, true)?;
        }
        if index != Index::Offset {
            self.set_reg(rn, offset_addr);
        }
        Ok(())
    }

    /// LDREX/LDREXB/LDREXH: the load marks the local monitor exclusive.
    pub(crate) fn exec_ldrex<B: Bus>(
        &mut self,
        bus: &mut B,
        rt: u8,
        rn: u8,
        imm: u16,
        bytes: u8,
    ) -> Result<(), Trap> {
        let addr = self.reg(rn).wrapping_add(u32::from(imm));
        let v = self.load(bus, addr, exclusive_width(bytes), true)?;
        self.exclusive = true;
        self.set_reg(rt, v);
        Ok(())
    }

    /// STREX/STREXB/STREXH: stores only while the local monitor is exclusive (the
    /// Cortex-M4's monitor does not compare addresses), and always clears it.
    pub(crate) fn exec_strex<B: Bus>(
        &mut self,
        bus: &mut B,
        rd: u8,
        rt: u8,
        rn: u8,
        imm: u16,
        bytes: u8,
    ) -> Result<(), Trap> {
        let addr = self.reg(rn).wrapping_add(u32::from(imm));
        let w = exclusive_width(bytes);
        if addr & (w.bytes() - 1) != 0 {
            return Err(Fault::Unaligned.into());
        }
        if self.exclusive {
            self.store(bus, addr, w, self.reg(rt), true)?;
            self.set_reg(rd, 0);
        } else {
            self.set_reg(rd, 1);
        }
        self.exclusive = false;
        Ok(())
    }
}

fn exclusive_width(bytes: u8) -> Width {
    match bytes {
        1 => Width::Byte,
        2 => Width::Half,
        _ => Width::Word,
    }
}
