//! `flatray serve`, the real binary on a real port, asked over HTTP as a
//! page asks it: edits, undo, save, the watch of the file on disk, two
//! pages at once, and nothing served but the page and the one scene; and
//! as another site's page, a stalled client or a strange file would ask
//! it: foreign hosts and origins, missing tokens, large and slow bodies,
//! a pipe or a link at the scene's path, a file changed behind the page.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;

const ROOM: &str = "// A test room: a lamp, a wall.
Scene(
    canvas: (120, 90),
    floor: Color((0.5, 0.5, 0.5)),
    walls: [
        Wall(a: (60, 10), b: (60, 80)), // the partition
    ],
    lights: [
        Point(at: (30, 45), intensity: 20), // the lamp
    ],
    render: (samples: 4),
)
";

/// A running `flatray serve` on a free port, stopped when dropped.
struct Server {
    _serving: common::Serving,
    url: String,
    token: String,
    dir: PathBuf,
    scene: PathBuf,
}

impl Server {
    fn start(name: &str, text: &str) -> Server {
        let dir = std::env::temp_dir().join(format!("flatray-serve-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("room.ron");
        std::fs::write(&scene, text).unwrap();
        let serving = common::serve(&scene);
        let url = serving.url.clone();
        let token = serving.token.clone();
        Server {
            _serving: serving,
            url,
            token,
            dir,
            scene,
        }
    }

    fn get(&self, path: &str) -> (u16, Vec<u8>) {
        match ureq::get(&format!("{}{path}", self.url)).call() {
            Ok(mut r) => (r.status().as_u16(), r.body_mut().read_to_vec().unwrap()),
            Err(ureq::Error::StatusCode(code)) => (code, Vec::new()),
            Err(e) => panic!("{path}: {e}"),
        }
    }

    fn json(&self, path: &str) -> serde_json::Value {
        let (code, body) = self.get(path);
        assert_eq!(code, 200, "{path}");
        serde_json::from_slice(&body).unwrap()
    }

    fn post(&self, path: &str, body: &str) -> (u16, serde_json::Value) {
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .build()
            .into();
        let mut r = agent
            .post(&format!("{}{path}", self.url))
            .content_type("application/json")
            .header("x-flatray-token", &self.token)
            .send(body)
            .unwrap();
        let code = r.status().as_u16();
        let text = r.body_mut().read_to_string().unwrap_or_default();
        (code, serde_json::from_str(&text).unwrap_or_default())
    }

    /// Waits until `/api/items` satisfies `ok`, for at most 20 s.
    fn wait_for(&self, what: &str, ok: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        let started = Instant::now();
        loop {
            let items = self.json("/api/items");
            if ok(&items) {
                return items;
            }
            assert!(
                started.elapsed() < Duration::from_secs(20),
                "{what}: {items}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// The events of one page, read on a thread of their own.
fn events(url: &str) -> std::sync::mpsc::Receiver<serde_json::Value> {
    let (tx, rx) = std::sync::mpsc::channel();
    let url = format!("{url}/api/events");
    std::thread::spawn(move || {
        let Ok(response) = ureq::get(&url).call() else {
            return;
        };
        let reader = BufReader::new(response.into_body().into_reader());
        for line in reader.lines() {
            let Ok(line) = line else { return };
            if let Some(data) = line.strip_prefix("data: ")
                && let Ok(value) = serde_json::from_str(data)
                && tx.send(value).is_err()
            {
                return;
            }
        }
    });
    rx
}

/// The first event that satisfies `ok`, within 30 s.
fn event_where(
    rx: &std::sync::mpsc::Receiver<serde_json::Value>,
    ok: impl Fn(&serde_json::Value) -> bool,
) -> serde_json::Value {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let event = rx.recv_timeout(left).expect("no such event within 30 s");
        if ok(&event) {
            return event;
        }
    }
}

#[test]
fn the_page_and_the_scene_are_served_and_nothing_else() {
    let server = Server::start("only", ROOM);
    let (code, page) = server.get("/");
    assert_eq!(code, 200);
    assert!(String::from_utf8_lossy(&page).contains("EventSource(\"/api/events\")"));
    let items = server.json("/api/items");
    assert_eq!(items["canvas"], serde_json::json!([120, 90]));
    assert_eq!(items["lights"][0]["at"], serde_json::json!([30.0, 45.0]));
    let (code, scene) = server.get("/api/scene.ron");
    assert_eq!(
        (code, String::from_utf8_lossy(&scene).as_ref()),
        (200, ROOM)
    );
    for path in [
        "/room.ron",
        "/api/../room.ron",
        "/%2e%2e/Cargo.toml",
        "/etc/passwd",
        "/api/frame.png/../../room.ron",
        "/cli/src/serve/page.html",
    ] {
        assert_eq!(server.get(path).0, 404, "{path}");
    }
    // A body larger than any edit is refused unread.
    let (code, _) = server.post("/api/edit", &"x".repeat(64 * 1024));
    assert_eq!(code, 413);
}

#[test]
fn an_edit_renders_anew_and_a_bad_one_changes_nothing() {
    let server = Server::start("edit", ROOM);
    let page = events(&server.url);
    let first = event_where(&page, |e| {
        e["quick"] == false && e["spp"].as_u64() >= Some(16)
    });
    assert_eq!(first["job"], 1);
    let (code, reply) = server.post(
        "/api/edit",
        r#"{"op": "move_light", "index": 0, "to": [90, 45]}"#,
    );
    assert_eq!(code, 200, "{reply}");
    let version = reply["version"].as_u64().unwrap();
    // The quick frame first, then the full size.
    let quick = event_where(&page, |e| e["job"].as_u64() == Some(version));
    assert_eq!(quick["quick"], true, "{quick}");
    event_where(&page, |e| {
        e["job"].as_u64() == Some(version) && e["quick"] == false
    });
    let items = server.json("/api/items");
    assert_eq!(items["lights"][0]["at"], serde_json::json!([90.0, 45.0]));
    assert_eq!(items["unsaved"], true);
    // The file on disk is untouched until saved.
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), ROOM);
    for bad in [
        r#"{"op": "light_intensity", "index": 0, "value": -5}"#,
        r#"{"op": "move_wall_end", "index": 0, "end": "a", "to": [60, 80]}"#,
        r#"{"op": "move_light", "index": 3, "to": [1, 1]}"#,
        r#"{"op": "paint", "index": 0}"#,
        "not json",
    ] {
        let (code, reply) = server.post("/api/edit", bad);
        assert!(code == 422 || code == 400, "{bad}: {code} {reply}");
        assert!(
            reply["message"].as_str().is_some_and(|m| !m.is_empty()),
            "{bad}: {reply}"
        );
    }
    let after = server.json("/api/items");
    assert_eq!(
        after["version"].as_u64(),
        Some(version),
        "a refused edit makes no version"
    );
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), ROOM);
    // Undo goes back to the file's text.
    let (code, _) = server.post("/api/undo", "");
    assert_eq!(code, 200);
    let (_, scene) = server.get("/api/scene.ron");
    assert_eq!(String::from_utf8_lossy(&scene), ROOM);
    let (code, _) = server.post("/api/undo", "");
    assert_eq!(code, 409, "nothing left to undo");
}

#[test]
fn save_writes_the_edits_keeps_the_comments_and_a_backup() {
    let server = Server::start("save", ROOM);
    for edit in [
        r#"{"op": "move_light", "index": 0, "to": [25.5, 40]}"#,
        r#"{"op": "light_color", "index": 0, "value": [1, 0.5, 0.25]}"#,
        r#"{"op": "wall_material", "index": 0, "material": "Mirror"}"#,
    ] {
        assert_eq!(server.post("/api/edit", edit).0, 200, "{edit}");
    }
    let (code, reply) = server.post("/api/save", "");
    assert_eq!(code, 200, "{reply}");
    let saved = std::fs::read_to_string(&server.scene).unwrap();
    assert!(
        saved.starts_with("// A test room: a lamp, a wall."),
        "{saved}"
    );
    assert!(
        saved.contains("Wall(a: (60, 10), b: (60, 80), material: Mirror()), // the partition"),
        "{saved}"
    );
    assert!(
        saved.contains("Point(at: (25.5, 40), intensity: 20, color: (1, 0.5, 0.25)), // the lamp"),
        "{saved}"
    );
    let backup = Path::new(&server.scene).with_file_name("room.ron.bak");
    assert_eq!(std::fs::read_to_string(backup).unwrap(), ROOM);
    assert_eq!(server.json("/api/items")["unsaved"], false);
    // What was saved loads as a scene.
    let check = Command::new(env!("CARGO_BIN_EXE_flatray"))
        .args(["check", server.scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(check.status.code(), Some(0), "{check:?}");
}

#[test]
fn the_file_changed_on_disk_is_reloaded_and_a_bad_one_keeps_the_last_render() {
    let server = Server::start("watch", ROOM);
    let page = events(&server.url);
    event_where(&page, |e| e["quick"] == false);
    std::fs::write(&server.scene, ROOM.replace("(30, 45)", "(100, 20)")).unwrap();
    let items = server.wait_for("the reload", |i| {
        i["lights"][0]["at"] == serde_json::json!([100.0, 20.0])
    });
    let version = items["version"].as_u64().unwrap();
    event_where(&page, |e| {
        e["job"].as_u64() == Some(version) && e["quick"] == false
    });
    // A broken file: its error, located, on the page; the render stays.
    std::fs::write(
        &server.scene,
        ROOM.replace("canvas: (120, 90),", "canvas: (120, 90)"),
    )
    .unwrap();
    let items = server.wait_for("the error", |i| !i["error"].is_null());
    let error = &items["error"];
    assert_eq!(error["line"], 3, "{error}");
    assert!(
        error["message"]
            .as_str()
            .unwrap_or_default()
            .contains("expected a comma"),
        "{error}"
    );
    assert_eq!(
        items["lights"][0]["at"],
        serde_json::json!([100.0, 20.0]),
        "the last good scene"
    );
    let (code, png) = server.get("/api/frame.png");
    assert_eq!(code, 200);
    assert!(png.starts_with(b"\x89PNG"));
    let (code, _) = server.get("/api/export.png");
    assert_eq!(code, 200);
    // Fixed again: rendered again.
    std::fs::write(&server.scene, ROOM).unwrap();
    server.wait_for("the fix", |i| {
        i["error"].is_null() && i["lights"][0]["at"] == serde_json::json!([30.0, 45.0])
    });
}

#[test]
fn two_pages_see_the_same_state() {
    let server = Server::start("two", ROOM);
    let (one, two) = (events(&server.url), events(&server.url));
    event_where(&one, |e| e["quick"] == false);
    event_where(&two, |e| e["quick"] == false);
    let (_, reply) = server.post(
        "/api/edit",
        r#"{"op": "light_intensity", "index": 0, "value": 40}"#,
    );
    let version = reply["version"].as_u64().unwrap();
    let a = event_where(&one, |e| {
        e["job"].as_u64() == Some(version) && e["spp"].as_u64() >= Some(16) && e["quick"] == false
    });
    let b = event_where(&two, |e| e["frame"] == a["frame"]);
    assert_eq!(a, b);
    // Exports of the full-size image, in both formats.
    let (code, exr) = server.get("/api/export.exr");
    assert_eq!(code, 200);
    assert!(
        exr.starts_with(&[0x76, 0x2f, 0x31, 0x01]),
        "an EXR's magic number"
    );
    let (code, noise) = server.get("/api/noise.txt");
    assert_eq!(code, 200);
    assert!(String::from_utf8_lossy(&noise).contains("spp"));
}

/// `flatray render --watch` renders again when the scene is saved.
#[test]
fn render_watch_renders_again_on_save() {
    let dir = std::env::temp_dir().join(format!("flatray-watch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("room.ron");
    std::fs::write(&scene, ROOM).unwrap();
    let out = dir.join("room.png");
    let mut child = Command::new(env!("CARGO_BIN_EXE_flatray"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--watch",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    stdout.read_line(&mut line).unwrap();
    assert!(line.starts_with("wrote "), "{line}");
    let first = std::fs::read(&out).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    std::fs::write(&scene, ROOM.replace("(30, 45)", "(90, 45)")).unwrap();
    line.clear();
    stdout.read_line(&mut line).unwrap();
    assert!(line.starts_with("wrote "), "{line}");
    let second = std::fs::read(&out).unwrap();
    assert_ne!(first, second, "the lamp moved: another image");
    let _ = child.kill();
    let _ = child.wait();
    let mut rest = String::new();
    let _ = stdout.read_to_string(&mut rest);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A request's headers, as name and value.
type Headers = Vec<(String, String)>;

/// What a raw request got: the status (0 when none came), the body, and
/// whether the server closed the connection before `wait` ran out.
struct Answer {
    status: u16,
    body: String,
    closed: bool,
    after: Duration,
}

/// Sends `request` byte for byte, as another site's page, a broken client
/// or an attacker would, and reads what comes back within `wait`. The
/// answer is read while the request is still being sent: a server that
/// refuses a body past its limit answers and closes before the body is
/// all sent, and the bytes sent after that are met with a reset that
/// would lose an answer not yet read.
fn raw(url: &str, request: &[u8], wait: Duration) -> Answer {
    let address = url.trim_start_matches("http://");
    let mut stream = std::net::TcpStream::connect(address).unwrap();
    stream.set_read_timeout(Some(wait)).unwrap();
    let started = Instant::now();
    let mut writer = stream.try_clone().unwrap();
    let request = request.to_vec();
    let sending = std::thread::spawn(move || {
        // Refused midway is an answer too: the write's error is not.
        let _ = writer.write_all(&request);
    });
    let mut answer = Vec::new();
    let closed = stream.read_to_end(&mut answer).is_ok();
    let _ = sending.join();
    let text = String::from_utf8_lossy(&answer).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let body = text
        .split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .unwrap_or_default();
    Answer {
        status,
        body,
        closed,
        after: started.elapsed(),
    }
}

/// A whole request: `headers` as given, then `Connection: close` and the
/// body's length (unless `headers` declare one).
fn request(method: &str, path: &str, headers: &[(&str, &str)], body: &[u8]) -> Vec<u8> {
    let mut out = format!("{method} {path} HTTP/1.1\r\n");
    for (k, v) in headers {
        out.push_str(&format!("{k}: {v}\r\n"));
    }
    if !headers
        .iter()
        .any(|(k, _)| k.eq_ignore_ascii_case("content-length"))
    {
        out.push_str(&format!("Content-Length: {}\r\n", body.len()));
    }
    out.push_str("Connection: close\r\n\r\n");
    let mut bytes = out.into_bytes();
    bytes.extend_from_slice(body);
    bytes
}

impl Server {
    fn host(&self) -> String {
        self.url.trim_start_matches("http://").to_string()
    }

    /// The headers the page itself sends with a change.
    fn page_headers(&self) -> Headers {
        vec![
            ("Host".into(), self.host()),
            ("Origin".into(), self.url.clone()),
            ("Content-Type".into(), "application/json".into()),
            ("X-Flatray-Token".into(), self.token.clone()),
        ]
    }

    /// The page's headers with `name` set to `value` (or left out when
    /// `value` is `None`).
    fn headers_but(&self, name: &str, value: Option<&str>) -> Headers {
        let mut h: Vec<_> = self
            .page_headers()
            .into_iter()
            .filter(|(k, _)| !k.eq_ignore_ascii_case(name))
            .collect();
        if let Some(v) = value {
            h.push((name.to_string(), v.to_string()));
        }
        h
    }

    fn send(&self, method: &str, path: &str, headers: &[(String, String)], body: &[u8]) -> Answer {
        let h: Vec<(&str, &str)> = headers
            .iter()
            .map(|(k, v)| (k.as_str(), v.as_str()))
            .collect();
        raw(
            &self.url,
            &request(method, path, &h, body),
            Duration::from_secs(20),
        )
    }
}

const MOVE: &str = r#"{"op": "move_light", "index": 0, "to": [90, 45]}"#;

#[test]
fn another_sites_page_can_neither_read_nor_change_the_scene() {
    let server = Server::start("foreign", ROOM);
    // The page's own headers pass: the check is not refusing everything.
    let ok = server.send("POST", "/api/edit", &server.page_headers(), MOVE.as_bytes());
    assert_eq!(ok.status, 200, "{}", ok.body);
    let (code, _) = server.post("/api/undo", "{}");
    assert_eq!(code, 200);
    let version = server.json("/api/items")["version"].clone();

    // DNS rebinding: the attacker's name, pointed at this machine.
    let rebound = [("Host", "attacker.example:8421")];
    for path in ["/", "/api/scene.ron", "/api/items", "/api/frame.png"] {
        let a = raw(
            &server.url,
            &request("GET", path, &rebound, b""),
            Duration::from_secs(20),
        );
        assert_eq!(a.status, 403, "{path}: {}", a.body);
        assert!(!a.body.contains("partition"), "{path}: the scene leaked");
    }
    let port = server.host().rsplit(':').next().unwrap().to_string();
    let cases: Vec<(&str, Headers, u16)> = vec![
        (
            "a foreign Host",
            server.headers_but("Host", Some(&format!("attacker.example:{port}"))),
            403,
        ),
        (
            "a foreign Origin",
            server.headers_but("Origin", Some("http://attacker.example")),
            403,
        ),
        (
            "Origin null",
            server.headers_but("Origin", Some("null")),
            403,
        ),
        (
            "another port's page",
            server.headers_but("Origin", Some("http://127.0.0.1:1")),
            403,
        ),
        (
            "cross-site",
            server.headers_but("Sec-Fetch-Site", Some("cross-site")),
            403,
        ),
        (
            "text/plain",
            server.headers_but("Content-Type", Some("text/plain")),
            415,
        ),
        (
            "a form",
            server.headers_but("Content-Type", Some("application/x-www-form-urlencoded")),
            415,
        ),
        ("no token", server.headers_but("X-Flatray-Token", None), 403),
        (
            "a wrong token",
            server.headers_but("X-Flatray-Token", Some("00112233445566778899aabbccddeeff")),
            403,
        ),
    ];
    for (case, headers, status) in &cases {
        for (path, body) in [
            ("/api/edit", MOVE),
            ("/api/undo", "{}"),
            ("/api/save", "{}"),
            ("/api/resolve", r#"{"keep": "mine"}"#),
        ] {
            let a = server.send("POST", path, headers, body.as_bytes());
            assert_eq!(a.status, *status, "{case} {path}: {}", a.body);
            assert!(a.body.contains("message"), "{case} {path}: {}", a.body);
        }
    }
    // The cross-site form post of the attack, exactly: text/plain, a
    // foreign Origin, no token.
    let attack = request(
        "POST",
        "/api/edit",
        &[
            ("Host", &server.host()),
            ("Origin", "http://attacker.example"),
            ("Content-Type", "text/plain"),
        ],
        MOVE.as_bytes(),
    );
    assert_ne!(
        raw(&server.url, &attack, Duration::from_secs(20)).status,
        200
    );
    let items = server.json("/api/items");
    assert_eq!(items["version"], version, "nothing changed");
    assert_eq!(items["lights"][0]["at"], serde_json::json!([30.0, 45.0]));
    assert_eq!(items["undo"], 0, "the undo was not taken either");
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), ROOM);
    assert!(!server.dir.join("room.ron.bak").exists(), "no save ran");
    // The page may not be framed by another site.
    let page = ureq::get(&format!("{}/", server.url)).call().unwrap();
    assert_eq!(page.headers().get("x-frame-options").unwrap(), "DENY");
}

#[test]
fn bodies_are_bounded_on_every_route_and_a_stalled_client_is_let_go() {
    let server = Server::start("bodies", ROOM);
    assert_eq!(server.post("/api/edit", MOVE).0, 200);
    // A declared length past the limit: refused at once, nothing read.
    let mut headers = server.page_headers();
    headers.push(("Content-Length".into(), "20000".into()));
    let a = server.send("POST", "/api/edit", &headers, b"");
    assert_eq!(a.status, 413, "{}", a.body);
    assert!(a.after < Duration::from_secs(2), "at once: {:?}", a.after);
    // A 1 MiB body on every route that changes something.
    let large = vec![b' '; 1 << 20];
    for path in ["/api/edit", "/api/undo", "/api/save", "/api/resolve"] {
        let a = server.send("POST", path, &server.page_headers(), &large);
        assert_eq!(a.status, 413, "{path}: {}", a.body);
    }
    // The same without a declared length (chunked): still refused.
    let mut chunked = format!(
        "POST /api/undo HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\nX-Flatray-Token: {}\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n",
        server.host(),
        server.token
    )
    .into_bytes();
    for _ in 0..64 {
        chunked.extend_from_slice(b"4000\r\n");
        chunked.extend_from_slice(&[b' '; 0x4000]);
        chunked.extend_from_slice(b"\r\n");
    }
    chunked.extend_from_slice(b"0\r\n\r\n");
    assert_eq!(
        raw(&server.url, &chunked, Duration::from_secs(20)).status,
        413
    );
    let items = server.json("/api/items");
    assert_eq!(items["undo"], 1, "no undo was done");
    assert_eq!(items["lights"][0]["at"], serde_json::json!([90.0, 45.0]));
    assert_eq!(
        std::fs::read_to_string(&server.scene).unwrap(),
        ROOM,
        "no save"
    );

    // Headers that never end, and a body that never comes: both let go
    // within seconds, and the server answers others meanwhile.
    let url = server.url.clone();
    let host = server.host();
    let stalled_headers = std::thread::spawn({
        let (url, host) = (url.clone(), host.clone());
        move || {
            raw(
                &url,
                format!("GET /api/items HTTP/1.1\r\nHost: {host}\r\n").as_bytes(),
                Duration::from_secs(30),
            )
        }
    });
    let mut headers = server.page_headers();
    headers.push(("Content-Length".into(), "100".into()));
    let h: Vec<(&str, &str)> = headers
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    let short = request("POST", "/api/edit", &h, b"{\"op\"");
    let stalled_body = std::thread::spawn(move || raw(&url, &short, Duration::from_secs(30)));
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(server.json("/api/items")["undo"], 1, "others are answered");
    let a = stalled_headers.join().unwrap();
    assert!(
        a.closed && a.after < Duration::from_secs(15),
        "headers: {:?} {}",
        a.after,
        a.body
    );
    let b = stalled_body.join().unwrap();
    assert_eq!(b.status, 408, "{}", b.body);
    assert!(b.after < Duration::from_secs(15), "body: {:?}", b.after);
}

/// A server that answers within 10 s, or the test fails.
fn answers(server: &Server) -> serde_json::Value {
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .timeout_global(Some(Duration::from_secs(10)))
        .build()
        .into();
    let mut r = agent
        .get(&format!("{}/api/items", server.url))
        .call()
        .expect("the server answers");
    serde_json::from_str(&r.body_mut().read_to_string().unwrap()).unwrap()
}

#[test]
fn a_pipe_at_the_scene_path_blocks_nothing() {
    let server = Server::start("fifo", ROOM);
    assert_eq!(server.post("/api/edit", MOVE).0, 200);
    std::fs::remove_file(&server.scene).unwrap();
    let made = Command::new("mkfifo").arg(&server.scene).status().unwrap();
    assert!(made.success());
    // The watcher sees it, says so, and reads nothing.
    let started = Instant::now();
    loop {
        let items = answers(&server);
        if items["error"]["message"]
            .as_str()
            .is_some_and(|m| m.contains("not a regular file"))
        {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(20), "{items}");
        std::thread::sleep(Duration::from_millis(100));
    }
    let (code, reply) = server.post("/api/save", "{}");
    assert_eq!(code, 403, "{reply}");
    assert!(
        reply["message"]
            .as_str()
            .unwrap()
            .contains("not a regular file"),
        "{reply}"
    );
    // Every route still answers.
    assert_eq!(server.post("/api/undo", "{}").0, 200);
    assert_eq!(
        answers(&server)["lights"][0]["at"],
        serde_json::json!([30.0, 45.0])
    );
    assert_eq!(server.get("/api/scene.ron").0, 200);
    let _ = std::fs::remove_file(&server.scene);
}

#[test]
fn a_link_is_followed_once_and_a_link_put_in_the_files_place_never() {
    let server = Server::start("link", ROOM);
    // The scene served through a link: saves go to the file it points
    // at, and the link stays.
    let real = server.dir.join("real.ron");
    std::fs::write(&real, ROOM).unwrap();
    let link = server.dir.join("link.ron");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let through = common::serve(&link);
    let headers = |agent: &ureq::Agent, path: &str, body: &str| {
        agent
            .post(&format!("{}{path}", through.url))
            .content_type("application/json")
            .header("x-flatray-token", &through.token)
            .send(body)
            .map(|r| r.status().as_u16())
            .unwrap_or(0)
    };
    let agent: ureq::Agent = ureq::Agent::config_builder().build().into();
    assert_eq!(headers(&agent, "/api/edit", MOVE), 200);
    assert_eq!(headers(&agent, "/api/save", "{}"), 200);
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(std::fs::read_to_string(&real).unwrap().contains("(90, 45)"));
    assert_eq!(
        std::fs::read_to_string(server.dir.join("real.ron.bak")).unwrap(),
        ROOM
    );
    drop(through);

    // A link to another file put where the scene was: not read, not
    // replaced, and the other file's text never reaches a page.
    let secret = server.dir.join("secret.txt");
    std::fs::write(&secret, "hunter2 is the password").unwrap();
    std::fs::remove_file(&server.scene).unwrap();
    std::os::unix::fs::symlink(&secret, &server.scene).unwrap();
    let started = Instant::now();
    let items = loop {
        let items = answers(&server);
        if !items["error"].is_null() {
            break items;
        }
        assert!(started.elapsed() < Duration::from_secs(20), "{items}");
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(
        items["error"]["message"]
            .as_str()
            .unwrap()
            .contains("symbolic link"),
        "{items}"
    );
    assert!(!items.to_string().contains("hunter2"), "{items}");
    assert_eq!(server.post("/api/edit", MOVE).0, 200);
    let (code, reply) = server.post("/api/save", "{}");
    assert_eq!(code, 403, "{reply}");
    assert_eq!(
        std::fs::read_to_string(&secret).unwrap(),
        "hunter2 is the password"
    );
    assert!(
        std::fs::symlink_metadata(&server.scene)
            .unwrap()
            .file_type()
            .is_symlink()
    );
}

/// Waits for the watcher to see the file (it looks every 250 ms).
fn settle() {
    std::thread::sleep(Duration::from_millis(800));
}

#[test]
fn an_edit_in_the_page_outlives_a_change_on_disk_and_the_user_chooses() {
    let server = Server::start("conflict", ROOM);
    let editor = ROOM.replace("intensity: 20", "intensity: 35");
    // Keep mine: the page's edit stays; the file's change is kept in the
    // backup when the page saves.
    assert_eq!(server.post("/api/edit", MOVE).0, 200);
    std::fs::write(&server.scene, &editor).unwrap();
    let items = server.wait_for("the conflict", |i| !i["conflict"].is_null());
    assert_eq!(
        items["lights"][0]["at"],
        serde_json::json!([90.0, 45.0]),
        "the page's edit stays"
    );
    assert_eq!(items["conflict"]["file"], editor.as_str());
    assert_eq!(items["unsaved"], true);
    assert_eq!(
        std::fs::read_to_string(&server.scene).unwrap(),
        editor,
        "the file's stays too"
    );
    let (code, reply) = server.post("/api/save", "{}");
    assert_eq!(code, 409, "a save would lose the file's change: {reply}");
    assert_eq!(reply["changed"], true);
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), editor);
    assert_eq!(server.post("/api/resolve", r#"{"keep": "mine"}"#).0, 200);
    let items = server.json("/api/items");
    assert!(items["conflict"].is_null());
    assert_eq!(items["unsaved"], true);
    assert_eq!(server.post("/api/save", "{}").0, 200);
    let saved = std::fs::read_to_string(&server.scene).unwrap();
    assert!(saved.contains("(90, 45), intensity: 20"), "{saved}");
    assert_eq!(
        std::fs::read_to_string(server.dir.join("room.ron.bak")).unwrap(),
        editor
    );
    assert_eq!(
        server.post("/api/resolve", r#"{"keep": "mine"}"#).0,
        409,
        "nothing to choose"
    );

    // Take the file's: the file's text is rendered; undo brings the
    // page's edit back.
    settle();
    let page_edit = r#"{"op": "light_intensity", "index": 0, "value": 7}"#;
    assert_eq!(server.post("/api/edit", page_edit).0, 200);
    let editor2 = saved.replace("(90, 45)", "(20, 20)");
    std::fs::write(&server.scene, &editor2).unwrap();
    server.wait_for("the second conflict", |i| !i["conflict"].is_null());
    assert_eq!(server.post("/api/resolve", r#"{"keep": "file"}"#).0, 200);
    let items = server.json("/api/items");
    assert_eq!(items["lights"][0]["at"], serde_json::json!([20.0, 20.0]));
    assert_eq!(items["lights"][0]["intensity"], 20.0);
    assert_eq!(items["unsaved"], false);
    assert_eq!(server.post("/api/undo", "{}").0, 200);
    let items = server.json("/api/items");
    assert_eq!(
        items["lights"][0]["intensity"], 7.0,
        "the page's edit, back"
    );
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), editor2);
}

#[test]
fn save_refuses_a_file_changed_since_it_was_loaded_and_a_read_only_one() {
    let server = Server::start("stale", ROOM);
    // Changed on disk, then saved at once (before the watcher may look):
    // refused, then written when told to overwrite, the editor's text in
    // the backup.
    let editor = ROOM.replace("intensity: 20", "intensity: 35");
    assert_eq!(server.post("/api/edit", MOVE).0, 200);
    std::fs::write(&server.scene, &editor).unwrap();
    let (code, reply) = server.post("/api/save", "{}");
    assert_eq!(code, 409, "{reply}");
    assert!(
        reply["message"]
            .as_str()
            .unwrap()
            .contains("changed on disk"),
        "{reply}"
    );
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), editor);
    let (code, reply) = server.post("/api/save", r#"{"overwrite": true}"#);
    assert_eq!(code, 200, "{reply}");
    assert!(
        std::fs::read_to_string(&server.scene)
            .unwrap()
            .contains("(90, 45)")
    );
    assert_eq!(
        std::fs::read_to_string(server.dir.join("room.ron.bak")).unwrap(),
        editor
    );
    // A second save keeps the first backup a generation down.
    settle();
    assert_eq!(
        server
            .post(
                "/api/edit",
                r#"{"op": "light_intensity", "index": 0, "value": 9}"#
            )
            .0,
        200
    );
    let before = std::fs::read_to_string(&server.scene).unwrap();
    assert_eq!(server.post("/api/save", "{}").0, 200);
    assert_eq!(
        std::fs::read_to_string(server.dir.join("room.ron.bak")).unwrap(),
        before
    );
    assert_eq!(
        std::fs::read_to_string(server.dir.join("room.ron.bak.1")).unwrap(),
        editor
    );
    // Read-only: refused, the file untouched (even for root, who could).
    settle();
    let mut permissions = std::fs::metadata(&server.scene).unwrap().permissions();
    permissions.set_readonly(true);
    std::fs::set_permissions(&server.scene, permissions).unwrap();
    let kept = std::fs::read_to_string(&server.scene).unwrap();
    assert_eq!(
        server
            .post("/api/edit", MOVE.replace("90", "80").as_str())
            .0,
        200
    );
    let (code, reply) = server.post("/api/save", r#"{"overwrite": true}"#);
    assert_eq!(code, 403, "{reply}");
    assert!(
        reply["message"].as_str().unwrap().contains("read-only"),
        "{reply}"
    );
    assert_eq!(std::fs::read_to_string(&server.scene).unwrap(), kept);
    let mut permissions = std::fs::metadata(&server.scene).unwrap().permissions();
    #[allow(clippy::permissions_set_readonly_false)]
    permissions.set_readonly(false);
    std::fs::set_permissions(&server.scene, permissions).unwrap();
}

/// The text the server at `url` answers a GET of `path` with.
fn text_of(url: &str, path: &str) -> String {
    ureq::get(&format!("{url}{path}"))
        .call()
        .unwrap()
        .body_mut()
        .read_to_string()
        .unwrap()
}

/// `flatray serve MAP.dd2vtt` imports the map into MAP.ron beside it, with
/// its floor image, and serves that; served again, the scene (with the
/// user's edits) is served as it is, never imported over.
#[test]
fn a_map_is_imported_beside_itself_and_then_served_and_never_imported_over() {
    let dir = std::env::temp_dir().join(format!("flatray-serve-map-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/maps/tavern.dd2vtt");
    let map = dir.join("tavern.dd2vtt");
    std::fs::copy(&root, &map).unwrap();
    let scene = dir.join("tavern.ron");
    {
        let serving = common::serve(&map);
        let text = std::fs::read_to_string(&scene).unwrap();
        assert!(
            text.contains("floor: Image(\"tavern-floor.png\")"),
            "{text}"
        );
        assert!(dir.join("tavern-floor.png").is_file());
        let body = text_of(&serving.url, "/api/scene.ron");
        assert_eq!(body, text);
        let items: serde_json::Value =
            serde_json::from_str(&text_of(&serving.url, "/api/items")).unwrap();
        assert_eq!(items["canvas"], serde_json::json!([896, 640]));
        assert_eq!(items["lights"].as_array().map(Vec::len), Some(3));
    }
    // The user's scene, edited since: served as it is.
    let edited = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("render: (samples: 64", "render: (samples: 8");
    std::fs::write(&scene, &edited).unwrap();
    {
        let serving = common::serve(&map);
        let body = text_of(&serving.url, "/api/scene.ron");
        assert_eq!(body, edited);
    }
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), edited);
    let _ = std::fs::remove_dir_all(&dir);
}
