//! Runs one image alone on its board for a while and prints where its core is: a debugging
//! aid for bringing an image up (`cargo run --release -p pil --example debug_boot -- flight
//! dist/flight-brushedsparky.elf 500`).

use flight_app::outputs::Protocol;
use pil::board::flight::{FlightBoard, FlightBoardKind};
use pil::board::module::ModuleBoard;
use pil::runner::Platform;
use pil::runner::emulated::EmulatedBoards;
use pil::runner::image::Image;
use pil::world::Radios;
use pil::world::machine::Machine;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(which), Some(path), Some(ms)) = (args.get(1), args.get(2), args.get(3)) else {
        eprintln!("usage: debug_boot flight|module IMAGE MS");
        return;
    };
    let Ok(image) = Image::load(std::path::Path::new(path)) else {
        eprintln!("cannot load {path}");
        return;
    };
    let ms: u64 = ms.parse().unwrap_or(100);
    let mut radios = Radios::new(1, 0.0);
    if which == "flight" {
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
        let Ok(mut m) =
            EmulatedBoards.flight(&image, board, &(0x0800_8000, vec![0xFF; 4]), None, 1)
        else {
            return;
        };
        for step in 0..ms {
            let _ = m.run_until((step + 1) * 1_000_000);
            if step % 50 == 0 || step + 1 == ms {
                let pc = m.cpu().read_reg(m4_sim::Reg::R(15));
                println!(
                    "{} ms: pc 0x{pc:08x} polled {:?} {:?} unmodelled {} violations {}",
                    step + 1,
                    m.tasks_polled(),
                    m.stats(),
                    m.soc().unmodelled().len(),
                    m.soc().violations().len()
                );
            }
        }
        let msp = m.cpu().read_reg(m4_sim::Reg::Msp);
        let ram = m.soc().sram_contents();
        let word = |a: u32| {
            let o = a.wrapping_sub(0x2000_0000) as usize;
            ram.get(o..o + 4)
                .and_then(|b| b.try_into().ok())
                .map(u32::from_le_bytes)
        };
        println!(
            "msp 0x{msp:08x}: {:x?}",
            (0..12).map(|k| word(msp + 4 * k)).collect::<Vec<_>>()
        );
        let code: Vec<String> = (0..400u32)
            .filter_map(|k| word(msp + 4 * k))
            .filter(|w| (0x0801_0000..0x0806_0000).contains(w) && w & 1 == 1)
            .map(|w| format!("{w:08x}"))
            .collect();
        println!("code addresses on the stack: {}", code.join(" "));
        for u in m.soc().unmodelled().iter().take(20) {
            println!("unmodelled: {u:?}");
        }
        for v in m.soc().violations().iter().take(20) {
            println!("violation: {v:?}");
        }
    } else {
        let Some(radio) = radios.module.take() else {
            return;
        };
        let Some(board) = pil::world::module_board(&mut Radios::new(2, 0.0)) else {
            return;
        };
        let _ = radio;
        let Ok(mut m) = EmulatedBoards.module(&image, board, &(0xEC000, vec![0xFF; 4]), 1) else {
            return;
        };
        for step in 0..ms {
            let _ = m.run_until((step + 1) * 1_000_000);
            if step % 50 == 0 || step + 1 == ms {
                let pc = m.cpu().read_reg(m4_sim::Reg::R(15));
                println!(
                    "{} ms: pc 0x{pc:08x} polled {:?} {:?}",
                    step + 1,
                    m.tasks_polled(),
                    m.stats()
                );
            }
        }
        for u in m.soc().unmodelled().iter().take(20) {
            println!("unmodelled: {u:?}");
        }
        let _: Option<&ModuleBoard> = None;
    }
}
