//! `flight-sitl serve [ADDR]` (and `taulink-sim --serve [ADDR]`, which calls [`main`]):
//! serves the web ground station (the built app, static files) and, on `/ws`, a WebSocket
//! per page with its own firmware-in-the-loop world ([`session`]) running in (scaled) real
//! time: binary messages to the page carry what the module's HM-10 sends to a phone, binary
//! messages from the page go into the HM-10's input, as the module firmware's HM-10 task
//! moves them. `/api/sent` tells what the latest world sent the page and which setting
//! changes its flight application took (for tests). Binds 127.0.0.1:8018 by default;
//! connections, request heads, pipes and worlds are bounded.

pub mod cli;
mod http;
pub mod pilot;
pub mod session;

pub use session::{Sent, Session, WorldOptions};

use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tungstenite::{Message as WsMessage, WebSocket};

/// Default address: loopback only.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8018";
/// Connections served at once (each a thread).
const MAX_CONNECTIONS: usize = 16;
/// Simulated worlds at once (each a WebSocket).
const MAX_WORLDS: usize = 4;
/// Wall-clock step of a world.
const TICK: Duration = Duration::from_millis(20);
/// Largest WebSocket message accepted from a page.
const MAX_WS_MESSAGE: usize = 4096;
/// Virtual seconds per wall second accepted.
pub const SPEEDS: core::ops::RangeInclusive<f64> = 0.01..=100.0;

/// What the server needs.
#[derive(Debug, Clone)]
pub struct Options {
    /// Address to bind.
    pub addr: SocketAddr,
    /// The built app (`telemetry/ground-station/dist`).
    pub dist: PathBuf,
    /// Virtual seconds per wall second.
    pub speed: f64,
    /// What each page's world is made of.
    pub world: WorldOptions,
}

/// The built ground station in this checkout.
pub fn default_dist() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../telemetry/ground-station/dist"
    ))
}

/// Shared between connections.
struct Shared {
    options: Options,
    connections: AtomicUsize,
    worlds: AtomicUsize,
    sent: Mutex<String>,
}

/// Runs the server until the process ends; returns the exit code on a startup error.
pub fn main(options: Options) -> i32 {
    if !options.dist.join("index.html").is_file() {
        eprintln!(
            "no built app in {} (build it with: cargo xtask web)",
            options.dist.display()
        );
        return 2;
    }
    let listener = match TcpListener::bind(options.addr) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("cannot bind {}: {e}", options.addr);
            return 1;
        }
    };
    let addr = listener.local_addr().unwrap_or(options.addr);
    // `?sim`: the page connects to this server's world by itself.
    println!("TauLink ground station: open http://{addr}/?sim");
    println!(
        "binding phrase of both simulated ends (the settings view asks for it): {}",
        session::SERVE_PHRASE
    );
    let shared = Arc::new(Shared {
        options,
        connections: AtomicUsize::new(0),
        worlds: AtomicUsize::new(0),
        sent: Mutex::new("{}".into()),
    });
    for stream in listener.incoming().flatten() {
        if shared.connections.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
            shared.connections.fetch_sub(1, Ordering::SeqCst);
            http::respond(&stream, 503, "text/plain", b"busy");
            continue;
        }
        let shared = shared.clone();
        std::thread::spawn(move || {
            connection(&shared, stream);
            shared.connections.fetch_sub(1, Ordering::SeqCst);
        });
    }
    0
}

fn connection(shared: &Shared, stream: TcpStream) {
    let _ = stream.set_read_timeout(Some(Duration::from_secs(10)));
    let Some(request) = http::peek_request(&stream) else {
        http::respond(&stream, 400, "text/plain", b"bad request");
        return;
    };
    if !request.websocket {
        http::consume(&stream, &request);
    }
    match (request.path.as_str(), request.websocket) {
        ("/ws", true) => {
            if shared.worlds.fetch_add(1, Ordering::SeqCst) >= MAX_WORLDS {
                shared.worlds.fetch_sub(1, Ordering::SeqCst);
                http::respond(&stream, 503, "text/plain", b"too many simulations");
                return;
            }
            if let Ok(ws) = tungstenite::accept(stream) {
                world(shared, ws);
            }
            shared.worlds.fetch_sub(1, Ordering::SeqCst);
        }
        ("/api/sent", false) => {
            let body = shared.sent.lock().map(|s| s.clone()).unwrap_or_default();
            http::respond(&stream, 200, "application/json", body.as_bytes());
        }
        (path, false) => http::serve_file(&stream, &shared.options.dist, path),
        _ => http::respond(&stream, 400, "text/plain", b"bad request"),
    }
}

/// Runs one world in real time (× speed) against one page.
fn world(shared: &Shared, mut ws: WebSocket<TcpStream>) {
    let mut session = Session::new(&shared.options.world);
    let _ = ws
        .get_ref()
        .set_read_timeout(Some(Duration::from_millis(2)));
    let start = Instant::now();
    loop {
        loop {
            match ws.read() {
                Ok(WsMessage::Binary(bytes)) if bytes.len() <= MAX_WS_MESSAGE => {
                    session.from_page(&bytes);
                }
                Ok(WsMessage::Close(_)) => return,
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    break;
                }
                Err(_) => return,
            }
        }
        let target = start.elapsed().mul_f64(shared.options.speed);
        session.run_until(target);
        let bytes = session.take_to_page();
        if !bytes.is_empty() && ws.send(WsMessage::Binary(bytes.into())).is_err() {
            return;
        }
        if let Ok(mut sent) = shared.sent.lock() {
            *sent = session.sent.to_json();
        }
        std::thread::sleep(TICK);
    }
}
