//! The decoded form of one instruction: what the decoder produces once per code address and
//! the executor runs every time. Operands are resolved as far as the encoding allows
//! (immediates expanded, PC-relative addresses made absolute, shifts decoded), so executing
//! is a match on [`Insn`] and a few register reads.

/// A data-processing operation of the general ALU group (ARM ARM A5.3.1/A5.3.11, A5.2.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DpOp {
    And,
    Bic,
    Orr,
    Orn,
    Eor,
    Add,
    Adc,
    Sub,
    Sbc,
    Rsb,
    Mov,
    Mvn,
    Tst,
    Teq,
    Cmp,
    Cmn,
}

/// Whether an instruction updates the flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sf {
    /// Never (32-bit encodings with S = 0).
    No,
    /// Always (S = 1, compares).
    Yes,
    /// Outside an IT block only (most 16-bit encodings).
    OutsideIt,
}

/// The carry out of an expanded modified immediate (`ThumbExpandImm_C`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImmCarry {
    /// The immediate was not rotated: C is unchanged.
    Keep,
    /// Rotated: C becomes bit 31 of the immediate.
    Bit31,
}

/// A shift type (`DecodeImmShift`, `DecodeRegShift`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shift {
    Lsl,
    Lsr,
    Asr,
    Ror,
    /// Rotate right by one through the carry.
    Rrx,
}

/// Width and sign of a single load or store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemOp {
    Ldr,
    Ldrh,
    Ldrsh,
    Ldrb,
    Ldrsb,
    Str,
    Strh,
    Strb,
}

impl MemOp {
    /// A store (true) or a load.
    pub const fn is_store(self) -> bool {
        matches!(self, MemOp::Str | MemOp::Strh | MemOp::Strb)
    }
}

/// How an immediate-offset access forms its address and updates its base.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Index {
    /// `[Rn, #off]`: no writeback.
    Offset,
    /// `[Rn, #off]!`: access at Rn+off, Rn := Rn+off.
    Pre,
    /// `[Rn], #off`: access at Rn, Rn := Rn+off.
    Post,
}

/// The sign- and zero-extensions (SXTB … UXTAB16).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ext {
    Sxtb,
    Sxth,
    Uxtb,
    Uxth,
    Sxtb16,
    Uxtb16,
}

/// Byte and bit reversals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reverse {
    Rev,
    Rev16,
    Revsh,
    Rbit,
}

/// The arithmetic of a parallel add/subtract (A5.3.13), lane size and direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParOp {
    Add16,
    Asx,
    Sax,
    Sub16,
    Add8,
    Sub8,
}

/// The flavour of a parallel add/subtract: plain (sets GE), saturating or halving, signed
/// or unsigned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParKind {
    S,
    Q,
    Sh,
    U,
    Uq,
    Uh,
}

/// QADD, QSUB, QDADD, QDSUB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QOp {
    Add,
    Sub,
    Dadd,
    Dsub,
}

/// The 32×32 → 64 multiplies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LongMul {
    Smull,
    Umull,
    Smlal,
    Umlal,
    Umaal,
}

/// Two-operand floating-point arithmetic (and the multiply-accumulates, which also read Sd).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VOp {
    Add,
    Sub,
    Mul,
    Nmul,
    Div,
    /// Sd + Sn*Sm, product rounded.
    Mla,
    /// Sd - Sn*Sm, product rounded.
    Mls,
    /// -Sd - Sn*Sm, product rounded.
    Nmla,
    /// -Sd + Sn*Sm, product rounded.
    Nmls,
    /// Sd + Sn*Sm fused.
    Fma,
    /// Sd - Sn*Sm fused.
    Fms,
    /// -Sd - Sn*Sm fused.
    Fnma,
    /// -Sd + Sn*Sm fused.
    Fnms,
}

/// One-operand floating-point operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VUnary {
    Mov,
    Abs,
    Neg,
    Sqrt,
}

/// Conversions between single precision and 32-bit integers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VCvtInt {
    /// From a signed integer.
    FromS32,
    /// From an unsigned integer.
    FromU32,
    /// To a signed integer; `true` rounds toward zero, `false` uses FPSCR's mode (VCVTR).
    ToS32(bool),
    /// To an unsigned integer, as `ToS32`.
    ToU32(bool),
}

/// A decoded instruction. Register fields are numbers 0–15 (core) or 0–31 (S registers);
/// `15` in an optional accumulator field means "none".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Insn {
    /// Not yet decoded (the cache's empty slot).
    Empty,
    /// UNDEFINED or UNPREDICTABLE: UsageFault UNDEFINSTR.
    Undefined,
    /// UDF, the permanently undefined instruction (what `trap` compiles to): a defined
    /// encoding whose execution is a UsageFault UNDEFINSTR.
    Udf,
    /// A coprocessor instruction for a coprocessor the core does not have: UsageFault NOCP.
    NoCoprocessor,
    /// NOP, YIELD, unallocated hints, PLD/PLI.
    Nop,
    /// DMB, DSB, ISB.
    Barrier,
    Clrex,
    Wfi,
    Wfe,
    Sev,
    /// IT: `firstcond:mask` as the ITSTATE byte it loads.
    It {
        state: u8,
    },
    Bkpt {
        imm: u8,
    },
    Svc,
    Cps {
        disable: bool,
        primask: bool,
        faultmask: bool,
    },
    Mrs {
        rd: u8,
        sysm: u8,
    },
    Msr {
        rn: u8,
        sysm: u8,
        mask: u8,
    },

    B {
        target: u32,
    },
    BCond {
        cond: u8,
        target: u32,
    },
    Bl {
        target: u32,
    },
    Bx {
        rm: u8,
    },
    BlxReg {
        rm: u8,
    },
    Cbz {
        rn: u8,
        nonzero: bool,
        target: u32,
    },
    Tbb {
        rn: u8,
        rm: u8,
        half: bool,
    },

    DpImm {
        op: DpOp,
        s: Sf,
        rd: u8,
        rn: u8,
        carry: ImmCarry,
        imm: u32,
    },
    DpReg {
        op: DpOp,
        s: Sf,
        rd: u8,
        rn: u8,
        rm: u8,
        shift: Shift,
        amount: u8,
    },
    /// LSL/LSR/ASR/ROR by a register (`Rd = Rn shift Rm<7:0>`).
    ShiftReg {
        shift: Shift,
        s: Sf,
        rd: u8,
        rn: u8,
        rm: u8,
    },
    MovT {
        rd: u8,
        imm: u16,
    },
    Bfi {
        rd: u8,
        rn: u8,
        lsb: u8,
        msb: u8,
    },
    Bfc {
        rd: u8,
        lsb: u8,
        msb: u8,
    },
    Bfx {
        rd: u8,
        rn: u8,
        lsb: u8,
        width: u8,
        signed: bool,
    },
    /// SSAT/USAT: saturate `Rn shifted` to `sat` bits.
    Sat {
        rd: u8,
        rn: u8,
        sat: u8,
        shift: Shift,
        amount: u8,
        unsigned: bool,
    },
    Sat16 {
        rd: u8,
        rn: u8,
        sat: u8,
        unsigned: bool,
    },
    /// SXTB … UXTAB16; `rn == 15` for the forms without an addend.
    Extend {
        ext: Ext,
        rd: u8,
        rn: u8,
        rm: u8,
        rot: u8,
    },
    Rev {
        op: Reverse,
        rd: u8,
        rm: u8,
    },
    Clz {
        rd: u8,
        rm: u8,
    },
    /// PKHBT (`tb == false`) / PKHTB.
    Pkh {
        rd: u8,
        rn: u8,
        rm: u8,
        tb: bool,
        amount: u8,
    },
    Parallel {
        op: ParOp,
        kind: ParKind,
        rd: u8,
        rn: u8,
        rm: u8,
    },
    QArith {
        op: QOp,
        rd: u8,
        rn: u8,
        rm: u8,
    },
    Sel {
        rd: u8,
        rn: u8,
        rm: u8,
    },
    /// USAD8 (`ra == 15`) / USADA8.
    Usad8 {
        rd: u8,
        rn: u8,
        rm: u8,
        ra: u8,
    },

    Mul {
        s: Sf,
        rd: u8,
        rn: u8,
        rm: u8,
    },
    /// MLA (`sub == false`) / MLS.
    Mla {
        rd: u8,
        rn: u8,
        rm: u8,
        ra: u8,
        sub: bool,
    },
    MulLong {
        op: LongMul,
        lo: u8,
        hi: u8,
        rn: u8,
        rm: u8,
    },
    Div {
        rd: u8,
        rn: u8,
        rm: u8,
        signed: bool,
    },
    /// SMULxy (`ra == 15`) / SMLAxy: halves chosen by `nt`/`mt` (top when true).
    SmulXy {
        rd: u8,
        rn: u8,
        rm: u8,
        ra: u8,
        nt: bool,
        mt: bool,
    },
    /// SMULWy / SMLAWy.
    SmulW {
        rd: u8,
        rn: u8,
        rm: u8,
        ra: u8,
        mt: bool,
    },
    /// SMLALxy.
    SmlalXy {
        lo: u8,
        hi: u8,
        rn: u8,
        rm: u8,
        nt: bool,
        mt: bool,
    },
    /// SMUAD/SMUSD (`ra == 15`), SMLAD/SMLSD; `x` swaps Rm's halves.
    Dual {
        rd: u8,
        rn: u8,
        rm: u8,
        ra: u8,
        sub: bool,
        x: bool,
    },
    /// SMLALD / SMLSLD.
    DualLong {
        lo: u8,
        hi: u8,
        rn: u8,
        rm: u8,
        sub: bool,
        x: bool,
    },
    /// SMMUL (`ra == 15`), SMMLA, SMMLS (`sub`); `round` for the R forms.
    Smmul {
        rd: u8,
        rn: u8,
        rm: u8,
        ra: u8,
        sub: bool,
        round: bool,
    },

    /// A single load/store with an immediate offset (`add` false subtracts it).
    MemImm {
        op: MemOp,
        rt: u8,
        rn: u8,
        index: Index,
        add: bool,
        /// LDRT/STRT and friends: the access is unprivileged.
        user: bool,
        imm: u16,
    },
    /// A single load/store at `Rn + (Rm << amount)`.
    MemReg {
        op: MemOp,
        rt: u8,
        rn: u8,
        rm: u8,
        amount: u8,
    },
    /// A literal load: the address is resolved.
    MemLit {
        op: MemOp,
        rt: u8,
        addr: u32,
    },
    /// LDRD/STRD with an immediate offset.
    Dual64 {
        load: bool,
        rt: u8,
        rt2: u8,
        rn: u8,
        index: Index,
        add: bool,
        imm: u16,
    },
    /// LDRD (literal).
    Dual64Lit {
        rt: u8,
        rt2: u8,
        addr: u32,
    },
    /// LDREX/LDREXB/LDREXH at `Rn + imm`.
    Ldrex {
        rt: u8,
        rn: u8,
        imm: u16,
        bytes: u8,
    },
    /// STREX/STREXB/STREXH: `rd` receives 0 on success.
    Strex {
        rd: u8,
        rt: u8,
        rn: u8,
        imm: u16,
        bytes: u8,
    },
    /// LDM/STM/PUSH/POP: increment after (`db == false`) or decrement before.
    Multi {
        load: bool,
        rn: u8,
        regs: u16,
        wback: bool,
        db: bool,
    },

    VArith {
        op: VOp,
        sd: u8,
        sn: u8,
        sm: u8,
    },
    VUnary {
        op: VUnary,
        sd: u8,
        sm: u8,
    },
    VMovImm {
        sd: u8,
        imm: u32,
    },
    /// VCMP(E) with Sm or with zero (`zero`); `e` signals on quiet NaNs too.
    VCmp {
        sd: u8,
        sm: u8,
        zero: bool,
        e: bool,
    },
    VCvt {
        op: VCvtInt,
        sd: u8,
        sm: u8,
    },
    /// Fixed-point VCVT in place on Sd: `frac` fraction bits of a 16- or 32-bit value.
    VCvtFixed {
        sd: u8,
        to_fixed: bool,
        unsigned: bool,
        half: bool,
        frac: u8,
    },
    /// VCVTB/VCVTT: `top` selects the upper half of the half-precision side.
    VCvtHalf {
        sd: u8,
        sm: u8,
        to_half: bool,
        top: bool,
    },
    /// VMOV between a core register and an S register (also the 32-bit scalar forms).
    VMovCore {
        sn: u8,
        rt: u8,
        to_core: bool,
    },
    /// VMOV between two core registers and S[sm], S[sm+1] (also the D form).
    VMovPair {
        rt: u8,
        rt2: u8,
        sm: u8,
        to_core: bool,
    },
    /// VMRS: `rt == 15` copies FPSCR's NZCV to the APSR.
    Vmrs {
        rt: u8,
    },
    Vmsr {
        rt: u8,
    },
    /// VLDR/VSTR of one S register or (`words == 2`) a D register as S[sd], S[sd+1].
    VMem {
        load: bool,
        sd: u8,
        rn: u8,
        add: bool,
        words: u8,
        imm: u16,
    },
    /// VLDM/VSTM/VPUSH/VPOP of `count` consecutive S registers from `sd`.
    VMulti {
        load: bool,
        sd: u8,
        count: u8,
        rn: u8,
        wback: bool,
        db: bool,
    },
}
