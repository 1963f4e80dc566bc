//! Instruction counts of the RFM22B driver with the SPI mocked as no-ops: computing a modem
//! configuration, a full init (reset + configure), sending a 16-byte packet, and receiving
//! one (arm RX, service one nIRQ with sync + packet-valid, read 16 bytes); then the same
//! send and receive at the link's 29- and 34-byte frames.
//! m4count regions: 1 = modem configuration, 3 = init, 5 = send 16 B, 7 = receive 16 B,
//! 9/11 = send/receive 29 B, 13/15 = send/receive 34 B; the even regions are setup.
//! The fake SPI also counts the bytes each operation clocks (address bytes included); the
//! bench prints them over semihosting, so the SPI transfer time (bytes × 8 / SPI clock) is
//! stated from the same run.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod bench {
    use core::convert::Infallible;
    use core::future::Future;
    use core::hint::black_box;
    use core::pin::pin;
    use core::sync::atomic::{AtomicU8, AtomicU32, Ordering};
    use core::task::{Context, Poll, Waker};

    use embedded_hal_async::spi::{ErrorType, Operation, SpiDevice};
    use radio_rfm22b::{Carrier, Config, ModemConfig, PacketConfig, Rfm22b, RxOutcome};

    /// A no-op SPI device that answers reads with plausible chip bytes: identification B1,
    /// status "packet sent / sync + valid packet" (plus "chip ready" while `STATUS_2` says so,
    /// i.e. during init), a 16-byte received length.
    /// With `COUNT` it also adds the bytes of every operation to `SPI_BYTES`: a second
    /// radio on that variant measures the transfer sizes outside the counted regions, so the
    /// counted one carries no counting code.
    struct FakeSpi<const COUNT: bool>;

    /// Interrupt status 2 as the fake reports it: chip ready + sync during init, then sync.
    static STATUS_2: AtomicU8 = AtomicU8::new(0x82);
    /// The received packet length the fake reports in register 0x4B.
    static RX_LEN: AtomicU8 = AtomicU8::new(16);
    /// Bytes clocked over the SPI since the last reset (address bytes included).
    static SPI_BYTES: AtomicU32 = AtomicU32::new(0);

    impl<const COUNT: bool> ErrorType for FakeSpi<COUNT> {
        type Error = Infallible;
    }

    impl<const COUNT: bool> SpiDevice for FakeSpi<COUNT> {
        async fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
            let mut address = 0u8;
            let rx_len = RX_LEN.load(Ordering::Relaxed);
            let header = [1, 2, 3, 4, rx_len];
            for op in ops.iter_mut() {
                if COUNT {
                    let len = match op {
                        Operation::Write(b) => b.len(),
                        Operation::Read(b) => b.len(),
                        Operation::Transfer(r, w) => r.len().max(w.len()),
                        Operation::TransferInPlace(b) => b.len(),
                        Operation::DelayNs(_) => 0,
                    };
                    SPI_BYTES.fetch_add(len as u32, Ordering::Relaxed);
                }
                match op {
                    Operation::Write([first, ..]) => address = *first,
                    Operation::Read(buf) => {
                        let answer: &[u8] = match address {
                            0x00 => &[0x08, 0x06],
                            0x03 => &[0x06, STATUS_2.load(Ordering::Relaxed)],
                            0x47 => &header,
                            0x26 => &[100],
                            _ => &[],
                        };
                        // Answer bytes, then zeros (a FIFO read gets zeros): two block
                        // copies, so the mock's cost hardly grows with the packet.
                        let n = answer.len().min(buf.len());
                        let (head, tail) = buf.split_at_mut(n);
                        head.copy_from_slice(answer.get(..n).unwrap_or(&[]));
                        tail.fill(0);
                    }
                    _ => {}
                }
            }
            Ok(())
        }
    }

    /// nIRQ always low: every wait returns at once.
    struct LowIrq;
    impl embedded_hal::digital::ErrorType for LowIrq {
        type Error = Infallible;
    }
    impl embedded_hal_async::digital::Wait for LowIrq {
        async fn wait_for_high(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
        async fn wait_for_low(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
        async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
        async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
        async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
    }

    /// Short delays return at once; operation deadlines (≥ 1 s here) never expire.
    struct Delay;
    impl embedded_hal_async::delay::DelayNs for Delay {
        async fn delay_ns(&mut self, ns: u32) {
            if ns >= 1_000_000_000 {
                core::future::pending::<()>().await;
            }
        }
    }

    /// Ends the run with a failure status: a wrong driver result invalidates the counts.
    fn fail() -> ! {
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
        #[allow(clippy::empty_loop)]
        loop {}
    }

    /// The trivial executor: poll with a no-op waker until ready. Not si4432-sim's
    /// `Simulation` (a host-only, std executor over virtual time): this runs bare-metal on the
    /// Cortex-M4 under QEMU against a register mock that never waits, and its few
    /// instructions are part of the counted region, so it stays this small and fixed.
    fn block_on<F: Future>(future: F) -> F::Output {
        let mut future = pin!(future);
        let mut cx = Context::from_waker(Waker::noop());
        loop {
            if let Poll::Ready(out) = future.as_mut().poll(&mut cx) {
                return out;
            }
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        use m4_bench::{exit, m4count_marker};

        let rate = black_box(57_600u32);
        let deviation = black_box(28_800u32);
        m4count_marker();
        // Region 1: compute the modem registers.
        let modem = ModemConfig::try_new(rate, deviation);
        m4count_marker();
        let Ok(modem) = black_box(modem) else { fail() };

        let config = Config::new(modem, PacketConfig::new(), Carrier::new(433_000_000));
        let mut radio = Rfm22b::new_without_sdn(FakeSpi::<false>, LowIrq, Delay);
        let mut sizer = Rfm22b::new_without_sdn(FakeSpi::<true>, LowIrq, Delay);
        m4count_marker();
        // Region 2: init = reset (probe, software reset, chip-ready) + every register.
        let init = block_on(radio.init(black_box(config)));
        m4count_marker();
        if init.is_err() || block_on(sizer.init(config)).is_err() {
            fail()
        }
        STATUS_2.store(0x80, Ordering::Relaxed);

        let mut buf = [0u8; 64];
        for len in [16u8, 29, 34] {
            RX_LEN.store(len, Ordering::Relaxed);
            let packet = [0x5Au8; 64];
            let packet = black_box(packet.get(..usize::from(len)).unwrap_or(&[]));
            m4count_marker();
            // Send (FIFO load, TX on, one nIRQ: packet sent).
            let sent = block_on(radio.transmit(packet, 1_000_000_000));
            m4count_marker();
            if sent.is_err() {
                fail()
            }
            m4count_marker();
            // Receive (arm RX, one nIRQ with sync + valid, RSSI/AFC, header + length, FIFO
            // read).
            let received = block_on(radio.receive(&mut buf, 1_000_000_000));
            m4count_marker();
            match received {
                Ok(RxOutcome::Packet(p)) if p.len == usize::from(len) => {
                    black_box(p.len);
                }
                _ => fail(),
            }
            // The same two operations on the counting variant, outside the regions.
            SPI_BYTES.store(0, Ordering::Relaxed);
            if block_on(sizer.transmit(packet, 1_000_000_000)).is_err() {
                fail()
            }
            let tx_bytes = SPI_BYTES.swap(0, Ordering::Relaxed);
            if block_on(sizer.receive(&mut buf, 1_000_000_000)).is_err() {
                fail()
            }
            let rx_bytes = SPI_BYTES.load(Ordering::Relaxed);
            cortex_m_semihosting::hprintln!("{} B: SPI bytes tx {} rx {}", len, tx_bytes, rx_bytes);
        }
        black_box(&buf);
        exit()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
