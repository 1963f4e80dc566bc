//! The receiver's channel (IF) filter: register 0x1C and its bandwidth table (datasheet
//! filter-bandwidth table; AN440). Pure lookup, `const`.

/// One row of the datasheet table: the filter's −3 dB bandwidth and its 0x1C value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Row {
    /// Bandwidth in units of 100 Hz (the datasheet gives one decimal in kHz).
    bandwidth_100hz: u16,
    /// dwn3_bypass (bit 7) | ndec_exp (bits 6:4) | filset (bits 3:0).
    register: u8,
}

const fn row(bandwidth_100hz: u16, dwn3_bypass: u8, ndec_exp: u8, filset: u8) -> Row {
    Row {
        bandwidth_100hz,
        register: (dwn3_bypass << 7) | (ndec_exp << 4) | filset,
    }
}

/// The 57 filters of the datasheet table, narrowest first. Silicon Labs' calculator (and
/// OpenLRSng's `rfm22calc.c`, and the Tau Labs table) pick the narrowest filter whose
/// bandwidth is at least the wanted one.
const TABLE: [Row; 57] = [
    row(26, 0, 5, 1),
    row(28, 0, 5, 2),
    row(31, 0, 5, 3),
    row(32, 0, 5, 4),
    row(37, 0, 5, 5),
    row(42, 0, 5, 6),
    row(45, 0, 5, 7),
    row(49, 0, 4, 1),
    row(54, 0, 4, 2),
    row(59, 0, 4, 3),
    row(61, 0, 4, 4),
    row(72, 0, 4, 5),
    row(82, 0, 4, 6),
    row(88, 0, 4, 7),
    row(95, 0, 3, 1),
    row(106, 0, 3, 2),
    row(115, 0, 3, 3),
    row(121, 0, 3, 4),
    row(142, 0, 3, 5),
    row(162, 0, 3, 6),
    row(175, 0, 3, 7),
    row(189, 0, 2, 1),
    row(210, 0, 2, 2),
    row(227, 0, 2, 3),
    row(240, 0, 2, 4),
    row(282, 0, 2, 5),
    row(322, 0, 2, 6),
    row(347, 0, 2, 7),
    row(377, 0, 1, 1),
    row(417, 0, 1, 2),
    row(452, 0, 1, 3),
    row(479, 0, 1, 4),
    row(562, 0, 1, 5),
    row(641, 0, 1, 6),
    row(692, 0, 1, 7),
    row(752, 0, 0, 1),
    row(832, 0, 0, 2),
    row(900, 0, 0, 3),
    row(953, 0, 0, 4),
    row(1121, 0, 0, 5),
    row(1279, 0, 0, 6),
    row(1379, 0, 0, 7),
    row(1428, 1, 1, 4),
    row(1678, 1, 1, 5),
    row(1811, 1, 1, 9),
    row(1915, 1, 0, 15),
    row(2251, 1, 0, 1),
    row(2488, 1, 0, 2),
    row(2693, 1, 0, 3),
    row(2849, 1, 0, 4),
    row(3355, 1, 0, 8),
    row(3618, 1, 0, 9),
    row(4202, 1, 0, 10),
    row(4684, 1, 0, 11),
    row(5188, 1, 0, 12),
    row(5770, 1, 0, 13),
    row(6207, 1, 0, 14),
];

/// A channel filter setting (register 0x1C).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IfFilter {
    register: u8,
}

impl IfFilter {
    /// The widest filter of the table: 620.7 kHz.
    pub const MAX_BANDWIDTH_HZ: u32 = 620_700;

    /// The narrowest datasheet filter at least `bandwidth_hz` wide, or `None` above 620.7 kHz.
    pub const fn for_bandwidth_hz(bandwidth_hz: u32) -> Option<Self> {
        let mut rest: &[Row] = &TABLE;
        while let [row, tail @ ..] = rest {
            if bandwidth_hz <= row.bandwidth_100hz as u32 * 100 {
                return Some(Self {
                    register: row.register,
                });
            }
            rest = tail;
        }
        None
    }

    /// Any 0x1C value with filset ≠ 0 and ndec_exp ≤ 5. Values outside the datasheet table
    /// (some hand-tuned profiles use them, e.g. OpenLRSng's 4800 bps 0x1A) are accepted; their
    /// bandwidth is then unknown.
    pub const fn from_register(register: u8) -> Option<Self> {
        let filset = register & 0x0F;
        let ndec_exp = (register >> 4) & 0x07;
        if filset == 0 || ndec_exp > 5 {
            return None;
        }
        Some(Self { register })
    }

    /// The 0x1C value.
    pub const fn register(self) -> u8 {
        self.register
    }

    /// dwn3_bypass: the decimate-by-3 stage is bypassed (wide filters).
    pub const fn dwn3_bypass(self) -> bool {
        self.register & 0x80 != 0
    }

    /// ndec_exp: the IF decimation exponent.
    pub const fn ndec_exp(self) -> u8 {
        (self.register >> 4) & 0x07
    }

    /// The −3 dB bandwidth from the datasheet table, if this setting is in it.
    pub const fn bandwidth_hz(self) -> Option<u32> {
        let mut rest: &[Row] = &TABLE;
        while let [row, tail @ ..] = rest {
            if row.register == self.register {
                return Some(row.bandwidth_100hz as u32 * 100);
            }
            rest = tail;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_the_narrowest_filter_that_fits() {
        // Carson bandwidths (bit rate + 2 × deviation) of the rates in the data-rate table of
        // Tau Labs `flight/PiOS/Common/pios_rfm22b.c`; 75.2 kHz is the widest the 0x01 setting
        // of the Si4432 datasheet's IF-filter table (register 1Ch) passes.
        assert_eq!(IfFilter::for_bandwidth_hz(69_600).unwrap().register(), 0x01);
        assert_eq!(IfFilter::for_bandwidth_hz(75_200).unwrap().register(), 0x01);
        assert_eq!(IfFilter::for_bandwidth_hz(75_201).unwrap().register(), 0x02);
        assert_eq!(
            IfFilter::for_bandwidth_hz(147_600).unwrap().register(),
            0x95
        );
        assert_eq!(
            IfFilter::for_bandwidth_hz(556_000).unwrap().register(),
            0x8D
        );
        assert_eq!(IfFilter::for_bandwidth_hz(1).unwrap().register(), 0x51);
        assert_eq!(IfFilter::for_bandwidth_hz(620_701), None);
    }

    #[test]
    fn table_is_sorted_and_round_trips() {
        for pair in TABLE.windows(2) {
            assert!(pair[0].bandwidth_100hz < pair[1].bandwidth_100hz);
        }
        for r in TABLE {
            let f = IfFilter::from_register(r.register).unwrap();
            assert_eq!(f.bandwidth_hz(), Some(u32::from(r.bandwidth_100hz) * 100));
        }
        assert_eq!(IfFilter::from_register(0x1A).unwrap().bandwidth_hz(), None);
        assert_eq!(IfFilter::from_register(0x10), None);
        assert_eq!(IfFilter::from_register(0x61), None);
    }
}
