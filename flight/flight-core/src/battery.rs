//! Battery voltage and current from the ADC, cell count, consumed charge, and the warning /
//! critical levels with hysteresis and a hold time (so a punch-out's sag does not alarm).

/// How the battery is wired to the ADC and where the thresholds are.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BatteryConfig {
    /// VBAT / V_adc: 2.0 on the BrushedSparky (10 k / 10 k).
    pub voltage_divider: f32,
    /// Current-sense gain, mV at the ADC per amp (≈ 50 on the BrushedSparky); `None` if absent.
    pub current_mv_per_amp: Option<f32>,
    /// ADC reference, mV (3300), full scale 4095.
    pub adc_reference_mv: f32,
    /// Cell count; `None` detects it from the first reading.
    pub cells: Option<u8>,
    /// Per-cell warning threshold, mV.
    pub cell_warning_mv: u16,
    /// Per-cell critical threshold, mV.
    pub cell_critical_mv: u16,
    /// A level is left only this far above its threshold, mV per cell.
    pub hysteresis_mv: u16,
    /// A level is entered only after the voltage stayed below it this long.
    pub hold_ms: u32,
}

impl BatteryConfig {
    /// The BrushedSparky's on-board sensing with LiPo thresholds.
    pub const fn brushed_sparky() -> Self {
        Self {
            voltage_divider: 2.0,
            current_mv_per_amp: Some(50.0),
            adc_reference_mv: 3300.0,
            cells: None,
            cell_warning_mv: 3500,
            cell_critical_mv: 3300,
            hysteresis_mv: 100,
            hold_ms: 2_000,
        }
    }
}

/// How worried the pilot should be.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BatteryLevel {
    /// Fine.
    Ok,
    /// Land soon.
    Warning,
    /// Land now.
    Critical,
}

/// One reading, processed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BatteryStatus {
    /// Filtered pack voltage, mV.
    pub voltage_mv: u32,
    /// Current, mA (0 without a sensor).
    pub current_ma: u32,
    /// Charge used since boot, mAh.
    pub consumed_mah: u32,
    /// Cells in series (0 until known).
    pub cells: u8,
    /// Current level.
    pub level: BatteryLevel,
    /// The level changed with this reading.
    pub level_changed: bool,
}

/// The monitor. Feed it raw 12-bit ADC samples at any steady rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatteryMonitor {
    config: BatteryConfig,
    cells: Option<u8>,
    filtered_mv: Option<f32>,
    consumed_mas: f32,
    level: BatteryLevel,
    below_since: Option<(BatteryLevel, u32)>,
    last_ms: Option<u32>,
    /// A level has been judged since power-up.
    judged: bool,
}

/// Voltage filter time constant: long enough to ride out a punch-out, short enough to see
/// a real drop within a second or two.
const FILTER_TAU_MS: f32 = 500.0;
/// The highest per-cell voltage of a charged LiPo (HV cells), used to count cells.
const CELL_MAX_MV: f32 = 4350.0;

impl BatteryMonitor {
    /// A monitor with `config`.
    pub const fn new(config: BatteryConfig) -> Self {
        Self {
            config,
            cells: config.cells,
            filtered_mv: None,
            consumed_mas: 0.0,
            level: BatteryLevel::Ok,
            below_since: None,
            last_ms: None,
            judged: false,
        }
    }

    fn adc_to_mv(&self, raw: u16) -> f32 {
        f32::from(raw.min(4095)) * self.config.adc_reference_mv / 4095.0
    }

    /// Processes one sample taken at `now_ms`.
    pub fn update(
        &mut self,
        now_ms: u32,
        voltage_raw: u16,
        current_raw: Option<u16>,
    ) -> BatteryStatus {
        let dt_ms = self
            .last_ms
            .map_or(0.0, |last| now_ms.wrapping_sub(last) as f32);
        self.last_ms = Some(now_ms);
        let pack_mv = self.adc_to_mv(voltage_raw) * self.config.voltage_divider;
        let filtered = match self.filtered_mv {
            None => pack_mv,
            Some(f) => f + (pack_mv - f) * (dt_ms / (FILTER_TAU_MS + dt_ms)),
        };
        self.filtered_mv = Some(filtered);
        // Counting cells needs a plugged-in battery (> 0.5 V); the count is then fixed.
        if self.cells.is_none() && filtered > 500.0 {
            self.cells = Some(libm::ceilf(filtered / CELL_MAX_MV) as u8);
        }
        let current_ma = match (current_raw, self.config.current_mv_per_amp) {
            (Some(raw), Some(gain)) if gain > 0.0 => self.adc_to_mv(raw) / gain * 1000.0,
            _ => 0.0,
        };
        self.consumed_mas += current_ma * dt_ms / 1000.0;
        let previous = self.level;
        if let Some(cells) = self.cells.filter(|&c| c > 0) {
            self.update_level(now_ms, filtered / f32::from(cells));
        }
        BatteryStatus {
            voltage_mv: filtered as u32,
            current_ma: current_ma as u32,
            consumed_mah: (self.consumed_mas / 3600.0) as u32,
            cells: self.cells.unwrap_or(0),
            level: self.level,
            level_changed: self.level != previous,
        }
    }

    fn update_level(&mut self, now_ms: u32, cell_mv: f32) {
        let c = &self.config;
        let wanted = if cell_mv < f32::from(c.cell_critical_mv) {
            BatteryLevel::Critical
        } else if cell_mv < f32::from(c.cell_warning_mv) {
            BatteryLevel::Warning
        } else {
            BatteryLevel::Ok
        };
        if !self.judged {
            // The first verdict needs no hold: at power-up the motors are stopped, so a low
            // reading is no load sag, and arming must see a flat pack at once.
            self.judged = true;
            self.level = wanted;
        } else if wanted > self.level {
            // Worse: only after it stayed worse for the hold time.
            match self.below_since {
                Some((level, since)) if level == wanted => {
                    if now_ms.wrapping_sub(since) >= c.hold_ms {
                        self.level = wanted;
                        self.below_since = None;
                    }
                }
                _ => self.below_since = Some((wanted, now_ms)),
            }
        } else {
            self.below_since = None;
            // Better: only with a margin above the threshold being left (a rested pack
            // recovers a little; that must not silence the alarm).
            let threshold = match self.level {
                BatteryLevel::Critical => c.cell_critical_mv,
                BatteryLevel::Warning => c.cell_warning_mv,
                BatteryLevel::Ok => return,
            };
            if cell_mv > f32::from(threshold) + f32::from(c.hysteresis_mv) {
                self.level = wanted;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ADC count for a pack voltage on the BrushedSparky divider.
    fn raw(pack_mv: f32) -> u16 {
        (pack_mv / 2.0 / 3300.0 * 4095.0).round() as u16
    }

    #[test]
    fn voltage_cells_and_current() {
        let mut m = BatteryMonitor::new(BatteryConfig::brushed_sparky());
        // 2 A through 50 mV/A = 100 mV at the ADC.
        let current = (100.0 / 3300.0 * 4095.0_f32).round() as u16;
        let s = m.update(0, raw(4150.0), Some(current));
        assert_eq!(s.cells, 1);
        assert!((4145..=4155).contains(&s.voltage_mv), "{}", s.voltage_mv);
        assert!((1995..=2005).contains(&s.current_ma), "{}", s.current_ma);
        // One hour at 2 A in 1 s steps = 2000 mAh.
        let mut last = s;
        for t in 1..=3600u32 {
            last = m.update(t * 1000, raw(4150.0), Some(current));
        }
        assert!(
            (1990..=2010).contains(&last.consumed_mah),
            "{}",
            last.consumed_mah
        );
        let mut two = BatteryMonitor::new(BatteryConfig::brushed_sparky());
        assert_eq!(
            two.update(0, raw(7000.0), None).cells,
            2,
            "a flat 2S is still 2S"
        );
    }

    #[test]
    fn levels_need_the_hold_time_and_leave_with_hysteresis() {
        let mut m = BatteryMonitor::new(BatteryConfig::brushed_sparky());
        m.update(0, raw(3900.0), None);
        // A 300 ms punch-out sag to 3.2 V does not alarm.
        for t in (10..300).step_by(10) {
            assert_eq!(m.update(t, raw(3200.0), None).level, BatteryLevel::Ok);
        }
        for t in (300..2_000).step_by(10) {
            m.update(t, raw(3900.0), None);
        }
        // A real drop to 3.45 V/cell at 2 s: the 500 ms filter crosses 3.5 V after
        // 0.5 s × ln(450 / 50) = 1.1 s, then the 2 s hold: warning at about 5.1 s.
        let mut warned_at = None;
        for t in (2_000..6_000).step_by(10) {
            let s = m.update(t, raw(3450.0), None);
            if s.level_changed {
                assert_eq!(s.level, BatteryLevel::Warning);
                warned_at = Some(t);
            }
        }
        let warned_at = warned_at.expect("warning raised");
        assert!(
            (5_050..=5_150).contains(&warned_at),
            "warned at {warned_at} ms"
        );
        // Recovering to 3.55 V (inside the 100 mV hysteresis) keeps the warning.
        for t in (6_000..9_000).step_by(10) {
            assert_eq!(m.update(t, raw(3550.0), None).level, BatteryLevel::Warning);
        }
        // 3.65 V clears it.
        let s = (9_000..12_000)
            .step_by(10)
            .map(|t| m.update(t, raw(3650.0), None))
            .last()
            .unwrap();
        assert_eq!(s.level, BatteryLevel::Ok);
    }

    #[test]
    fn a_flat_pack_at_power_up_is_critical_at_once() {
        let mut m = BatteryMonitor::new(BatteryConfig::brushed_sparky());
        // 3.2 V on a 1S pack from the first reading: no hold time (motors are off).
        let s = m.update(0, raw(3200.0), None);
        assert_eq!(s.level, BatteryLevel::Critical);
        assert!(s.level_changed);
        let mut fine = BatteryMonitor::new(BatteryConfig::brushed_sparky());
        assert_eq!(fine.update(0, raw(4100.0), None).level, BatteryLevel::Ok);
    }
}
