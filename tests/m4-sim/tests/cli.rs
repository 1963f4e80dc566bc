//! The `m4-sim` tool as a user meets it: `--help` lists the commands, a misspelt command is
//! refused (exit 2), files that cannot be read or are not ELF fail with the reason (exit 1),
//! and `run` executes a program to its semihosting exit and reports its count and status.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use cli_test::Run;

fn m4sim(args: &[&str]) -> Run {
    cli_test::run(env!("CARGO_BIN_EXE_m4-sim"), args)
}

/// A minimal ELF32 image: one loadable segment at 0 holding a vector table and `code` at
/// 0x40.
fn elf(code: &[u16]) -> Vec<u8> {
    let mut image = Vec::new();
    image.extend(0x2000_1000u32.to_le_bytes());
    image.extend(0x41u32.to_le_bytes());
    image.resize(0x40, 0);
    image.extend(code.iter().flat_map(|h| h.to_le_bytes()));
    let mut e = vec![0u8; 0x54];
    e[..6].copy_from_slice(&[0x7F, b'E', b'L', b'F', 1, 1]);
    e[0x1C..0x20].copy_from_slice(&0x34u32.to_le_bytes()); // program headers
    e[0x2A..0x2C].copy_from_slice(&32u16.to_le_bytes());
    e[0x2C..0x2E].copy_from_slice(&1u16.to_le_bytes());
    let ph = 0x34;
    e[ph..ph + 4].copy_from_slice(&1u32.to_le_bytes()); // PT_LOAD
    e[ph + 4..ph + 8].copy_from_slice(&0x54u32.to_le_bytes()); // offset
    e[ph + 16..ph + 20].copy_from_slice(&(image.len() as u32).to_le_bytes()); // filesz
    e.extend(image);
    e
}

fn write_elf(name: &str, code: &[u16]) -> std::path::PathBuf {
    let path = std::env::temp_dir().join(format!("m4-sim-cli-{}-{name}.elf", std::process::id()));
    std::fs::write(&path, elf(code)).unwrap();
    path
}

#[test]
fn help_lists_the_commands() {
    m4sim(&["--help"]).assert_lists(&["run", "compare", "coverage", "speed", "diff"]);
    m4sim(&["run", "--help"]).assert_lists(&["--marker <MARKER>", "--cycles"]);
}

#[test]
fn a_misspelt_command_is_refused() {
    m4sim(&["rnu", "x.elf"]).assert_refused("'rnu'");
    m4sim(&["compar"]).assert_refused("compare");
    m4sim(&["run"]).assert_refused("<ELF>");
}

#[test]
fn unreadable_and_non_elf_files_fail_with_the_reason() {
    let out = m4sim(&["run", "/nonexistent/program.elf"]);
    assert_eq!(out.code, Some(1));
    assert!(
        out.stderr.contains("/nonexistent/program.elf"),
        "{}",
        out.stderr
    );
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let out = m4sim(&["coverage", manifest]);
    assert_eq!(out.code, Some(1));
    assert!(
        out.stderr.contains("not a 32-bit little-endian ELF"),
        "{}",
        out.stderr
    );
}

#[test]
fn run_reports_the_count_and_the_exit_status() {
    // movs r0, #0x18; movw r1, #0x26; movt r1, #2; bkpt #0xab: SYS_EXIT, normal exit.
    let ok = write_elf("ok", &[0x2018, 0xF240, 0x0126, 0xF2C0, 0x0102, 0xBEAB]);
    let out = m4sim(&["run", ok.to_str().unwrap()]);
    assert!(out.success(), "{}", out.stderr);
    assert_eq!(out.stdout.trim(), "total 4");
    // The same exit with reason 0x20023 (a run-time error): status 1.
    let failed = write_elf("fail", &[0x2018, 0xF240, 0x0123, 0xF2C0, 0x0102, 0xBEAB]);
    let out = m4sim(&["run", failed.to_str().unwrap()]);
    assert_eq!(out.code, Some(1));
    assert!(out.stderr.contains("exit status 1"), "{}", out.stderr);
    let cov = m4sim(&["coverage", ok.to_str().unwrap()]);
    assert!(cov.success(), "{}", cov.stderr);
    let _ = std::fs::remove_file(ok);
    let _ = std::fs::remove_file(failed);
}
