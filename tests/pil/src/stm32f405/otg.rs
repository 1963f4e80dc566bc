//! The USB OTG FS core in device mode (RM0090 §34, the Synopsys DWC2 core embassy's
//! `embassy-usb-synopsys-otg` drives), enough for that driver: the global registers
//! (GAHBCFG, GUSBCFG, GRSTCTL flushes, GINTSTS/GINTMSK, GRXSTSR/P, GRXFSIZ, the TX FIFO
//! sizes, GCCFG, CID 0x1200), the device registers (DCFG address, DCTL soft disconnect,
//! DSTS, DIEPMSK/DOEPMSK, DAINT/DAINTMSK, DIEPEMPMSK) and endpoints 0–3 (DxEPCTL with
//! USBAEP/NAK/STALL/EPENA/EPDIS, DxEPINT, DxEPTSIZ, DTXFSTS) with the shared RX FIFO and
//! per-endpoint TX FIFOs (slave mode, 320 words).
//!
//! The wire side is a [`UsbHost`] on the cable (absent until plugged in). With no host the
//! core, once connected (PHY powered, soft disconnect released), sees an idle bus and
//! signals suspend after 3 ms, as the silicon does. Transactions follow DWC2 slave mode:
//! SETUPs are always accepted; an OUT packet is accepted while the endpoint is active and
//! not NAKing, after which the core NAKs it until the application clears NAK; an IN token
//! gets a packet from the TX FIFO once the application enabled the endpoint with the data
//! written. Not modelled (recorded): host mode, OTG protocols, isochronous endpoints, DMA,
//! VBUS sensing, the SOF output.

use std::collections::VecDeque;

use super::usb_host::UsbHost;

/// Endpoints of the F405's OTG FS core.
pub const ENDPOINTS: usize = 4;
/// Shared FIFO RAM, words (1.25 KiB).
const FIFO_WORDS: u32 = 320;
/// Idle bus time before the core flags suspend (USB 2.0 §7.1.7.6).
const SUSPEND_IDLE_NS: u64 = 3_000_000;

// Global registers.
const GOTGCTL: u32 = 0x000;
const GOTGINT: u32 = 0x004;
const GAHBCFG: u32 = 0x008;
const GUSBCFG: u32 = 0x00C;
const GRSTCTL: u32 = 0x010;
const GINTSTS: u32 = 0x014;
const GINTMSK: u32 = 0x018;
const GRXSTSR: u32 = 0x01C;
const GRXSTSP: u32 = 0x020;
const GRXFSIZ: u32 = 0x024;
const DIEPTXF0: u32 = 0x028;
const HNPTXSTS: u32 = 0x02C;
const GCCFG: u32 = 0x038;
const CID: u32 = 0x03C;
const GHWCFG4: u32 = 0x050;
const HPTXFSIZ: u32 = 0x100;
const DIEPTXF1: u32 = 0x104;
const DIEPTXF3: u32 = 0x10C;
// Device registers.
const DCFG: u32 = 0x800;
const DCTL: u32 = 0x804;
const DSTS: u32 = 0x808;
const DIEPMSK: u32 = 0x810;
const DOEPMSK: u32 = 0x814;
const DAINT: u32 = 0x818;
const DAINTMSK: u32 = 0x81C;
const DVBUSDIS: u32 = 0x828;
const DVBUSPULSE: u32 = 0x82C;
const DIEPEMPMSK: u32 = 0x834;
const DIEP_BASE: u32 = 0x900;
const DOEP_BASE: u32 = 0xB00;
const PCGCCTL: u32 = 0xE00;
const FIFO_BASE: u32 = 0x1000;

// GINTSTS bits.
const CMOD: u32 = 1 << 0;
const OTGINT: u32 = 1 << 2;
const SOF: u32 = 1 << 3;
const RXFLVL: u32 = 1 << 4;
const NPTXFE: u32 = 1 << 5;
const USBSUSP: u32 = 1 << 11;
const USBRST: u32 = 1 << 12;
const ENUMDNE: u32 = 1 << 13;
const EOPF: u32 = 1 << 15;
const IEPINT: u32 = 1 << 18;
const OEPINT: u32 = 1 << 19;
const PTXFE: u32 = 1 << 26;
/// The GINTSTS bits software clears by writing 1.
const GINTSTS_W1C: u32 = 0xF070_FC0A;

// Endpoint control bits.
const USBAEP: u32 = 1 << 15;
const NAKSTS: u32 = 1 << 17;
const STALL: u32 = 1 << 21;
const CNAK: u32 = 1 << 26;
const SNAK: u32 = 1 << 27;
const EPDIS: u32 = 1 << 30;
const EPENA: u32 = 1 << 31;
// Endpoint interrupt bits.
const XFRC: u32 = 1 << 0;
const EPDISD: u32 = 1 << 1;
const STUP: u32 = 1 << 3;
const TXFE: u32 = 1 << 7;

// RX FIFO packet status (GRXSTSP.PKTSTS, device mode).
const OUT_DATA_RX: u32 = 2;
const OUT_DATA_DONE: u32 = 3;
const SETUP_DATA_DONE: u32 = 4;
const SETUP_DATA_RX: u32 = 6;

/// The device's answer to a host transaction.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Handshake {
    /// Accepted (OUT/SETUP) or a data packet (IN).
    Ack,
    /// Data for an IN token.
    Data(Vec<u8>),
    /// Not now.
    Nak,
    /// Halted.
    Stall,
    /// No answer (not connected, wrong address, in reset).
    Timeout,
}

/// One RX FIFO entry: the status word the application pops and the data behind it.
#[derive(Clone, Debug)]
struct RxEntry {
    status: u32,
    data: VecDeque<u32>,
}

#[derive(Clone, Copy, Debug, Default)]
struct Endpoint {
    ctl: u32,
    int: u32,
    tsiz: u32,
    nak: bool,
}

/// The device side of the core: registers, FIFOs, endpoint state.
pub struct Device {
    gotgctl: u32,
    gahbcfg: u32,
    gusbcfg: u32,
    gintsts: u32,
    gintmsk: u32,
    grxfsiz: u32,
    txfsiz: [u32; ENDPOINTS],
    hptxfsiz: u32,
    gccfg: u32,
    dcfg: u32,
    dctl: u32,
    diepmsk: u32,
    doepmsk: u32,
    daintmsk: u32,
    diepempmsk: u32,
    pcgcctl: u32,
    din: [Endpoint; ENDPOINTS],
    dout: [Endpoint; ENDPOINTS],
    rx: VecDeque<RxEntry>,
    /// Data words of the entry popped last, read through the FIFO window.
    rx_current: VecDeque<u32>,
    tx: [VecDeque<u8>; ENDPOINTS],
    /// The address tokens must carry (latched at each SETUP).
    address: u8,
    suspended: bool,
    /// When the device became visible on an idle bus (for suspend detection).
    idle_since: Option<u64>,
    frame: u32,
    /// 5 V on VBUS (a host on the cable).
    vbus: bool,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Default for Device {
    fn default() -> Self {
        Self::new()
    }
}

impl Device {
    /// Reset state.
    pub fn new() -> Self {
        Self {
            gotgctl: 0x0001_0000,
            gahbcfg: 0,
            gusbcfg: 0x0000_0A00,
            gintsts: NPTXFE | PTXFE,
            gintmsk: 0,
            grxfsiz: 0x200,
            txfsiz: [0x0200_0200, 0x0200_0400, 0x0200_0400, 0x0200_0400],
            hptxfsiz: 0x0200_0600,
            gccfg: 0,
            dcfg: 0x0220_0000,
            dctl: 0,
            diepmsk: 0,
            doepmsk: 0,
            daintmsk: 0,
            diepempmsk: 0,
            pcgcctl: 0,
            din: [Endpoint::default(); ENDPOINTS],
            dout: [Endpoint::default(); ENDPOINTS],
            rx: VecDeque::new(),
            rx_current: VecDeque::new(),
            tx: Default::default(),
            address: 0,
            suspended: false,
            idle_since: None,
            frame: 0,
            vbus: false,
            unmodelled: Vec::new(),
        }
    }

    /// D+ pulled up: PHY powered, soft disconnect released, device mode, and a B-session
    /// valid — assumed with NOVBUSSENS, else VBUS sensed on PA9 (a host on the cable).
    pub fn connected(&self) -> bool {
        let session = self.gccfg & (1 << 21) != 0 || (self.gccfg & (1 << 19) != 0 && self.vbus);
        self.gccfg & (1 << 16) != 0
            && self.dctl & 2 == 0
            && self.gusbcfg & (1 << 29) == 0
            && session
    }

    fn mps(&self, ep: usize, dir_in: bool) -> usize {
        let ctl = if dir_in {
            self.din.get(ep).map_or(0, |e| e.ctl)
        } else {
            self.dout.get(ep).map_or(0, |e| e.ctl)
        };
        if ep == 0 {
            [64, 32, 16, 8]
                .get((ctl & 3) as usize)
                .copied()
                .unwrap_or(64)
        } else {
            (ctl & 0x7FF) as usize
        }
    }

    fn tx_depth_words(&self, ep: usize) -> u32 {
        self.txfsiz.get(ep).map_or(0, |v| v >> 16)
    }

    fn tx_free_words(&self, ep: usize) -> u32 {
        let used = self.tx.get(ep).map_or(0, |q| q.len().div_ceil(4) as u32);
        self.tx_depth_words(ep).saturating_sub(used)
    }

    fn rx_used_words(&self) -> u32 {
        self.rx.iter().map(|e| 1 + e.data.len() as u32).sum::<u32>() + self.rx_current.len() as u32
    }

    /// The core's interrupt line.
    pub fn irq(&self) -> bool {
        self.gahbcfg & 1 != 0 && self.gintsts_value() & self.gintmsk != 0
    }

    fn daint(&self) -> u32 {
        let mut v = 0;
        for (i, e) in self.din.iter().enumerate() {
            let empty_mask = if self.diepempmsk & (1 << i) != 0 {
                TXFE
            } else {
                0
            };
            if self.diepint_value(i, e) & (self.diepmsk | empty_mask) != 0 {
                v |= 1 << i;
            }
        }
        for (i, e) in self.dout.iter().enumerate() {
            if e.int & self.doepmsk != 0 {
                v |= 1 << (16 + i);
            }
        }
        v
    }

    fn diepint_value(&self, i: usize, e: &Endpoint) -> u32 {
        let mut v = e.int & !TXFE;
        if self.tx.get(i).is_some_and(VecDeque::is_empty) {
            v |= TXFE;
        }
        v
    }

    fn gintsts_value(&self) -> u32 {
        let mut v = self.gintsts & !(RXFLVL | IEPINT | OEPINT | CMOD | OTGINT);
        if !self.rx.is_empty() {
            v |= RXFLVL;
        }
        let daint = self.daint() & self.daintmsk;
        if daint & 0xFFFF != 0 {
            v |= IEPINT;
        }
        if daint >> 16 != 0 {
            v |= OEPINT;
        }
        v
    }

    /// A bus reset started (host drives SE0).
    pub fn bus_reset(&mut self) {
        self.gintsts |= USBRST;
        self.suspended = false;
        self.idle_since = None;
        self.address = 0;
        for (i, e) in self.din.iter_mut().enumerate() {
            e.ctl &= !(EPENA | STALL | if i == 0 { 0 } else { USBAEP });
            e.nak = true;
        }
        for (i, e) in self.dout.iter_mut().enumerate() {
            e.ctl &= !(EPENA | STALL | if i == 0 { 0 } else { USBAEP });
            e.nak = true;
        }
        for q in &mut self.tx {
            q.clear();
        }
    }

    /// The bus reset ended: enumeration done at full speed.
    pub fn reset_done(&mut self) {
        self.gintsts |= ENUMDNE;
    }

    /// A start of frame.
    pub fn start_of_frame(&mut self) {
        self.frame = (self.frame + 1) & 0x3FFF;
        self.gintsts |= SOF | EOPF;
    }

    fn tokens_answered(&self, address: u8) -> bool {
        self.connected() && address == self.address && self.pcgcctl & 1 == 0
    }

    /// A SETUP transaction to `address`, endpoint 0.
    pub fn setup(&mut self, address: u8, data: [u8; 8]) -> Handshake {
        if self.connected() && address == ((self.dcfg >> 4) & 0x7F) as u8 {
            self.address = address;
        }
        if !self.tokens_answered(address) {
            return Handshake::Timeout;
        }
        if self.rx_used_words() + 4 > self.grxfsiz & 0xFFFF {
            return Handshake::Timeout;
        }
        let [a, b, c, d, e, f, g, h] = data;
        let words = VecDeque::from([
            u32::from_le_bytes([a, b, c, d]),
            u32::from_le_bytes([e, f, g, h]),
        ]);
        self.rx.push_back(RxEntry {
            status: SETUP_DATA_RX << 17 | 8 << 4,
            data: words,
        });
        self.rx.push_back(RxEntry {
            status: SETUP_DATA_DONE << 17,
            data: VecDeque::new(),
        });
        // A SETUP clears EP0's STALL and makes both directions NAK (DWC2 control flow).
        for e in [&mut self.din[0], &mut self.dout[0]] {
            e.ctl &= !STALL;
            e.nak = true;
        }
        let ts = &mut self.dout[0].tsiz;
        let stupcnt = (*ts >> 29) & 3;
        *ts = (*ts & !(3 << 29)) | (stupcnt.saturating_sub(1) << 29);
        Handshake::Ack
    }

    /// An OUT transaction with `data` to `address`/`ep`.
    pub fn out(&mut self, address: u8, ep: usize, data: &[u8]) -> Handshake {
        if !self.tokens_answered(address) || ep >= ENDPOINTS {
            return Handshake::Timeout;
        }
        let mps = self.mps(ep, false);
        let Some(e) = self.dout.get(ep).copied() else {
            return Handshake::Timeout;
        };
        if e.ctl & STALL != 0 {
            return Handshake::Stall;
        }
        let active = ep == 0 || e.ctl & USBAEP != 0;
        let words = data.len().div_ceil(4) as u32 + 2;
        if !active || e.nak || self.rx_used_words() + words > self.grxfsiz & 0xFFFF {
            return Handshake::Nak;
        }
        let mut payload = VecDeque::new();
        for chunk in data.chunks(4) {
            let mut w = [0u8; 4];
            if let Some(s) = w.get_mut(..chunk.len()) {
                s.copy_from_slice(chunk);
            }
            payload.push_back(u32::from_le_bytes(w));
        }
        let epn = ep as u32;
        self.rx.push_back(RxEntry {
            status: OUT_DATA_RX << 17 | (data.len() as u32) << 4 | epn,
            data: payload,
        });
        // The transfer ends with this packet (one packet per transfer as the driver
        // programs it, or a short packet): the completion entry follows.
        let pktcnt_mask = if ep == 0 { 1 << 19 } else { 0x3FF << 19 };
        let Some(out) = self.dout.get_mut(ep) else {
            return Handshake::Timeout;
        };
        let pktcnt = (out.tsiz & pktcnt_mask) >> 19;
        let left = pktcnt.saturating_sub(1);
        out.tsiz = (out.tsiz & !pktcnt_mask) | (left << 19);
        if left == 0 || data.len() < mps {
            self.rx.push_back(RxEntry {
                status: OUT_DATA_DONE << 17 | epn,
                data: VecDeque::new(),
            });
        }
        out.nak = true;
        Handshake::Ack
    }

    /// An IN token to `address`/`ep`.
    pub fn in_token(&mut self, address: u8, ep: usize) -> Handshake {
        if !self.tokens_answered(address) || ep >= ENDPOINTS {
            return Handshake::Timeout;
        }
        let mps = self.mps(ep, true);
        let Some(e) = self.din.get(ep).copied() else {
            return Handshake::Timeout;
        };
        if e.ctl & STALL != 0 {
            return Handshake::Stall;
        }
        if e.ctl & EPENA == 0 || e.nak {
            return Handshake::Nak;
        }
        let (xfr_mask, pkt_mask) = if ep == 0 {
            (0x7F, 3 << 19)
        } else {
            (0x7_FFFF, 0x3FF << 19)
        };
        let xfrsiz = (e.tsiz & xfr_mask) as usize;
        let len = xfrsiz.min(mps);
        let Some(q) = self.tx.get_mut(ep) else {
            return Handshake::Timeout;
        };
        if q.len() < len {
            // Not all of the packet is in the FIFO yet.
            return Handshake::Nak;
        }
        let packet: Vec<u8> = q.drain(..len).collect();
        // Words are pushed whole: drop the padding of the last one.
        let pad = ((4 - len % 4) % 4).min(q.len());
        q.drain(..pad);
        let pktcnt = ((e.tsiz & pkt_mask) >> 19).saturating_sub(1);
        let Some(ein) = self.din.get_mut(ep) else {
            return Handshake::Timeout;
        };
        ein.tsiz =
            (e.tsiz & !(xfr_mask | pkt_mask)) | ((xfrsiz - len) as u32 & xfr_mask) | (pktcnt << 19);
        if pktcnt == 0 {
            ein.ctl &= !EPENA;
            ein.int |= XFRC;
        }
        Handshake::Data(packet)
    }

    /// Whether an IN endpoint has a packet ready for a token.
    pub fn in_ready(&self, ep: usize) -> bool {
        self.din
            .get(ep)
            .is_some_and(|e| e.ctl & EPENA != 0 && !e.nak)
    }

    /// The idle-bus suspend timer (no host on the cable).
    pub fn next_suspend(&self) -> u64 {
        match self.idle_since {
            Some(t) if !self.suspended => t + SUSPEND_IDLE_NS,
            _ => u64::MAX,
        }
    }

    /// Marks the bus idle from `now` (no host) or busy (`None`).
    pub fn set_idle(&mut self, since: Option<u64>) {
        self.idle_since = since;
    }

    /// Suspend due at `now`.
    pub fn process_suspend(&mut self, now: u64) {
        if now >= self.next_suspend() {
            self.suspended = true;
            self.gintsts |= USBSUSP;
        }
    }

    /// Register read.
    pub fn read(&mut self, offset: u32) -> Option<u32> {
        if offset >= FIFO_BASE {
            return Some(self.rx_current.pop_front().unwrap_or(0));
        }
        Some(match offset {
            GOTGCTL => self.gotgctl,
            GOTGINT => 0,
            GAHBCFG => self.gahbcfg,
            GUSBCFG => self.gusbcfg,
            // AHB idle, no reset or flush in progress (they complete at once).
            GRSTCTL => 1 << 31,
            GINTSTS => self.gintsts_value(),
            GINTMSK => self.gintmsk,
            GRXSTSR => self.rx.front().map_or(0, |e| e.status),
            GRXSTSP => self.pop_rx(),
            GRXFSIZ => self.grxfsiz,
            DIEPTXF0 => *self.txfsiz.first()?,
            HNPTXSTS => 0x0008_0000 | self.tx_free_words(0),
            GCCFG => self.gccfg,
            CID => 0x0000_1200,
            GHWCFG4 => 0,
            HPTXFSIZ => self.hptxfsiz,
            DIEPTXF1..=DIEPTXF3 => *self.txfsiz.get(((offset - DIEPTXF1) / 4 + 1) as usize)?,
            DCFG => self.dcfg,
            DCTL => self.dctl,
            // Full speed (ENUMSPD 3), the frame number, suspend status.
            DSTS => u32::from(self.suspended) | 3 << 1 | self.frame << 8,
            DIEPMSK => self.diepmsk,
            DOEPMSK => self.doepmsk,
            DAINT => self.daint(),
            DAINTMSK => self.daintmsk,
            DVBUSDIS | DVBUSPULSE => 0,
            DIEPEMPMSK => self.diepempmsk,
            DIEP_BASE..=0xAFF => self.read_ep(offset - DIEP_BASE, true)?,
            DOEP_BASE..=0xCFF => self.read_ep(offset - DOEP_BASE, false)?,
            PCGCCTL => self.pcgcctl,
            _ => return None,
        })
    }

    fn pop_rx(&mut self) -> u32 {
        let Some(entry) = self.rx.pop_front() else {
            return 0;
        };
        let ep = (entry.status & 0xF) as usize;
        match (entry.status >> 17) & 0xF {
            SETUP_DATA_DONE => {
                if let Some(e) = self.dout.get_mut(0) {
                    e.int |= STUP;
                    e.ctl &= !EPENA;
                }
            }
            OUT_DATA_DONE => {
                if let Some(e) = self.dout.get_mut(ep) {
                    e.int |= XFRC;
                    e.ctl &= !EPENA;
                }
            }
            _ => {}
        }
        self.rx_current = entry.data;
        entry.status
    }

    fn read_ep(&self, rel: u32, dir_in: bool) -> Option<u32> {
        let n = (rel / 0x20) as usize;
        let e = if dir_in {
            self.din.get(n)?
        } else {
            self.dout.get(n)?
        };
        Some(match rel % 0x20 {
            0x00 => {
                let mut ctl = e.ctl & !(NAKSTS | CNAK | SNAK);
                if e.nak {
                    ctl |= NAKSTS;
                }
                if n == 0 {
                    ctl |= USBAEP;
                }
                ctl
            }
            0x08 if dir_in => self.diepint_value(n, e),
            0x08 => e.int,
            0x10 => e.tsiz,
            0x18 if dir_in => self.tx_free_words(n),
            _ => 0,
        })
    }

    /// Register write.
    pub fn write(&mut self, offset: u32, value: u32) -> Option<()> {
        if offset >= FIFO_BASE {
            let ep = ((offset - FIFO_BASE) / 0x1000) as usize;
            let q = self.tx.get_mut(ep)?;
            q.extend(value.to_le_bytes());
            return Some(());
        }
        match offset {
            GOTGCTL => {
                self.gotgctl = (self.gotgctl & 0x000F_0000) | (value & 0xFFF0_FFFF);
                if value & 0x0F != 0 {
                    self.unmodelled.push("OTG session request / HNP");
                }
            }
            GOTGINT => {}
            GAHBCFG => self.gahbcfg = value & 0x1A1,
            GUSBCFG => {
                self.gusbcfg = value;
                if value & (1 << 29) != 0 {
                    self.unmodelled.push("USB OTG FS host mode");
                }
            }
            GRSTCTL => self.write_grstctl(value),
            GINTSTS => self.gintsts &= !(value & GINTSTS_W1C),
            GINTMSK => self.gintmsk = value,
            GRXSTSR | GRXSTSP => {}
            GRXFSIZ => self.grxfsiz = value & 0xFFFF,
            DIEPTXF0 => {
                *self.txfsiz.first_mut()? = value;
                self.check_fifo_ram(value);
            }
            GCCFG => {
                self.gccfg = value & 0x003D_0000;
                if value & (1 << 20) != 0 {
                    self.unmodelled.push("USB OTG FS SOF output");
                }
            }
            HPTXFSIZ => self.hptxfsiz = value,
            DIEPTXF1..=DIEPTXF3 => {
                *self
                    .txfsiz
                    .get_mut(((offset - DIEPTXF1) / 4 + 1) as usize)? = value;
                self.check_fifo_ram(value);
            }
            DCFG => self.dcfg = value,
            DCTL => self.dctl = value & 0xF8B,
            DIEPMSK => self.diepmsk = value,
            DOEPMSK => self.doepmsk = value,
            DAINTMSK => self.daintmsk = value,
            DIEPEMPMSK => self.diepempmsk = value & 0xFFFF,
            DIEP_BASE..=0xAFF => self.write_ep(offset - DIEP_BASE, true, value)?,
            DOEP_BASE..=0xCFF => self.write_ep(offset - DOEP_BASE, false, value)?,
            PCGCCTL => self.pcgcctl = value & 0x13,
            DSTS | DAINT | CID | HNPTXSTS | GHWCFG4 | DVBUSDIS | DVBUSPULSE => {}
            _ => return None,
        }
        Some(())
    }

    /// A TX FIFO (start, depth) written past the 320 words of FIFO RAM overlaps nothing.
    fn check_fifo_ram(&mut self, value: u32) {
        if (value & 0xFFFF) + (value >> 16) > FIFO_WORDS {
            self.unmodelled
                .push("USB TX FIFO placed beyond the 320-word FIFO RAM");
        }
    }

    fn write_grstctl(&mut self, value: u32) {
        if value & 1 != 0 {
            // Core soft reset: state machines and FIFOs, not the configuration registers.
            self.rx.clear();
            self.rx_current.clear();
            for q in &mut self.tx {
                q.clear();
            }
            self.gintsts &= !GINTSTS_W1C;
        }
        if value & (1 << 4) != 0 {
            self.rx.clear();
            self.rx_current.clear();
        }
        if value & (1 << 5) != 0 {
            let num = ((value >> 6) & 0x1F) as usize;
            for (i, q) in self.tx.iter_mut().enumerate() {
                if num == 0x10 || num == i {
                    q.clear();
                }
            }
        }
    }

    fn write_ep(&mut self, rel: u32, dir_in: bool, value: u32) -> Option<()> {
        let n = (rel / 0x20) as usize;
        let e = if dir_in {
            self.din.get_mut(n)?
        } else {
            self.dout.get_mut(n)?
        };
        match rel % 0x20 {
            0x00 => {
                if value & SNAK != 0 {
                    e.nak = true;
                }
                if value & CNAK != 0 && value & SNAK == 0 {
                    e.nak = false;
                }
                let mut ctl = value & !(CNAK | SNAK | NAKSTS | EPDIS);
                if value & EPDIS != 0 && e.ctl & EPENA != 0 {
                    ctl &= !EPENA;
                    e.int |= EPDISD;
                }
                e.ctl = ctl;
                if (value >> 18) & 3 == 1 {
                    self.unmodelled.push("USB isochronous endpoints");
                }
            }
            0x08 => e.int &= !(value & !TXFE),
            0x10 => e.tsiz = value,
            _ => {}
        }
        Some(())
    }
}

/// The OTG FS block: the device core and the host on its cable.
#[derive(Default)]
pub struct Otg {
    dev: Device,
    host: UsbHost,
    clock_ok: bool,
    was_connected: bool,
    /// The core's interrupt line (kept current after every change).
    line: bool,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Otg {
    /// Reset state (the host stays on the cable).
    pub fn new() -> Self {
        Self::default()
    }

    /// A peripheral or system reset: the core's pull-up drops; the host sees a detach.
    pub fn reset(&mut self) {
        let vbus = self.dev.vbus;
        self.dev = Device::new();
        self.dev.vbus = vbus;
        self.was_connected = false;
        self.line = false;
        self.host.device_gone();
    }

    /// The 48 MHz clock is right (the core only works on it).
    pub fn set_clock_ok(&mut self, ok: bool) {
        self.clock_ok = ok;
    }

    /// The host on the cable.
    pub fn host(&self) -> &UsbHost {
        &self.host
    }

    /// Plugs the host in (or pulls it) at `now`.
    pub fn plug(&mut self, plugged: bool, now: u64) {
        self.dev.vbus = plugged;
        self.connection_changed(now);
        if plugged {
            self.host.plug_in(self.was_connected, now);
            self.dev.set_idle(None);
        } else {
            self.host.unplug();
            if self.was_connected {
                self.dev.set_idle(Some(now));
            }
        }
        self.line = self.dev.irq();
    }

    /// Queues console input at `now`.
    pub fn send(&mut self, bytes: &[u8], now: u64) {
        self.host.send(bytes, now);
    }

    /// Takes what the device sent.
    pub fn take_received(&mut self) -> Vec<u8> {
        self.host.take_received()
    }

    /// The next time the core or its host acts.
    pub fn next_event(&self) -> u64 {
        self.dev.next_suspend().min(self.host.next_event())
    }

    /// Bus activity due by `now`.
    pub fn process(&mut self, now: u64) {
        loop {
            let t = self.next_event();
            if t > now {
                return;
            }
            if self.dev.next_suspend() <= t {
                self.dev.process_suspend(t);
            } else {
                self.host.step(&mut self.dev, t);
            }
            self.line = self.dev.irq();
        }
    }

    /// The OTG_FS interrupt line.
    pub fn irq(&self) -> bool {
        self.line
    }

    fn connection_changed(&mut self, now: u64) {
        let connected = self.dev.connected() && self.clock_ok;
        if connected != self.was_connected {
            self.was_connected = connected;
            if connected {
                self.host.device_attached(now);
                self.dev
                    .set_idle(if self.host.present() { None } else { Some(now) });
            } else {
                self.dev.set_idle(None);
                self.host.device_gone();
            }
        }
    }

    /// Register read at `now`.
    pub fn read(&mut self, offset: u32, now: u64) -> Option<u32> {
        let v = self.dev.read(offset);
        self.connection_changed(now);
        self.line = self.dev.irq();
        v
    }

    /// Register write at `now`.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        let r = self.dev.write(offset, value);
        self.unmodelled.append(&mut self.dev.unmodelled);
        self.connection_changed(now);
        self.host.device_changed(&self.dev, now);
        self.line = self.dev.irq();
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WKUPINT: u32 = 1 << 31;

    /// The driver's init as far as "connect": device mode, PHY on, no VBUS sensing,
    /// FIFOs, EP0 64 bytes, interrupts, SDIS released.
    fn embassy_init(d: &mut Device) {
        d.write(GUSBCFG, 1 << 30 | 1 << 6);
        assert_eq!(d.read(GINTSTS).unwrap() & CMOD, 0);
        d.write(GCCFG, 1 << 16 | 1 << 21);
        d.write(DCTL, 2);
        d.write(DCFG, 3);
        d.write(DIEPMSK, XFRC);
        d.write(DOEPMSK, STUP);
        d.write(
            GINTMSK,
            USBRST | ENUMDNE | USBSUSP | WKUPINT | IEPINT | OEPINT | RXFLVL,
        );
        d.write(GINTSTS, u32::MAX);
        d.write(GAHBCFG, 1);
        d.write(DCTL, 0);
    }

    #[test]
    fn core_id_and_idle_registers_as_the_driver_expects() {
        let mut d = Device::new();
        assert_eq!(d.read(CID), Some(0x1200));
        assert_eq!(d.read(GRSTCTL).unwrap() & 1 << 31, 1 << 31, "AHBIDL");
        embassy_init(&mut d);
        assert!(d.connected());
        assert!(!d.irq());
    }

    #[test]
    fn a_setup_packet_goes_through_the_rx_fifo_and_raises_stup_when_popped() {
        let mut d = Device::new();
        embassy_init(&mut d);
        d.bus_reset();
        assert!(d.irq(), "USBRST");
        d.write(GINTSTS, USBRST);
        d.write(GRXFSIZ, 30 + 16);
        d.write(DOEP_BASE + 0x10, 3 << 29 | 64);
        d.write(DAINTMSK, 0x0001_0001);
        assert_eq!(d.setup(0, [0x80, 6, 0, 1, 0, 0, 64, 0]), Handshake::Ack);
        assert_eq!(d.read(GINTSTS).unwrap() & RXFLVL, RXFLVL);
        let st = d.read(GRXSTSP).unwrap();
        assert_eq!((st >> 17) & 0xF, SETUP_DATA_RX);
        assert_eq!((st >> 4) & 0x7FF, 8);
        assert_eq!(d.read(FIFO_BASE), Some(0x0100_0680));
        assert_eq!(d.read(FIFO_BASE), Some(0x0040_0000));
        assert_eq!(
            d.read(GINTSTS).unwrap() & OEPINT,
            0,
            "STUP only once the done entry is popped"
        );
        d.read(GRXSTSP);
        assert_eq!(d.read(GINTSTS).unwrap() & (RXFLVL | OEPINT), OEPINT);
        assert_eq!(d.read(DOEP_BASE + 8), Some(STUP));
    }

    #[test]
    fn in_packets_come_from_the_fifo_once_enabled_and_complete_the_transfer() {
        let mut d = Device::new();
        embassy_init(&mut d);
        d.write(DIEPTXF0, 16 << 16 | 46);
        assert_eq!(d.in_token(0, 0), Handshake::Nak);
        // write(): DIEPTSIZ, then CNAK + EPENA, then the FIFO words.
        d.write(DIEP_BASE + 0x10, 1 << 19 | 5);
        d.write(DIEP_BASE, CNAK | EPENA);
        assert_eq!(d.read(DIEP_BASE + 0x18), Some(16));
        d.write(FIFO_BASE, u32::from_le_bytes(*b"hell"));
        d.write(FIFO_BASE, u32::from_le_bytes([b'o', 0, 0, 0]));
        assert_eq!(d.read(DIEP_BASE + 0x18), Some(14));
        assert_eq!(d.in_token(0, 0), Handshake::Data(b"hello".to_vec()));
        assert_eq!(d.read(DIEP_BASE).unwrap() & EPENA, 0);
        assert_eq!(d.read(DIEP_BASE + 8).unwrap() & XFRC, XFRC);
        assert_eq!(d.read(DIEP_BASE + 0x18), Some(16));
        // A zero-length packet (accept()).
        d.write(DIEP_BASE + 0x10, 1 << 19);
        d.write(DIEP_BASE, CNAK | EPENA);
        assert_eq!(d.in_token(0, 0), Handshake::Data(vec![]));
    }

    #[test]
    fn out_packets_are_nakd_until_the_application_clears_nak() {
        let mut d = Device::new();
        embassy_init(&mut d);
        d.write(GRXFSIZ, 46);
        // Bulk OUT EP2, 64 bytes, enabled as endpoint_set_enabled does.
        let ep2 = DOEP_BASE + 2 * 0x20;
        d.write(ep2, 64 | 2 << 18 | 1 << 28);
        d.write(ep2 + 0x10, 1 << 19 | 64);
        d.write(ep2, 64 | 2 << 18 | USBAEP | CNAK | EPENA);
        assert_eq!(d.out(0, 2, b"status\n"), Handshake::Ack);
        assert_eq!(d.out(0, 2, b"more"), Handshake::Nak, "NAK after a packet");
        let st = d.read(GRXSTSP).unwrap();
        assert_eq!(
            (st & 0xF, (st >> 4) & 0x7FF, (st >> 17) & 0xF),
            (2, 7, OUT_DATA_RX)
        );
        // read(): pktcnt 1 and CNAK only — the endpoint takes the next packet.
        d.write(ep2 + 0x10, 1 << 19 | 64);
        let ctl = d.read(ep2).unwrap();
        d.write(ep2, ctl | CNAK);
        assert_eq!(d.out(0, 2, b"more"), Handshake::Ack);
    }

    #[test]
    fn with_no_host_the_core_signals_suspend_after_3_ms_of_idle_bus() {
        let mut o = Otg::new();
        o.set_clock_ok(true);
        o.write(DCTL, 2, 0);
        o.write(GUSBCFG, 1 << 30 | 1 << 6, 0);
        o.write(GCCFG, 1 << 16 | 1 << 21, 0);
        o.write(GINTMSK, USBSUSP, 0);
        o.write(GAHBCFG, 1, 0);
        o.write(DCTL, 0, 1_000);
        assert_eq!(o.next_event(), 1_000 + SUSPEND_IDLE_NS);
        o.process(1_000 + SUSPEND_IDLE_NS);
        assert!(o.irq());
        o.write(GINTSTS, USBSUSP, 4_000_000);
        assert!(!o.irq());
        assert_eq!(
            o.next_event(),
            u64::MAX,
            "nothing more happens without a host"
        );
    }
}
