//! The emulated MCUs the `pil` binary flies: the STM32F405 and nRF52840 SoC models of this
//! crate on `m4-sim`'s Cortex-M4F core. Until those models are on this branch the platform
//! refuses, naming what is missing.

use super::Platform;
use super::image::Image;
use crate::board::flight::FlightBoard;
use crate::board::module::ModuleBoard;
use crate::world::machine::FakeMachine;

/// The emulated boards.
#[derive(Debug, Clone, Copy, Default)]
pub struct Emulated;

/// What is missing.
const MISSING: &str = "the STM32F405 and nRF52840 models (tests/pil/src/stm32f405, nrf52840) and m4-sim's core are not on this branch yet";

impl Platform for Emulated {
    type Flight = FakeMachine<FlightBoard>;
    type Module = FakeMachine<ModuleBoard>;

    fn flight(
        &self,
        _image: &Image,
        _board: FlightBoard,
        _settings: &(u32, Vec<u8>),
        _lsi_hz: Option<f64>,
        _seed: u64,
    ) -> Result<Self::Flight, String> {
        Err(MISSING.into())
    }

    fn module(
        &self,
        _image: &Image,
        _board: ModuleBoard,
        _settings: &(u32, Vec<u8>),
        _seed: u64,
    ) -> Result<Self::Module, String> {
        Err(MISSING.into())
    }
}
