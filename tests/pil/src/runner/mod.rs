//! The `pil` runner: a named scenario flown by the images of `cargo xtask dist` on the
//! emulated boards ([`crate::world`]), reduced to flight-sitl's figures plus each image's.
//!
//! **flight-sitl is reused, not copied**: the scenarios that exist there (`hover`,
//! `link-cut`, `imu-stall`) take its timeline (`flight_sitl::runner::plan`: the pilot's
//! `PilotPlan`, the fault's time), its pilot (`flight_sitl::runner::scenario`), its figures
//! (`report::extract`) and its acceptance (`acceptance::check`); the PIL-only ones
//! (`boot`, `i2c-stuck`, `settings-save`, `panic`) build on the same pieces. The time the
//! climb reaches the altitude comes from flight-sitl's probe run (`reach_times`, the SITL
//! world, ≈ 150× real time) rather than a probe of the emulated world: the pilot's hold
//! starts there, then flies by the truth it sees in this world.
//!
//! The emulated MCUs come from a [`Platform`] (the STM32F405 and nRF52840 models on
//! `m4-sim`'s core; a scripted fake in the tests).

pub mod binding;
pub mod cli;
pub mod emulated;
pub mod image;
pub mod report;
pub mod variant;

use std::path::PathBuf;

use flight_app::outputs::Protocol;
use flight_sitl::runner::pilot::PilotPlan;
use flight_sitl::runner::{Kind as SitlKind, Options as SitlOptions, Plan, RunError};

use crate::board::flight::{FlightBoard, FlightBoardKind};
use crate::board::module::ModuleBoard;
use crate::world::machine::{Injection, Machine};
use crate::world::{Radios, World, WorldConfig};
use image::Image;
pub use report::Outcome;

/// The binding phrase both ends carry unless told otherwise.
pub const DEFAULT_PHRASE: &str = "amber kettle under the oak";

/// The module's nRF52840 FICR DEVICEID, which a [`Platform`] programs into the model: the
/// module derives its HM-10 pairing PIN from it (`module_core::hm10::at::Pin::factory`), and
/// the pilot's phone knows that PIN, as printed on the module's label.
pub const MODULE_DEVICE_ID: u64 = 0x5A17_0002_8840_0001;

/// A named PIL scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Both boards power up; every task of both images is polled, the link comes up, no
    /// reset, no fault.
    Boot,
    /// flight-sitl's `hover` (30 s at F250 unless `--duration`).
    Hover,
    /// flight-sitl's `link-cut`.
    LinkCut,
    /// flight-sitl's `imu-stall`: the MPU-9250's data-ready stops for 1 s.
    ImuStall,
    /// The MS5611 holds SDA low from power-on (an MCU reset mid-read): the image must clock
    /// the bus free and fly without a watchdog reset (issue 29's stuck I²C).
    I2cStuck,
    /// The phone changes a setting over the link, the flight side saves it to flash, the
    /// board is power-cycled and comes back with it (flight-sitl's `power-cycle` timeline).
    SettingsSave,
    /// A DMA transfer error on the IMU's stream panics the flight image in the air: how
    /// soon the motors stop, and what the image does next.
    Panic,
}

impl Kind {
    /// Every scenario.
    pub const ALL: [Kind; 7] = [
        Kind::Boot,
        Kind::Hover,
        Kind::LinkCut,
        Kind::ImuStall,
        Kind::I2cStuck,
        Kind::SettingsSave,
        Kind::Panic,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Boot => "boot",
            Kind::Hover => "hover",
            Kind::LinkCut => "link-cut",
            Kind::ImuStall => "imu-stall",
            Kind::I2cStuck => "i2c-stuck",
            Kind::SettingsSave => "settings-save",
            Kind::Panic => "panic",
        }
    }

    /// The flight-sitl scenario whose timeline and pilot it flies.
    pub fn sitl(self) -> SitlKind {
        match self {
            Kind::LinkCut => SitlKind::LinkCut,
            Kind::ImuStall => SitlKind::ImuStall,
            Kind::SettingsSave => SitlKind::PowerCycle,
            Kind::Panic => SitlKind::Panic,
            Kind::Boot | Kind::Hover | Kind::I2cStuck => SitlKind::Hover,
        }
    }
}

/// What a run is asked for.
#[derive(Debug, Clone)]
pub struct Options {
    /// The scenario.
    pub kind: Kind,
    /// The flight board.
    pub board: FlightBoardKind,
    /// flight-sitl's options: rate, seed, settings, airframe, altitude, fault time, duration.
    pub sitl: SitlOptions,
    /// The flight board's LSI (IWDG clock), Hz (None: the model's nominal 32 kHz).
    pub lsi_hz: Option<f64>,
    /// The flight image.
    pub flight_image: PathBuf,
    /// The module image.
    pub module_image: PathBuf,
    /// The binding phrase on both ends (None: unauthenticated).
    pub phrase: Option<String>,
    /// The lockstep quantum, ns.
    pub quantum_ns: u64,
    /// A USB host at the flight console asks `status` every 10 ms from the take-off.
    pub console_busy: bool,
}

impl Options {
    /// Factory settings (flight-sitl's), the BrushedSparky, the dist images, the default
    /// phrase, `kind`.
    pub fn new(kind: Kind) -> Self {
        Self {
            kind,
            board: FlightBoardKind::BrushedSparky,
            sitl: SitlOptions::factory(),
            lsi_hz: None,
            flight_image: image::dist_dir().join("flight-brushedsparky.elf"),
            module_image: image::dist_dir().join("module-nrf52840.elf"),
            phrase: Some(DEFAULT_PHRASE.to_owned()),
            quantum_ns: crate::world::QUANTUM_NS,
            console_busy: false,
        }
    }
}

/// Makes the emulated MCUs: loads an image and the settings flash into a SoC model on its
/// board.
pub trait Platform {
    /// The flight MCU.
    type Flight: Machine<Board = FlightBoard>;
    /// The module MCU.
    type Module: Machine<Board = ModuleBoard>;

    /// The STM32F405 on `board` running `image`, its settings sectors holding `settings`
    /// (address, bytes), its LSI at `lsi_hz`.
    ///
    /// # Errors
    /// When the image or the flash contents cannot be loaded.
    fn flight(
        &self,
        image: &Image,
        board: FlightBoard,
        settings: &(u32, Vec<u8>),
        lsi_hz: Option<f64>,
        seed: u64,
    ) -> Result<Self::Flight, String>;

    /// The nRF52840 on `board` running `image`, its settings pages holding `settings`, its
    /// FICR DEVICEID [`MODULE_DEVICE_ID`].
    ///
    /// # Errors
    /// As [`Platform::flight`].
    fn module(
        &self,
        image: &Image,
        board: ModuleBoard,
        settings: &(u32, Vec<u8>),
        seed: u64,
    ) -> Result<Self::Module, String>;
}

/// Why a run could not be made.
#[derive(Debug, Clone, PartialEq)]
pub enum PilError {
    /// An image file.
    Image(String),
    /// The scenario's timeline (flight-sitl's planning).
    Plan(RunError),
    /// Building a machine.
    Platform(String),
    /// The settings could not be stored.
    Settings(String),
}

impl core::fmt::Display for PilError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PilError::Image(e) => write!(f, "{e}"),
            PilError::Plan(e) => write!(f, "{e}"),
            PilError::Platform(e) => write!(f, "{e}"),
            PilError::Settings(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for PilError {}

/// The timeline of `opts`: flight-sitl's plan for its scenario (with the climb's reach
/// time from flight-sitl's probe), or for `boot` a pilot who never touches the sticks.
///
/// # Errors
/// When flight-sitl cannot plan it (altitude not reached, fault too early).
pub fn plan(opts: &Options) -> Result<Plan, RunError> {
    let sitl = sitl_options(opts);
    let kind = opts.kind.sitl();
    if opts.kind == Kind::Boot {
        let idle = PilotPlan {
            start_s: f64::INFINITY,
            ..PilotPlan::climb(&sitl.quad, 0.0)
        };
        return Ok(Plan {
            kind,
            rate: sitl.rate,
            seed: sitl.seed,
            fault_at_s: None,
            fault_end_s: None,
            hold_from_s: None,
            duration_s: opts.sitl.duration_s.unwrap_or(BOOT_S),
            pilot: idle,
            gps: sitl.gps,
            wind_mps: sitl.wind_mps,
        });
    }
    let altitude = sitl.altitude_m.unwrap_or(kind.default_altitude_m());
    let reach = if kind == SitlKind::PowerCycle {
        (0.0, 0.0)
    } else {
        let start = if kind == SitlKind::LinkCut {
            altitude
        } else {
            (altitude - flight_sitl::runner::pilot::HOLD_LEAD_M).max(altitude / 2.0)
        };
        flight_sitl::runner::reach_times(&sitl, &[start])?
            .first()
            .copied()
            .unwrap_or((0.0, 0.0))
    };
    // flight-sitl's timeline; the panic's fault is the PIL's own (a DMA transfer error at
    // `fault_at_s`, injected by `run`), not the SITL's `flight_panic` input.
    flight_sitl::runner::plan(kind, &sitl, reach)
}

/// The scenario time `boot` runs after the 4 s warm-up, s.
pub const BOOT_S: f64 = 1.0;
/// `hover`'s length unless told, s (issue 28: 30 s).
pub const HOVER_S: f64 = 30.0;

fn sitl_options(opts: &Options) -> SitlOptions {
    let mut sitl = opts.sitl.clone();
    if opts.kind == Kind::Hover && sitl.duration_s.is_none() {
        sitl.duration_s = Some(HOVER_S);
    }
    sitl
}

/// The output protocol the flight settings choose (what the motors are read with).
pub fn protocol(settings: &flight_app::settings::Settings) -> Protocol {
    flight_app::pipeline::from_settings(settings)
        .map(|s| s.protocol)
        .unwrap_or(Protocol::Brushed {
            frequency_hz: 32_000,
        })
}

/// The IMU's SPI1 RX stream: DMA2 stream 0 (flight-fw `board.rs`).
pub const IMU_RX_DMA: Injection = Injection::DmaTransferError {
    controller: 2,
    stream: 0,
};

/// The world of `opts` on `platform` at virtual 0: both images loaded onto their boards, the
/// bound settings in their flash, the phone knowing the module's PIN; with the scenario's
/// plan and the two images.
///
/// # Errors
/// When an image, the plan, the settings or a machine cannot be made.
pub fn world<P: Platform>(platform: &P, opts: &Options) -> Result<Prepared<P>, PilError> {
    let flight_image =
        Image::load(&opts.flight_image).map_err(|e| PilError::Image(e.to_string()))?;
    let module_image =
        Image::load(&opts.module_image).map_err(|e| PilError::Image(e.to_string()))?;
    let plan = plan(opts).map_err(PilError::Plan)?;
    let sitl_opts = sitl_options(opts);
    let mut scenario = flight_sitl::runner::scenario(&sitl_opts, plan.clone());
    if opts.kind == Kind::SettingsSave {
        scenario.setting_changes = vec![report::saved_change()];
    }
    let (flight_settings, module_settings) =
        binding::bound_pair(&scenario, opts.phrase.as_deref()).map_err(PilError::Settings)?;
    let flight_flash = binding::flight_flash(&flight_settings).map_err(PilError::Settings)?;
    let module_flash = binding::module_flash(&module_settings).map_err(PilError::Settings)?;
    // The change key the pilot's phone got by proving the phrase to the module (spec §12.5).
    let key = flight_settings
        .link_key()
        .map(|k| telemetry::change_auth::ChangeKey::from_link_key(&k));
    let config = WorldConfig {
        board: opts.board,
        quantum_ns: opts.quantum_ns,
        i2c_stuck: (opts.kind == Kind::I2cStuck).then_some((0, 9)),
        phone_key: key,
        phone_pin: Some(module_core::hm10::at::Pin::factory(MODULE_DEVICE_ID).value()),
        console_busy_from: opts
            .console_busy
            .then(|| report::virtual_ns(flight_sitl::runner::pilot::TAKEOFF_S)),
        ..WorldConfig::default()
    };
    let mut radios = Radios::new(scenario.seed, scenario.packet_loss);
    let protocol = protocol(&flight_settings);
    let fb = crate::world::flight_board(&config, &mut radios, protocol, &scenario)
        .ok_or_else(|| PilError::Platform("no flight radio".into()))?;
    let mb = crate::world::module_board(&mut radios)
        .ok_or_else(|| PilError::Platform("no module radio".into()))?;
    let seed = scenario.seed;
    let flight = platform
        .flight(&flight_image, fb, &flight_flash, opts.lsi_hz, seed)
        .map_err(PilError::Platform)?;
    let module = platform
        .module(&module_image, mb, &module_flash, seed)
        .map_err(PilError::Platform)?;
    Ok(Prepared {
        world: World::new(scenario, config, radios, flight, module),
        plan,
        images: [flight_image, module_image],
    })
}

/// A world ready to run ([`world`]).
pub struct Prepared<P: Platform> {
    /// The co-simulation at virtual 0.
    pub world: World<P::Flight, P::Module>,
    /// The scenario's timeline.
    pub plan: Plan,
    /// The flight and the module image.
    pub images: [Image; 2],
}

/// Runs `opts` on `platform`.
///
/// # Errors
/// When an image, the plan, the settings or a machine cannot be made.
pub fn run<P: Platform>(platform: &P, opts: &Options) -> Result<Outcome, PilError> {
    let Prepared {
        mut world,
        plan,
        images: [flight_image, module_image],
    } = world(platform, opts)?;
    let started = std::time::Instant::now();
    let cpu_before = report::thread_cpu_s();
    let injected = if let (Kind::Panic, Some(at)) = (opts.kind, plan.fault_at_s) {
        world.run_until(report::virtual_ns(at));
        Some((world.now_ns(), world.flight.inject(IMU_RX_DMA)))
    } else {
        None
    };
    world.run_to_end();
    let wall_s = started.elapsed().as_secs_f64();
    let cpu_s = report::thread_cpu_s().zip(cpu_before).map(|(a, b)| a - b);
    Ok(report::Outcome::measure(
        opts,
        plan,
        &mut world,
        [&flight_image, &module_image],
        injected,
        wall_s,
        cpu_s,
    ))
}

#[cfg(test)]
mod tests;
