//! Decoded instructions by code address, so each halfword of code is decoded once: a
//! two-level table of 64 KiB chunks (one slot per halfword), allocated as code runs.

use crate::insn::Insn;

/// One decoded instruction and what the run loop needs about it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Slot {
    pub insn: Insn,
    /// 2 or 4 bytes.
    pub len: u8,
    /// Base cycles (`crate::cycles::base`).
    pub cycles: u8,
    /// A PC hook is set at this address.
    pub hook: bool,
}

const EMPTY: Slot = Slot {
    insn: Insn::Empty,
    len: 2,
    cycles: 0,
    hook: false,
};

const CHUNK_BITS: u32 = 16;
const SLOTS: usize = 1 << (CHUNK_BITS - 1);

/// The table.
pub(crate) struct Cache {
    chunks: Vec<Option<Box<[Slot]>>>,
}

impl Cache {
    pub fn new() -> Self {
        Cache {
            chunks: vec![None; 1 << (32 - CHUNK_BITS)],
        }
    }

    #[inline(always)]
    fn index(addr: u32) -> (usize, usize) {
        (
            (addr >> CHUNK_BITS) as usize,
            ((addr & ((1 << CHUNK_BITS) - 1)) >> 1) as usize,
        )
    }

    /// The slot at `addr` (possibly [`Insn::Empty`]), if its chunk exists.
    #[inline(always)]
    pub fn get(&self, addr: u32) -> Option<Slot> {
        let (c, s) = Self::index(addr);
        self.chunks.get(c)?.as_ref()?.get(s).copied()
    }

    /// Stores a decoded instruction.
    pub fn put(&mut self, addr: u32, slot: Slot) {
        if let Some(s) = self.slot_mut(addr, true) {
            *s = slot;
        }
    }

    fn slot_mut(&mut self, addr: u32, create: bool) -> Option<&mut Slot> {
        let (c, s) = Self::index(addr);
        let chunk = self.chunks.get_mut(c)?;
        if chunk.is_none() && create {
            *chunk = Some(vec![EMPTY; SLOTS].into_boxed_slice());
        }
        chunk.as_mut()?.get_mut(s)
    }

    /// Marks or unmarks a hook at `addr`, keeping the mark on an empty slot so the next
    /// decode finds it through the hook set.
    pub fn set_hook(&mut self, addr: u32, on: bool) {
        if let Some(s) = self.slot_mut(addr, false) {
            s.hook = on;
        }
    }

    /// Forgets the instructions that a store of `bytes` at `addr` may have changed (the
    /// halfword before it too: a 32-bit instruction may start there).
    #[inline]
    pub fn invalidate(&mut self, addr: u32, bytes: u32) {
        let (c, _) = Self::index(addr);
        if !matches!(self.chunks.get(c), Some(Some(_))) {
            return;
        }
        let first = addr & !1;
        let last = addr.wrapping_add(bytes.max(1) - 1) & !1;
        let halfwords = (last.wrapping_sub(first) >> 1) + 2;
        for i in 0..halfwords {
            let a = first.wrapping_sub(2).wrapping_add(2 * i);
            if let Some(s) = self.slot_mut(a, false) {
                s.insn = Insn::Empty;
            }
        }
    }

    /// Forgets everything.
    pub fn clear(&mut self) {
        for c in &mut self.chunks {
            *c = None;
        }
    }
}
