//! What the model saw the image do that it does not model, or that the silicon would not
//! do as the firmware expects: kept as lists a runner prints and a test can assert empty,
//! instead of answering 0 in silence.

use std::fmt;

/// An access to something the model has no behaviour for. Reads answered 0, writes dropped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unmodelled {
    /// The address accessed (or the peripheral register that holds the unmodelled setting).
    pub addr: u32,
    /// A store (true) or a load.
    pub write: bool,
    /// The value written (0 for reads).
    pub value: u32,
    /// What is not modelled there.
    pub what: String,
    /// Virtual time of the first such access, ns.
    pub first_ns: u64,
    /// How many accesses of this kind (same address, direction and description).
    pub count: u64,
}

/// A use of the chip the silicon would not honour or would punish: an access to a block
/// whose clock is off, too few flash wait states for HCLK, a DMA stream pointed at
/// memory it cannot reach, …
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Violation {
    /// What happened, with the reference-manual rule it breaks.
    pub what: String,
    /// Virtual time of the first occurrence, ns.
    pub first_ns: u64,
    /// Occurrences.
    pub count: u64,
}

impl fmt::Display for Unmodelled {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let dir = if self.write { "write" } else { "read" };
        write!(
            f,
            "{dir} 0x{:08x} ({}){} ×{} from {:.3} ms",
            self.addr,
            self.what,
            if self.write {
                format!(" value 0x{:08x}", self.value)
            } else {
                String::new()
            },
            self.count,
            self.first_ns as f64 / 1e6
        )
    }
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ×{} from {:.3} ms",
            self.what,
            self.count,
            self.first_ns as f64 / 1e6
        )
    }
}

/// The two lists, deduplicated.
#[derive(Clone, Debug, Default)]
pub struct Diagnostics {
    unmodelled: Vec<Unmodelled>,
    violations: Vec<Violation>,
}

impl Diagnostics {
    /// Records an unmodelled access (merged with an earlier identical one).
    pub fn unmodelled(&mut self, addr: u32, write: bool, value: u32, what: &str, now_ns: u64) {
        if let Some(u) = self
            .unmodelled
            .iter_mut()
            .find(|u| u.addr == addr && u.write == write && u.what == what)
        {
            u.count += 1;
            return;
        }
        self.unmodelled.push(Unmodelled {
            addr,
            write,
            value,
            what: what.to_string(),
            first_ns: now_ns,
            count: 1,
        });
    }

    /// Records a violation (merged with an earlier one of the same text).
    pub fn violation(&mut self, what: &str, now_ns: u64) {
        if let Some(v) = self.violations.iter_mut().find(|v| v.what == what) {
            v.count += 1;
            return;
        }
        self.violations.push(Violation {
            what: what.to_string(),
            first_ns: now_ns,
            count: 1,
        });
    }

    /// Every unmodelled access so far.
    pub fn unmodelled_list(&self) -> &[Unmodelled] {
        &self.unmodelled
    }

    /// Every violation so far.
    pub fn violation_list(&self) -> &[Violation] {
        &self.violations
    }

    /// Forgets both lists.
    pub fn clear(&mut self) {
        self.unmodelled.clear();
        self.violations.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeated_accesses_are_counted_once_per_kind() {
        let mut d = Diagnostics::default();
        d.unmodelled(0x4000_0800, false, 0, "TIM4", 10);
        d.unmodelled(0x4000_0800, false, 0, "TIM4", 20);
        d.unmodelled(0x4000_0800, true, 5, "TIM4", 30);
        d.violation("x", 1);
        d.violation("x", 2);
        assert_eq!(d.unmodelled_list().len(), 2);
        assert_eq!(d.unmodelled_list()[0].count, 2);
        assert_eq!(d.unmodelled_list()[0].first_ns, 10);
        assert_eq!(d.violation_list()[0].count, 2);
        assert_eq!(
            d.unmodelled_list()[1].to_string(),
            "write 0x40000800 (TIM4) value 0x00000005 ×1 from 0.000 ms"
        );
    }
}
