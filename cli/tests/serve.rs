//! `flatray serve`, the real binary on a real port, asked over HTTP as a
//! page asks it: edits, undo, save, the watch of the file on disk, two
//! pages at once, and nothing served but the page and the one scene.

use std::io::{BufRead, BufReader, Read};
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
        Server {
            _serving: serving,
            url,
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
