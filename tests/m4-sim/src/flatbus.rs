//! A flat test bus: memory regions and nothing else (no peripherals, no interrupts), shaped
//! by default like QEMU's `mps2-an386` as the m4-bench programs expect it (4 MiB of flash at
//! 0, 4 MiB of RAM at 0x2000_0000). For the core's own tests, the `m4-sim` tool and the QEMU
//! comparison; SoC models live in `tests/pil`.

use crate::bus::{Bus, BusFault, Width};

/// One memory region.
#[derive(Clone, Debug)]
struct Region {
    base: u32,
    bytes: Vec<u8>,
}

/// Memory regions at fixed addresses; accesses anywhere else are bus faults.
#[derive(Clone, Debug)]
pub struct FlatBus {
    regions: Vec<Region>,
    hz: u32,
    /// IRQ lines a test drives by hand.
    pub irq: [u32; 8],
    /// The next event a test schedules (`u64::MAX`: none).
    pub next_event: u64,
    /// Times at which `advance` was called (tests of the time contract).
    pub advanced: Vec<u64>,
    /// A reset the test wants the core to take.
    pub reset_request: Option<crate::bus::ResetCause>,
    /// Bumped by every [`FlatBus::load`]: the core re-decodes what it had cached.
    generation: u64,
}

/// `mps2-an386`'s flash and RAM.
pub const MPS2_FLASH: (u32, u32) = (0x0000_0000, 4 << 20);
/// See [`MPS2_FLASH`].
pub const MPS2_RAM: (u32, u32) = (0x2000_0000, 4 << 20);

impl FlatBus {
    /// Regions given as (base, size), zero-filled, with a core clock of `hz`.
    pub fn new(regions: &[(u32, u32)], hz: u32) -> Self {
        FlatBus {
            regions: regions
                .iter()
                .map(|&(base, size)| Region {
                    base,
                    bytes: vec![0; size as usize],
                })
                .collect(),
            hz,
            irq: [0; 8],
            next_event: u64::MAX,
            advanced: Vec::new(),
            reset_request: None,
            generation: 0,
        }
    }

    /// The `mps2-an386` layout at 25 MHz (QEMU's clock for that board).
    pub fn mps2_an386() -> Self {
        Self::new(&[MPS2_FLASH, MPS2_RAM], 25_000_000)
    }

    fn find(&self, addr: u32, len: u32) -> Option<(usize, usize)> {
        self.regions.iter().enumerate().find_map(|(i, r)| {
            let off = addr.checked_sub(r.base)? as usize;
            (off + len as usize <= r.bytes.len()).then_some((i, off))
        })
    }

    /// Copies `data` to `addr` (loading an image); false if it does not fit a region.
    pub fn load(&mut self, addr: u32, data: &[u8]) -> bool {
        self.generation += 1;
        let Some((i, off)) = self.find(addr, data.len() as u32) else {
            return false;
        };
        match self
            .regions
            .get_mut(i)
            .and_then(|r| r.bytes.get_mut(off..off + data.len()))
        {
            Some(dst) => {
                dst.copy_from_slice(data);
                true
            }
            None => false,
        }
    }

    /// Reads `len` bytes at `addr` (for tests).
    pub fn peek(&self, addr: u32, len: u32) -> Option<&[u8]> {
        let (i, off) = self.find(addr, len)?;
        self.regions.get(i)?.bytes.get(off..off + len as usize)
    }

    /// Sets the core clock.
    pub fn set_hz(&mut self, hz: u32) {
        self.hz = hz;
    }
}

impl Bus for FlatBus {
    fn fetch(&mut self, addr: u32) -> Option<u16> {
        let b = self.peek(addr, 2)?;
        Some(u16::from_le_bytes([*b.first()?, *b.get(1)?]))
    }

    fn read(&mut self, addr: u32, width: Width, _now_ns: u64) -> Result<u32, BusFault> {
        let fault = BusFault { addr, write: false };
        let b = self.peek(addr, width.bytes()).ok_or(fault)?;
        let mut v = [0u8; 4];
        for (d, s) in v.iter_mut().zip(b) {
            *d = *s;
        }
        Ok(u32::from_le_bytes(v))
    }

    fn write(&mut self, addr: u32, width: Width, value: u32, _now_ns: u64) -> Result<(), BusFault> {
        let fault = BusFault { addr, write: true };
        let n = width.bytes();
        let (i, off) = self.find(addr, n).ok_or(fault)?;
        let dst = self
            .regions
            .get_mut(i)
            .and_then(|r| r.bytes.get_mut(off..off + n as usize))
            .ok_or(fault)?;
        dst.copy_from_slice(value.to_le_bytes().get(..n as usize).ok_or(fault)?);
        Ok(())
    }

    fn code_generation(&self) -> u64 {
        self.generation
    }

    fn irq_lines(&self) -> [u32; 8] {
        self.irq
    }

    fn next_event_ns(&self) -> u64 {
        self.next_event
    }

    fn advance(&mut self, now_ns: u64) {
        self.advanced.push(now_ns);
        if self.next_event <= now_ns {
            self.next_event = u64::MAX;
        }
    }

    fn core_hz(&self) -> u32 {
        self.hz
    }

    fn take_reset_request(&mut self) -> Option<crate::bus::ResetCause> {
        self.reset_request.take()
    }
}
