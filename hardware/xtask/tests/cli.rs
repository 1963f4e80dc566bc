//! `cargo xtask` as a user meets it: `--help` exits 0 and lists the tasks, a misspelt task
//! or a flag of the other board is refused with clap's message (exit 2). Nothing is built.

#![allow(clippy::unwrap_used)] // test helpers

use std::process::{Command, Output};

fn xtask(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_xtask"))
        .args(args)
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn help_lists_the_tasks_and_exits_0() {
    let out = xtask(&["--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for n in ["build", "dist", "size", "Examples:"] {
        assert!(help.contains(n), "help lacks {n:?}:\n{help}");
    }
    let out = xtask(&["build", "flight", "--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    assert!(
        help.contains("--sparky2") && help.contains("Tau Labs bootloader"),
        "{help}"
    );
}

#[test]
fn misspellings_and_wrong_board_flags_are_refused() {
    let out = xtask(&["dsit"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("a similar subcommand exists: 'dist'"));
    let out = xtask(&["build", "flight", "--sparky"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("'--sparky2'"));
    // --uf2 belongs to the module image.
    let out = xtask(&["build", "flight", "--uf2"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("unexpected argument '--uf2'"));
}
