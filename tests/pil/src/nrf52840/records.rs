//! What a run leaves for the runner to print and the tests to assert on: accesses the model
//! does not cover (instead of reading 0 in silence), EasyDMA transfers the silicon would
//! fault on, and notes where the image used a modelled peripheral in a way the model does
//! not cover or the silicon would misbehave.

/// At most this many distinct records of each kind are kept (the counts go on).
const MAX_RECORDS: usize = 256;

/// An access to an address the model does not implement (it reads 0, writes are dropped).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unmodelled {
    /// The address.
    pub addr: u32,
    /// A store (true) or a load.
    pub write: bool,
    /// The value stored, or 0 for a load.
    pub value: u32,
    /// The instruction that made it first: the address of the last instruction fetched.
    pub pc: u32,
    /// When it happened first, ns.
    pub first_ns: u64,
    /// How often it happened.
    pub count: u64,
}

/// An EasyDMA transfer outside Data RAM: on the silicon a HardFault or corrupted memory
/// (PS "EasyDMA"); the model transfers zeros.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DmaFault {
    /// The peripheral, e.g. "SPIM3 TXD".
    pub channel: &'static str,
    /// The pointer it was given.
    pub addr: u32,
    /// The byte count.
    pub len: u32,
    /// When, ns.
    pub at_ns: u64,
}

/// A modelled peripheral used in a way the model does not cover, or the silicon would do
/// something the image does not expect.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Note {
    /// The block, e.g. "PWM0".
    pub block: &'static str,
    /// What happened.
    pub what: String,
    /// When first, ns.
    pub first_ns: u64,
    /// How often.
    pub count: u64,
}

/// The records of one chip since power-on.
#[derive(Clone, Debug, Default)]
pub struct Records {
    unmodelled: Vec<Unmodelled>,
    dma_faults: Vec<DmaFault>,
    notes: Vec<Note>,
    /// The address of the last instruction fetched (`Bus::fetch_stall`): the PC that a
    /// data access belongs to.
    pub pc: u32,
}

impl Records {
    /// Records an access to an unimplemented address.
    pub fn unmodelled(&mut self, addr: u32, write: bool, value: u32, now: u64) {
        if let Some(r) = self
            .unmodelled
            .iter_mut()
            .find(|r| r.addr == addr && r.write == write)
        {
            r.count += 1;
            return;
        }
        if self.unmodelled.len() < MAX_RECORDS {
            self.unmodelled.push(Unmodelled {
                addr,
                write,
                value,
                pc: self.pc,
                first_ns: now,
                count: 1,
            });
        }
    }

    /// Records an EasyDMA pointer outside Data RAM.
    pub fn dma_fault(&mut self, channel: &'static str, addr: u32, len: u32, now: u64) {
        if self.dma_faults.len() < MAX_RECORDS {
            self.dma_faults.push(DmaFault {
                channel,
                addr,
                len,
                at_ns: now,
            });
        }
    }

    /// Records a note about `block`.
    pub fn note(&mut self, block: &'static str, what: &str, now: u64) {
        if let Some(n) = self
            .notes
            .iter_mut()
            .find(|n| n.block == block && n.what == what)
        {
            n.count += 1;
            return;
        }
        if self.notes.len() < MAX_RECORDS {
            self.notes.push(Note {
                block,
                what: what.to_owned(),
                first_ns: now,
                count: 1,
            });
        }
    }

    /// Accesses to unimplemented addresses, in order of first occurrence.
    pub fn unmodelled_accesses(&self) -> &[Unmodelled] {
        &self.unmodelled
    }

    /// EasyDMA pointers outside Data RAM.
    pub fn dma_faults(&self) -> &[DmaFault] {
        &self.dma_faults
    }

    /// Notes, in order of first occurrence.
    pub fn notes(&self) -> &[Note] {
        &self.notes
    }
}
