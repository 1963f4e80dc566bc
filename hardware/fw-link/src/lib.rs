//! The firmware images' link set-up, one implementation for the build scripts of
//! `flight/flight-fw` and `taulink-module/module-fw` (a build-dependency of both): each
//! script picks its `memory.x` by feature and hands it to [`link_image`].
//!
//! The layout is written to OUT_DIR because the linker runs in the workspace root and would
//! not find a memory.x next to the build script. Host builds (the firmware crates' stub
//! `main`) get nothing. The boot contracts behind the layouts are in
//! `hardware/xtask/src/layout.rs`, checked on the built images by `cargo xtask verify`.

use std::{env, fs, path::PathBuf};

/// Whether the crate being built has cargo feature `name` on (spelled as in Cargo.toml).
pub fn feature(name: &str) -> bool {
    let var = format!("CARGO_FEATURE_{}", name.to_uppercase().replace('-', "_"));
    env::var_os(var).is_some()
}

/// For an MCU build (`target_os = "none"`): writes `memory_x` to OUT_DIR as `memory.x`, puts
/// OUT_DIR on the link search path and links the binaries with cortex-m-rt's `link.x` and
/// defmt's `defmt.x`. Does nothing on the host.
pub fn link_image(memory_x: &str) {
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap_or_default());
    if let Err(e) = fs::write(out.join("memory.x"), memory_x) {
        println!("cargo:warning=cannot write memory.x: {e}");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
