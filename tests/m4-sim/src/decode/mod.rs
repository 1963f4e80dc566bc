//! Thumb instruction decoding (ARMv7-M ARM, DDI 0403E, chapters A5–A7) into the core's
//! decoded form: the 16-bit encodings (`thumb16`), the 32-bit ones (`thumb32`, `memory`) and
//! the floating-point extension (`vfp`). UNDEFINED and UNPREDICTABLE encodings both decode
//! to "undefined" (the core raises UsageFault UNDEFINSTR for them); [`is_defined`] tells
//! which encodings decode, for the coverage check over firmware images.

mod memory;
mod thumb16;
mod thumb32;
mod vfp;

use crate::insn::Insn;

/// Bits `hi..=lo` of `v`, right-aligned.
#[inline]
pub(crate) const fn bits(v: u32, hi: u32, lo: u32) -> u32 {
    (v >> lo) & ((1u32 << (hi - lo + 1)) - 1)
}

/// Bit `n` of `v`.
#[inline]
pub(crate) const fn bit(v: u32, n: u32) -> bool {
    (v >> n) & 1 != 0
}

/// Register field `hi..=lo` (4 bits or fewer) as a register number.
#[inline]
pub(crate) const fn reg(v: u32, lo: u32) -> u8 {
    ((v >> lo) & 0xF) as u8
}

/// Sign-extends the low `width` bits of `v`.
#[inline]
pub(crate) const fn sign_extend(v: u32, width: u32) -> u32 {
    let shift = 32 - width;
    (((v << shift) as i32) >> shift) as u32
}

/// Whether `hw1` starts a 32-bit instruction.
#[inline]
pub const fn is_32bit(hw1: u16) -> bool {
    (hw1 >> 11) >= 0b11101
}

/// Decodes the instruction at `addr` whose first halfword is `hw1` and, for a 32-bit
/// instruction, second halfword `hw2`. Returns the instruction and its length in bytes.
pub(crate) fn decode(hw1: u16, hw2: u16, addr: u32) -> (Insn, u8) {
    if is_32bit(hw1) {
        (thumb32::decode(u32::from(hw1), u32::from(hw2), addr), 4)
    } else {
        (thumb16::decode(u32::from(hw1), addr), 2)
    }
}

/// Whether the instruction `hw1`(`hw2`) decodes to something other than UNDEFINED, and its
/// length in bytes: the decode-coverage check over firmware images uses this.
pub fn is_defined(hw1: u16, hw2: u16) -> (bool, u8) {
    let (insn, len) = decode(hw1, hw2, 0);
    (insn != Insn::Undefined, len)
}

/// `ThumbExpandImm_C` (A5.3.2): the 32-bit immediate of a modified-immediate encoding and
/// whether it also sets the carry; `None` for the UNPREDICTABLE zero replications.
pub(crate) fn thumb_expand_imm(imm12: u32) -> Option<(u32, crate::insn::ImmCarry)> {
    use crate::insn::ImmCarry;
    let imm8 = imm12 & 0xFF;
    if bits(imm12, 11, 10) == 0 {
        let v = match bits(imm12, 9, 8) {
            0 => imm8,
            1 => (imm8 << 16) | imm8,
            2 => (imm8 << 24) | (imm8 << 8),
            _ => imm8 * 0x0101_0101,
        };
        if bits(imm12, 9, 8) != 0 && imm8 == 0 {
            return None;
        }
        Some((v, ImmCarry::Keep))
    } else {
        let unrotated = 0x80 | (imm12 & 0x7F);
        Some((unrotated.rotate_right(bits(imm12, 11, 7)), ImmCarry::Bit31))
    }
}

/// `DecodeImmShift` (A7.4.2): shift type and amount from the 2-bit type and 5-bit immediate.
pub(crate) fn decode_imm_shift(ty: u32, imm5: u32) -> (crate::insn::Shift, u8) {
    use crate::insn::Shift;
    let amount = imm5 as u8;
    match ty {
        0 => (Shift::Lsl, amount),
        1 => (Shift::Lsr, if amount == 0 { 32 } else { amount }),
        2 => (Shift::Asr, if amount == 0 { 32 } else { amount }),
        _ if amount == 0 => (Shift::Rrx, 1),
        _ => (Shift::Ror, amount),
    }
}

/// `Align(PC, 4)` as an instruction at `addr` reads it.
#[inline]
pub(crate) const fn pc_aligned(addr: u32) -> u32 {
    addr.wrapping_add(4) & !3
}

#[cfg(test)]
mod tests;
