//! Shared pieces of the instruction-count benchmarks: the region marker that m4count looks
//! for, the exit, and the panic handler. Each `src/bin/*.rs` is one benchmark program:
//! build with `cargo build -p m4-bench --target thumbv7em-none-eabihf --release --bin NAME`
//! and run `../shared/tools/m4count/m4count target/thumbv7em-none-eabihf/release/NAME`.
#![cfg_attr(target_os = "none", no_std)]

#[cfg(target_os = "none")]
mod target {
    use cortex_m_semihosting::debug;

    /// Region boundary: m4count prints the instructions executed between two calls.
    #[unsafe(no_mangle)]
    #[inline(never)]
    pub extern "C" fn m4count_marker() {
        // SAFETY: a single `nop` touches no memory and no registers.
        unsafe { core::arch::asm!("nop") }
    }

    /// Ends the QEMU run.
    pub fn exit() -> ! {
        debug::exit(debug::EXIT_SUCCESS);
        #[allow(clippy::empty_loop)]
        loop {}
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        debug::exit(debug::EXIT_FAILURE);
        #[allow(clippy::empty_loop)]
        loop {}
    }
}

#[cfg(target_os = "none")]
pub use target::{exit, m4count_marker};
