//! The runner the command-line tests share (`tests/cli.rs` of taulink-sim, flight-sitl and
//! xtask): run a binary as a user would, read what it printed and how it exited, and the two
//! checks every such test makes (a help lists its items; a usage error exits 2 and says why).
//! A dev-dependency only.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Test support: a binary that cannot be started is a failed test, said loudly.
#![allow(clippy::expect_used, clippy::panic)]

use std::process::Command;

/// One run of a binary: its exit code and its output as text.
#[derive(Debug)]
pub struct Run {
    /// The exit code (`None` when a signal ended the process).
    pub code: Option<i32>,
    /// Standard output (lossy UTF-8).
    pub stdout: String,
    /// Standard error (lossy UTF-8).
    pub stderr: String,
}

/// Runs `bin` (a path, e.g. `env!("CARGO_BIN_EXE_taulink-sim")`) with `args` and waits.
pub fn run(bin: &str, args: &[&str]) -> Run {
    let out = Command::new(bin)
        .args(args)
        .output()
        .expect("the binary under test starts");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

impl Run {
    /// Exited with 0.
    pub fn success(&self) -> bool {
        self.code == Some(0)
    }

    /// Asserts exit 0 and that standard output contains every one of `items`.
    pub fn assert_lists(&self, items: &[&str]) {
        assert!(self.success(), "exit {:?}: {}", self.code, self.stderr);
        for item in items {
            assert!(
                self.stdout.contains(item),
                "output lacks {item:?}:\n{}",
                self.stdout
            );
        }
    }

    /// Asserts a usage error: exit 2 (clap's code) with `reason` on standard error.
    pub fn assert_refused(&self, reason: &str) {
        assert_eq!(self.code, Some(2), "not refused: {}", self.stderr);
        assert!(
            self.stderr.contains(reason),
            "refusal does not say {reason:?}: {}",
            self.stderr
        );
    }
}
