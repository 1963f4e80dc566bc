//! The runner's flow with scripted MCUs: images read and hashed, flight-sitl's plans, both
//! ends' settings flashed, the report's keys and criteria.

use super::*;
use crate::world::machine::FakeMachine;

/// A minimal firmware ELF: one loadable segment at 0x0800_0000 holding a vector table.
fn tiny_elf() -> Vec<u8> {
    let data: Vec<u8> = [0x2002_0000u32, 0x0800_0009]
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .collect();
    let mut e = vec![0u8; 84];
    e[..7].copy_from_slice(&[0x7F, b'E', b'L', b'F', 1, 1, 1]);
    e[16..18].copy_from_slice(&2u16.to_le_bytes()); // executable
    e[18..20].copy_from_slice(&40u16.to_le_bytes()); // ARM
    e[20..24].copy_from_slice(&1u32.to_le_bytes());
    e[24..28].copy_from_slice(&0x0800_0009u32.to_le_bytes());
    e[28..32].copy_from_slice(&52u32.to_le_bytes()); // program headers
    e[40..42].copy_from_slice(&52u16.to_le_bytes());
    e[42..44].copy_from_slice(&32u16.to_le_bytes());
    e[44..46].copy_from_slice(&1u16.to_le_bytes());
    e[46..48].copy_from_slice(&40u16.to_le_bytes());
    let ph = [1u32, 84, 0x0800_0000, 0x0800_0000, 8, 8, 5, 4];
    for (i, w) in ph.iter().enumerate() {
        e[52 + 4 * i..56 + 4 * i].copy_from_slice(&w.to_le_bytes());
    }
    e.extend(data);
    e
}

/// Scripted MCUs: the flight side keeps the settings it was flashed with.
struct Fakes {
    flashed: std::cell::RefCell<Vec<(u32, usize)>>,
}

impl Platform for Fakes {
    type Flight = FakeMachine<FlightBoard>;
    type Module = FakeMachine<ModuleBoard>;

    fn flight(
        &self,
        image: &Image,
        board: FlightBoard,
        settings: &(u32, Vec<u8>),
        _lsi: Option<f64>,
        _seed: u64,
    ) -> Result<Self::Flight, String> {
        assert_eq!(image.stack_top, 0x2002_0000);
        self.flashed
            .borrow_mut()
            .push((settings.0, settings.1.len()));
        Ok(FakeMachine::new(board, |_, _, _| {}))
    }

    fn module(
        &self,
        _image: &Image,
        board: ModuleBoard,
        settings: &(u32, Vec<u8>),
        _seed: u64,
    ) -> Result<Self::Module, String> {
        self.flashed
            .borrow_mut()
            .push((settings.0, settings.1.len()));
        Ok(FakeMachine::new(board, |_, _, _| {}))
    }
}

fn options(kind: Kind) -> (Options, tempdir::Dir) {
    let dir = tempdir::Dir::new();
    let path = dir.path.join("image.elf");
    std::fs::write(&path, tiny_elf()).unwrap();
    let mut o = Options::new(kind);
    o.flight_image = path.clone();
    o.module_image = path;
    o.quantum_ns = 100_000;
    (o, dir)
}

/// A scratch folder removed at the end.
mod tempdir {
    pub struct Dir {
        pub path: std::path::PathBuf,
    }

    impl Dir {
        pub fn new() -> Self {
            let path = std::env::temp_dir().join(format!(
                "pil-runner-{}-{:?}",
                std::process::id(),
                std::thread::current().id()
            ));
            std::fs::create_dir_all(&path).unwrap();
            Self { path }
        }
    }

    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

#[test]
fn boot_with_silent_mcus_fails_its_criteria_and_names_them() {
    let (opts, _dir) = options(Kind::Boot);
    let fakes = Fakes {
        flashed: std::cell::RefCell::new(Vec::new()),
    };
    let out = run(&fakes, &opts).unwrap();
    // Both settings areas were programmed: flight sectors 2–3, the module's pages.
    assert_eq!(
        *fakes.flashed.borrow(),
        vec![(0x0800_8000, 0x8000), (0xEC000, 0x8000)]
    );
    assert_eq!(out.plan.duration_s, BOOT_S);
    assert!(
        out.failed.contains(
            &"every flight task spawned and polled (none first polled in the last second)"
                .to_owned()
        ),
        "{:?}",
        out.failed
    );
    assert!(
        out.failed
            .contains(&"telemetry reaches the phone (link up)".to_owned())
    );
    let json = out.to_json();
    assert!(
        json.starts_with("{\"scenario\":\"boot\",\"rate\":\"F250\",\"seed\":7,"),
        "{json}"
    );
    let sha = image::sha256_hex(&tiny_elf());
    assert!(json.contains(&format!("\"image_sha256\":\"{sha}\"")));
    for key in [
        "\"watchdog_resets\":{\"flight\":0,\"module\":0}",
        "\"instructions\":",
        "\"boot_ms\":null",
        "\"tasks_polled\":0,\"tasks_in_image\":0,",
        "\"max_stack_bytes\":",
        "\"cpu_load_pct\":",
        "\"loop_jitter_p99_us\":",
        "\"imu_samples_missed\":0",
        "\"final_state\":\"disarmed-on-ground\"",
        "\"criteria_failed\":[",
    ] {
        assert!(json.contains(key), "{key} in {json}");
    }
    assert!(out.to_text().contains("criteria failed: "));
}

#[test]
fn flight_sitl_scenarios_keep_their_plans_and_hover_flies_30_s() {
    let (opts, _dir) = options(Kind::LinkCut);
    let p = plan(&opts).unwrap();
    let sitl = flight_sitl::runner::Options::factory();
    let reach = flight_sitl::runner::reach_times(&sitl, &[30.0]).unwrap()[0];
    assert_eq!(
        p,
        flight_sitl::runner::plan(SitlKind::LinkCut, &sitl, reach).unwrap()
    );
    let (opts, _dir) = options(Kind::Hover);
    let p = plan(&opts).unwrap();
    assert_eq!(p.duration_s, HOVER_S);
    assert_eq!(p.kind, SitlKind::Hover);
    let (opts, _dir) = options(Kind::Panic);
    let p = plan(&opts).unwrap();
    assert_eq!(
        p.kind,
        SitlKind::Panic,
        "flight-sitl's panic timeline and figures"
    );
    assert!(
        p.fault_at_s
            .is_some_and(|a| a > p.hold_from_s.unwrap_or(0.0))
    );
}

#[test]
fn a_missing_image_is_a_clear_error() {
    let (mut opts, _dir) = options(Kind::Boot);
    opts.flight_image = "/nonexistent/flight.elf".into();
    let fakes = Fakes {
        flashed: std::cell::RefCell::new(Vec::new()),
    };
    let err = run(&fakes, &opts).err().unwrap();
    assert!(err.to_string().contains("/nonexistent/flight.elf"), "{err}");
}
