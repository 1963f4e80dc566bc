//! `dual::DualRadio` on a virtual Si4432: the chip goes to an OpenLRSng radio and back to
//! TauLink's `LinkRadio` with nothing lost (its SDN pin still drives hard resets), and an
//! OpenLRSng step on another band gets a radio for that band.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use core::time::Duration;
use std::cell::RefCell;
use std::rc::Rc;

use openlrs::dual::DualRadio;
use openlrs::{BindingVersion, RfmType};
use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{RadioConfig, Simulation};

/// Runs `op` on a fresh chip with SDN wired; returns how long each driver reset took, in
/// virtual time, before and after the chip was lent to OpenLRSng (`lend`).
fn reset_times(lend: bool) -> (Duration, Duration) {
    let sim = Simulation::new(7);
    let medium = sim.medium();
    let handle = medium.add_radio(RadioConfig::at([0.0; 3]).with_instant_bus());
    let driver = Rfm22b::new(handle.spi, handle.nirq, handle.sdn, handle.delay);
    let time = medium.clone();
    let clock = move || time.now().as_micros() as u64;
    let out = Rc::new(RefCell::new(None));
    let result = out.clone();
    let now = medium.clone();
    let task = sim.spawn(async move {
        let mut chip = DualRadio::new(driver, TxPower::MAX, clock);
        let start = now.now();
        chip.taulink().unwrap().driver().reset().await.unwrap();
        let before = now.now() - start;
        if lend {
            let radio = chip.openlrs(BindingVersion::V39, RfmType::Mhz433).unwrap();
            assert_eq!(radio.band(), RfmType::Mhz433);
            // Another band: a radio for it, from the same parts.
            let radio = chip.openlrs(BindingVersion::V39, RfmType::Mhz868).unwrap();
            assert_eq!(radio.band(), RfmType::Mhz868);
        }
        let start = now.now();
        chip.taulink().unwrap().driver().reset().await.unwrap();
        *result.borrow_mut() = Some((before, now.now() - start));
    });
    assert!(sim.run_until_or(Duration::from_secs(1), || task.is_finished()));
    out.take().expect("the task finished")
}

#[test]
fn the_chip_comes_back_from_openlrs_with_its_sdn_pin() {
    let (before, after) = reset_times(true);
    // A hard reset holds SDN high then waits out the power-on reset (> 30 ms); a driver
    // rebuilt without its pin would only do the software reset (about 1 ms).
    assert!(before > Duration::from_millis(30), "{before:?}");
    assert_eq!(after, before);
    assert_eq!(reset_times(false), (before, before));
}
