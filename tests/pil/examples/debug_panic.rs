//! Runs the flight image alone until it panics and prints the frame-pointer chain at the
//! panic's entry (`rust_begin_unwind`): a debugging aid (`cargo run --release -p pil
//! --example debug_panic -- IMAGE MS`).

use flight_app::outputs::Protocol;
use m4_sim::{Bus, Cpu, Reg, Stop, Width};
use pil::board::flight::{FlightBoard, FlightBoardKind};
use pil::runner::image::Image;
use pil::stm32f405::{Config, Stm32f405};
use pil::world::Radios;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(path), Some(ms)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: debug_panic IMAGE MS");
        return;
    };
    let Ok(image) = Image::load(std::path::Path::new(path)) else {
        return;
    };
    let ms: u64 = ms.parse().unwrap_or(100);
    let Ok(symbols) = fw_elf::symbols(&image.bytes) else {
        return;
    };
    let Some(unwind) = symbols
        .iter()
        .find(|s| s.name.contains("rust_begin_unwind"))
    else {
        eprintln!("no rust_begin_unwind");
        return;
    };
    let mut radios = Radios::new(1, 0.0);
    let Some(radio) = radios.flight.take() else {
        return;
    };
    let board = FlightBoard::new(
        FlightBoardKind::BrushedSparky,
        radio,
        Protocol::Brushed {
            frequency_hz: 32_000,
        },
        0,
        (0.0, 0.0),
    );
    let mut soc = Stm32f405::new(board, Config::default());
    if soc.load_elf(&image.bytes).is_err() {
        return;
    }
    let mut cpu = Cpu::new(pil::runner::emulated::stm32f405_core());
    cpu.reset(&mut soc);
    cpu.add_pc_hook(unwind.address & !1);
    let name = |a: u32| {
        symbols
            .iter()
            .filter(|s| s.address & !1 <= a && s.size > 0 && a < (s.address & !1) + s.size)
            .map(|s| s.name.clone())
            .next()
            .unwrap_or_default()
    };
    let trace_from: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(u64::MAX);
    let mut stop = Stop::Deadline;
    let mut trace: std::collections::VecDeque<String> = std::collections::VecDeque::new();
    while stop == Stop::Deadline && cpu.now_ns() < ms * 1_000_000 {
        let step = if cpu.now_ns() >= trace_from {
            cpu.now_ns() + 50
        } else {
            trace_from.min(ms * 1_000_000)
        };
        stop = cpu.run_until(&mut soc, step);
        if cpu.now_ns() >= trace_from {
            let pc = cpu.read_reg(Reg::R(15));
            let line = format!(
                "{:>10} pc {pc:08x} ipsr {:3} sp {:08x} lr {:08x} {}",
                cpu.now_ns(),
                cpu.read_reg(Reg::Xpsr) & 0x1FF,
                cpu.read_reg(Reg::R(13)),
                cpu.read_reg(Reg::R(14)),
                name(pc).chars().take(90).collect::<String>()
            );
            if trace.back() != Some(&line) {
                trace.push_back(line);
            }
            if trace.len() > 120 {
                trace.pop_front();
            }
        }
    }
    for l in &trace {
        println!("{l}");
    }
    println!("stop {stop:?} at {} ns", cpu.now_ns());
    if let Stop::Hook { .. } = stop {
        let mut fp = cpu.read_reg(Reg::R(7));
        println!(
            "lr 0x{:08x} {}",
            cpu.read_reg(Reg::R(14)),
            name(cpu.read_reg(Reg::R(14)) & !1)
        );
        for _ in 0..30 {
            let (Ok(prev), Ok(lr)) = (
                soc.read(fp, Width::Word, 0),
                soc.read(fp + 4, Width::Word, 0),
            ) else {
                break;
            };
            println!("  0x{lr:08x} {}", name(lr & !1));
            if prev <= fp {
                break;
            }
            fp = prev;
        }
        println!("ipsr {}", cpu.read_reg(Reg::Xpsr) & 0x1FF);
    }
}
