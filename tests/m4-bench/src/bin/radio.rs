//! Instruction counts of the RFM22B driver with the SPI mocked as no-ops: computing a modem
//! configuration, a full init (reset + configure), sending a 16-byte packet, and receiving
//! one (arm RX, service one nIRQ with sync + packet-valid, read 16 bytes).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod bench {
    use core::convert::Infallible;
    use core::future::Future;
    use core::hint::black_box;
    use core::pin::pin;
    use core::sync::atomic::{AtomicU8, Ordering};
    use core::task::{Context, Poll, Waker};

    use embedded_hal_async::spi::{ErrorType, Operation, SpiDevice};
    use radio_rfm22b::{Carrier, Config, ModemConfig, PacketConfig, Rfm22b, RxOutcome};

    /// A no-op SPI device that answers reads with plausible chip bytes: identification B1,
    /// status "packet sent / sync + valid packet" (plus "chip ready" while `STATUS_2` says so,
    /// i.e. during init), a 16-byte received length.
    struct FakeSpi;

    /// Interrupt status 2 as the fake reports it: chip ready + sync during init, then sync.
    static STATUS_2: AtomicU8 = AtomicU8::new(0x82);

    impl ErrorType for FakeSpi {
        type Error = Infallible;
    }

    impl SpiDevice for FakeSpi {
        async fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
            let mut address = 0u8;
            for op in ops.iter_mut() {
                match op {
                    Operation::Write([first, ..]) => address = *first,
                    Operation::Read(buf) => {
                        let answer: &[u8] = match address {
                            0x00 => &[0x08, 0x06],
                            0x03 => &[0x06, STATUS_2.load(Ordering::Relaxed)],
                            0x47 => &[1, 2, 3, 4, 16],
                            0x26 => &[100],
                            _ => &[],
                        };
                        for (dst, src) in buf
                            .iter_mut()
                            .zip(answer.iter().chain(core::iter::repeat(&0)))
                        {
                            *dst = *src;
                        }
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

    /// The trivial executor: poll with a no-op waker until ready.
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
        let mut radio = Rfm22b::new_without_sdn(FakeSpi, LowIrq, Delay);
        m4count_marker();
        // Region 2: init = reset (probe, software reset, chip-ready) + every register.
        let init = block_on(radio.init(black_box(config)));
        m4count_marker();
        if init.is_err() {
            fail()
        }
        STATUS_2.store(0x80, Ordering::Relaxed);

        let packet = black_box([0x5Au8; 16]);
        m4count_marker();
        // Region 3: send a 16-byte packet (FIFO load, TX on, one nIRQ: packet sent).
        let sent = block_on(radio.transmit(&packet, 1_000_000_000));
        m4count_marker();
        if sent.is_err() {
            fail()
        }

        let mut buf = [0u8; 64];
        m4count_marker();
        // Region 4: receive a 16-byte packet (arm RX, one nIRQ with sync + valid, RSSI/AFC,
        // header + length, FIFO read).
        let received = block_on(radio.receive(&mut buf, 1_000_000_000));
        m4count_marker();
        match received {
            Ok(RxOutcome::Packet(p)) if p.len == 16 => {
                black_box(p.len);
            }
            _ => fail(),
        }
        black_box(&buf);
        exit()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
