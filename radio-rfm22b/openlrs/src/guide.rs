//! Embedding guide: wiring, an OpenLRSng receiver and transmitter, failsafe, an absent chip,
//! and host tests of your link against the virtual Si4432 (`si4432-sim`).
//!
//! This module holds documentation only; its text is `src/guide.md`, whose snippets
//! `cargo test --doc -p openlrs-ng` compiles and runs.
#![doc = include_str!("guide.md")]
