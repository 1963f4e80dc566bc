//! FPv4-SP instructions: the access check (`ExecuteFPCheck`: CPACR, automatic FP context
//! with FPCCR.ASPEN and FPDSCR), arithmetic through [`crate::softfloat`], conversions, moves,
//! loads and stores of S and D registers, VMRS/VMSR.

use super::Trap;
use crate::bus::{Bus, Width};
use crate::cpu::Cpu;
use crate::exception::{control, fpccr};
use crate::fault::Fault;
use crate::insn::{Insn, VCvtInt, VOp, VUnary};
use crate::softfloat as sf;

/// The FPSCR bits FPv4-SP implements.
pub(crate) const FPSCR_MASK: u32 = 0xF7C0_009F;
/// The FPSCR mode bits a new FP context takes from FPDSCR (AHP, DN, FZ, RMode).
const FPDSCR_BITS: u32 = 0x07C0_0000;

impl Cpu {
    /// `ExecuteFPCheck`: NOCP unless CPACR grants CP10; a first FP instruction with
    /// FPCCR.ASPEN starts an FP context (CONTROL.FPCA, FPSCR modes from FPDSCR).
    #[inline(always)]
    fn fp_check(&mut self) -> Result<(), Fault> {
        if self.fp_ready {
            return Ok(());
        }
        self.fp_check_slow()
    }

    #[inline(never)]
    fn fp_check_slow(&mut self) -> Result<(), Fault> {
        let allowed = match self.scb.cpacr >> 20 & 3 {
            0b11 => true,
            0b01 => self.privileged(),
            _ => false,
        };
        if !allowed {
            return Err(Fault::NoCp);
        }
        if self.scb.fpccr & fpccr::ASPEN != 0 && self.control & control::FPCA == 0 {
            self.fpscr = self.fpscr & !FPDSCR_BITS | self.scb.fpdscr & FPDSCR_BITS;
            self.control |= control::FPCA;
        }
        self.fp_ready = true;
        Ok(())
    }

    fn sreg(&self, n: u8) -> u32 {
        self.s.get(usize::from(n & 31)).copied().unwrap_or(0)
    }

    fn set_sreg(&mut self, n: u8, v: u32) {
        if let Some(s) = self.s.get_mut(usize::from(n & 31)) {
            *s = v;
        }
    }

    /// Two-operand arithmetic and the multiply-accumulates.
    #[inline(always)]
    pub(crate) fn exec_varith(&mut self, op: VOp, sd: u8, sn: u8, sm: u8) -> Result<(), Trap> {
        self.fp_check()?;
        let (d, n, m) = (self.sreg(sd), self.sreg(sn), self.sreg(sm));
        let neg = |v: u32| v ^ 0x8000_0000;
        let mut f = self.fpscr;
        let r = match op {
            VOp::Add => sf::add(n, m, &mut f),
            VOp::Sub => sf::sub(n, m, &mut f),
            VOp::Mul => sf::mul(n, m, &mut f),
            VOp::Nmul => neg(sf::mul(n, m, &mut f)),
            VOp::Div => sf::div(n, m, &mut f),
            VOp::Mla => {
                let p = sf::mul(n, m, &mut f);
                sf::add(d, p, &mut f)
            }
            VOp::Mls => {
                let p = sf::mul(n, m, &mut f);
                sf::add(d, neg(p), &mut f)
            }
            VOp::Nmla => {
                let p = sf::mul(n, m, &mut f);
                sf::add(neg(d), neg(p), &mut f)
            }
            VOp::Nmls => {
                let p = sf::mul(n, m, &mut f);
                sf::add(neg(d), p, &mut f)
            }
            VOp::Fma => sf::mul_add(d, n, m, &mut f),
            VOp::Fms => sf::mul_add(d, neg(n), m, &mut f),
            VOp::Fnma => sf::mul_add(neg(d), neg(n), m, &mut f),
            VOp::Fnms => sf::mul_add(neg(d), n, m, &mut f),
        };
        self.fpscr = f;
        self.set_sreg(sd, r);
        Ok(())
    }

    /// VLDR/VSTR.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn exec_vmem<B: Bus>(
        &mut self,
        bus: &mut B,
        load: bool,
        sd: u8,
        rn: u8,
        add: bool,
        words: u8,
        imm: u16,
    ) -> Result<(), Trap> {
        self.fp_check()?;
        let base = if rn == 15 {
            self.r[15] & !3
        } else {
            self.reg(rn)
        };
        let addr = if add {
            base.wrapping_add(u32::from(imm))
        } else {
            base.wrapping_sub(u32::from(imm))
        };
        self.transfer_s(bus, load, sd, words, addr)?;
        Ok(())
    }

    /// Loads or stores `count` consecutive S registers from `sd` at `addr`.
    fn transfer_s<B: Bus>(
        &mut self,
        bus: &mut B,
        load: bool,
        sd: u8,
        count: u8,
        addr: u32,
    ) -> Result<(), Fault> {
        for i in 0..count {
            let a = addr.wrapping_add(4 * u32::from(i));
            let r = sd.wrapping_add(i);
            if load {
                let v = self.load(bus, a, Width::Word, true)?;
                self.set_sreg(r, v);
            } else {
                self.store(bus, a, Width::Word, self.sreg(r), true)?;
            }
        }
        Ok(())
    }

    /// The other FP instructions.
    pub(crate) fn exec_fp_other<B: Bus>(&mut self, bus: &mut B, insn: Insn) -> Result<(), Trap> {
        self.fp_check()?;
        let mut f = self.fpscr;
        match insn {
            Insn::VUnary { op, sd, sm } => {
                let m = self.sreg(sm);
                let r = match op {
                    VUnary::Mov => m,
                    VUnary::Abs => m & 0x7FFF_FFFF,
                    VUnary::Neg => m ^ 0x8000_0000,
                    VUnary::Sqrt => sf::sqrt(m, &mut f),
                };
                self.set_sreg(sd, r);
            }
            Insn::VMovImm { sd, imm } => self.set_sreg(sd, imm),
            Insn::VCmp { sd, sm, zero, e } => {
                let m = if zero { 0 } else { self.sreg(sm) };
                let nzcv = sf::compare(self.sreg(sd), m, e, &mut f);
                f = f & 0x0FFF_FFFF | nzcv;
            }
            Insn::VCvt { op, sd, sm } => {
                let m = self.sreg(sm);
                let r = match op {
                    VCvtInt::FromS32 => sf::from_fixed(m, 0, false, 32, false, &mut f),
                    VCvtInt::FromU32 => sf::from_fixed(m, 0, true, 32, false, &mut f),
                    VCvtInt::ToS32(rz) => sf::to_fixed(m, 0, false, 32, rz, &mut f),
                    VCvtInt::ToU32(rz) => sf::to_fixed(m, 0, true, 32, rz, &mut f),
                };
                self.set_sreg(sd, r);
            }
            Insn::VCvtFixed {
                sd,
                to_fixed,
                unsigned,
                half,
                frac,
            } => {
                let v = self.sreg(sd);
                let size = if half { 16 } else { 32 };
                let frac = u32::from(frac);
                // To fixed point rounds toward zero, from fixed point to nearest, whatever
                // the FPSCR says.
                let r = if to_fixed {
                    sf::to_fixed(v, frac, unsigned, size, true, &mut f)
                } else {
                    sf::from_fixed(v, frac, unsigned, size, true, &mut f)
                };
                self.set_sreg(sd, r);
            }
            Insn::VCvtHalf {
                sd,
                sm,
                to_half,
                top,
            } => {
                let m = self.sreg(sm);
                let shift = if top { 16 } else { 0 };
                if to_half {
                    let h = sf::single_to_half(m, &mut f);
                    let d = self.sreg(sd) & !(0xFFFF << shift) | (h & 0xFFFF) << shift;
                    self.set_sreg(sd, d);
                } else {
                    let r = sf::half_to_single(m >> shift & 0xFFFF, &mut f);
                    self.set_sreg(sd, r);
                }
            }
            Insn::VMovCore { sn, rt, to_core } => {
                if to_core {
                    self.set_reg(rt, self.sreg(sn));
                } else {
                    self.set_sreg(sn, self.reg(rt));
                }
            }
            Insn::VMovPair {
                rt,
                rt2,
                sm,
                to_core,
            } => {
                if to_core {
                    self.set_reg(rt, self.sreg(sm));
                    self.set_reg(rt2, self.sreg(sm + 1));
                } else {
                    self.set_sreg(sm, self.reg(rt));
                    self.set_sreg(sm + 1, self.reg(rt2));
                }
            }
            Insn::Vmrs { rt } => {
                if rt == 15 {
                    self.flags.n = f >> 31 & 1 != 0;
                    self.flags.z = f >> 30 & 1 != 0;
                    self.flags.c = f >> 29 & 1 != 0;
                    self.flags.v = f >> 28 & 1 != 0;
                } else {
                    self.set_reg(rt, f);
                }
            }
            Insn::Vmsr { rt } => f = self.reg(rt) & FPSCR_MASK,
            Insn::VMulti {
                load,
                sd,
                count,
                rn,
                wback,
                db,
            } => {
                let base = self.reg(rn);
                let size = 4 * u32::from(count);
                let addr = if db { base.wrapping_sub(size) } else { base };
                self.transfer_s(bus, load, sd, count, addr)?;
                if wback {
                    let new = if db {
                        base.wrapping_sub(size)
                    } else {
                        base.wrapping_add(size)
                    };
                    self.set_reg(rn, new);
                }
            }
            _ => return Err(Fault::Undefined.into()),
        }
        self.fpscr = f;
        Ok(())
    }
}
