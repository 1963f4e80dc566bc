//! The STM32F405 image's memory layouts, one chosen by feature; writing it to OUT_DIR and
//! the link arguments are `fw-link`'s (hardware/fw-link, shared with module-fw). Host builds
//! (the stub `main`) get nothing.

/// Sectors 0–3 are 16 KiB each; sectors 2–3 (0x0800_8000–0x0800_FFFF) hold the settings,
/// where Tau Labs kept them on boards without external flash (hardware/brushedsparky).
const DIRECT: &str = "\
/* Flashed at 0x08000000 (probe or USB DFU). The vector table sits in sector 0; code starts
   at sector 4 so that sectors 2-3 stay free for settings. */
MEMORY
{
  FLASH : ORIGIN = 0x08000000, LENGTH = 1024K
  RAM   : ORIGIN = 0x20000000, LENGTH = 128K
}
_stext = 0x08010000;
";

const BOOTLOADER: &str = "\
/* Behind the Tau Labs bootloader: its bank is sectors 0-1, settings sectors 2-3, firmware
   from sector 5 (0x08020000, 384 KiB; the last 100 bytes hold the firmware descriptor that
   the GCS writes from the .tlfw). The bootloader starts the firmware only if
   (initial SP & 0x2FFE0000) == 0x20000000, which the end of the 128 KiB SRAM (0x20020000)
   fails; flip-link (.cargo/config.toml) starts the stack below the statics, well inside
   (`cargo xtask verify` checks it). */
MEMORY
{
  FLASH : ORIGIN = 0x08020000, LENGTH = 384K - 100
  RAM   : ORIGIN = 0x20000000, LENGTH = 128K
}
";

/// Test variants for the processor-in-the-loop runner (`tests/pil` builds them from this
/// source to show it models the hardware, not the app, and that each of issue 29's glue
/// fixes is what passes its scenario); `cargo xtask dist` never sets `TAULINK_PIL_VARIANT`,
/// so no flashable image carries one. Comma-separated names:
/// - `radio-cs-pc13` wires the RFM22B's nSEL to PC13 instead of PA15 (a board with the wrong
///   pin), `iwdg-half` sets the independent watchdog's timeout to half the supervisor's feed
///   period (no feeding meets it);
/// - the glue as it was before a fix: `i2c-unguarded` (no bus clear, no transaction
///   timeout), `fault-halts` (panic and HardFault spin with the motors as they were, as
///   panic-probe did, until the watchdog), `no-resume` (every reset boots cold),
///   `flash-slow` (the flash accelerator left off: 5 wait states, no caches or prefetch).
const PIL_VARIANTS: [(&str, &str); 6] = [
    ("radio-cs-pc13", "pil_radio_cs_pc13"),
    ("iwdg-half", "pil_iwdg_half"),
    ("i2c-unguarded", "pil_i2c_unguarded"),
    ("fault-halts", "pil_fault_halts"),
    ("no-resume", "pil_no_resume"),
    ("flash-slow", "pil_flash_slow"),
];

fn pil_variants() {
    println!("cargo:rerun-if-env-changed=TAULINK_PIL_VARIANT");
    for (_, cfg) in PIL_VARIANTS {
        println!("cargo::rustc-check-cfg=cfg({cfg})");
    }
    let Ok(wanted) = std::env::var("TAULINK_PIL_VARIANT") else {
        return;
    };
    for name in wanted.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        match PIL_VARIANTS.iter().find(|(n, _)| *n == name) {
            Some((_, cfg)) => println!("cargo::rustc-cfg={cfg}"),
            None => {
                eprintln!("TAULINK_PIL_VARIANT: unknown variant {name:?}");
                std::process::exit(1);
            }
        }
    }
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    pil_variants();
    fw_link::link_image(if fw_link::feature("taulabs-bootloader") {
        BOOTLOADER
    } else {
        DIRECT
    });
}
