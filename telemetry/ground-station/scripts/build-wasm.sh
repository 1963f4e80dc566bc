#!/bin/sh
# Builds the telemetry-wasm crate for the browser and generates its JavaScript bindings into
# src/wasm/ (not committed). Needs the wasm32-unknown-unknown target and wasm-bindgen-cli of
# the same version as the wasm-bindgen crate in Cargo.lock.
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
cargo build --release -p telemetry-wasm --target wasm32-unknown-unknown
wasm-bindgen --target web --out-dir "$here/src/wasm" --out-name telemetry_wasm \
    "$root/target/wasm32-unknown-unknown/release/telemetry_wasm.wasm"
