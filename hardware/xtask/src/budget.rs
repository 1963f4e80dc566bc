//! The images' flash budgets, declared once (issue 33): `cargo xtask verify` fails an image
//! whose text is over its package's budget or that fills more than [`PARTITION_PERCENT`] of
//! a bootloader's partition, and the README's sizes table shows each image against both.
//! The budgets leave room for what is still to come (logging, security, hardening) inside
//! the smallest flash any of the boards gives an image.

use crate::layout::Layout;

/// Text (code and read-only data, the `size` count) an image of each firmware package may
/// have, bytes: the flight images 256 KiB, the module 160 KiB.
pub const TEXT_BUDGETS: &[(&str, u32)] = &[("flight-fw", 256 * 1024), ("module-fw", 160 * 1024)];

/// The most of a bootloader's application partition (the load range it accepts) an image
/// may fill, percent.
pub const PARTITION_PERCENT: u32 = 75;

/// The text budget of a package's images.
pub fn text_budget(package: &str) -> Option<u32> {
    TEXT_BUDGETS
        .iter()
        .find(|(p, _)| *p == package)
        .map(|&(_, b)| b)
}

/// The bootloader partition an image of `layout` loads into, bytes (None: nothing starts
/// it but the chip's reset).
pub fn partition(layout: &Layout) -> Option<u32> {
    layout
        .behind_bootloader
        .then(|| layout.accepted.end - layout.accepted.start)
}

/// What one image breaks: its text over its package's budget, its flash (everything it
/// loads) over [`PARTITION_PERCENT`] of its bootloader's partition.
pub fn problems(package: &str, layout: &Layout, text: u32, flash: u32) -> Vec<String> {
    let mut out = Vec::new();
    match text_budget(package) {
        Some(budget) if text > budget => out.push(format!(
            "text {text} B is over the {package} budget of {budget} B (budget::TEXT_BUDGETS)"
        )),
        Some(_) => {}
        None => out.push(format!(
            "no text budget for {package} (budget::TEXT_BUDGETS)"
        )),
    }
    if let Some(size) = partition(layout)
        && u64::from(flash) * 100 > u64::from(size) * u64::from(PARTITION_PERCENT)
    {
        out.push(format!(
            "{flash} B fill {} of the {}'s {size}-byte partition, over {PARTITION_PERCENT} %",
            percent(flash, size),
            layout.starter
        ));
    }
    out
}

/// `part` of `whole` in percent with one decimal ("94.6 %").
pub fn percent(part: u32, whole: u32) -> String {
    let tenths = (u64::from(part) * 1000 + u64::from(whole) / 2) / u64::from(whole.max(1));
    format!("{}.{} %", tenths / 10, tenths % 10)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{F405_DIRECT, F405_TAULABS, NRF_UF2};

    #[test]
    fn the_budgets_are_issue_33s() {
        assert_eq!(text_budget("flight-fw"), Some(262_144));
        assert_eq!(text_budget("module-fw"), Some(163_840));
        assert_eq!(partition(&F405_TAULABS), Some(393_116));
        assert_eq!(partition(&NRF_UF2), Some(0xEA000 - 0x26000));
        assert_eq!(partition(&F405_DIRECT), None);
    }

    #[test]
    fn text_over_the_budget_fails_and_at_it_passes() {
        assert!(problems("flight-fw", &F405_DIRECT, 262_144, 262_144).is_empty());
        let p = problems("flight-fw", &F405_DIRECT, 262_145, 262_145);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].contains("over the flight-fw budget"), "{p:?}");
        assert!(!problems("nothing", &F405_DIRECT, 1, 1).is_empty());
    }

    #[test]
    fn more_than_three_quarters_of_a_partition_fails() {
        // 75 % of 393 116 B is 294 837 B: that passes, a byte more does not.
        assert!(problems("module-fw", &F405_TAULABS, 1, 294_837).is_empty());
        let p = problems("module-fw", &F405_TAULABS, 1, 294_838);
        assert!(p.iter().any(|m| m.contains("over 75 %")), "{p:?}");
        // The same bytes at reset, with no bootloader, are only the text budget's matter.
        assert!(problems("module-fw", &F405_DIRECT, 1, 294_838).is_empty());
    }

    #[test]
    fn percentages_have_one_rounded_decimal() {
        assert_eq!(percent(1, 3), "33.3 %");
        assert_eq!(percent(2, 3), "66.7 %");
        assert_eq!(percent(262_144, 262_144), "100.0 %");
        assert_eq!(percent(5, 0), "500.0 %");
    }
}
