//! The chip as the core sees it: register sequences the HAL uses, through `m4_sim::Bus`,
//! checked against what RM0090 says happens on the pins, the IRQ lines and in time.

use m4_sim::bus::ResetCause;
use m4_sim::{Bus, BusFault, Width};

use super::rcc::ResetKind;
use super::testing::Board;
use super::{Config, Stm32f405};
use crate::wire::{Drive, I2cReply, I2cStep, Pin, Pull};

const RCC: u32 = 0x4002_3800;
const FLASH_ACR: u32 = 0x4002_3C00;
const GPIOA: u32 = 0x4002_0000;
const GPIOB: u32 = 0x4002_0400;
const GPIOC: u32 = 0x4002_0800;
const SYSCFG: u32 = 0x4001_3800;
const EXTI: u32 = 0x4001_3C00;
const TIM2: u32 = 0x4000_0000;
const TIM3: u32 = 0x4000_0400;
const SPI1: u32 = 0x4001_3000;
const I2C1: u32 = 0x4000_5400;
const DMA1: u32 = 0x4002_6000;
const DMA2: u32 = 0x4002_6400;
const IWDG: u32 = 0x4000_3000;

fn chip() -> Stm32f405<Board> {
    Stm32f405::new(Board::default(), Config::default())
}

fn w(c: &mut Stm32f405<Board>, addr: u32, value: u32, now: u64) {
    c.write(addr, Width::Word, value, now).unwrap();
}

fn r(c: &mut Stm32f405<Board>, addr: u32, now: u64) -> u32 {
    c.read(addr, Width::Word, now).unwrap()
}

fn irq(c: &Stm32f405<Board>, n: u32) -> bool {
    c.irq_lines()[(n / 32) as usize] & (1 << (n % 32)) != 0
}

/// embassy_stm32::init's clock set-up for board::clocks(), polling as the HAL does.
fn clocks_168(c: &mut Stm32f405<Board>) -> u64 {
    let mut now = 1_000;
    w(c, RCC + 0x40, 1 << 28, now); // PWR clock
    w(c, 0x4000_7000, 1 << 14, now); // VOS scale 1
    w(c, RCC, 0x81 | 1 << 16, now); // HSEON
    while r(c, RCC, now) & 1 << 17 == 0 {
        now += 10_000;
    }
    w(c, RCC + 4, 8 | 336 << 6 | 1 << 22 | 7 << 24, now);
    w(c, RCC, 0x81 | 1 << 16 | 1 << 24, now);
    while r(c, RCC, now) & 1 << 25 == 0 {
        now += 10_000;
    }
    w(c, FLASH_ACR, 5, now);
    w(c, RCC + 8, 2 | 0b101 << 10 | 0b100 << 13, now);
    while r(c, RCC + 8, now) & 0xC != 8 {
        now += 100;
    }
    now
}

#[test]
fn boot_clock_setup_reaches_168_mhz_without_violations() {
    let mut c = chip();
    assert_eq!(c.core_hz(), 16_000_000, "reset runs on the 16 MHz HSI");
    let done = clocks_168(&mut c);
    assert_eq!(c.core_hz(), 168_000_000);
    assert!(
        (2_100_000..2_200_000).contains(&done),
        "HSE 2 ms + PLL 100 µs: {done}"
    );
    assert!(c.violations().is_empty(), "{:?}", c.violations());
    assert!(c.unmodelled().is_empty(), "{:?}", c.unmodelled());
}

#[test]
fn switching_to_168_mhz_before_raising_the_wait_states_is_a_violation() {
    let mut c = chip();
    let mut now = 0;
    w(&mut c, RCC, 0x81 | 1 << 16, now);
    now += 3_000_000;
    w(&mut c, RCC + 4, 8 | 336 << 6 | 1 << 22 | 7 << 24, now);
    w(&mut c, RCC, 0x81 | 1 << 16 | 1 << 24, now);
    now += 200_000;
    w(&mut c, RCC + 8, 2 | 0b101 << 10 | 0b100 << 13, now);
    assert_eq!(c.violations().len(), 1);
    assert!(c.violations()[0].what.contains("LATENCY 0"));
}

#[test]
fn a_peripheral_with_its_clock_off_reads_zero_and_is_recorded() {
    let mut c = chip();
    w(&mut c, SPI1, 0x344, 0);
    assert_eq!(r(&mut c, SPI1, 0), 0);
    assert_eq!(c.violations().len(), 2);
    w(&mut c, RCC + 0x44, 1 << 12, 0);
    w(&mut c, SPI1, 0x344, 0);
    assert_eq!(r(&mut c, SPI1, 0), 0x344);
}

#[test]
fn unmodelled_blocks_and_holes_are_told_apart() {
    let mut c = chip();
    assert_eq!(
        r(&mut c, 0x4000_0800, 5),
        0,
        "TIM4 exists but is not modelled"
    );
    assert_eq!(c.unmodelled().len(), 1);
    assert_eq!(c.unmodelled()[0].what, "TIM4");
    assert_eq!(
        c.read(0x4000_2400, Width::Word, 5),
        Err(BusFault {
            addr: 0x4000_2400,
            write: false
        })
    );
    assert!(c.read(0x6000_0000, Width::Word, 5).is_err());
    assert!(
        c.fetch(0x1000_0000).is_none(),
        "no instruction fetch from CCM"
    );
}

#[test]
fn memories_aliases_and_bitband() {
    let mut c = chip();
    c.program_flash(
        0x0800_0000,
        &[0x00, 0x10, 0x00, 0x20, 0x01, 0x02, 0x00, 0x08],
    )
    .unwrap();
    assert_eq!(
        c.read(0, Width::Word, 0),
        Ok(0x2000_1000),
        "flash aliased at 0"
    );
    assert_eq!(c.fetch(0x0800_0004), Some(0x0201));
    c.write(0x2000_0010, Width::Word, 0, 0).unwrap();
    c.write(0x2200_0000 + 0x10 * 32 + 5 * 4, Width::Word, 1, 0)
        .unwrap();
    assert_eq!(c.read(0x2000_0010, Width::Word, 0), Ok(1 << 5));
    assert_eq!(
        c.read(0x1FFF_7A22, Width::Half, 0),
        Ok(1024),
        "flash size register"
    );
    assert_eq!(c.read(0xE004_2000, Width::Word, 0), Ok(0x1007_0413));
    let e = c.boot_entry().unwrap();
    assert_eq!(
        (e.vector_table, e.initial_sp, e.reset_pc),
        (0x0800_0000, 0x2000_1000, 0x0800_0201)
    );
}

#[test]
fn a_bad_flash_key_is_a_bus_error() {
    let mut c = chip();
    assert_eq!(
        c.write(0x4002_3C04, Width::Word, 0x1234, 0),
        Err(BusFault {
            addr: 0x4002_3C04,
            write: true
        })
    );
}

/// ExtiInput::new(PC5, Pull::None) then wait_for_high: EXTICR2 line 5 = port C, rising
/// edge, unmasked. The board's queued edge pends EXTI9_5 at its exact time.
#[test]
fn a_queued_input_edge_raises_exti9_5_at_its_time() {
    let mut c = chip();
    w(&mut c, RCC + 0x30, 0x1FF, 0);
    w(&mut c, RCC + 0x44, 1 << 14, 0);
    w(&mut c, SYSCFG + 0x0C, 2 << 4, 0);
    w(&mut c, EXTI + 0x08, 1 << 5, 0);
    w(&mut c, EXTI, 1 << 5, 0);
    c.drive_input(Pin::new(2, 5), true, 1_234_567);
    assert_eq!(c.next_event_ns(), 1_234_567);
    c.advance(1_234_566);
    assert!(!irq(&c, 23));
    c.advance(1_234_567);
    assert!(irq(&c, 23));
    assert_eq!(r(&mut c, GPIOC + 0x10, 1_300_000) & 1 << 5, 1 << 5);
    w(&mut c, EXTI + 0x14, 1 << 5, 1_300_000);
    assert!(!irq(&c, 23));
}

/// The time driver: TIM2 at 1 MHz; CC1 and update interrupts reach the NVIC line 28 at the
/// counter's instants, and the core is told about them through next_event_ns.
#[test]
fn tim2_half_period_interrupt_arrives_at_32_768_ms() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    w(&mut c, RCC + 0x40, 1 << 28 | 1, t0);
    w(&mut c, TIM2 + 0x28, 83, t0);
    w(&mut c, TIM2 + 0x2C, 0xFFFF, t0);
    w(&mut c, TIM2, 4, t0);
    w(&mut c, TIM2 + 0x14, 1, t0);
    w(&mut c, TIM2, 0, t0);
    w(&mut c, TIM2 + 0x34, 0x8000, t0);
    w(&mut c, TIM2 + 0x0C, 3, t0);
    w(&mut c, TIM2, 1, t0);
    assert_eq!(c.next_event_ns(), t0 + 32_768_000);
    c.advance(t0 + 32_768_000);
    assert!(irq(&c, 28));
    assert_eq!(r(&mut c, TIM2 + 0x24, t0 + 32_768_500), 0x8000);
}

/// MotorTimer on TIM3 CH3 (PB0, AF2) at 400 Hz PWM: the board sees the edges with their
/// times; the timer has no interrupts, so the core is never stopped for them.
#[test]
fn pwm_edges_reach_the_board_without_waking_the_core() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    w(&mut c, RCC + 0x30, 0x2, t0);
    w(&mut c, RCC + 0x40, 1 << 28 | 1 << 1, t0);
    w(&mut c, GPIOB + 0x20, 2, t0);
    w(&mut c, GPIOB, 0x280 | 2, t0);
    w(&mut c, TIM3 + 0x28, 83, t0);
    w(&mut c, TIM3 + 0x2C, 2499, t0);
    w(&mut c, TIM3 + 0x1C, 0x68, t0);
    w(&mut c, TIM3 + 0x3C, 1000, t0);
    w(&mut c, TIM3 + 0x20, 1 << 8, t0);
    w(&mut c, TIM3 + 0x14, 1, t0);
    w(&mut c, TIM3, 0x81, t0);
    assert_eq!(c.next_event_ns(), u64::MAX, "nothing for the core");
    c.advance(t0 + 10_000_000);
    let pb0 = c.outside().edges(Pin::new(1, 0));
    let highs: Vec<u64> = pb0
        .iter()
        .filter(|e| e.0 == Drive::High)
        .map(|e| e.1 - t0)
        .collect();
    assert_eq!(&highs[..4], &[0, 2_500_000, 5_000_000, 7_500_000]);
    let p = c.pulses(Pin::new(1, 0)).unwrap();
    assert_eq!(p.last_high_ns, Some(1_000_000));
    assert_eq!(p.last_period_ns, Some(2_500_000));
    assert_eq!(c.pwm(3, 3).unwrap().high_ns, 1_000_000.0);
}

/// Spi::transfer on SPI1 with DMA2 streams 3 (TX) and 0 (RX), channel 3: the bytes reach
/// the board back to back, the answers land in SRAM and the RX stream's transfer-complete
/// interrupt (DMA2_Stream0 = 56) rises after the last byte.
#[test]
fn spi_dma_transfer_moves_bytes_both_ways() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    c.outside_mut().miso.extend([0x71, 0x00, 0x12]);
    w(&mut c, RCC + 0x30, 1 | 1 << 22, t0);
    w(&mut c, RCC + 0x44, 1 << 12, t0);
    c.write(0x2000_0100, Width::Word, 0x0000_8075, t0).unwrap();
    // SPI1: master, /8 → 10.5 MHz, mode 3, SSM/SSI.
    w(&mut c, SPI1, 4 | 2 << 3 | 3 | 1 << 8 | 1 << 9, t0);
    // RX stream 0: PAR = DR, M0AR = 0x2000_0200, 3 items, MINC, TCIE, TEIE, ch 3.
    let rx = DMA2 + 0x10;
    w(&mut c, rx + 0x08, SPI1 + 0x0C, t0);
    w(&mut c, rx + 0x0C, 0x2000_0200, t0);
    w(&mut c, rx + 0x04, 3, t0);
    w(&mut c, rx, 3 << 25 | 1 << 10 | 1 << 4 | 1 << 2 | 1, t0);
    let tx = DMA2 + 0x10 + 3 * 0x18;
    w(&mut c, tx + 0x08, SPI1 + 0x0C, t0);
    w(&mut c, tx + 0x0C, 0x2000_0100, t0);
    w(&mut c, tx + 0x04, 3, t0);
    w(
        &mut c,
        tx,
        3 << 25 | 1 << 10 | 1 << 6 | 1 << 4 | 1 << 2 | 1,
        t0,
    );
    w(&mut c, SPI1 + 4, 3, t0); // TXDMAEN | RXDMAEN
    w(&mut c, SPI1, 4 | 2 << 3 | 3 | 1 << 8 | 1 << 9 | 1 << 6, t0); // SPE
    let byte = (8 * 8 * 1_000_000_000u64).div_ceil(84_000_000);
    assert_eq!(c.next_event_ns(), t0 + byte);
    c.advance(t0 + 3 * byte);
    let spi: Vec<(u8, u8, u64)> = c.outside().spi.clone();
    assert_eq!(
        spi,
        vec![
            (1, 0x75, t0 + byte),
            (1, 0x80, t0 + 2 * byte),
            (1, 0x00, t0 + 3 * byte)
        ]
    );
    assert_eq!(
        c.read(0x2000_0200, Width::Word, t0 + 3 * byte).unwrap() & 0xFF_FFFF,
        0x12_0071
    );
    assert!(irq(&c, 56), "DMA2 stream 0 transfer complete");
    assert_eq!(
        r(&mut c, SPI1 + 8, t0 + 3 * byte) & 0x83,
        0x02,
        "TXE, not BSY, not RXNE"
    );
}

/// A DMA stream pointed at the CCM (a buffer on a stack placed there) fails with TEIF and
/// the violation is recorded.
#[test]
fn dma_into_ccm_is_a_transfer_error() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    w(&mut c, RCC + 0x30, 1 << 22, t0);
    w(&mut c, RCC + 0x44, 1 << 12, t0);
    w(&mut c, SPI1, 4 | 1 << 8 | 1 << 9, t0);
    let tx = DMA2 + 0x10 + 3 * 0x18;
    w(&mut c, tx + 0x08, SPI1 + 0x0C, t0);
    w(&mut c, tx + 0x0C, 0x1000_0100, t0);
    w(&mut c, tx + 0x04, 1, t0);
    w(&mut c, tx, 3 << 25 | 1 << 6 | 1 << 4 | 1 << 2 | 1, t0);
    w(&mut c, SPI1 + 4, 2, t0);
    assert_eq!(
        r(&mut c, DMA2, t0) & 1 << 25,
        1 << 25,
        "TEIF3: LISR bit 22 + 3"
    );
    assert!(irq(&c, 59));
    assert!(c.violations().iter().any(|v| v.what.contains("CCM")));
}

/// embassy's I2C write with DMA (DMA1 stream 6, channel 1) to the MS5611: the board sees
/// START, address, bytes and STOP at 400 kHz byte times.
#[test]
fn i2c_dma_write_reaches_the_board() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    c.outside_mut().levels.insert(Pin::new(1, 8), true);
    c.outside_mut().levels.insert(Pin::new(1, 9), true);
    w(&mut c, RCC + 0x30, 2 | 1 << 21, t0);
    w(&mut c, RCC + 0x40, 1 << 28 | 1 << 21, t0);
    // PB8/PB9 AF4 open drain.
    w(&mut c, GPIOB + 0x04, 3 << 8, t0);
    w(&mut c, GPIOB + 0x24, 0x44, t0);
    w(&mut c, GPIOB, 0x280 | 0xA << 16, t0);
    w(&mut c, I2C1 + 4, 42, t0);
    w(&mut c, I2C1 + 0x1C, 1 << 15 | 35, t0);
    w(&mut c, I2C1, 1, t0);
    c.write(0x2000_0300, Width::Byte, 0x1E, t0).unwrap();
    w(&mut c, I2C1 + 4, 42 | 1 << 11 | 1 << 9 | 1 << 8, t0);
    w(&mut c, I2C1, 1 | 1 << 8, t0);
    let start = c.next_event_ns();
    assert_eq!(start, t0 + 2_500);
    c.advance(start);
    assert!(irq(&c, 31), "SB raises the event interrupt");
    assert_eq!(r(&mut c, I2C1 + 0x14, start), 1);
    w(&mut c, I2C1 + 0x10, 0x77 << 1, start);
    c.advance(start + 22_500);
    assert_eq!(r(&mut c, I2C1 + 0x14, start + 22_500) & 2, 2);
    // DMA1 stream 6 channel 1 for TX, then clear ADDR.
    let s6 = DMA1 + 0x10 + 6 * 0x18;
    w(&mut c, s6 + 0x08, I2C1 + 0x10, start + 22_500);
    w(&mut c, s6 + 0x0C, 0x2000_0300, start + 22_500);
    w(&mut c, s6 + 0x04, 1, start + 22_500);
    w(
        &mut c,
        s6,
        1 << 25 | 1 << 10 | 1 << 6 | 1 << 4 | 1,
        start + 22_500,
    );
    r(&mut c, I2C1 + 0x18, start + 22_500);
    assert!(
        irq(&c, 17),
        "DMA1 stream 6 done: the byte is in the shifter"
    );
    c.advance(start + 50_000);
    assert_eq!(r(&mut c, I2C1 + 0x14, start + 50_000) & 4, 4, "BTF");
    w(&mut c, I2C1, 1 | 1 << 9, start + 50_000);
    c.advance(start + 60_000);
    let steps: Vec<I2cStep> = c.outside().i2c.iter().map(|s| s.1).collect();
    assert_eq!(
        steps,
        vec![
            I2cStep::Start,
            I2cStep::Address {
                addr: 0x77,
                read: false
            },
            I2cStep::Write(0x1E),
            I2cStep::Stop
        ]
    );
}

/// The board holds SDA low: BUSY reads set once the pins are on I2C1, a START never
/// completes; the firmware clocks SCL as a GPIO, the board releases SDA, a STOP frees it.
#[test]
fn a_stuck_i2c_bus_is_freed_by_clocking_it_from_gpio() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    let (scl, sda) = (Pin::new(1, 8), Pin::new(1, 9));
    c.outside_mut().levels.insert(scl, true);
    c.outside_mut().levels.insert(sda, false);
    w(&mut c, RCC + 0x30, 2, t0);
    w(&mut c, RCC + 0x40, 1 << 28 | 1 << 21, t0);
    w(&mut c, GPIOB + 0x04, 3 << 8, t0);
    w(&mut c, GPIOB + 0x24, 0x44, t0);
    w(&mut c, GPIOB, 0x280 | 0xA << 16, t0);
    w(&mut c, I2C1 + 4, 42 | 1 << 9, t0);
    w(&mut c, I2C1 + 0x1C, 1 << 15 | 35, t0);
    w(&mut c, I2C1, 1, t0);
    assert_eq!(r(&mut c, I2C1 + 0x18, t0) & 2, 2, "BUSY");
    w(&mut c, I2C1, 1 | 1 << 8, t0);
    c.advance(t0 + 100_000_000);
    assert!(c.outside().i2c.is_empty());
    assert!(!irq(&c, 31));
    // Recovery: PB8/PB9 as open-drain outputs, 9 SCL pulses, then a STOP.
    w(&mut c, GPIOB + 0x14, 3 << 8, t0 + 100_000_000);
    w(&mut c, GPIOB, 0x280 | 0x5 << 16, t0 + 100_000_000);
    let mut t = t0 + 100_000_000;
    for _ in 0..9 {
        w(&mut c, GPIOB + 0x18, 1 << 24, t);
        t += 5_000;
        w(&mut c, GPIOB + 0x18, 1 << 8, t);
        t += 5_000;
    }
    // The board saw the pulses as pin changes and lets go of SDA.
    let pulses = c
        .outside()
        .edges(scl)
        .iter()
        .filter(|e| e.0 == Drive::Low)
        .count();
    assert_eq!(pulses, 9);
    c.outside_mut().levels.insert(sda, true);
    w(&mut c, GPIOB + 0x18, 1 << 25, t); // SDA low (SCL high)
    t += 5_000;
    w(&mut c, GPIOB + 0x18, 1 << 9, t); // SDA high while SCL high: STOP
    assert_eq!(c.outside().drive(sda), Some(Drive::Released(Pull::None)));
    w(&mut c, GPIOB, 0x280 | 0xA << 16, t);
    c.advance(t + 10_000);
    assert_eq!(c.outside().i2c.first().map(|s| s.1), Some(I2cStep::Start));
    assert!(irq(&c, 31), "the waiting START went out: SB");
    let _ = I2cReply::Ack;
}

/// IndependentWatchdog::new(250 ms) (÷4, RLR 1999), started, fed once at 1 ms and never
/// again: RLR + 1 ticks later it resets the chip; the reset releases every pin and RCC_CSR
/// says why.
#[test]
fn an_unfed_watchdog_resets_the_chip_and_leaves_its_flag() {
    let mut c = chip();
    w(&mut c, RCC + 0x74, 1 << 24, 0); // RMVF: forget the power-on flags
    w(&mut c, IWDG, 0x5555, 0);
    w(&mut c, IWDG + 4, 0, 0);
    w(&mut c, IWDG + 8, 1999, 0);
    w(&mut c, IWDG, 0xCCCC, 0);
    w(&mut c, IWDG, 0xAAAA, 1_000_000);
    w(&mut c, RCC + 0x30, 1, 1_000_000);
    w(&mut c, GPIOA, 0xA800_0000 | 1, 1_000_000);
    assert_eq!(c.outside().drive(Pin::new(0, 0)), Some(Drive::Low));
    assert_eq!(c.next_event_ns(), 251_000_000);
    c.advance(250_999_999);
    assert_eq!(c.take_reset_request(), None);
    c.advance(251_000_000);
    assert_eq!(c.take_reset_request(), Some(ResetCause::Watchdog));
    c.reset(ResetCause::Watchdog);
    assert_eq!(
        c.outside().drive(Pin::new(0, 0)),
        Some(Drive::Released(Pull::None))
    );
    assert_eq!(
        r(&mut c, RCC + 0x74, 251_000_000) & 0xFE00_0000,
        1 << 29 | 1 << 26
    );
    assert_eq!(c.core_hz(), 16_000_000);
    assert_eq!(c.resets(), 1);
}

#[test]
fn a_pin_reset_requested_by_the_runner_sets_only_pinrstf() {
    let mut c = chip();
    w(&mut c, RCC + 0x74, 1 << 24, 0);
    c.request_reset(ResetKind::Pin);
    assert_eq!(c.take_reset_request(), Some(ResetCause::Other));
    c.reset(ResetCause::Other);
    assert_eq!(r(&mut c, RCC + 0x74, 0) & 0xFE00_0000, 1 << 26);
}

/// A settings-sector erase from flash code: the next fetch from flash waits out the erase
/// (single bank), and a watchdog set shorter than the erase still bites.
#[test]
fn a_sector_erase_stalls_fetches_and_the_watchdog_still_runs() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    w(&mut c, IWDG, 0xCCCC, t0);
    w(&mut c, 0x4002_3C04, 0x4567_0123, t0);
    w(&mut c, 0x4002_3C04, 0xCDEF_89AB, t0);
    w(&mut c, 0x4002_3C10, 1 << 1 | 2 << 3, t0);
    w(&mut c, 0x4002_3C10, 1 << 1 | 2 << 3 | 1 << 16, t0);
    let stall = c.fetch_stall(0x0801_0000, false);
    // ×8 parallelism (PSIZE left at reset): 400 ms, at 168 MHz, plus the 5 wait states.
    assert_eq!(stall, 400 * 168_000 + 5);
    c.advance(t0 + 400_000_000);
    assert_eq!(
        c.take_reset_request(),
        None,
        "4096 ticks at 8 kHz is 512 ms"
    );
    c.advance(t0 + 600_000_000);
    assert_eq!(c.take_reset_request(), Some(ResetCause::Watchdog));
}

/// With PRFTEN/ICEN/DCEN off (embassy's reset FLASH_ACR), straight-line code pays 5 wait
/// states every 16 bytes; with them on, a loop runs from the I-cache.
#[test]
fn the_flash_accelerator_changes_what_code_costs() {
    let mut c = chip();
    let t0 = clocks_168(&mut c);
    let run = |c: &mut Stm32f405<Board>| -> u32 {
        (0..4)
            .flat_map(|_| (0..64u32).map(|i| 0x0801_0000 + i * 2))
            .map(|a| c.fetch_stall(a, true))
            .sum()
    };
    assert_eq!(run(&mut c), 4 * 8 * 5);
    w(&mut c, FLASH_ACR, 5 | 7 << 8, t0);
    let warm = run(&mut c);
    assert_eq!(warm, 5, "one miss, the rest prefetched or cached");
}

/// An application linked at 0x0802_0000 whose reset handler stores 0x5A at 0x2000_0100.
fn app_behind_the_bootloader(c: &mut Stm32f405<Board>) {
    let app: [u8; 20] = [
        0x00, 0x00, 0x01, 0x20, // MSP 0x2001_0000
        0x09, 0x00, 0x02, 0x08, // reset handler 0x0802_0008, Thumb
        0x5A, 0x20, // movs r0, #0x5A
        0x01, 0x49, // ldr r1, [pc, #4]
        0x08, 0x60, // str r0, [r1]
        0xFE, 0xE7, // b .
        0x00, 0x01, 0x00, 0x20, // 0x2000_0100
    ];
    c.program_flash(0x0802_0000, &app).unwrap();
    c.install_bootloader_handover(0x0802_0000).unwrap();
}

#[test]
fn the_bootloader_stand_in_hands_over_with_the_applications_stack_and_entry() {
    let mut c = chip();
    app_behind_the_bootloader(&mut c);
    assert_eq!(c.boot_entry().map(|e| e.vector_table), Some(0x0800_0000));
    let mut cpu = m4_sim::Cpu::new(super::mcu::core_config());
    cpu.reset(&mut c);
    cpu.run_until(&mut c, 100_000);
    assert_eq!(c.read(0x2000_0100, Width::Word, 100_000), Ok(0x5A));
    assert_eq!(cpu.read_reg(m4_sim::Reg::Msp), 0x2001_0000);
}

#[test]
fn a_power_cycle_releases_the_pins_loses_ram_and_boots_again() {
    let mut c = chip();
    app_behind_the_bootloader(&mut c);
    let mut cpu = m4_sim::Cpu::new(super::mcu::core_config());
    cpu.reset(&mut c);
    cpu.run_until(&mut c, 100_000);
    w(&mut c, RCC + 0x30, 1, 100_000);
    w(&mut c, GPIOA, 0xA800_0000 | 1, 100_000);
    assert_eq!(c.outside().drive(Pin::new(0, 0)), Some(Drive::Low));
    c.set_powered(false);
    assert_eq!(
        c.outside().drive(Pin::new(0, 15)),
        Some(Drive::Released(Pull::None))
    );
    assert_eq!(
        c.outside().drive(Pin::new(0, 0)),
        Some(Drive::Released(Pull::None))
    );
    assert!(
        c.read(0x2000_0100, Width::Word, 200_000).is_err(),
        "nothing answers"
    );
    cpu.run_until(&mut c, 10_000_000);
    assert_eq!(c.resets(), 0);
    c.set_powered(true);
    // The core takes the reset at its next look at the bus (at the latest the deadline).
    cpu.run_until(&mut c, 10_100_000);
    cpu.run_until(&mut c, 10_200_000);
    assert_eq!(c.resets(), 1);
    assert_eq!(
        c.read(0x2000_0100, Width::Word, 10_200_000),
        Ok(0x5A),
        "booted again"
    );
    assert_eq!(
        r(&mut c, RCC + 0x74, 10_200_000) & 1 << 27,
        1 << 27,
        "PORRSTF"
    );
    assert_eq!(
        c.outside().drive(Pin::new(0, 15)),
        Some(Drive::Released(Pull::Up))
    );
}
