//! Just enough HTTP/1.1 for the server: the request head read with `httparse` (peeked, so a
//! WebSocket upgrade can still be handed to tungstenite whole), static files from the built
//! app with a path check, and plain responses. One request per connection.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::Path;

/// Largest request head read.
const MAX_HEAD: usize = 8192;

/// What the server looks at in a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// The path, without the query.
    pub path: String,
    /// An `Upgrade: websocket` request.
    pub websocket: bool,
    /// Length of the head, bytes.
    pub head_len: usize,
}

/// Parses a complete request head.
pub fn parse_head(bytes: &[u8]) -> Option<Request> {
    let mut headers = [httparse::EMPTY_HEADER; 32];
    let mut req = httparse::Request::new(&mut headers);
    let httparse::Status::Complete(head_len) = req.parse(bytes).ok()? else {
        return None;
    };
    if req.method != Some("GET") {
        return None;
    }
    let path = req.path?.split('?').next()?.to_string();
    let websocket = req.headers.iter().any(|h| {
        h.name.eq_ignore_ascii_case("upgrade") && h.value.eq_ignore_ascii_case(b"websocket")
    });
    Some(Request {
        path,
        websocket,
        head_len,
    })
}

/// Peeks the request head off `stream` without consuming it.
pub fn peek_request(stream: &TcpStream) -> Option<Request> {
    let mut buf = vec![0u8; MAX_HEAD];
    for _ in 0..50 {
        let n = stream.peek(&mut buf).ok()?;
        if n == 0 {
            return None;
        }
        if let Some(r) = parse_head(buf.get(..n)?) {
            return Some(r);
        }
        if n == MAX_HEAD {
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    None
}

/// Reads the peeked head off `stream`: closing a socket with unread input resets the
/// connection, and the client may lose the response.
pub fn consume(mut stream: &TcpStream, request: &Request) {
    let mut head = vec![0u8; request.head_len];
    let _ = stream.read_exact(&mut head);
}

/// The file under `root` a request path names: only plain names (letters, digits, `-_.`)
/// between slashes, no `..`; `/` is `index.html`.
pub fn resolve(root: &Path, path: &str) -> Option<std::path::PathBuf> {
    let rel = path.strip_prefix('/')?;
    let rel = if rel.is_empty() { "index.html" } else { rel };
    let ok = rel.split('/').all(|part| {
        !part.is_empty()
            && !part.starts_with('.')
            && part
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
    });
    ok.then(|| root.join(rel))
}

fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript",
        Some("css") => "text/css",
        Some("wasm") => "application/wasm",
        Some("json" | "webmanifest") => "application/manifest+json",
        Some("svg") => "image/svg+xml",
        Some("png") => "image/png",
        _ => "application/octet-stream",
    }
}

/// Serves `path` from `root`, or 404.
pub fn serve_file(stream: &TcpStream, root: &Path, path: &str) {
    match resolve(root, path).and_then(|p| std::fs::read(&p).ok().map(|b| (p, b))) {
        Some((file, body)) => respond(stream, 200, content_type(&file), &body),
        None => respond(stream, 404, "text/plain", b"not found"),
    }
}

/// Writes a complete response and closes.
pub fn respond(mut stream: &TcpStream, status: u16, content_type: &str, body: &[u8]) {
    let reason = match status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        _ => "Service Unavailable",
    };
    let head = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\nCache-Control: no-cache\r\nConnection: close\r\n\r\n",
        body.len()
    );
    let _ = stream.write_all(head.as_bytes());
    let _ = stream.write_all(body);
    let _ = stream.flush();
    let _ = stream.shutdown(std::net::Shutdown::Write);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_heads_and_paths() {
        let r =
            parse_head(b"GET /ws?x=1 HTTP/1.1\r\nHost: a\r\nUpgrade: websocket\r\n\r\n").unwrap();
        assert_eq!((r.path.as_str(), r.websocket), ("/ws", true));
        assert!(
            parse_head(b"GET / HTTP/1.1\r\nHost: a\r\n").is_none(),
            "incomplete"
        );
        assert!(parse_head(b"POST / HTTP/1.1\r\n\r\n").is_none());
        let root = Path::new("/srv");
        assert_eq!(resolve(root, "/"), Some(root.join("index.html")));
        assert_eq!(
            resolve(root, "/assets/app-1.js"),
            Some(root.join("assets/app-1.js"))
        );
        for bad in [
            "/../etc/passwd",
            "/a/../b",
            "/.git/config",
            "//x",
            "/a b",
            "x",
        ] {
            assert_eq!(resolve(root, bad), None, "{bad}");
        }
    }
}
