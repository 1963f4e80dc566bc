//! Shared helpers of the integration tests: locating the conformance vectors.
#![allow(dead_code, clippy::unwrap_used, clippy::panic)] // test code

pub mod spi;

use std::path::PathBuf;

/// The vector set `<name>`: `$TAULINK_VECTORS/<name>` if set, else the repository's
/// `testdata/<name>` (its README says where the vectors come from).
pub fn vectors_dir(name: &str) -> PathBuf {
    match std::env::var("TAULINK_VECTORS") {
        Ok(dir) => PathBuf::from(dir).join(name),
        Err(_) => PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../testdata")
            .join(name),
    }
}

/// Parses one vector file.
pub fn load(name: &str, file: &str) -> serde_json::Value {
    let path = vectors_dir(name).join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}
