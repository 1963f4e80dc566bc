//! The console's behaviour: a line of `settings::console`'s command language in, the answer
//! out. Changes go to the live settings (the gains are re-designed); `save` requests a
//! write; `bind [PHRASE]` opens the bind window (the only way this controller binds), with
//! the binding phrase the module has (spec §12.1: the phrase is held in RAM for the window
//! only, never stored or printed; the bind agrees a random link key, whose fingerprint
//! `status` shows so the pilot can compare both ends); `set`, `save`, `defaults` and `bind`
//! are refused while armed; `magcal` runs the magnetometer calibration (`super::magcal`),
//! disarmed only. The USB adapter only moves lines and bytes.
//!
//! Whole numbers are written as `u32` (`u32::from`, [`Signed`]), words as [`Word`]: core
//! has a formatter per integer type, and `u32`'s is all the image needs (920 B less of the
//! Sparky2's flash, measured, than one each for `u8`, `u16`, `u64`, `i32` and their hex).

use core::fmt::Write;

use super::link::{BindError, BindReport};
use super::{FlightApp, resume};
use telemetry::link::Fingerprint;

use crate::battery::BatteryLevel;
use crate::sensors::ubx::config::Status;
use crate::sensors::ubx::{FixType, Generation};
use crate::settings::decimal::{Fixed, Shortest};
use crate::settings::{
    Command, LineError, MagcalAction, Settings, Signed, Word, parse_line, write_list, write_setting,
};

/// The bind window in whole seconds, as the console says it.
const BIND_WINDOW_S: u32 = (super::BIND_WINDOW_US / 1_000_000) as u32;

const HELP: &str = "help | list [prefix] | get NAME | set NAME VALUE [NAME VALUE]... | save | defaults | status | bind [PHRASE] | magcal start|status|save|cancel\r\n";

impl FlightApp {
    /// Answers what the line assembler (`settings::LineAssembler`) produced: a whole line,
    /// or the reason one was refused (too long, not text) — never a cut line.
    pub fn on_console_input(
        &mut self,
        line: Result<&str, &LineError>,
        out: &mut dyn Write,
    ) -> core::fmt::Result {
        match line {
            Ok(line) => self.on_console_line(line, out),
            Err(e) => write!(out, "{e}\r\n"),
        }
    }

    /// Answers one console line (without its line ending) into `out`.
    pub fn on_console_line(&mut self, line: &str, out: &mut dyn Write) -> core::fmt::Result {
        let armed = self.armed();
        match parse_line(line) {
            Ok(Command::Nothing) => Ok(()),
            Ok(Command::Help) => out.write_str(HELP),
            Ok(Command::List(prefix)) => write_list(out, &self.live, prefix),
            Ok(Command::Get(name)) => write_setting(out, &self.live, name),
            Ok(
                Command::Set { .. }
                | Command::SetAll(_)
                | Command::Save
                | Command::Defaults
                | Command::Bind(_)
                | Command::Magcal(_),
            ) if armed => out.write_str("refused: disarm first\r\n"),
            Ok(Command::Magcal(action)) => self.on_magcal(action, out),
            Ok(Command::Set { name, value }) => match self.live.set_text(name, value) {
                Ok(()) => {
                    self.settings_changed();
                    write_setting(out, &self.live, name)
                }
                Err(e) => write!(out, "{e}\r\n"),
            },
            Ok(Command::SetAll(pairs)) => match self.live.set_text_pairs(pairs) {
                Ok(()) => {
                    self.settings_changed();
                    out.write_str("ok\r\n")
                }
                Err(e) => write!(out, "{e}\r\n"),
            },
            Ok(Command::Save) => {
                self.request_save();
                out.write_str("saving\r\n")
            }
            Ok(Command::Defaults) => {
                let key = self.live.link_key();
                self.live = Settings::default();
                if key.is_some() {
                    self.on_link_key_changed();
                }
                self.settings_changed();
                out.write_str("factory values (not saved)\r\n")
            }
            Ok(Command::Status) => self.write_status(out),
            Ok(Command::Bind(phrase)) => match self.request_bind(phrase) {
                Ok(with_phrase) => write!(
                    out,
                    "bind window open for {} s {}: start the bind on the module\r\n",
                    BIND_WINDOW_S,
                    Word(if with_phrase {
                        "with the phrase (held until the window closes, never stored)"
                    } else {
                        "without a phrase"
                    })
                ),
                Err(BindError::Armed) => out.write_str("refused: disarm first\r\n"),
                Err(BindError::Phrase(e)) => write!(out, "refused: {e}\r\n"),
                Err(BindError::NoRandomness) => {
                    out.write_str("refused: the RNG failed at boot; power-cycle and bind again\r\n")
                }
            },
            Err(e) => write!(out, "{e}\r\n"),
        }
    }

    fn on_magcal(&mut self, action: MagcalAction, out: &mut dyn Write) -> core::fmt::Result {
        match action {
            MagcalAction::Start => {
                self.magcal.start();
                out.write_str(
                    "magcal: turn the frame through every orientation (each axis up and down), then magcal status / magcal save\r\n",
                )
            }
            MagcalAction::Cancel => {
                self.magcal.cancel();
                out.write_str("magcal: cancelled, nothing stored\r\n")
            }
            MagcalAction::Status => {
                self.write_magcal_samples(out)?;
                match self.magcal.fit() {
                    Ok(cal) => {
                        write_calibration(out, &cal)?;
                        out.write_str("checks pass: magcal save stores it\r\n")
                    }
                    Err(e) => write!(out, "not yet: {e}\r\n"),
                }
            }
            MagcalAction::Save => match self.store_magcal() {
                Ok(cal) => {
                    write_calibration(out, &cal)?;
                    out.write_str("stored, saving\r\n")
                }
                Err(super::magcal::StoreRefused::NotStarted) => {
                    out.write_str("refused: magcal start first\r\n")
                }
                Err(e) => write!(out, "refused: {e}; nothing stored\r\n"),
            },
        }
    }

    fn write_magcal_samples(&self, out: &mut dyn Write) -> core::fmt::Result {
        let m = &self.magcal;
        write!(
            out,
            "magcal {}: {} readings{}\r\n",
            Word(if m.collecting() { "collecting" } else { "idle" }),
            m.len(),
            Word(if m.is_full() { " (full)" } else { "" })
        )
    }

    fn write_status(&self, out: &mut dyn Write) -> core::fmt::Result {
        let link = Word(if self.link_input.up { "up" } else { "down" });
        match self.last_output() {
            Some(state) => {
                write!(
                    out,
                    "mode {}, failsafe {}, link {}, arm blockers {:#x}, attitude ",
                    Word(state.mode.name()),
                    Word::of_bool(state.failsafe),
                    link,
                    u32::from(self.arming_blockers()),
                )?;
                write_vector(out, state.attitude.deg(), |v| Fixed(v, 1))?;
                out.write_str(" deg\r\n")?
            }
            None => out.write_str("flight loop not running (IMU?)\r\n")?,
        }
        if let Some(estimator) = self.view.as_ref().map(|v| v.estimator) {
            write!(
                out,
                "estimator {} (ins.mode {}), fallbacks {}, gps fix {}\r\n",
                Word(estimator.source.name()),
                Word(estimator.mode.name()),
                u32::from(estimator.fallbacks),
                Word::of_bool(estimator.gps_fix)
            )?;
        }
        if let Some((pvt, _)) = self.gps_latest() {
            let (generation, config) = self.gps_config_status();
            write!(
                out,
                "gps {} sats {} hacc {} mm, receiver {}, config ",
                Word(fix_name(pvt.fix_type)),
                u32::from(pvt.num_sv),
                pvt.h_acc_mm,
                Word(match generation {
                    Generation::M8 => "M8",
                    Generation::M9M10 => "M9/M10",
                }),
            )?;
            match config {
                Status::Pending { step } => write!(out, "waiting for ACK {}", u32::from(step))?,
                Status::Done => out.write_str("done")?,
                Status::Refused { id } => write!(out, "refused CFG {:#04x}", u32::from(id))?,
                Status::NoAnswer { id } => write!(out, "no answer to CFG {:#04x}", u32::from(id))?,
            }
            out.write_str("\r\n")?;
        }
        if let Some(home) = self.view.as_ref().and_then(|v| v.estimator.home) {
            write!(
                out,
                "home lat {} lon {} (1e-7 deg) msl {} mm\r\n",
                Signed(home.lat_e7),
                Signed(home.lon_e7),
                Signed(home.h_msl_mm)
            )?;
        }
        if let Some(fault) = self.imu_fault() {
            write!(
                out,
                "IMU fault: {} (motors stopped, re-arm needed)\r\n",
                Word(fault.name())
            )?;
        }
        if let Some(p) = self.settings_problem {
            write!(
                out,
                "settings problem at boot: {p}; arming refused until saved\r\n"
            )?;
        }
        if let Some(e) = self.setup_error {
            write!(out, "stored settings not flyable ({e}): factory setup\r\n")?;
        }
        self.write_health(out)?;
        self.write_link_state(out)?;
        let armed = Word::of_bool(self.armed());
        match self.battery {
            Some(b) => write!(
                out,
                "armed {armed}, battery {} mV {} mA {}\r\n",
                b.voltage_mv,
                b.current_ma,
                Word(match b.level {
                    BatteryLevel::Ok => "ok",
                    BatteryLevel::Warning => "warning",
                    BatteryLevel::Critical => "critical",
                })
            ),
            None => write!(out, "armed {armed}, battery unknown\r\n"),
        }
    }
}

impl FlightApp {
    /// The firmware's standing, a line each: the loop's misses, what the boot found, the
    /// baro, a resumed flight, the USB host.
    fn write_health(&self, out: &mut dyn Write) -> core::fmt::Result {
        let h = self.health();
        write!(
            out,
            "loop: {} IMU samples missed, {} overruns\r\n",
            u32::from(h.imu_missed),
            u32::from(h.loop_overruns)
        )?;
        if self.board.boot.clock_fallback {
            out.write_str("HSE crystal did not start: clocks on the HSI (USB unreliable)\r\n")?;
        }
        if self.board.boot.rng_fallback {
            out.write_str("RNG failed at boot: seeds from the unique ID and timing\r\n")?;
        }
        if self.baro.failed() {
            write!(
                out,
                "baro failed ({} failed readings): hold modes fall back to attitude\r\n",
                self.baro.failures()
            )?;
        }
        if let Some(fault) = self.resumed {
            // In words and numbers: `Debug` would link core's struct formatting.
            out.write_str("flight resumed after a reset in the air (")?;
            match fault {
                None => out.write_str("watchdog")?,
                Some(f) => {
                    let reason = Word(match f.reason {
                        resume::FaultReason::Panic => "panic",
                        resume::FaultReason::HardFault => "HardFault",
                    });
                    write!(out, "{reason} at {} ms, address {:#x}", f.at_ms, f.address)?;
                }
            }
            out.write_str(")\r\n")?;
        }
        if self.board.usb_connected {
            out.write_str("USB connected: arming refused (unplug to fly)\r\n")?;
        }
        Ok(())
    }

    /// The link's key as the console shows it (its fingerprint, never the key) and how the
    /// last bind window ended.
    fn write_link_state(&self, out: &mut dyn Write) -> core::fmt::Result {
        match (self.link_params(), self.live.link_key()) {
            (Some(_), Some(key)) => write!(
                out,
                "link authenticated, key fingerprint {} (the module shows the same)\r\n",
                key.fingerprint()
            )?,
            (Some(_), None) => {
                out.write_str("link unauthenticated (link.unauthenticated 1)\r\n")?
            }
            (None, _) => out.write_str("not bound: bind [PHRASE] opens the bind window\r\n")?,
        }
        match self.last_bind() {
            Some(BindReport::Bound { fingerprint, .. }) => match fingerprint {
                Some(f) => write!(out, "last bind: bound, key {}\r\n", Fingerprint(f)),
                None => out.write_str("last bind: bound unauthenticated\r\n"),
            },
            Some(BindReport::Refused(why)) => {
                write!(out, "last bind: not bound, {}\r\n", Word(why.describe()))
            }
            Some(BindReport::NoOffer) => out.write_str("last bind: no offer heard\r\n"),
            None => Ok(()),
        }
    }
}

/// A NAV-PVT fix type in words (`Debug` text would link core's struct formatting).
fn fix_name(fix: FixType) -> &'static str {
    match fix {
        FixType::NoFix => "none",
        FixType::DeadReckoning => "dead-reckoning",
        FixType::Fix2D => "2D",
        FixType::Fix3D => "3D",
        FixType::GnssDeadReckoning => "3D+dead-reckoning",
        FixType::TimeOnly => "time-only",
        FixType::Unknown(_) => "unknown",
    }
}

/// The fit and its checks, one line each.
fn write_calibration(
    out: &mut dyn Write,
    cal: &crate::estimation::magcal::MagCalibration,
) -> core::fmt::Result {
    let [[xx, xy, xz], [_, yy, yz], [_, _, zz]] = cal.matrix.map(|row| row.map(Shortest));
    out.write_str("offset ")?;
    write_vector(out, cal.offset, Shortest)?;
    write!(
        out,
        "\r\nmatrix xx {xx} yy {yy} zz {zz} xy {xy} xz {xz} yz {yz}\r\nfield {}, residual {} % (round: < 3 %), coverage {} (≥ 0.3)\r\n",
        Shortest(cal.field),
        Fixed(cal.residual_pct, 2),
        Fixed(cal.coverage, 2)
    )
}

/// `[x, y, z]`, each value written as `text` makes it.
fn write_vector<T: core::fmt::Display>(
    out: &mut dyn Write,
    v: [f32; 3],
    text: impl Fn(f32) -> T,
) -> core::fmt::Result {
    let [x, y, z] = v.map(text);
    write!(out, "[{x}, {y}, {z}]")
}
