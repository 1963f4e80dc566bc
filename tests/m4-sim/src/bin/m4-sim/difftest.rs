//! Differential testing against QEMU: random straight-line programs of ALU, DSP and FPU
//! instructions (with IT blocks and FPSCR mode changes), assembled with `llvm-mc`, linked
//! with `rust-lld` for mps2-an386, run under `qemu-system-arm` and under m4-sim; each prints
//! its final registers (R0–R12, APSR, FPSCR, S0–S31) through semihosting and the two must
//! agree. A disagreement is narrowed down to the first instruction that causes it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use sim_rng::SplitMix64;

/// Where the register dump and its text go in RAM.
const DUMP: u32 = 0x2000_1000;
const TEXT: u32 = 0x2000_2000;
/// Scratch memory the generated loads and stores use (64 bytes, dumped too).
const SCRATCH: u32 = 0x2000_0800;
/// Words in the dump: S0–S31, APSR, FPSCR, R0–R12 (the order `vpush`/`push` leave them),
/// then the scratch memory.
const NAMES: [&str; 63] = [
    "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14",
    "s15", "s16", "s17", "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27",
    "s28", "s29", "s30", "s31", "apsr", "fpscr", "r0", "r1", "r2", "r3", "r4", "r5", "r6", "r7",
    "r8", "r9", "r10", "r11", "r12", "m0", "m4", "m8", "m12", "m16", "m20", "m24", "m28", "m32",
    "m36", "m40", "m44", "m48", "m52", "m56", "m60",
];

const LINKER_SCRIPT: &str = "\
MEMORY { FLASH : ORIGIN = 0, LENGTH = 4M RAM : ORIGIN = 0x20000000, LENGTH = 4M }
ENTRY(reset)
SECTIONS {
  .vectors 0 : { KEEP(*(.vectors)) } > FLASH
  .text : { *(.text*) } > FLASH
}
";

/// The tools the test needs.
pub struct Tools {
    llvm_mc: PathBuf,
    lld: PathBuf,
    qemu: PathBuf,
    dir: PathBuf,
}

fn which(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

impl Tools {
    /// Finds llvm-mc (or $LLVM_MC), rust-lld (the toolchain's) and qemu-system-arm.
    pub fn find() -> Result<Tools, String> {
        let llvm_mc = std::env::var_os("LLVM_MC")
            .map(PathBuf::from)
            .or_else(|| which("llvm-mc"))
            .ok_or("llvm-mc not found (apt-get install llvm, or set LLVM_MC)")?;
        let qemu = which("qemu-system-arm")
            .ok_or("qemu-system-arm not found (apt-get install qemu-system-arm)")?;
        let sysroot = Command::new("rustc")
            .args(["--print", "sysroot"])
            .output()
            .map_err(|e| format!("cannot run rustc: {e}"))?;
        let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
        let lld = std::fs::read_dir(sysroot.join("lib/rustlib"))
            .map_err(|e| format!("{}: {e}", sysroot.display()))?
            .filter_map(|e| e.ok())
            .map(|e| e.path().join("bin/rust-lld"))
            .find(|p| p.is_file())
            .ok_or("rust-lld not found in the Rust toolchain")?;
        let dir = std::env::temp_dir().join(format!("m4-sim-diff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        Ok(Tools {
            llvm_mc,
            lld,
            qemu,
            dir,
        })
    }

    /// Assembles and links a program; returns the ELF's path.
    fn build(&self, source: &str) -> Result<PathBuf, String> {
        let s = self.dir.join("t.s");
        let o = self.dir.join("t.o");
        let ld = self.dir.join("link.ld");
        let elf = self.dir.join("t.elf");
        std::fs::write(&s, source).map_err(|e| e.to_string())?;
        std::fs::write(&ld, LINKER_SCRIPT).map_err(|e| e.to_string())?;
        run_tool(
            Command::new(&self.llvm_mc)
                .args([
                    "-triple=thumbv7em-none-eabihf",
                    "-mattr=+vfp4d16sp,+dsp",
                    "-filetype=obj",
                    "-o",
                ])
                .arg(&o)
                .arg(&s),
        )?;
        run_tool(
            Command::new(&self.lld)
                .args(["-flavor", "gnu", "-T"])
                .arg(&ld)
                .arg("-o")
                .arg(&elf)
                .arg(&o),
        )?;
        Ok(elf)
    }

    /// QEMU's semihosting output for the program (QEMU writes its semihosting console to
    /// standard error).
    fn qemu(&self, elf: &Path) -> Result<String, String> {
        let out = Command::new(&self.qemu)
            .args([
                "-M",
                "mps2-an386",
                "-nographic",
                "-monitor",
                "none",
                "-serial",
                "none",
            ])
            .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
            .arg(elf)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", self.qemu.display()))?;
        Ok(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

impl Drop for Tools {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn run_tool(cmd: &mut Command) -> Result<(), String> {
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {cmd:?}: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{cmd:?} failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// A register value worth testing: edges, special floats, random bits.
fn value(rng: &mut SplitMix64) -> u32 {
    const SPECIAL: [u32; 24] = [
        0,
        1,
        0x7FFF_FFFF,
        0x8000_0000,
        0xFFFF_FFFF,
        0x8000_0001,
        0x0000_8000,
        0x0000_7FFF,
        0xFFFF_8000,
        0x0080_0000,
        0x007F_FFFF,
        0x0000_0001,
        0x7F80_0000,
        0xFF80_0000,
        0x7FC0_0000,
        0x7F80_0001,
        0x3F80_0000,
        0xBF80_0000,
        0x4F00_0000,
        0xCF00_0000,
        0x3F00_0000,
        0x7F7F_FFFF,
        0x4040_0000,
        0x0000_00FF,
    ];
    let r = rng.next_u64();
    match r % 4 {
        0 => SPECIAL
            .get((r >> 8) as usize % SPECIAL.len())
            .copied()
            .unwrap_or(0),
        // A float of moderate magnitude.
        1 => (r >> 16) as u32 & 0x83FF_FFFF | 0x3800_0000,
        _ => (r >> 16) as u32,
    }
}

fn pick<'a>(rng: &mut SplitMix64, items: &[&'a str]) -> &'a str {
    items
        .get((rng.next_u64() % items.len() as u64) as usize)
        .copied()
        .unwrap_or("")
}

fn below(rng: &mut SplitMix64, n: u32) -> u32 {
    (rng.next_u64() % u64::from(n.max(1))) as u32
}

/// A core register R0–R12.
fn r(rng: &mut SplitMix64) -> String {
    format!("r{}", below(rng, 13))
}

/// Two different core registers.
fn r_pair(rng: &mut SplitMix64) -> (String, String) {
    let a = below(rng, 13);
    let b = (a + 1 + below(rng, 12)) % 13;
    (format!("r{a}"), format!("r{b}"))
}

fn s(rng: &mut SplitMix64) -> String {
    format!("s{}", below(rng, 32))
}

/// A modified immediate (ThumbExpandImm) in one of its four forms.
fn modified_imm(rng: &mut SplitMix64) -> u32 {
    let b = below(rng, 255) + 1;
    match below(rng, 5) {
        0 => b,
        1 => b * 0x0001_0001,
        2 => b * 0x0100_0100,
        3 => b * 0x0101_0101,
        _ => (0x80 | b & 0x7F).rotate_right(8 + below(rng, 24)),
    }
}

fn shift_suffix(rng: &mut SplitMix64) -> String {
    match below(rng, 6) {
        0 => String::new(),
        1 => format!(", lsl #{}", 1 + below(rng, 31)),
        2 => format!(", lsr #{}", 1 + below(rng, 32)),
        3 => format!(", asr #{}", 1 + below(rng, 32)),
        4 => format!(", ror #{}", 1 + below(rng, 31)),
        _ => ", rrx".into(),
    }
}

/// One instruction; `c` is the condition suffix inside an IT block ("" outside).
fn instruction(rng: &mut SplitMix64, c: &str) -> String {
    let (d, n, m, a) = (r(rng), r(rng), r(rng), r(rng));
    let flags = if below(rng, 2) == 0 { "s" } else { "" };
    match below(rng, 30) {
        0..=3 => {
            let op = pick(
                rng,
                &[
                    "and", "orr", "eor", "bic", "orn", "add", "adc", "sub", "sbc", "rsb",
                ],
            );
            format!("{op}{flags}{c}.w {d}, {n}, {m}{}", shift_suffix(rng))
        }
        4..=5 => {
            let op = pick(
                rng,
                &[
                    "and", "orr", "eor", "bic", "orn", "add", "adc", "sub", "sbc", "rsb",
                ],
            );
            format!("{op}{flags}{c} {d}, {n}, #{}", modified_imm(rng))
        }
        6 => {
            let op = pick(rng, &["lsl", "lsr", "asr", "ror"]);
            format!("{op}{flags}{c}.w {d}, {n}, {m}")
        }
        7 => {
            let op = pick(rng, &["cmp", "cmn", "tst", "teq"]);
            if below(rng, 2) == 0 {
                format!("{op}{c}.w {n}, {m}{}", shift_suffix(rng))
            } else {
                format!("{op}{c} {n}, #{}", modified_imm(rng))
            }
        }
        8 => match below(rng, 3) {
            0 => format!("mov{flags}{c}.w {d}, {m}{}", shift_suffix(rng)),
            1 => format!("mvn{flags}{c} {d}, #{}", modified_imm(rng)),
            _ => format!(
                "{}{c} {d}, #{}",
                pick(rng, &["movw", "movt"]),
                below(rng, 0x10000)
            ),
        },
        9 => {
            let op = pick(rng, &["mul", "mla", "mls"]);
            if op == "mul" {
                format!("mul{c} {d}, {n}, {m}")
            } else {
                format!("{op}{c} {d}, {n}, {m}, {a}")
            }
        }
        10 => {
            let (lo, hi) = r_pair(rng);
            let op = pick(rng, &["umull", "smull", "umlal", "smlal", "umaal"]);
            format!("{op}{c} {lo}, {hi}, {n}, {m}")
        }
        11 => format!("{}{c} {d}, {n}, {m}", pick(rng, &["sdiv", "udiv"])),
        12 => format!(
            "{}{c} {d}, {m}",
            pick(rng, &["clz", "rbit", "rev", "rev16", "revsh"])
        ),
        13 => {
            let lsb = below(rng, 32);
            let width = 1 + below(rng, 32 - lsb);
            match below(rng, 4) {
                0 => format!("ubfx{c} {d}, {n}, #{lsb}, #{width}"),
                1 => format!("sbfx{c} {d}, {n}, #{lsb}, #{width}"),
                2 => format!("bfi{c} {d}, {n}, #{lsb}, #{width}"),
                _ => format!("bfc{c} {d}, #{lsb}, #{width}"),
            }
        }
        14 => match below(rng, 4) {
            0 => format!(
                "ssat{c} {d}, #{}, {n}, lsl #{}",
                1 + below(rng, 32),
                below(rng, 32)
            ),
            1 => format!(
                "usat{c} {d}, #{}, {n}, asr #{}",
                below(rng, 32),
                1 + below(rng, 31)
            ),
            2 => format!("ssat16{c} {d}, #{}, {n}", 1 + below(rng, 16)),
            _ => format!("usat16{c} {d}, #{}, {n}", below(rng, 16)),
        },
        15 => {
            let rot = 8 * below(rng, 4);
            let op = pick(rng, &["sxtb", "uxtb", "sxth", "uxth", "sxtb16", "uxtb16"]);
            if below(rng, 2) == 0 {
                let wide = if op.ends_with("16") { "" } else { ".w" };
                format!("{op}{c}{wide} {d}, {m}, ror #{rot}")
            } else {
                let add = op.replacen("xt", "xta", 1);
                format!("{add}{c} {d}, {n}, {m}, ror #{rot}")
            }
        }
        16..=17 => {
            let p = pick(rng, &["s", "q", "sh", "u", "uq", "uh"]);
            let op = pick(rng, &["add16", "asx", "sax", "sub16", "add8", "sub8"]);
            format!("{p}{op}{c} {d}, {n}, {m}")
        }
        18 => match below(rng, 3) {
            0 => format!("sel{c} {d}, {n}, {m}"),
            1 => format!("usad8{c} {d}, {n}, {m}"),
            _ => format!("usada8{c} {d}, {n}, {m}, {a}"),
        },
        19 => format!(
            "{}{c} {d}, {m}, {n}",
            pick(rng, &["qadd", "qsub", "qdadd", "qdsub"])
        ),
        20 => {
            let (x, y) = (pick(rng, &["b", "t"]), pick(rng, &["b", "t"]));
            match below(rng, 4) {
                0 => format!("smul{x}{y}{c} {d}, {n}, {m}"),
                1 => format!("smla{x}{y}{c} {d}, {n}, {m}, {a}"),
                2 => format!("smulw{y}{c} {d}, {n}, {m}"),
                _ => format!("smlaw{y}{c} {d}, {n}, {m}, {a}"),
            }
        }
        21 => {
            let x = pick(rng, &["", "x"]);
            let (lo, hi) = r_pair(rng);
            match below(rng, 5) {
                0 => format!("{}{x}{c} {d}, {n}, {m}", pick(rng, &["smuad", "smusd"])),
                1 => format!(
                    "{}{x}{c} {d}, {n}, {m}, {a}",
                    pick(rng, &["smlad", "smlsd"])
                ),
                2 => format!(
                    "{}{x}{c} {lo}, {hi}, {n}, {m}",
                    pick(rng, &["smlald", "smlsld"])
                ),
                3 => {
                    let (p, q) = (pick(rng, &["b", "t"]), pick(rng, &["b", "t"]));
                    format!("smlal{p}{q}{c} {lo}, {hi}, {n}, {m}")
                }
                _ => {
                    let rr = pick(rng, &["", "r"]);
                    match below(rng, 3) {
                        0 => format!("smmul{rr}{c} {d}, {n}, {m}"),
                        1 => format!("smmla{rr}{c} {d}, {n}, {m}, {a}"),
                        _ => format!("smmls{rr}{c} {d}, {n}, {m}, {a}"),
                    }
                }
            }
        }
        22 => {
            if below(rng, 2) == 0 {
                format!("pkhbt{c} {d}, {n}, {m}, lsl #{}", below(rng, 32))
            } else {
                format!("pkhtb{c} {d}, {n}, {m}, asr #{}", 1 + below(rng, 32))
            }
        }
        23..=25 => {
            let (sd, sn, sm) = (s(rng), s(rng), s(rng));
            let op = pick(
                rng,
                &[
                    "add", "sub", "mul", "nmul", "div", "mla", "mls", "nmla", "nmls", "fma", "fms",
                    "fnma", "fnms",
                ],
            );
            format!("v{op}{c}.f32 {sd}, {sn}, {sm}")
        }
        26 => {
            let (sd, sm) = (s(rng), s(rng));
            match below(rng, 4) {
                0 => format!(
                    "v{}{c}.f32 {sd}, {sm}",
                    pick(rng, &["abs", "neg", "sqrt", "mov"])
                ),
                1 => {
                    let e = pick(rng, &["", "e"]);
                    if below(rng, 3) == 0 {
                        format!("vcmp{e}{c}.f32 {sd}, #0")
                    } else {
                        format!("vcmp{e}{c}.f32 {sd}, {sm}")
                    }
                }
                2 => format!("vmrs{c} APSR_nzcv, fpscr"),
                _ => format!(
                    "vmov{c}.f32 {sd}, #{}",
                    pick(rng, &["1.0", "-2.5", "0.125", "31.0", "-0.1875", "16.0"])
                ),
            }
        }
        27 => {
            let (sd, sm) = (s(rng), s(rng));
            match below(rng, 4) {
                0 => format!(
                    "vcvt{}{c}.{}.f32 {sd}, {sm}",
                    pick(rng, &["", "r"]),
                    pick(rng, &["s32", "u32"])
                ),
                1 => format!("vcvt{c}.f32.{} {sd}, {sm}", pick(rng, &["s32", "u32"])),
                2 => {
                    let ty = pick(rng, &["s16", "u16", "s32", "u32"]);
                    let max = if ty.ends_with("16") { 16 } else { 32 };
                    let fbits = 1 + below(rng, max);
                    if below(rng, 2) == 0 {
                        format!("vcvt{c}.{ty}.f32 {sd}, {sd}, #{fbits}")
                    } else {
                        format!("vcvt{c}.f32.{ty} {sd}, {sd}, #{fbits}")
                    }
                }
                _ => {
                    let bt = pick(rng, &["b", "t"]);
                    let dir = pick(rng, &["f16.f32", "f32.f16"]);
                    format!("vcvt{bt}{c}.{dir} {sd}, {sm}")
                }
            }
        }
        28 => {
            let (sd, sm) = (s(rng), s(rng));
            if below(rng, 2) == 0 {
                format!("vmov{c} {sd}, {d}")
            } else {
                format!("vmov{c} {d}, {sm}")
            }
        }
        _ => format!("vmrs{c} {d}, fpscr"),
    }
}

/// A low register R0–R7 (the 16-bit encodings).
fn lo(rng: &mut SplitMix64) -> String {
    format!("r{}", below(rng, 8))
}

/// A 16-bit instruction on low registers; in an IT block (`c` not empty) the arithmetic
/// forms do not set the flags, outside they do.
fn narrow(rng: &mut SplitMix64, c: &str) -> String {
    let (d, n, m) = (lo(rng), lo(rng), lo(rng));
    let sf = if c.is_empty() { "s" } else { "" };
    match below(rng, 9) {
        0 => format!("{}{sf}{c} {d}, {n}, {m}", pick(rng, &["add", "sub"])),
        1 => format!(
            "{}{sf}{c} {d}, {n}, #{}",
            pick(rng, &["add", "sub"]),
            below(rng, 8)
        ),
        2 => format!(
            "{}{sf}{c} {d}, #{}",
            pick(rng, &["add", "sub", "mov"]),
            below(rng, 256)
        ),
        3 => {
            let op = pick(
                rng,
                &[
                    "and", "eor", "orr", "bic", "adc", "sbc", "ror", "lsl", "lsr", "asr",
                ],
            );
            format!("{op}{sf}{c} {d}, {m}")
        }
        4 => format!(
            "{}{sf}{c} {d}, {m}, #{}",
            pick(rng, &["lsl", "lsr", "asr"]),
            1 + below(rng, 31)
        ),
        5 => format!("mul{sf}{c} {d}, {m}, {d}"),
        6 => format!("{}{sf}{c} {d}, {m}", pick(rng, &["mvn", "mov"])),
        7 if c.is_empty() => format!("rsbs {d}, {m}, #0"),
        _ => format!("{}{c} {n}, {m}", pick(rng, &["cmp", "cmn", "tst"])),
    }
}

/// A load or store at the scratch memory through R11 (set up in the same atom).
fn memory(rng: &mut SplitMix64) -> String {
    let base = SCRATCH + 4 * below(rng, 4);
    let mut text = format!(
        "movw r11, #{}\n  movt r11, #{}\n",
        base & 0xFFFF,
        base >> 16
    );
    let (t, t2) = r_pair(rng);
    let t = if t == "r11" { "r0".to_string() } else { t };
    let t2 = if t2 == "r11" || t2 == t {
        "r1".to_string()
    } else {
        t2
    };
    let off = below(rng, 44);
    let line = match below(rng, 7) {
        0 => format!(
            "{} {t}, [r11, #{off}]",
            pick(rng, &["ldr", "ldrb", "ldrh", "ldrsb", "ldrsh"])
        ),
        1 => format!("{} {t}, [r11, #{off}]", pick(rng, &["str", "strb", "strh"])),
        2 => format!(
            "{} {t}, [r11, #{off}]!",
            pick(rng, &["ldr", "str", "ldrh", "strb"])
        ),
        3 if t != t2 => format!(
            "{} {t}, {t2}, [r11, #{}]",
            pick(rng, &["ldrd", "strd"]),
            4 * below(rng, 8)
        ),
        4 => {
            let mut regs: Vec<u32> = (0..11).filter(|_| below(rng, 3) == 0).collect();
            if regs.len() < 2 {
                regs = vec![2, 5];
            }
            let list: Vec<String> = regs.iter().map(|r| format!("r{r}")).collect();
            format!(
                "{}.w r11, {{{}}}",
                pick(rng, &["ldm", "stm"]),
                list.join(", ")
            )
        }
        5 => format!("ldrex {t}, [r11]\n  strex {t2}, {t}, [r11]"),
        _ => format!(
            "{} {t}, [r11, #{}]",
            pick(rng, &["ldr", "str"]),
            4 * below(rng, 12)
        ),
    };
    text.push_str("  ");
    text.push_str(&line);
    text.push('\n');
    text
}

/// One unit of a program: an instruction, an IT block with its instructions, an FPSCR
/// mode change, or a memory access with its base.
fn atom(rng: &mut SplitMix64) -> String {
    match below(rng, 16) {
        12 | 13 => format!("{}\n", narrow(rng, "")),
        14 => memory(rng),
        0 => {
            const CONDS: [&str; 14] = [
                "eq", "ne", "hs", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le",
            ];
            let cond = pick(rng, &CONDS);
            let pair = |c: &str| -> &str {
                let i = CONDS.iter().position(|&x| x == c).unwrap_or(0);
                CONDS.get(i ^ 1).copied().unwrap_or("ne")
            };
            let len = 1 + below(rng, 4) as usize;
            let mut pattern = String::new();
            let mut conds = vec![cond];
            for _ in 1..len {
                let then = below(rng, 2) == 0;
                pattern.push(if then { 't' } else { 'e' });
                conds.push(if then { cond } else { pair(cond) });
            }
            let mut text = format!("it{pattern} {cond}\n");
            for c in conds {
                // 16-bit arithmetic does not set the flags inside an IT block.
                let insn = if below(rng, 3) == 0 {
                    narrow(rng, c)
                } else {
                    instruction(rng, c)
                };
                let _ = writeln!(text, "  {insn}");
            }
            text
        }
        1 => {
            let t = r(rng);
            let mode = (below(rng, 4) << 22)
                | below(rng, 2) << 24
                | below(rng, 2) << 25
                | below(rng, 2) << 26
                | below(rng, 4) << 28;
            format!(
                "movw {t}, #{}\n  movt {t}, #{}\n  vmsr fpscr, {t}\n",
                mode & 0xFFFF,
                mode >> 16
            )
        }
        _ => format!("{}\n", instruction(rng, "")),
    }
}

/// The whole program around `atoms`: vector table, FPU enable, initial state, the atoms,
/// the register dump in hex over semihosting, exit.
fn program(atoms: &[String], init: &[u32; 47]) -> String {
    let mut s = String::from(
        ".syntax unified\n.thumb\n.section .vectors, \"a\"\n.word 0x20010000\n.word reset\n",
    );
    for _ in 2..16 {
        s.push_str(".word fault\n");
    }
    s.push_str(".text\n.global reset\n.thumb_func\nfault:\n  movs r0, #0x18\n  ldr r1, =0x20023\n  bkpt #0xab\n");
    s.push_str(".thumb_func\nreset:\n");
    s.push_str("  ldr r0, =0xE000ED88\n  ldr r1, [r0]\n  orr r1, r1, #0xF00000\n  str r1, [r0]\n  dsb\n  isb\n");
    s.push_str("  adr r0, init_s\n  vldm r0, {s0-s31}\n");
    s.push_str(
        "  ldr r1, [r0, #132]\n  vmsr fpscr, r1\n  ldr r1, [r0, #128]\n  msr APSR_nzcvqg, r1\n",
    );
    s.push_str("  add r0, r0, #136\n  ldm.w r0, {r0-r12}\n");
    for a in atoms {
        s.push_str("  ");
        s.push_str(a);
        if !a.ends_with('\n') {
            s.push('\n');
        }
    }
    let _ = write!(
        s,
        "  ldr sp, ={}\n  push {{r0-r12}}\n  mrs r0, apsr\n  vmrs r1, fpscr\n  push {{r0, r1}}\n  vpush {{s0-s31}}\n",
        DUMP + 4 * 47
    );
    let _ = write!(
        s,
        "  ldr r0, ={SCRATCH}\n  add r1, sp, #188\n  ldm r0!, {{r2-r9}}\n  stm r1!, {{r2-r9}}\n  ldm r0!, {{r2-r9}}\n  stm r1!, {{r2-r9}}\n"
    );
    let _ = write!(
        s,
        "  mov r4, sp\n  movs r5, #63\n  ldr r6, ={TEXT}\n\
         1: ldr r0, [r4], #4\n  movs r1, #8\n\
         2: ror r0, r0, #28\n  and r2, r0, #15\n  cmp r2, #10\n  ite lo\n  addlo r2, r2, #48\n  addhs r2, r2, #87\n\
         \x20 strb r2, [r6], #1\n  subs r1, #1\n  bne 2b\n  movs r2, #10\n  strb r2, [r6], #1\n  subs r5, #1\n  bne 1b\n\
         \x20 movs r2, #0\n  strb r2, [r6]\n  movs r0, #4\n  ldr r1, ={TEXT}\n  bkpt #0xab\n\
         \x20 movs r0, #0x18\n  ldr r1, =0x20026\n  bkpt #0xab\n"
    );
    s.push_str("  .ltorg\n.p2align 2\ninit_s:\n");
    for v in init {
        let _ = writeln!(s, "  .word 0x{v:08x}");
    }
    s
}

/// The initial state: S0–S31, APSR, FPSCR (its mode bits), R0–R12.
fn initial_state(rng: &mut SplitMix64) -> [u32; 47] {
    let mut init = [0u32; 47];
    for (i, v) in init.iter_mut().enumerate() {
        *v = match i {
            32 => (rng.next_u64() as u32) & 0xF80F_0000,
            33 => (rng.next_u64() as u32) & 0x07C0_0000,
            _ => value(rng),
        };
    }
    init
}

/// The outputs of both emulators for a program, m4-sim's first.
fn run_both(tools: &Tools, source: &str) -> Result<(String, String), String> {
    let elf = tools.build(source)?;
    let ours = crate::execute(&elf, "m4count_marker", 10)
        .map(|o| String::from_utf8_lossy(&o.output).into_owned());
    let ours = ours.unwrap_or_else(|e| format!("m4-sim: {e}"));
    Ok((ours, tools.qemu(&elf)?))
}

/// Named register differences between two dumps.
fn differences(ours: &str, qemu: &str) -> String {
    let a: Vec<&str> = ours.lines().collect();
    let b: Vec<&str> = qemu.lines().collect();
    if a.len() != NAMES.len() || b.len() != NAMES.len() {
        return format!(
            "m4-sim printed {:?}\nQEMU printed {:?}",
            ours.trim(),
            qemu.trim()
        );
    }
    let mut out = String::new();
    for (name, (x, y)) in NAMES.iter().zip(a.iter().zip(&b)) {
        if x != y {
            let _ = writeln!(out, "  {name}: m4-sim {x}, QEMU {y}");
        }
    }
    out
}

/// Runs `programs` random programs of `length` atoms from `seed`; prints each
/// disagreement narrowed to the atom that causes it. Returns the number of disagreements.
pub fn run(tools: &Tools, seed: u64, programs: u32, length: usize) -> Result<u32, String> {
    let mut rng = SplitMix64::new(seed);
    let mut failures = 0;
    for p in 0..programs {
        let init = initial_state(&mut rng);
        let atoms: Vec<String> = (0..length).map(|_| atom(&mut rng)).collect();
        let (ours, qemu) = run_both(tools, &program(&atoms, &init))?;
        if ours == qemu {
            continue;
        }
        failures += 1;
        // The shortest prefix that disagrees: its last atom is the culprit.
        let (mut good, mut bad) = (0usize, atoms.len());
        while bad - good > 1 {
            let mid = (good + bad) / 2;
            let (o, q) = run_both(tools, &program(atoms.get(..mid).unwrap_or(&[]), &init))?;
            if o == q {
                good = mid;
            } else {
                bad = mid;
            }
        }
        let prefix = atoms.get(..bad).unwrap_or(&[]);
        let (o, q) = run_both(tools, &program(prefix, &init))?;
        println!(
            "DIFF program {p} (seed {seed}), atom {}:\n  {}\n{}",
            bad - 1,
            atoms
                .get(bad - 1)
                .map_or("", |a| a.trim_end())
                .replace('\n', "\n  "),
            differences(&o, &q)
        );
    }
    Ok(failures)
}
