//! The sensor crates this one's API speaks: [`ubx`] (the u-blox protocol, `flight/ubx`),
//! re-exported because [`FlightApp::on_gps_bytes`](crate::app::FlightApp::on_gps_bytes)
//! drives its parser and configurator and the estimator fuses its
//! [`NavPvt`](ubx::NavPvt). The chip drivers (`flight/mpu9250`, `flight/ms5611`) are their
//! own crates too, used by the firmware's tasks directly: the core never talks to a bus.

pub use ubx;
