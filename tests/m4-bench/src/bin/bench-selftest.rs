//! Checks the counting chain: a loop of known length must measure 2 instructions per turn
//! plus the marker call overhead (m4count's README: 1000 turns measure 2010).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use m4_bench::{exit, m4count_marker};
    let turns: u32 = core::hint::black_box(1000);
    m4count_marker();
    // SAFETY: a register-only countdown loop (subs + bne per turn).
    unsafe {
        core::arch::asm!("1:", "subs {n}, #1", "bne 1b", n = inout(reg) turns => _);
    }
    m4count_marker();
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
