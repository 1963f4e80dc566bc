//! Executing decoded instructions: the dispatch ([`Cpu::exec`]), register access with the
//! PC and SP rules, condition codes and the IT state. The instruction groups are in
//! [`alu`] (data processing), [`dsp`] (multiplies and the DSP extension), [`memory`]
//! (loads and stores), [`control`] (branches and system instructions) and [`fp`] (FPv4).

pub(crate) mod alu;
pub(crate) mod control;
pub(crate) mod dsp;
pub(crate) mod fp;
pub(crate) mod memory;

use crate::bus::Bus;
use crate::cpu::{Cpu, Stop};
use crate::fault::Fault;
use crate::insn::{Insn, Sf};

/// Why an instruction did not simply complete.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Trap {
    /// A synchronous fault: the instruction did not complete.
    Fault(Fault),
    /// The instruction completed and the run stops (semihosting exit, breakpoint).
    Stop(Stop),
}

impl From<Fault> for Trap {
    fn from(f: Fault) -> Self {
        Trap::Fault(f)
    }
}

/// `ITAdvance`: the ITSTATE after one instruction of the block.
#[inline(always)]
pub(crate) const fn it_advance(it: u8) -> u8 {
    if it & 0x7 == 0 {
        0
    } else {
        (it & 0xE0) | ((it << 1) & 0x1F)
    }
}

impl Cpu {
    /// R[n] as an instruction reads it (R15: the instruction's address + 4).
    #[inline(always)]
    pub(crate) fn reg(&self, n: u8) -> u32 {
        self.r.get(usize::from(n & 15)).copied().unwrap_or(0)
    }

    /// Writes R[d]: SP keeps bits 1:0 clear, a write to the PC is a branch
    /// (`ALUWritePC`/`BranchWritePC`).
    #[inline(always)]
    pub(crate) fn set_reg(&mut self, d: u8, v: u32) {
        match d {
            0..=12 | 14 => {
                if let Some(r) = self.r.get_mut(usize::from(d)) {
                    *r = v;
                }
            }
            13 => {
                self.r[13] = v & !3;
                self.note_sp(v & !3);
            }
            _ => self.branch(v),
        }
    }

    /// `BranchWritePC`.
    #[inline(always)]
    pub(crate) fn branch(&mut self, target: u32) {
        self.next_pc = target & !1;
        self.refill = true;
    }

    /// `BXWritePC`: interworking branch, or exception return in Handler mode.
    pub(crate) fn bx_write_pc<B: Bus>(&mut self, bus: &mut B, target: u32) -> Result<(), Fault> {
        if self.ipsr != 0 && target >> 28 == 0xF {
            return self.exception_return(bus, target);
        }
        self.thumb = target & 1 != 0;
        if !self.thumb {
            self.stop_at = 0;
        }
        self.branch(target);
        Ok(())
    }

    /// Whether the flags update: per the encoding and the IT state.
    #[inline(always)]
    pub(crate) fn sets_flags(&self, s: Sf) -> bool {
        match s {
            Sf::No => false,
            Sf::Yes => true,
            Sf::OutsideIt => !self.in_it,
        }
    }

    /// `ConditionPassed` for a 4-bit condition.
    #[inline(always)]
    pub(crate) fn cond_passed(&self, cond: u8) -> bool {
        let f = &self.flags;
        let result = match cond >> 1 {
            0 => f.z,
            1 => f.c,
            2 => f.n,
            3 => f.v,
            4 => f.c && !f.z,
            5 => f.n == f.v,
            6 => f.n == f.v && !f.z,
            _ => true,
        };
        if cond & 1 != 0 && cond != 0xF {
            !result
        } else {
            result
        }
    }

    /// Sets N and Z from a result.
    #[inline(always)]
    pub(crate) fn set_nz(&mut self, result: u32) {
        self.flags.n = result >> 31 != 0;
        self.flags.z = result == 0;
    }

    /// Executes one decoded instruction (its condition has passed). Inline in the run
    /// loop's step: a call per instruction costs more than the hot arms themselves.
    #[inline(always)]
    pub(crate) fn exec<B: Bus>(&mut self, bus: &mut B, insn: Insn) -> Result<(), Trap> {
        match insn {
            Insn::DpImm {
                op,
                s,
                rd,
                rn,
                carry,
                imm,
            } => {
                let c = match carry {
                    crate::insn::ImmCarry::Keep => self.flags.c,
                    crate::insn::ImmCarry::Bit31 => imm >> 31 != 0,
                };
                let setflags = self.sets_flags(s);
                self.data_processing(op, setflags, rd, self.reg(rn), imm, c);
            }
            Insn::DpReg {
                op,
                s,
                rd,
                rn,
                rm,
                shift,
                amount,
            } => {
                let (b, c) = alu::shift_c(self.reg(rm), shift, u32::from(amount), self.flags.c);
                let setflags = self.sets_flags(s);
                self.data_processing(op, setflags, rd, self.reg(rn), b, c);
            }
            Insn::ShiftReg {
                shift,
                s,
                rd,
                rn,
                rm,
            } => {
                let amount = self.reg(rm) & 0xFF;
                let (v, c) = alu::shift_c(self.reg(rn), shift, amount, self.flags.c);
                self.set_reg(rd, v);
                if self.sets_flags(s) {
                    self.set_nz(v);
                    self.flags.c = c;
                }
            }
            Insn::MemImm {
                op,
                rt,
                rn,
                index,
                add,
                user,
                imm,
            } => self.exec_mem_imm(bus, op, rt, rn, index, add, user, imm)?,
            Insn::MemReg {
                op,
                rt,
                rn,
                rm,
                amount,
            } => {
                let addr = self.reg(rn).wrapping_add(self.reg(rm) << amount);
                self.exec_mem_at(bus, op, rt, addr, rn, rm)?;
            }
            Insn::MemLit { op, rt, addr } => self.exec_mem_at(bus, op, rt, addr, 15, 15)?,
            Insn::B { target } => self.branch(target),
            Insn::BCond { cond, target } => {
                if self.in_it {
                    return Err(Fault::Undefined.into());
                }
                if self.cond_passed(cond) {
                    self.branch(target);
                }
            }
            Insn::Bl { target } => {
                self.r[14] = self.next_pc | 1;
                self.branch(target);
            }
            Insn::Bx { rm } => {
                let target = self.reg(rm);
                self.bx_write_pc(bus, target)?;
            }
            Insn::BlxReg { rm } => {
                let target = self.reg(rm);
                self.r[14] = self.next_pc | 1;
                self.thumb = target & 1 != 0;
                if !self.thumb {
                    self.stop_at = 0;
                }
                self.branch(target);
            }
            Insn::Cbz {
                rn,
                nonzero,
                target,
            } => {
                if self.in_it {
                    return Err(Fault::Undefined.into());
                }
                if (self.reg(rn) != 0) == nonzero {
                    self.branch(target);
                }
            }
            Insn::Multi {
                load,
                rn,
                regs,
                wback,
                db,
            } => self.exec_multi(bus, load, rn, regs, wback, db)?,
            Insn::It { state } => {
                if self.in_it {
                    return Err(Fault::Undefined.into());
                }
                self.it = state;
            }
            Insn::MovT { rd, imm } => {
                let v = self.reg(rd) & 0xFFFF | u32::from(imm) << 16;
                self.set_reg(rd, v);
            }
            Insn::VArith { op, sd, sn, sm } => self.exec_varith(op, sd, sn, sm)?,
            Insn::VMem {
                load,
                sd,
                rn,
                add,
                words,
                imm,
            } => self.exec_vmem(bus, load, sd, rn, add, words, imm)?,
            other => self.exec_rest(bus, other)?,
        }
        Ok(())
    }

    /// The less frequent instructions (kept out of `exec` so its hot arms stay compact).
    #[inline(never)]
    fn exec_rest<B: Bus>(&mut self, bus: &mut B, insn: Insn) -> Result<(), Trap> {
        match insn {
            Insn::Empty | Insn::Undefined | Insn::Udf => return Err(Fault::Undefined.into()),
            Insn::NoCoprocessor => return Err(Fault::NoCp.into()),
            Insn::Nop | Insn::Barrier => {}
            Insn::Clrex => self.exclusive = false,
            Insn::Wfi => self.sleep(bus, crate::cpu::RunState::SleepWfi),
            Insn::Wfe => {
                if self.event {
                    self.event = false;
                } else {
                    self.sleep(bus, crate::cpu::RunState::SleepWfe);
                }
            }
            Insn::Sev => {
                self.event = true;
            }
            Insn::Bkpt { imm } => return self.exec_bkpt(bus, imm),
            Insn::Svc => {
                // SVCall is taken after the SVC completes (return address: the next
                // instruction).
                self.pend_synchronous(crate::nvic::exc::SVCALL);
            }
            Insn::Cps {
                disable,
                primask,
                faultmask,
            } => self.exec_cps(disable, primask, faultmask),
            Insn::Mrs { rd, sysm } => {
                let v = self.read_special(sysm);
                self.set_reg(rd, v);
            }
            Insn::Msr { rn, sysm, mask } => self.write_special(sysm, mask, self.reg(rn)),
            Insn::Tbb { rn, rm, half } => {
                let base = self.reg(rn);
                let index = self.reg(rm);
                let offset = if half {
                    self.load(
                        bus,
                        base.wrapping_add(index << 1),
                        crate::Width::Half,
                        false,
                    )?
                } else {
                    self.load(bus, base.wrapping_add(index), crate::Width::Byte, false)?
                };
                let target = self.r[15].wrapping_add(offset << 1);
                self.branch(target);
            }
            Insn::Bfi { rd, rn, lsb, msb } => {
                let mask = alu::bit_mask(lsb, msb);
                let v = self.reg(rd) & !mask | (self.reg(rn) << lsb) & mask;
                self.set_reg(rd, v);
            }
            Insn::Bfc { rd, lsb, msb } => {
                let v = self.reg(rd) & !alu::bit_mask(lsb, msb);
                self.set_reg(rd, v);
            }
            Insn::Bfx {
                rd,
                rn,
                lsb,
                width,
                signed,
            } => {
                let v = alu::extract(self.reg(rn), lsb, width, signed);
                self.set_reg(rd, v);
            }
            Insn::Clz { rd, rm } => self.set_reg(rd, self.reg(rm).leading_zeros()),
            Insn::Rev { op, rd, rm } => self.set_reg(rd, alu::reverse(op, self.reg(rm))),
            Insn::Extend {
                ext,
                rd,
                rn,
                rm,
                rot,
            } => {
                let add = if rn == 15 { None } else { Some(self.reg(rn)) };
                let v = dsp::extend(ext, self.reg(rm).rotate_right(u32::from(rot)), add);
                self.set_reg(rd, v);
            }
            Insn::Dual64 {
                load,
                rt,
                rt2,
                rn,
                index,
                add,
                imm,
            } => self.exec_dual(bus, load, rt, rt2, rn, index, add, imm)?,
            Insn::Dual64Lit { rt, rt2, addr } => {
                let lo = self.load(bus, addr, crate::Width::Word, true)?;
                let hi = self.load(bus, addr.wrapping_add(4), crate::Width::Word, true)?;
                self.set_reg(rt, lo);
                self.set_reg(rt2, hi);
            }
            Insn::Ldrex { rt, rn, imm, bytes } => self.exec_ldrex(bus, rt, rn, imm, bytes)?,
            Insn::Strex {
                rd,
                rt,
                rn,
                imm,
                bytes,
            } => self.exec_strex(bus, rd, rt, rn, imm, bytes)?,
            Insn::VUnary { .. }
            | Insn::VMovImm { .. }
            | Insn::VCmp { .. }
            | Insn::VCvt { .. }
            | Insn::VCvtFixed { .. }
            | Insn::VCvtHalf { .. }
            | Insn::VMovCore { .. }
            | Insn::VMovPair { .. }
            | Insn::Vmrs { .. }
            | Insn::Vmsr { .. }
            | Insn::VMulti { .. } => self.exec_fp_other(bus, insn)?,
            other => self.exec_dsp(other)?,
        }
        Ok(())
    }
}
