//! Receiver role (state machine): bind, hop, failsafe.
