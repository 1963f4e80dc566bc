//! `cargo xtask web` and `cargo xtask wasm`: the web ground station from a clone in one
//! command. `wasm` builds the decoder crate (`telemetry-wasm`) for the browser and writes its
//! JavaScript bindings into the app's `src/wasm/` with the bindings generator as a library of
//! the very version `Cargo.lock` gives the `wasm-bindgen` crate, so no `wasm-bindgen-cli` is
//! installed; `web` then installs the app's npm packages (never a browser) and builds it into
//! `dist/`, and with `--test` runs its unit tests and, in Debian's Chromium, its browser
//! tests against `taulink-sim --serve`.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

use wasm_bindgen_cli_support::Bindgen;

/// The browser's Rust target (`rust-toolchain.toml` lists it).
const WASM_TARGET: &str = "wasm32-unknown-unknown";
/// The decoder crate and the file its build leaves.
const WASM_PACKAGE: &str = "telemetry-wasm";
const WASM_FILE: &str = "telemetry_wasm";
/// The app, from the workspace root.
const APP: &str = "telemetry/ground-station";
/// Where the browser tests look for Chromium unless `$CHROMIUM` says (playwright.config.ts).
const CHROMIUM: &str = "/usr/bin/chromium";

/// What `web` does beyond building the app.
#[derive(Debug, Clone, Copy)]
pub struct Web {
    /// Also run the unit tests and the browser tests.
    pub test: bool,
}

/// The decoder for the browser and its bindings in `src/wasm/`.
pub fn wasm(root: &Path, target_dir: &Path) -> Result<(), String> {
    ensure_wasm_target(root)?;
    cargo(
        root,
        &[
            "build",
            "--release",
            "-p",
            WASM_PACKAGE,
            "--target",
            WASM_TARGET,
        ],
    )?;
    let input = target_dir
        .join(WASM_TARGET)
        .join("release")
        .join(format!("{WASM_FILE}.wasm"));
    let out = root.join(APP).join("src").join("wasm");
    bindings(&input, &out)?;
    println!("wasm decoder and its bindings in {}", out.display());
    Ok(())
}

/// Everything from a clone to a built app (and, with `test`, its tests passed).
pub fn web(root: &Path, target_dir: &Path, options: Web) -> Result<(), String> {
    let app = root.join(APP);
    // Before any build: a missing Node.js is the one thing cargo cannot bring.
    npm(&app, &["--version"]).map_err(|e| {
        format!("{e}\nthe ground station needs Node.js ≥ 20.19 with npm (Debian: apt-get install nodejs npm)")
    })?;
    wasm(root, target_dir)?;
    npm(&app, &["ci", "--no-audit", "--no-fund"])?;
    npm(&app, &["run", "build"])?;
    if options.test {
        npm(&app, &["test"])?;
        let chromium =
            env::var_os("CHROMIUM").map_or_else(|| PathBuf::from(CHROMIUM), PathBuf::from);
        if !chromium.is_file() {
            return Err(format!(
                "the browser tests run in Debian's Chromium, not found at {} (apt-get install chromium, or set CHROMIUM)",
                chromium.display()
            ));
        }
        cargo(root, &["build", "--release", "-p", "taulink-sim"])?;
        npm(&app, &["run", "e2e"])?;
    }
    println!(
        "ground station built in {}; serve it with: cargo run --release -p taulink-sim -- --serve",
        app.join("dist").display()
    );
    Ok(())
}

/// Adds the wasm target through rustup when the toolchain lacks it (a toolchain installed
/// before `rust-toolchain.toml` listed it).
fn ensure_wasm_target(root: &Path) -> Result<(), String> {
    let sysroot = Command::new(env::var_os("RUSTC").unwrap_or_else(|| "rustc".into()))
        .current_dir(root)
        .args(["--print", "sysroot"])
        .output()
        .map_err(|e| format!("cannot run rustc: {e}"))?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
    if sysroot.join("lib/rustlib").join(WASM_TARGET).is_dir() {
        return Ok(());
    }
    run(
        Command::new("rustup")
            .current_dir(root)
            .args(["target", "add", WASM_TARGET]),
        "rustup target add",
    )
    .map_err(|e| format!("{e}\nthe ground station's decoder needs the {WASM_TARGET} target"))
}

/// The JavaScript bindings of `input` for a browser ES module, as
/// `wasm-bindgen --target web --out-name telemetry_wasm` writes them (with TypeScript
/// declarations, the module's default URL beside the script).
fn bindings(input: &Path, out: &Path) -> Result<(), String> {
    Bindgen::new()
        .input_path(input)
        .web(true)
        .map_err(|e| format!("wasm-bindgen: {e}"))?
        .typescript(true)
        .omit_default_module_path(false)
        .out_name(WASM_FILE)
        .generate(out)
        .map_err(|e| format!("wasm-bindgen {}: {e:#}", input.display()))
}

fn cargo(root: &Path, args: &[&str]) -> Result<(), String> {
    let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    run(
        Command::new(cargo).current_dir(root).args(args),
        &format!("cargo {}", args.join(" ")),
    )
}

/// npm in the app's folder; it never downloads a browser (the browser tests use Chromium
/// from the system).
fn npm(app: &Path, args: &[&str]) -> Result<(), String> {
    run(
        Command::new("npm")
            .current_dir(app)
            .env("PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD", "1")
            .args(args),
        &format!("npm {}", args.join(" ")),
    )
}

fn run(command: &mut Command, what: &str) -> Result<(), String> {
    let status = command
        .status()
        .map_err(|e| format!("cannot run {what}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed ({status})"))
    }
}
