//! A clean-room stand-in for what Nordic's MBR and the Adafruit nRF52 bootloader do at the
//! hand-off to a UF2 image (`hardware/boot-test/README.md` describes the real ones; their
//! code is not ours to commit). Written from that description and assembled by hand; the
//! assembly is in the comments (`llvm-mc -triple=thumbv7em-none-eabi` gives these bytes).
//!
//! - MBR at 0x0: its reset handler reads UICR.NRFFW[0] (the bootloader's address; 0x1000,
//!   the SoftDevice, when erased), stores it in the RAM word 0x2000_0000 and starts it (MSP
//!   and PC from its vector table). Every other vector forwards the exception through the
//!   table whose address that RAM word holds: `handler = table[IPSR]`.
//! - Bootloader at 0xF4000 (`bootloader_app_start`): stores the application's address in
//!   the forward word and starts it (MSP and PC from its table).
//! - UICR as the nice!nano's Adafruit bootloader leaves it after its first start: NRFFW[0]
//!   = 0xF4000, NRFFW[1] = 0xFE000 (MBR parameter page), REGOUT0 = 3.3 V (its `board.h`
//!   defines `UICR_REGOUT0_VALUE` 3V3 and `boards.c` programs it on a mismatch and resets).

use super::memory::uicr;

/// The bootloader's start (`UICR.NRFFW[0]`).
pub const BOOTLOADER: u32 = 0xF_4000;
/// The MBR parameter page (`UICR.NRFFW[1]`).
pub const MBR_PARAMS: u32 = 0xF_E000;
/// The RAM word through which the MBR forwards interrupts.
pub const FORWARD_WORD: u32 = 0x2000_0000;
/// The stack the stand-ins start with (top of RAM).
const STACK: u32 = 0x2004_0000;
/// Vector table entries: 16 system exceptions and the nRF52840's 48 interrupts.
const VECTORS: usize = 16 + 48;
/// REGOUT0 value for 3.3 V (VOUT = 5, other bits erased).
pub const REGOUT0_3V3: u32 = 0xFFFF_FFFD;

/// The MBR's reset handler, at 0x100.
const MBR_RESET: [u16; 16] = [
    0x4806, // ldr r0, [pc, #0x18]    ; =0x1000_1014 (UICR.NRFFW[0])
    0x6800, // ldr r0, [r0]
    0x1C41, // adds r1, r0, #1        ; erased?
    0xD101, // bne 1f
    0xF44F, 0x5080, // mov.w r0, #0x1000 ; no bootloader: the SoftDevice
    0xF04F, 0x5100, // 1: mov.w r1, #0x2000_0000
    0x6008, // str r0, [r1]           ; the forward word
    0x6802, // ldr r2, [r0]
    0xF382, 0x8808, // msr msp, r2
    0x6843, // ldr r3, [r0, #4]
    0x4718, // bx r3
    0x1014, 0x1000, // .word 0x1000_1014
];
/// The MBR's interrupt forwarder, at 0x120.
const MBR_FORWARD: [u16; 8] = [
    0xF3EF, 0x8005, // mrs r0, ipsr
    0xF04F, 0x5100, // mov.w r1, #0x2000_0000
    0x6809, // ldr r1, [r1]
    0xF851, 0x1020, // ldr.w r1, [r1, r0, lsl #2]
    0x4708, // bx r1
];
/// The bootloader's hand-off, at +0x100; the application address follows it.
const BOOT: [u16; 10] = [
    0x4804, // ldr r0, [pc, #0x10]    ; the application
    0xF04F, 0x5100, // mov.w r1, #0x2000_0000
    0x6008, // str r0, [r1]
    0x6802, // ldr r2, [r0]
    0xF382, 0x8808, // msr msp, r2
    0x6843, // ldr r3, [r0, #4]
    0x4718, // bx r3
    0xBF00, // nop (literal alignment)
];
/// `b .`, where the bootloader's unused vectors lead.
const HANG: u16 = 0xE7FE;

const MBR_RESET_AT: u32 = 0x100;
const MBR_FORWARD_AT: u32 = 0x120;
const BOOT_AT: u32 = BOOTLOADER + 0x100;
const HANG_AT: u32 = BOOTLOADER + 0x120;

fn halfwords(code: &[u16]) -> Vec<u8> {
    code.iter().flat_map(|h| h.to_le_bytes()).collect()
}

fn table(first: u32, reset: u32, others: u32) -> Vec<u8> {
    (0..VECTORS)
        .map(|i| match i {
            0 => first,
            1 => reset | 1,
            _ => others | 1,
        })
        .flat_map(u32::to_le_bytes)
        .collect()
}

/// The flash segments of the boot chain for an application at `app`.
pub fn flash_segments(app: u32) -> Vec<(u32, Vec<u8>)> {
    let mut boot = halfwords(&BOOT);
    boot.extend(app.to_le_bytes());
    vec![
        (0, table(STACK, MBR_RESET_AT, MBR_FORWARD_AT)),
        (MBR_RESET_AT, halfwords(&MBR_RESET)),
        (MBR_FORWARD_AT, halfwords(&MBR_FORWARD)),
        (BOOTLOADER, table(STACK, BOOT_AT, HANG_AT)),
        (BOOT_AT, boot),
        (HANG_AT, HANG.to_le_bytes().to_vec()),
    ]
}

/// The UICR words (offset, value) the bootloader has programmed.
pub const UICR_WORDS: [(u32, u32); 3] = [
    (uicr::NRFFW0, BOOTLOADER),
    (uicr::NRFFW1, MBR_PARAMS),
    (uicr::REGOUT0, REGOUT0_3V3),
];
