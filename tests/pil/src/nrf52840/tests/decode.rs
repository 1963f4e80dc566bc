//! Address decoding: unmapped addresses fault, peripherals that exist but are not modelled
//! are recorded with the PC, FICR contents embassy-nrf and the HM-10 task read, loading.

use m4_sim::{Bus, BusFault, Width};

use super::{chip, r};

#[test]
fn unmapped_addresses_fault() {
    let mut c = chip();
    for addr in [0x0010_0000, 0x2004_0000, 0x4002_B000, 0x6000_0000] {
        assert_eq!(
            c.read(addr, Width::Word, 0),
            Err(BusFault { addr, write: false })
        );
    }
    assert_eq!(
        c.write(0x2004_0000, Width::Word, 0, 0),
        Err(BusFault {
            addr: 0x2004_0000,
            write: true
        })
    );
}

#[test]
fn an_unmodelled_peripheral_reads_zero_and_is_recorded_with_its_pc() {
    let mut c = chip();
    c.fetch_stall(0x1234, false);
    assert_eq!(r(&mut c, 0x4000_1000, 0), 0, "RADIO");
    c.fetch_stall(0x1240, false);
    c.write(0x4000_C000, Width::Word, 1, 5).unwrap(); // TEMP TASKS_START
    let u = c.unmodelled();
    assert_eq!(u.len(), 2);
    assert_eq!(
        (u[0].addr, u[0].write, u[0].pc),
        (0x4000_1000, false, 0x1234)
    );
    assert_eq!(
        (u[1].addr, u[1].write, u[1].pc),
        (0x4000_C000, true, 0x1240)
    );
}

#[test]
fn ficr_holds_part_variant_sizes_and_device_id() {
    let mut c = chip();
    assert_eq!(r(&mut c, 0x1000_0100, 0), 0x5_2840);
    assert_eq!(r(&mut c, 0x1000_0104, 0), u32::from_be_bytes(*b"AAF0"));
    // embassy-nrf reads the build code as a byte: (VARIANT >> 8) as u8 = 'F'.
    assert_eq!(
        c.read(0x1000_0105, Width::Byte, 0).unwrap(),
        u32::from(b'F')
    );
    assert_eq!(r(&mut c, 0x1000_0010, 0), 4096);
    assert_eq!(r(&mut c, 0x1000_0014, 0), 256);
    assert_eq!(r(&mut c, 0x1000_0060, 0), 0x1234_5678);
    assert_eq!(r(&mut c, 0x1000_0064, 0), 0x5EED_0F0F);
    assert_eq!(r(&mut c, 0x1000_0404, 0), 0x326, "TEMP.A0 trim");
    assert!(c.unmodelled().is_empty());
}

#[test]
fn the_boot_chain_points_the_mbr_at_the_bootloader_and_it_at_the_app() {
    let mut c = chip();
    c.install_uf2_boot_chain(0x26000);
    assert_eq!(r(&mut c, 0x1000_1014, 0), 0xF4000, "UICR.NRFFW[0]");
    assert_eq!(c.gpio_supply_volts(), 3.3, "the bootloader set REGOUT0");
    assert_eq!(r(&mut c, 0x0000_0004, 0), 0x101, "MBR reset vector");
    assert_eq!(
        r(&mut c, 0x0000_0040, 0),
        0x121,
        "an IRQ vector → the forwarder"
    );
    assert_eq!(r(&mut c, 0x000F_4004, 0), 0xF4101);
    assert_eq!(r(&mut c, 0x000F_4114, 0), 0x26000, "the hand-off's literal");
}

#[test]
fn an_elf_outside_flash_is_refused() {
    let mut c = chip();
    assert!(c.load_elf(b"not an elf").is_err());
    assert!(c.load_segment(0x000F_FFFE, &[1, 2, 3, 4]).is_err());
    c.load_segment(0x1000_1304, &0xFFFF_FFFDu32.to_le_bytes())
        .unwrap();
    assert_eq!(
        c.gpio_supply_volts(),
        3.3,
        "UICR in the image applies from power-up"
    );
}
