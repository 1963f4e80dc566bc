//! Instructions of the bind's key agreement and the phrase's derivation on the Cortex-M4
//! (spec §12.1): CPace over ristretto255 — one party's start (the generator from the
//! phrase's derivation and its share) and finish (the peer's share decoded, the shared
//! point, the session key) — and PBKDF2-HMAC-SHA-512 iterations of the phrase's derivation.
//! m4count regions: 1 = CPace start, 3 = CPace finish, 5 = 16 derivation iterations.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use m4_bench::{exit, m4count_marker};
    use telemetry::link::pake::{Exchange, Role};
    use telemetry::link::phrase::Derivation;

    let prs: [u8; 32] = black_box(core::array::from_fn(|i| (i * 7) as u8));
    let sid: [u8; 12] = black_box([5; 12]);
    let peer = Exchange::start(&prs, b"TauLink/2 bind", &sid, &black_box([9; 32])).share();

    m4count_marker();
    let own = black_box(Exchange::start(
        &prs,
        b"TauLink/2 bind",
        &sid,
        &black_box([3; 32]),
    ));
    m4count_marker();
    m4count_marker();
    let isk = black_box(own.finish(Role::Initiator, &peer, b"", b"", &sid));
    m4count_marker();
    let mut derivation = Derivation::new(black_box("amber kettle under the oak"), [1; 8]);
    m4count_marker();
    let step = black_box(derivation.step(16));
    m4count_marker();
    if isk.is_none() || step.is_some() {
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    }
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
