//! The USB host at the other end of the OTG FS cable: it sees the device connect, resets
//! and enumerates it as far as embassy-usb needs (device and configuration descriptors,
//! SET_ADDRESS, SET_CONFIGURATION, then the CDC ACM class requests SET_LINE_CODING and
//! SET_CONTROL_LINE_STATE with DTR), finds the CDC data interface's bulk endpoints and then
//! carries bytes: console input out on bulk OUT, answers in on bulk IN.
//!
//! Timing (USB 2.0): attach debounce 100 ms (§7.1.7.3), bus reset 10 ms (§7.1.7.5), 10 ms
//! reset recovery, 2 ms after SET_ADDRESS (§9.2.6.3); one transaction per 125 µs slot while
//! there is work (a NAKed token is retried at the next slot). No SOFs are sent (the
//! firmware does not use them); data toggles are not checked.

use std::collections::VecDeque;

use super::otg::{Device, Handshake};

/// Attach debounce.
const DEBOUNCE_NS: u64 = 100_000_000;
/// Bus reset length.
const RESET_NS: u64 = 10_000_000;
/// Reset recovery before the first request.
const RECOVERY_NS: u64 = 10_000_000;
/// Recovery after SET_ADDRESS.
const SET_ADDRESS_NS: u64 = 2_000_000;
/// One transaction slot.
const SLOT_NS: u64 = 125_000;
/// Give up enumerating after this long.
const ENUMERATION_LIMIT_NS: u64 = 5_000_000_000;
/// The address the host assigns.
const ADDRESS: u8 = 1;

/// The CDC ACM data path the host found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CdcPorts {
    /// The communication interface (class requests go there).
    pub comm_interface: u8,
    /// Bulk IN endpoint number.
    pub bulk_in: u8,
    /// Bulk OUT endpoint number.
    pub bulk_out: u8,
    /// Their max packet size.
    pub max_packet: usize,
}

/// Where the host is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HostState {
    /// Not on the cable.
    Unplugged,
    /// On the cable, no device pulled D+ up.
    WaitingForDevice,
    /// Device seen, debouncing until `.0`.
    Debounce(u64),
    /// Driving reset until `.0`.
    Reset(u64),
    /// Waiting after reset or SET_ADDRESS until `.0`.
    Recovery(u64),
    /// Running enumeration step `.0`.
    Enumerating(usize),
    /// Enumerated, the CDC data path open.
    Ready,
    /// Enumeration failed: why.
    Failed(String),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Setup,
    DataIn,
    DataOut,
    StatusIn,
    StatusOut,
}

#[derive(Clone, Debug)]
struct Control {
    setup: [u8; 8],
    out_data: Vec<u8>,
    in_data: Vec<u8>,
    stage: Stage,
}

impl Control {
    fn new(setup: [u8; 8], out_data: Vec<u8>) -> Self {
        Self {
            setup,
            out_data,
            in_data: Vec::new(),
            stage: Stage::Setup,
        }
    }

    fn length(&self) -> usize {
        usize::from(u16::from_le_bytes([self.setup[6], self.setup[7]]))
    }

    fn device_to_host(&self) -> bool {
        self.setup[0] & 0x80 != 0
    }
}

/// The host.
pub struct UsbHost {
    state: HostState,
    next_step: u64,
    attached_at: u64,
    address: u8,
    ep0_mps: usize,
    control: Option<Control>,
    configuration: Vec<u8>,
    cdc: Option<CdcPorts>,
    to_device: VecDeque<u8>,
    out_packet: Option<Vec<u8>>,
    from_device: Vec<u8>,
    log: Vec<String>,
    /// Transactions the device NAKed.
    pub naks: u64,
}

impl Default for UsbHost {
    fn default() -> Self {
        Self {
            state: HostState::Unplugged,
            next_step: u64::MAX,
            attached_at: 0,
            address: 0,
            // As Linux and Windows do: the first GET_DESCRIPTOR asks 64 bytes at a 64-byte
            // packet size; a shorter packet ends the stage.
            ep0_mps: 64,
            control: None,
            configuration: Vec::new(),
            cdc: None,
            to_device: VecDeque::new(),
            out_packet: None,
            from_device: Vec::new(),
            log: Vec::new(),
            naks: 0,
        }
    }
}

impl UsbHost {
    /// Where the host is.
    pub fn state(&self) -> &HostState {
        &self.state
    }

    /// The CDC path once enumerated.
    pub fn cdc(&self) -> Option<CdcPorts> {
        self.cdc
    }

    /// What happened, in order (requests, answers, failures).
    pub fn log(&self) -> &[String] {
        &self.log
    }

    /// Whether the host is on the cable.
    pub fn present(&self) -> bool {
        self.state != HostState::Unplugged
    }

    /// Plugs the cable in at `now`; `device_connected`: the device already pulls D+ up.
    pub fn plug_in(&mut self, device_connected: bool, now: u64) {
        if self.state != HostState::Unplugged {
            return;
        }
        self.state = HostState::WaitingForDevice;
        if device_connected {
            self.device_attached(now);
        }
    }

    /// Pulls the cable.
    pub fn unplug(&mut self) {
        self.state = HostState::Unplugged;
        self.next_step = u64::MAX;
        self.cdc = None;
        self.control = None;
    }

    /// Queues console input for the bulk OUT endpoint.
    pub fn send(&mut self, bytes: &[u8], now: u64) {
        self.to_device.extend(bytes);
        if self.state == HostState::Ready && self.next_step == u64::MAX {
            self.next_step = slot_after(now);
        }
    }

    /// Takes what the device sent on bulk IN so far.
    pub fn take_received(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.from_device)
    }

    /// The device pulled D+ up at `now`.
    pub fn device_attached(&mut self, now: u64) {
        if matches!(self.state, HostState::Unplugged) {
            return;
        }
        self.attached_at = now;
        self.address = 0;
        self.cdc = None;
        self.control = None;
        self.state = HostState::Debounce(now + DEBOUNCE_NS);
        self.next_step = now + DEBOUNCE_NS;
        self.log
            .push(format!("{:.3} ms: device attached", now as f64 / 1e6));
    }

    /// The device went away (reset, soft disconnect).
    pub fn device_gone(&mut self) {
        if self.present() {
            self.state = HostState::WaitingForDevice;
            self.next_step = u64::MAX;
            self.cdc = None;
            self.control = None;
        }
    }

    /// A device register changed at `now`: an IN endpoint may have data now.
    pub fn device_changed(&mut self, dev: &Device, now: u64) {
        if self.state == HostState::Ready && self.next_step == u64::MAX && self.has_bulk_work(dev) {
            self.next_step = slot_after(now);
        }
    }

    fn has_bulk_work(&self, dev: &Device) -> bool {
        let Some(c) = self.cdc else { return false };
        !self.to_device.is_empty()
            || self.out_packet.is_some()
            || dev.in_ready(usize::from(c.bulk_in))
    }

    /// The next time the host acts.
    pub fn next_event(&self) -> u64 {
        self.next_step
    }

    /// One step of the host at `now`.
    pub fn step(&mut self, dev: &mut Device, now: u64) {
        self.next_step = u64::MAX;
        match self.state.clone() {
            HostState::Debounce(t) if now >= t => {
                dev.bus_reset();
                self.state = HostState::Reset(now + RESET_NS);
                self.next_step = now + RESET_NS;
            }
            HostState::Reset(t) if now >= t => {
                dev.reset_done();
                self.state = HostState::Recovery(now + RECOVERY_NS);
                self.next_step = now + RECOVERY_NS;
            }
            HostState::Recovery(t) if now >= t => {
                let step = match self.control {
                    None if self.address == 0 => 0,
                    _ => 2,
                };
                self.begin_step(step);
                self.next_step = slot_after(now);
            }
            HostState::Enumerating(step) => {
                if now > self.attached_at + ENUMERATION_LIMIT_NS {
                    self.fail("enumeration took longer than 5 s".into());
                    return;
                }
                self.enumerate(dev, step, now);
            }
            HostState::Ready => self.bulk(dev, now),
            _ => {}
        }
    }

    fn fail(&mut self, why: String) {
        self.log.push(format!("failed: {why}"));
        self.state = HostState::Failed(why);
        self.next_step = u64::MAX;
    }

    /// Starts enumeration step `step`'s control transfer.
    fn begin_step(&mut self, step: usize) {
        let comm = self.cdc.map_or(0, |c| c.comm_interface);
        let config_value = self.configuration.get(5).copied().unwrap_or(1);
        // wTotalLength of the configuration (from its 9-byte header once read).
        let tl = self.configuration.get(2).copied().unwrap_or(9);
        let th = self.configuration.get(3).copied().unwrap_or(0);
        let control = match step {
            0 => Control::new([0x80, 6, 0, 1, 0, 0, 64, 0], vec![]),
            1 => Control::new([0x00, 5, ADDRESS, 0, 0, 0, 0, 0], vec![]),
            2 => Control::new([0x80, 6, 0, 1, 0, 0, 18, 0], vec![]),
            3 => Control::new([0x80, 6, 0, 2, 0, 0, 9, 0], vec![]),
            4 => Control::new([0x80, 6, 0, 2, 0, 0, tl, th], vec![]),
            5 => Control::new([0x00, 9, config_value, 0, 0, 0, 0, 0], vec![]),
            // SET_LINE_CODING 115200 8N1, then SET_CONTROL_LINE_STATE DTR | RTS.
            6 => Control::new(
                [0x21, 0x20, 0, 0, comm, 0, 7, 0],
                vec![0x00, 0xC2, 0x01, 0x00, 0, 0, 8],
            ),
            _ => Control::new([0x21, 0x22, 3, 0, comm, 0, 0, 0], vec![]),
        };
        self.control = Some(control);
        self.state = HostState::Enumerating(step);
    }

    fn enumerate(&mut self, dev: &mut Device, step: usize, now: u64) {
        self.next_step = slot_after(now);
        let result = match self.control_step(dev) {
            None => return,
            Some(r) => r,
        };
        let data = match result {
            Ok(d) => d,
            Err(e) => {
                self.fail(format!("enumeration step {step}: {e}"));
                return;
            }
        };
        self.log.push(format!(
            "{:.3} ms: step {step} done, {} bytes",
            now as f64 / 1e6,
            data.len()
        ));
        match step {
            0 => {
                let Some(&mps) = data.get(7) else {
                    self.fail("device descriptor shorter than 8 bytes".into());
                    return;
                };
                self.ep0_mps = usize::from(mps).max(8);
                self.begin_step(1);
            }
            1 => {
                self.address = ADDRESS;
                self.control = None;
                self.state = HostState::Recovery(now + SET_ADDRESS_NS);
                self.next_step = now + SET_ADDRESS_NS;
            }
            3 => {
                self.configuration = data;
                self.begin_step(4);
            }
            4 => {
                self.configuration = data;
                match find_cdc(&self.configuration) {
                    Some(c) => {
                        self.cdc = Some(c);
                        self.begin_step(5);
                    }
                    None => self.fail("no CDC ACM data interface in the configuration".into()),
                }
            }
            7 => {
                self.control = None;
                self.state = HostState::Ready;
                self.log
                    .push(format!("{:.3} ms: CDC ACM ready", now as f64 / 1e6));
                self.next_step = if self.has_bulk_work(dev) {
                    slot_after(now)
                } else {
                    u64::MAX
                };
            }
            s => self.begin_step(s + 1),
        }
    }

    /// One transaction of the control transfer under way; `Some` when it ended.
    fn control_step(&mut self, dev: &mut Device) -> Option<Result<Vec<u8>, String>> {
        let addr = self.address;
        let mps = self.ep0_mps;
        let c = self.control.as_mut()?;
        match c.stage {
            Stage::Setup => match dev.setup(addr, c.setup) {
                Handshake::Ack => {
                    c.stage = match (c.length(), c.device_to_host()) {
                        (0, _) => Stage::StatusIn,
                        (_, true) => Stage::DataIn,
                        (_, false) => Stage::DataOut,
                    };
                    None
                }
                h => Some(Err(format!("SETUP answered {h:?}"))),
            },
            Stage::DataIn => match dev.in_token(addr, 0) {
                Handshake::Data(p) => {
                    let short = p.len() < mps;
                    c.in_data.extend(p);
                    if short || c.in_data.len() >= c.length() {
                        c.stage = Stage::StatusOut;
                    }
                    None
                }
                Handshake::Nak => {
                    self.naks += 1;
                    None
                }
                h => Some(Err(format!("IN data stage answered {h:?}"))),
            },
            Stage::DataOut => {
                let n = c.out_data.len().min(mps);
                let chunk: Vec<u8> = c.out_data.get(..n).unwrap_or_default().to_vec();
                match dev.out(addr, 0, &chunk) {
                    Handshake::Ack => {
                        c.out_data.drain(..n);
                        if c.out_data.is_empty() {
                            c.stage = Stage::StatusIn;
                        }
                        None
                    }
                    Handshake::Nak => {
                        self.naks += 1;
                        None
                    }
                    h => Some(Err(format!("OUT data stage answered {h:?}"))),
                }
            }
            Stage::StatusIn => match dev.in_token(addr, 0) {
                Handshake::Data(p) if p.is_empty() => Some(Ok(std::mem::take(&mut c.in_data))),
                Handshake::Nak => {
                    self.naks += 1;
                    None
                }
                h => Some(Err(format!("IN status stage answered {h:?}"))),
            },
            Stage::StatusOut => match dev.out(addr, 0, &[]) {
                Handshake::Ack => Some(Ok(std::mem::take(&mut c.in_data))),
                Handshake::Nak => {
                    self.naks += 1;
                    None
                }
                h => Some(Err(format!("OUT status stage answered {h:?}"))),
            },
        }
    }

    /// One bulk transaction: data in first if the device has some, else data out.
    fn bulk(&mut self, dev: &mut Device, now: u64) {
        let Some(c) = self.cdc else { return };
        if dev.in_ready(usize::from(c.bulk_in)) {
            match dev.in_token(self.address, usize::from(c.bulk_in)) {
                Handshake::Data(p) => self.from_device.extend(p),
                Handshake::Nak => self.naks += 1,
                h => self.log.push(format!("bulk IN answered {h:?}")),
            }
        } else if self.out_packet.is_some() || !self.to_device.is_empty() {
            let packet = self.out_packet.take().unwrap_or_else(|| {
                let n = self.to_device.len().min(c.max_packet);
                self.to_device.drain(..n).collect()
            });
            match dev.out(self.address, usize::from(c.bulk_out), &packet) {
                Handshake::Ack => {}
                Handshake::Nak => {
                    self.naks += 1;
                    self.out_packet = Some(packet);
                }
                h => self.log.push(format!("bulk OUT answered {h:?}")),
            }
        }
        if self.has_bulk_work(dev) {
            self.next_step = slot_after(now);
        }
    }
}

/// The first slot boundary after `now`.
fn slot_after(now: u64) -> u64 {
    (now / SLOT_NS + 1) * SLOT_NS
}

/// The CDC data interface's bulk endpoints and the communication interface before it.
fn find_cdc(config: &[u8]) -> Option<CdcPorts> {
    let mut i = 0;
    let (mut comm, mut in_data_interface) = (None, false);
    let (mut bulk_in, mut bulk_out, mut mps) = (None, None, 64);
    while i + 1 < config.len() {
        let len = usize::from(*config.get(i)?);
        let kind = *config.get(i + 1)?;
        if len == 0 {
            return None;
        }
        match kind {
            4 => {
                let number = *config.get(i + 2)?;
                let class = *config.get(i + 5)?;
                if class == 0x02 {
                    comm = Some(number);
                }
                in_data_interface = class == 0x0A;
            }
            5 if in_data_interface => {
                let addr = *config.get(i + 2)?;
                let attributes = *config.get(i + 3)?;
                let size = u16::from_le_bytes([*config.get(i + 4)?, *config.get(i + 5)?]);
                if attributes & 3 == 2 {
                    mps = usize::from(size);
                    if addr & 0x80 != 0 {
                        bulk_in = Some(addr & 0x0F);
                    } else {
                        bulk_out = Some(addr & 0x0F);
                    }
                }
            }
            _ => {}
        }
        i += len;
    }
    Some(CdcPorts {
        comm_interface: comm?,
        bulk_in: bulk_in?,
        bulk_out: bulk_out?,
        max_packet: mps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// embassy-usb's CDC ACM configuration: interface 0 (CDC, notification EP1 IN),
    /// interface 1 (CDC data, bulk EP2 OUT and EP2 IN... here EP3 IN / EP2 OUT).
    fn cdc_config() -> Vec<u8> {
        let mut c = vec![9, 2, 75, 0, 2, 1, 0, 0x80, 50];
        c.extend([8, 11, 0, 2, 2, 2, 1, 0]); // IAD
        c.extend([9, 4, 0, 0, 1, 2, 2, 1, 0]); // CDC comm interface
        c.extend([5, 0x24, 0, 0x10, 1]);
        c.extend([4, 0x24, 2, 2]);
        c.extend([5, 0x24, 6, 0, 1]);
        c.extend([5, 0x24, 1, 0, 1]);
        c.extend([7, 5, 0x81, 3, 8, 0, 255]);
        c.extend([9, 4, 1, 0, 2, 0x0A, 0, 0, 0]); // CDC data interface
        c.extend([7, 5, 0x02, 2, 64, 0, 0]);
        c.extend([7, 5, 0x83, 2, 64, 0, 0]);
        c
    }

    #[test]
    fn finds_the_cdc_data_endpoints() {
        assert_eq!(
            find_cdc(&cdc_config()),
            Some(CdcPorts {
                comm_interface: 0,
                bulk_in: 3,
                bulk_out: 2,
                max_packet: 64
            })
        );
        assert_eq!(find_cdc(&[9, 2, 9, 0, 0, 1, 0, 0x80, 50]), None);
        assert_eq!(
            find_cdc(&[0, 0, 0]),
            None,
            "a zero-length descriptor is refused"
        );
    }

    #[test]
    fn the_attach_sequence_follows_the_usb_timings() {
        let mut h = UsbHost::default();
        let mut d = Device::new();
        h.plug_in(false, 0);
        assert_eq!(h.next_event(), u64::MAX);
        h.device_attached(1_000);
        assert_eq!(h.next_event(), 1_000 + DEBOUNCE_NS);
        h.step(&mut d, 1_000 + DEBOUNCE_NS);
        assert_eq!(h.state(), &HostState::Reset(1_000 + DEBOUNCE_NS + RESET_NS));
        h.step(&mut d, h.next_event());
        assert!(matches!(h.state(), HostState::Recovery(_)));
        h.step(&mut d, h.next_event());
        assert_eq!(h.state(), &HostState::Enumerating(0));
        // No device answers (not connected): the SETUP times out and enumeration fails.
        h.step(&mut d, h.next_event());
        assert!(matches!(h.state(), HostState::Failed(_)));
    }
}
