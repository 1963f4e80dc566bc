//! Shared helpers of the integration tests: locating the conformance vectors.
#![allow(dead_code, clippy::unwrap_used, clippy::panic)] // test code

pub mod spi;

use std::path::PathBuf;

/// `shared/vectors/<name>`: `$TAULINK_VECTORS` if set, else the nearest ancestor of this
/// crate that has a `shared/vectors` directory (the workspace sits beside `shared/`).
pub fn vectors_dir(name: &str) -> PathBuf {
    if let Ok(dir) = std::env::var("TAULINK_VECTORS") {
        return PathBuf::from(dir).join(name);
    }
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for ancestor in manifest.ancestors() {
        let candidate = ancestor.join("shared").join("vectors").join(name);
        if candidate.is_dir() {
            return candidate;
        }
    }
    panic!(
        "shared/vectors/{name} not found above {}",
        manifest.display()
    );
}

/// Parses one vector file.
pub fn load(name: &str, file: &str) -> serde_json::Value {
    let path = vectors_dir(name).join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}
