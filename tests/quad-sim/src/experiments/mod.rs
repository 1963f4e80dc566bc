//! Experiments that reproduce a seed measurement in simulation, each a library function
//! (for tests and other tools' CLIs) plus a binary.

pub mod oneshot;
