//! `cargo xtask` as a user meets it: `--help` exits 0 and lists the tasks, a misspelt task
//! or a flag of the other board is refused with clap's message (exit 2). Nothing is built.

use cli_test::Run;

fn xtask(args: &[&str]) -> Run {
    cli_test::run(env!("CARGO_BIN_EXE_xtask"), args)
}

#[test]
fn help_lists_the_tasks_and_exits_0() {
    xtask(&["--help"]).assert_lists(&["build", "dist", "size", "size-report", "Examples:"]);
    xtask(&["size-report", "--help"]).assert_lists(&["--image", "--top", "--dist"]);
    xtask(&["build", "flight", "--help"]).assert_lists(&["--sparky2", "Tau Labs bootloader"]);
}

#[test]
fn misspellings_and_wrong_board_flags_are_refused() {
    xtask(&["dsit"]).assert_refused("a similar subcommand exists: 'dist'");
    xtask(&["build", "flight", "--sparky"]).assert_refused("'--sparky2'");
    // --uf2 belongs to the module image.
    xtask(&["build", "flight", "--uf2"]).assert_refused("unexpected argument '--uf2'");
    xtask(&["size-report", "--image", "flight"])
        .assert_refused("the images are flight-brushedsparky");
    xtask(&["size-report", "--top", "many"]).assert_refused("'--top <TOP>'");
}
