//! Issue 35's acceptance at chip level: the radio's device tool reaches the flight
//! controller (CRSF device 0xC8) through the module and the air. The radio side is a
//! scripted ExpressLRS Lua tool with its own CRSF codec, written from the protocol as the
//! script sends it: frames `EE len type payload crc8` (EdgeTX's `crossfireTelemetryPush`
//! to the module), a broadcast ping `00 EA`, reads `dest EF field chunk`, writes
//! `dest EF field value…`, and the answers taken from the module's JR-line bursts by sync
//! byte, length and CRC. Both ends fly a link key (writes need the keyed link);
//! the quad sits disarmed on the ground.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss,
    clippy::panic
)]

use std::time::Duration;

use flight_app::settings::{PARAMS, handles};
use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, World};
use module_core::settings::{InputProtocol, Settings as ModuleSettings};
use telemetry::link::LinkKey;

/// The Lua tool's own address.
const HANDSET: u8 = 0xEF;
const FC: u8 = 0xC8;
const PING: u8 = 0x28;
const DEVICE_INFO: u8 = 0x29;
const ENTRY: u8 = 0x2B;
const READ: u8 = 0x2C;
const WRITE: u8 = 0x2D;
/// How long the tool waits for an answer before asking again (the script's field timeout).
const TIMEOUT_MS: u64 = 500;

/// CRC-8/DVB-S2 (polynomial 0xD5) over type and payload.
fn crc8(bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0xD5
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// `crossfireTelemetryPush(kind, payload)` as EdgeTX puts it on the line.
fn push_frame(kind: u8, payload: &[u8]) -> Vec<u8> {
    let mut body = vec![kind];
    body.extend_from_slice(payload);
    let mut frame = vec![0xEE, body.len() as u8 + 1];
    frame.extend_from_slice(&body);
    frame.push(crc8(&body));
    frame
}

/// The frames (type, payload) in the module's bursts with a good CRC.
fn frames(bursts: &[(f64, Vec<u8>)]) -> Vec<(u8, Vec<u8>)> {
    let mut out = Vec::new();
    for (_, burst) in bursts {
        let mut i = 0;
        while i + 2 < burst.len() {
            let len = usize::from(burst[i + 1]);
            if !matches!(burst[i], 0xC8 | 0xEA) || len < 2 || i + 2 + len > burst.len() {
                i += 1;
                continue;
            }
            let body = &burst[i + 2..i + 1 + len];
            if crc8(body) == burst[i + 1 + len] {
                out.push((body[0], body[1..].to_vec()));
                i += 2 + len;
            } else {
                i += 1;
            }
        }
    }
    out
}

struct Tool {
    world: World,
    /// Frames sent and answers waited for.
    requests: u32,
    retries: u32,
}

impl Tool {
    fn new() -> Self {
        // Bound with a key, as after a bind's key agreement (the world hands the flight
        // side the module's key for the link).
        let (quad, settings) = default_airframe();
        let key = LinkKey::from_bytes(*b"the module's key");
        let mut scenario = Scenario::new(
            settings,
            quad,
            f64::INFINITY,
            Box::new(|_| PilotInput::default()),
        );
        scenario.module_settings = Some(ModuleSettings {
            input: InputProtocol::Crsf,
            link_key: Some(key),
            ..ModuleSettings::default()
        });
        let mut world = World::new(scenario);
        world.run_for(Duration::from_secs(4));
        let _ = world.take_handset_tx();
        Self {
            world,
            requests: 0,
            retries: 0,
        }
    }

    /// Sends `kind`/`payload` until an answer `want` accepts arrives; returns it.
    fn ask(&mut self, kind: u8, payload: &[u8], want: impl Fn(u8, &[u8]) -> bool) -> Vec<u8> {
        self.requests += 1;
        for _attempt in 0..10 {
            self.world.radio_send(&push_frame(kind, payload));
            for _ in 0..TIMEOUT_MS / 4 {
                self.world.run_for(Duration::from_millis(4));
                let got = frames(&self.world.take_handset_tx());
                if let Some((_, answer)) = got.into_iter().find(|(k, p)| want(*k, p)) {
                    return answer;
                }
            }
            self.retries += 1;
        }
        panic!("no answer to {kind:#04x} {payload:02x?}");
    }

    /// The broadcast ping; the devices that answered (origin, name, parameter count).
    fn ping(&mut self) -> Vec<(u8, String, u8)> {
        self.world.radio_send(&push_frame(PING, &[0x00, 0xEA]));
        let mut devices = Vec::new();
        for _ in 0..250 {
            self.world.run_for(Duration::from_millis(4));
            for (kind, p) in frames(&self.world.take_handset_tx()) {
                if kind == DEVICE_INFO {
                    let end = p[2..].iter().position(|b| *b == 0).unwrap() + 2;
                    let name = String::from_utf8(p[2..end].to_vec()).unwrap();
                    // serial, hardware id, firmware id (4 each), count, protocol version.
                    let count = p[end + 13];
                    devices.push((p[1], name, count));
                }
            }
        }
        devices
    }

    /// Field `field` of the flight controller, chunk by chunk.
    fn read(&mut self, field: u8) -> Vec<u8> {
        let mut entry = Vec::new();
        let mut chunk = 0u8;
        loop {
            let answer = self.ask(READ, &[FC, HANDSET, field, chunk], |k, p| {
                k == ENTRY && p[..3] == [HANDSET, FC, field]
            });
            entry.extend_from_slice(&answer[4..]);
            if answer[3] == 0 {
                return entry;
            }
            chunk += 1;
        }
    }

    /// Writes `value` to `field`, then reads the field back as the script does.
    fn write(&mut self, field: u8, value: &[u8]) -> Vec<u8> {
        let mut payload = vec![FC, HANDSET, field];
        payload.extend_from_slice(value);
        self.world.radio_send(&push_frame(WRITE, &payload));
        self.world.run_for(Duration::from_millis(200));
        self.read(field)
    }
}

/// (parent, type, name, the bytes after the name).
fn split(entry: &[u8]) -> (u8, u8, String, Vec<u8>) {
    let end = entry[2..].iter().position(|b| *b == 0).unwrap() + 2;
    (
        entry[0],
        entry[1],
        String::from_utf8(entry[2..end].to_vec()).unwrap(),
        entry[end + 1..].to_vec(),
    )
}

fn field_of(name: &str, names: &[(u8, String)]) -> u8 {
    names.iter().find(|(_, n)| n == name).unwrap().0
}

#[test]
fn the_device_tool_walks_the_flight_controller_and_its_writes_are_the_flight_cores_values() {
    let mut tool = Tool::new();
    let devices = tool.ping();
    let names: Vec<&str> = devices.iter().map(|(_, n, _)| n.as_str()).collect();
    assert!(names.contains(&"TauLink FC"), "{devices:?}");
    assert!(
        names.contains(&"TauLink"),
        "the module answers too: {devices:?}"
    );
    let &(origin, _, count) = devices.iter().find(|(_, n, _)| n == "TauLink FC").unwrap();
    assert_eq!(origin, FC);
    assert!(usize::from(count) > PARAMS.len(), "{count}");

    // The whole tree, as the tool loads it on entering the device.
    let start = tool.world.scenario_s();
    let mut rows = Vec::new();
    let mut folders = Vec::new();
    let mut hidden = 0;
    for field in 1..=count {
        let (parent, kind, name, _) = split(&tool.read(field));
        if kind & 0x80 != 0 {
            hidden += 1;
            continue;
        }
        if kind == 11 {
            folders.push(name.clone());
        } else if name.contains('.') {
            assert_ne!(parent, 0, "setting {name} sits in a folder");
        }
        rows.push((field, name));
    }
    let walk_s = tool.world.scenario_s() - start;
    for folder in [
        "Rates",
        "Control",
        "Modes & Switches",
        "Failsafe",
        "Outputs",
        "Battery",
        "Link",
    ] {
        assert!(folders.iter().any(|f| f == folder), "{folder}: {folders:?}");
    }
    assert_eq!(hidden, 4, "no VTX on this board: its folder and rows hide");
    println!(
        "{count} rows in {walk_s:.1} s ({} requests, {} repeated after a timeout)",
        tool.requests, tool.retries
    );

    // Three types: a FLOAT (a PID gain in thousandths), a UINT16, a selection.
    let kp = field_of("pid.roll.kp", &rows);
    let (_, _, _, rest) = split(&tool.write(kp, &4_500i32.to_be_bytes()));
    assert_eq!(&rest[..4], &4_500i32.to_be_bytes(), "reads back 4.500e-3");
    let cells = field_of("battery.cells", &rows);
    let (_, _, _, rest) = split(&tool.write(cells, &3u16.to_be_bytes()));
    assert_eq!(&rest[..2], &3u16.to_be_bytes());
    let high = field_of("mode.switch_high", &rows);
    let (_, kind, _, _) = split(&tool.write(high, &[2]));
    assert_eq!(kind, 9);

    let live = tool.world.flight_settings();
    assert!((live.get(handles::PID_ROLL_KP) - 0.0045).abs() < 1e-7);
    assert_eq!(live.get(handles::BATTERY_CELLS), 3);
    assert_eq!(live.get(handles::MODE_SWITCH_HIGH), 2);
}
