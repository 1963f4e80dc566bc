//! A register-level virtual Si4432 and a simulated RF medium (std), so radio code can be
//! tested on a PC through the same embedded-hal traits it uses on a board.
#![warn(missing_docs)]
