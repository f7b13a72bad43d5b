//! What every request to `flatray serve` passes before a route sees it.
//!
//! A server on loopback is reachable from every page the user's browser
//! opens, so a request is not trusted for coming from this machine:
//!
//! - its `Host` must name this server (`localhost` or an address written
//!   as numbers, with the port it listens on): a page of another site that
//!   had its name point at 127.0.0.1 (DNS rebinding) sends its own name;
//! - a request that changes something (every `POST`) must come from the
//!   page itself: its `Origin`, when sent, is the server's own, its
//!   `Sec-Fetch-Site`, when sent, is `same-origin`, its body is declared
//!   `application/json` (a form or a `text/plain` post from another site
//!   cannot declare that without the browser asking first, and the server
//!   never says yes), and it carries the token the page was served with,
//!   which no other site can read;
//! - a body is at most [`MAX_BODY`] bytes, refused at once when its
//!   declared length is larger, and must arrive within [`BODY_TIMEOUT`].
//!
//! The headers themselves must arrive within [`HEADER_TIMEOUT`]; that one
//! is enforced where connections are served ([`run`]).

use std::net::IpAddr;
use std::sync::Arc;
use std::time::Duration;

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{HeaderMap, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

/// The largest request body: an edit is a few dozen bytes.
pub(crate) const MAX_BODY: usize = 16 * 1024;

/// How long a request's headers may take to arrive.
pub(crate) const HEADER_TIMEOUT: Duration = Duration::from_secs(5);

/// How long a request's body may take to arrive once its headers have.
pub(crate) const BODY_TIMEOUT: Duration = Duration::from_secs(5);

/// The header that carries the page's token.
pub(crate) const TOKEN_HEADER: &str = "x-flatray-token";

/// What the checks need to know of the server.
pub(crate) struct Guard {
    /// The port the server listens on, which every `Host` must name.
    port: u16,
    /// The token the page carries, made afresh at each start.
    token: String,
}

impl Guard {
    /// A guard for a server on `port`, with a new random token.
    pub(crate) fn new(port: u16) -> Result<Guard, String> {
        let mut bytes = [0u8; 16];
        getrandom::fill(&mut bytes)
            .map_err(|e| format!("cannot make the page's token (no random numbers): {e}"))?;
        let token = bytes.iter().map(|b| format!("{b:02x}")).collect();
        Ok(Guard { port, token })
    }

    pub(crate) fn token(&self) -> &str {
        &self.token
    }

    /// Whether `host` (a `Host` header, or an `Origin` without its scheme)
    /// names this server: `localhost` or a numeric address, with the port.
    fn names_this_server(&self, host: &str) -> bool {
        let (name, port) = split_port(host);
        let port_ok = match port {
            Some(p) => p.parse::<u16>().ok() == Some(self.port),
            None => self.port == 80,
        };
        let name_ok = name.eq_ignore_ascii_case("localhost")
            || name.parse::<IpAddr>().is_ok()
            || name
                .strip_prefix('[')
                .and_then(|n| n.strip_suffix(']'))
                .is_some_and(|n| n.parse::<std::net::Ipv6Addr>().is_ok());
        port_ok && name_ok
    }

    /// Why a request is refused before it is read, or `None`.
    fn refusal(&self, method: &Method, headers: &HeaderMap) -> Option<(StatusCode, String)> {
        let host = headers
            .get(header::HOST)
            .and_then(|h| h.to_str().ok())
            .unwrap_or("");
        if !self.names_this_server(host) {
            return Some((
                StatusCode::FORBIDDEN,
                format!(
                    "this server answers only to localhost or its address, with port {}, not to the host {host:?}",
                    self.port
                ),
            ));
        }
        if let Some(length) = declared_length(headers)
            && length > MAX_BODY as u64
        {
            return Some((
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("a request body is at most {MAX_BODY} bytes; this one declares {length}"),
            ));
        }
        if method == Method::GET || method == Method::HEAD {
            return None;
        }
        if let Some(origin) = headers.get(header::ORIGIN) {
            let origin = origin.to_str().unwrap_or("");
            let same = origin
                .strip_prefix("http://")
                .is_some_and(|o| o.eq_ignore_ascii_case(host));
            if !same {
                return Some((
                    StatusCode::FORBIDDEN,
                    format!(
                        "a change is taken only from the page this server serves, not from {origin:?}"
                    ),
                ));
            }
        }
        if let Some(site) = headers.get("sec-fetch-site") {
            let site = site.to_str().unwrap_or("");
            if site != "same-origin" && site != "none" {
                return Some((
                    StatusCode::FORBIDDEN,
                    format!(
                        "a change is taken only from the page this server serves (the browser says {site:?})"
                    ),
                ));
            }
        }
        let json = headers
            .get(header::CONTENT_TYPE)
            .and_then(|c| c.to_str().ok())
            .and_then(|c| c.split(';').next())
            .is_some_and(|c| c.trim().eq_ignore_ascii_case("application/json"));
        if !json {
            return Some((
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "a change is sent as Content-Type: application/json".to_string(),
            ));
        }
        let token = headers.get(TOKEN_HEADER).and_then(|t| t.to_str().ok());
        if !token.is_some_and(|t| constant_time_eq(t.as_bytes(), self.token.as_bytes())) {
            return Some((
                StatusCode::FORBIDDEN,
                format!(
                    "a change needs the page's token (the {TOKEN_HEADER} header): reload the page"
                ),
            ));
        }
        None
    }
}

/// `name:port` -> (`name`, `Some(port)`); `[::1]:port` likewise.
fn split_port(host: &str) -> (&str, Option<&str>) {
    if host.starts_with('[') {
        return match host.find("]:") {
            Some(end) => (&host[..=end], Some(&host[end + 2..])),
            None => (host, None),
        };
    }
    match host.rsplit_once(':') {
        Some((name, port)) if !name.contains(':') => (name, Some(port)),
        _ => (host, None),
    }
}

fn declared_length(headers: &HeaderMap) -> Option<u64> {
    headers
        .get(header::CONTENT_LENGTH)
        .and_then(|l| l.to_str().ok())
        .and_then(|l| l.trim().parse().ok())
}

/// Compares two tokens in a time that does not depend on where they
/// first differ.
fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

fn refused(status: StatusCode, message: String) -> Response {
    let mut response = (
        status,
        axum::Json(serde_json::json!({ "message": message })),
    )
        .into_response();
    // The body that was not read cannot be skipped reliably: end the
    // connection after this answer.
    response.headers_mut().insert(
        header::CONNECTION,
        header::HeaderValue::from_static("close"),
    );
    response
}

/// The checks, as a middleware: a refused request never reaches a route,
/// and a route sees a body that has arrived whole within its limits.
pub(crate) async fn check(
    State(guard): State<Arc<Guard>>,
    request: Request,
    next: Next,
) -> Response {
    if let Some((status, message)) = guard.refusal(request.method(), request.headers()) {
        return refused(status, message);
    }
    let (parts, body) = request.into_parts();
    let bytes = match tokio::time::timeout(BODY_TIMEOUT, axum::body::to_bytes(body, MAX_BODY)).await
    {
        Ok(Ok(bytes)) => bytes,
        Ok(Err(_)) => {
            return refused(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("a request body is at most {MAX_BODY} bytes"),
            );
        }
        Err(_) => {
            return refused(
                StatusCode::REQUEST_TIMEOUT,
                format!(
                    "the request's body did not arrive within {} s",
                    BODY_TIMEOUT.as_secs()
                ),
            );
        }
    };
    next.run(Request::from_parts(parts, Body::from(bytes)))
        .await
}

/// Serves `app` on `listener` until the process ends: each connection on
/// a task of its own, its request headers given [`HEADER_TIMEOUT`] to
/// arrive (a client that stalls is disconnected, never waited on).
pub(crate) async fn run(listener: tokio::net::TcpListener, app: axum::Router) {
    use hyper_util::rt::{TokioIo, TokioTimer};
    use hyper_util::service::TowerToHyperService;
    loop {
        let stream = match listener.accept().await {
            Ok((stream, _)) => stream,
            // Out of file descriptors, or a connection reset before it was
            // taken: wait a moment and go on.
            Err(_) => {
                tokio::time::sleep(Duration::from_millis(20)).await;
                continue;
            }
        };
        let service = TowerToHyperService::new(app.clone());
        tokio::spawn(async move {
            let mut builder = hyper::server::conn::http1::Builder::new();
            builder
                .timer(TokioTimer::new())
                .header_read_timeout(HEADER_TIMEOUT);
            let _ = builder
                .serve_connection(TokioIo::new(stream), service)
                .await;
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headers(pairs: &[(&str, &str)]) -> HeaderMap {
        let mut map = HeaderMap::new();
        for (k, v) in pairs {
            map.insert(
                header::HeaderName::from_bytes(k.as_bytes()).unwrap(),
                v.parse().unwrap(),
            );
        }
        map
    }

    #[test]
    fn hosts_that_name_this_server() {
        let guard = Guard::new(8421).unwrap();
        for ok in [
            "127.0.0.1:8421",
            "localhost:8421",
            "LOCALHOST:8421",
            "[::1]:8421",
            "192.168.1.5:8421",
        ] {
            assert!(guard.names_this_server(ok), "{ok}");
        }
        for bad in [
            "attacker.example:8421",
            "127.0.0.1:80",
            "127.0.0.1",
            "localhost",
            "localhost.attacker.example:8421",
            "127.0.0.1.nip.io:8421",
            "",
            "[::1]",
            ":8421",
        ] {
            assert!(!guard.names_this_server(bad), "{bad}");
        }
    }

    #[test]
    fn a_change_needs_the_same_origin_json_and_the_token() {
        let guard = Guard::new(8421).unwrap();
        let token = guard.token().to_string();
        let good = [
            ("host", "127.0.0.1:8421"),
            ("origin", "http://127.0.0.1:8421"),
            ("content-type", "application/json"),
            ("x-flatray-token", token.as_str()),
        ];
        assert_eq!(guard.refusal(&Method::POST, &headers(&good)), None);
        let without = |name: &str| {
            let mut map = headers(&good);
            map.remove(name);
            map
        };
        let with = |name: &'static str, value: &str| {
            let mut map = headers(&good);
            map.insert(name, value.parse().unwrap());
            map
        };
        // No Origin is what a program other than a browser sends.
        assert_eq!(guard.refusal(&Method::POST, &without("origin")), None);
        for (case, h) in [
            ("no token", without("x-flatray-token")),
            ("a wrong token", with("x-flatray-token", "0123")),
            ("text/plain", with("content-type", "text/plain")),
            (
                "a form",
                with("content-type", "application/x-www-form-urlencoded"),
            ),
            ("no type", without("content-type")),
            (
                "a foreign origin",
                with("origin", "http://attacker.example"),
            ),
            ("origin null", with("origin", "null")),
            ("another port", with("origin", "http://127.0.0.1:8000")),
            ("cross-site", with("sec-fetch-site", "cross-site")),
            ("a foreign host", with("host", "attacker.example:8421")),
        ] {
            assert!(guard.refusal(&Method::POST, &h).is_some(), "{case}");
        }
        // Reading needs the right host only.
        assert_eq!(
            guard.refusal(&Method::GET, &headers(&[("host", "localhost:8421")])),
            None
        );
        assert!(
            guard
                .refusal(&Method::GET, &headers(&[("host", "attacker.example:8421")]))
                .is_some()
        );
    }

    #[test]
    fn tokens_differ_and_compare_whole() {
        let (a, b) = (Guard::new(1).unwrap(), Guard::new(1).unwrap());
        assert_eq!(a.token().len(), 32);
        assert_ne!(a.token(), b.token());
        assert!(constant_time_eq(b"abc", b"abc"));
        assert!(!constant_time_eq(b"abc", b"abd"));
        assert!(!constant_time_eq(b"abc", b"abcd"));
    }
}
