//! The cycle model: base cycles per instruction from the Cortex-M4 TRM (DDI 0439B, table
//! 3-1 "Cortex-M4 instruction set summary", and §3.3.2 "Load/store timings") and the
//! Cortex-M4 FPU TRM (table "FPU instruction set"), with zero-wait-state memory. The
//! executor adds what depends on the operands: a taken branch's pipeline refill (P),
//! the register count of LDM/STM, division's early termination, load pipelining. Wait
//! states come from the bus ([`crate::Bus::fetch_stall`], [`crate::Bus::access_stall`]).
//! The README lists where this is approximate.

use crate::insn::{Insn, VOp, VUnary};

/// P, the pipeline refill after a taken branch: the TRM gives 1–3 cycles "depending on the
/// alignment and width of the target instruction"; we take 2, and 3 for a 32-bit target at
/// a halfword (not word) aligned address (its fetch needs two bus words).
pub(crate) const fn refill(target: u32, len: u8) -> u64 {
    if len == 4 && target & 2 != 0 { 3 } else { 2 }
}

/// Exception entry: 12 cycles from the request to the first handler instruction with
/// zero-wait-state stacking (TRM §5.5 "Exception handling": latency), the FP extended frame
/// with lazy stacking (FPCCR.LSPEN) reserving its space in the same time.
pub(crate) const ENTRY: u64 = 12;
/// Extra entry cycles when the FP frame is stacked at once (FPCCR.LSPEN = 0): 18 more
/// words.
pub(crate) const ENTRY_FP_EAGER: u64 = 17;
/// Exception return (unstacking and refill), 10 cycles (TRM §5.5).
pub(crate) const RETURN: u64 = 10;
/// Extra return cycles when the FP part of the frame is restored.
pub(crate) const RETURN_FP: u64 = 17;
/// Tail-chaining from one handler into the next, 6 cycles (TRM §5.5).
pub(crate) const TAIL_CHAIN: u64 = 6;

/// The cycles of an instruction that do not depend on its operands.
pub(crate) fn base(insn: &Insn) -> u8 {
    match insn {
        Insn::MemImm { op, .. } | Insn::MemReg { op, .. } | Insn::MemLit { op, .. } => {
            // Loads take 2 (1 when pipelined behind another load: the executor takes one
            // off); a store is 1 ("STR Rx,[Ry,#imm] is always one cycle").
            if op.is_store() { 1 } else { 2 }
        }
        Insn::Dual64 { .. } | Insn::Dual64Lit { .. } => 3,
        Insn::Ldrex { .. } | Insn::Strex { .. } => 2,
        Insn::Multi { regs, .. } => 1 + regs.count_ones() as u8,
        Insn::Tbb { .. } => 2,
        Insn::Div { .. } => 2,
        // ISB flushes the pipeline; DMB/DSB wait for the (empty) write buffer.
        Insn::Barrier => 2,
        Insn::VArith { op, .. } => match op {
            VOp::Add | VOp::Sub | VOp::Mul | VOp::Nmul => 1,
            VOp::Div => 14,
            _ => 3,
        },
        Insn::VUnary {
            op: VUnary::Sqrt, ..
        } => 14,
        Insn::VMovCore { to_core, .. } => {
            if *to_core {
                1
            } else {
                2
            }
        }
        Insn::VMovPair { .. } => 2,
        Insn::Vmsr { .. } => 2,
        Insn::VMem { words, .. } => 1 + *words,
        Insn::VMulti { count, .. } => 1 + *count,
        _ => 1,
    }
}

/// SDIV/UDIV: 2–12 cycles with early termination on the operands' magnitudes. Modelled as
/// 2 when the quotient is 0 or the divisor 0, else 4 + ⌈q/4⌉ for a quotient of q
/// significant bits (the TRM gives only the range).
pub(crate) fn divide(dividend: u32, divisor: u32) -> u64 {
    if divisor == 0 || divisor > dividend {
        return 2;
    }
    let q_bits = (divisor.leading_zeros() - dividend.leading_zeros() + 1).min(32);
    u64::from(4 + q_bits.div_ceil(4)).min(12)
}
