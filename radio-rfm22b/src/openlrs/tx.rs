//! Transmitter role (state machine): bind, schedule, telemetry.
