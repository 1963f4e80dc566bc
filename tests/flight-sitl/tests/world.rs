//! The firmware-in-the-loop world itself: both applications boot on virtual chips, the link
//! comes up through the real driver, the module relays the flight side's telemetry, and
//! both independent watchdogs stay fed in normal flight.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;

use flight_sitl::scenario::default_airframe;
use flight_sitl::{BootCause, End, PilotInput, Scenario, run};

#[test]
fn both_ends_boot_once_link_and_stay_fed_on_the_ground() {
    let (quad, settings) = default_airframe();
    let sitl = run(Scenario::new(
        settings,
        quad,
        3.0,
        Box::new(|_| PilotInput::default()),
    ));
    println!(
        "boots {:?}, resets {:?}, samples {}, link up {}, module rx {}",
        sitl.boots,
        sitl.watchdog_resets,
        sitl.samples.len(),
        sitl.samples.iter().filter(|s| s.link_up).count(),
        sitl.module_rx.len()
    );
    assert_eq!(sitl.watchdog_resets.flight, 0);
    assert_eq!(sitl.watchdog_resets.module, 0);
    let ends: Vec<_> = sitl.boots.iter().map(|b| (b.end, b.cause)).collect();
    assert!(ends.contains(&(End::Flight, BootCause::PowerOn)));
    assert!(ends.contains(&(End::Module, BootCause::PowerOn)));
    assert_eq!(sitl.boots.len(), 2);
    assert!(sitl.samples.iter().all(|s| s.flight_up && s.link_up));
    assert!(!sitl.module_rx.is_empty(), "telemetry reaches the module's phone relay");
}
