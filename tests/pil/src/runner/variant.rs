//! Flight images built with a test knob `cargo xtask dist` never sets (flight-fw
//! `build.rs`, `TAULINK_PIL_VARIANT`): a board wired differently, or the glue as it was before
//! one of issue 29's fixes. The PIL flies them to show that it models the hardware, not the
//! app (`tests/hardware_not_app.rs`), and that each fix is what passes its scenario
//! (`tests/findings.rs`). Kept in `target/pil-variants/NAME.elf`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// Builds the BrushedSparky flight image with `variant` (comma-separated names) in the
/// workspace's target folder — where `cargo xtask dist` built the images, so only flight-fw
/// itself recompiles — and keeps a copy; returns the copy's path. One build at a time: they
/// share the folder.
///
/// # Errors
/// Cargo cannot run or the build fails (an unknown variant name among them), or the copy
/// cannot be made.
pub fn build(variant: &str) -> Result<PathBuf, String> {
    static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(&root)
        .env("TAULINK_PIL_VARIANT", variant)
        .args([
            "build",
            "--release",
            "-p",
            "flight-fw",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .status()
        .map_err(|e| format!("running cargo for the {variant} variant: {e}"))?;
    if !status.success() {
        return Err(format!("building the {variant} variant failed ({status})"));
    }
    let kept = target.join("pil-variants");
    std::fs::create_dir_all(&kept).map_err(|e| format!("{}: {e}", kept.display()))?;
    let elf = kept.join(format!("{variant}.elf"));
    let built = target.join("thumbv7em-none-eabihf/release/flight-fw");
    std::fs::copy(&built, &elf).map_err(|e| format!("{}: {e}", built.display()))?;
    Ok(elf)
}
