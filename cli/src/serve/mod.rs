//! `flatray serve`: a local page that shows a scene's render converge,
//! pass after pass, and edits the scene (drag a light or a wall's end,
//! change a light's intensity or colour, a wall's material; undo; save).
//!
//! The server (axum on tokio) serves its own page and the one scene,
//! nothing else. The scene's text is the state: an edit rewrites a value
//! in it (`flatray_io::edit`, comments kept), is checked by the loader,
//! and restarts the render; the file on disk changes only on save. A
//! worker thread renders (`render.rs`): a quick small frame first, then
//! the full size pass after pass, each published to every open page as
//! it is done (server-sent events).

mod render;

use std::net::{IpAddr, SocketAddr};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

use axum::Router;
use axum::extract::{DefaultBodyLimit, State};
use axum::http::{StatusCode, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use flatray_io::edit::Edit;
use flatray_io::{Loaded, SceneError};
use tokio_stream::StreamExt;
use tokio_stream::wrappers::WatchStream;

use crate::{Failure, stamp};
use render::{Frame, Job, Worker};

/// The page, served as it is.
const PAGE: &str = include_str!("page.html");

/// The largest request body: an edit is a few dozen bytes.
const MAX_BODY: usize = 16 * 1024;

/// How often the scene file is looked at for changes made elsewhere.
const WATCH_EVERY: Duration = Duration::from_millis(250);

#[derive(Debug, clap::Args)]
pub(crate) struct ServeArgs {
    /// The scene file (RON): rendered, edited, saved back.
    scene: PathBuf,
    /// The port to listen on (0: any free port, printed).
    #[arg(long, default_value_t = 8421)]
    port: u16,
    /// The address to listen on. Anything but loopback lets other machines
    /// see and edit the scene: give it only on a network you trust.
    #[arg(long, default_value = "127.0.0.1")]
    host: IpAddr,
    /// Open the page in the default browser.
    #[arg(long)]
    open: bool,
}

/// What every request and the watcher share.
struct Shared {
    path: PathBuf,
    base: PathBuf,
    state: Mutex<Scene>,
    worker: Worker,
}

/// The scene as the page sees it.
struct Scene {
    /// The text being rendered: the file's, with the edits made since.
    text: String,
    /// Texts before each edit, for undo.
    undo: Vec<String>,
    /// The text last read from or written to the file, and the file's
    /// modification time and length then.
    on_disk: String,
    stamp: Option<(SystemTime, u64)>,
    /// The last good scene and its items, as JSON.
    items: serde_json::Value,
    /// What is wrong with the file on disk, when a change made there does
    /// not load (the last good scene keeps rendering).
    error: Option<serde_json::Value>,
    /// Raised at each new scene, so the page reloads its items.
    version: u64,
}

pub(crate) fn serve(args: ServeArgs, out: &mut dyn std::io::Write) -> Result<(), Failure> {
    let path = args.scene.clone();
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let (text, loaded) = read_scene(&path).map_err(|e| Failure::usage(e.message))?;
    let items = items_json(&text, &loaded)?;
    let worker = Worker::start();
    let shared = Arc::new(Shared {
        path: path.clone(),
        base,
        state: Mutex::new(Scene {
            on_disk: text.clone(),
            stamp: stamp(&path),
            text,
            undo: Vec::new(),
            items,
            error: None,
            version: 1,
        }),
        worker,
    });
    shared.worker.submit(Job::new(1, loaded));

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| Failure::other(format!("cannot start the server: {e}")))?;
    let address = SocketAddr::new(args.host, args.port);
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind(address))
        .map_err(|e| Failure::usage(format!("cannot listen on {address}: {e}")))?;
    let bound = listener
        .local_addr()
        .map_err(|e| Failure::other(format!("cannot listen on {address}: {e}")))?;
    let url = format!("http://{bound}/");
    if !args.host.is_loopback() {
        let _ = writeln!(
            out,
            "WARNING: listening on {bound}, not on loopback: anyone who can reach this machine can see and edit {} and save it",
            path.display()
        );
    }
    let _ = writeln!(out, "serving {} at {url} (Ctrl-C to stop)", path.display());
    let _ = out.flush();
    if args.open {
        open_browser(&url);
    }

    let watcher = Arc::clone(&shared);
    std::thread::spawn(move || watch(&watcher));

    let app = Router::new()
        .route("/", get(page))
        .route("/api/events", get(events))
        .route("/api/frame.png", get(frame_png))
        .route("/api/items", get(scene_items))
        .route("/api/edit", post(edit))
        .route("/api/undo", post(undo))
        .route("/api/save", post(save))
        .route("/api/export.png", get(export_png))
        .route("/api/export.exr", get(export_exr))
        .route("/api/noise.txt", get(export_noise))
        .route("/api/scene.ron", get(export_scene))
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .with_state(shared);
    runtime
        .block_on(async { axum::serve(listener, app).await })
        .map_err(|e| Failure::other(format!("the server stopped: {e}")))
}

/// A scene file's text and what it loads as.
fn read_scene(path: &Path) -> Result<(String, Loaded), Refusal> {
    let bytes = flatray_io::read_within(path, flatray_io::MAX_INPUT_BYTES).map_err(|e| {
        Refusal::plain(format!(
            "{}: cannot read the scene file: {e}",
            path.display()
        ))
    })?;
    let text = String::from_utf8(bytes).map_err(|_| {
        Refusal::plain(format!(
            "{}: the scene file is not UTF-8 text",
            path.display()
        ))
    })?;
    let loaded = load_text(&text, path)?;
    Ok((text, loaded))
}

fn load_text(text: &str, path: &Path) -> Result<Loaded, Refusal> {
    let base = path.parent().unwrap_or(Path::new("."));
    flatray_io::parse(text, path, base).map_err(|e| Refusal::of(&e))
}

fn items_json(text: &str, loaded: &Loaded) -> Result<serde_json::Value, Failure> {
    let items = flatray_io::edit::items(text, loaded).map_err(Failure::usage)?;
    let mut value = serde_json::to_value(items)
        .map_err(|e| Failure::other(format!("cannot describe the scene: {e}")))?;
    value["warnings"] = crate::json::warnings(&loaded.warnings);
    Ok(value)
}

/// Why a scene or an edit was refused: the message, and where it points.
struct Refusal {
    message: String,
    line: Option<usize>,
    column: Option<usize>,
}

impl Refusal {
    fn plain(message: String) -> Refusal {
        Refusal {
            message,
            line: None,
            column: None,
        }
    }

    fn of(e: &SceneError) -> Refusal {
        let (line, column) = e
            .location()
            .map_or((None, None), |(l, c)| (Some(l), Some(c)));
        Refusal {
            message: e.to_string(),
            line,
            column,
        }
    }

    fn json(&self) -> serde_json::Value {
        serde_json::json!({"message": self.message, "line": self.line, "column": self.column})
    }
}

fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, Scene> {
    shared
        .state
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Makes `text` (which loads as `loaded`) the scene, and renders it anew.
fn adopt(shared: &Shared, scene: &mut Scene, text: String, loaded: Loaded) -> Result<(), Failure> {
    scene.items = items_json(&text, &loaded)?;
    scene.text = text;
    scene.error = None;
    scene.version += 1;
    shared.worker.submit(Job::new(scene.version, loaded));
    Ok(())
}

/// Looks at the scene file every [`WATCH_EVERY`]: a change made elsewhere
/// (an editor's save) is loaded and rendered, replacing the edits not
/// saved (they stay undoable); a change that does not load is shown on
/// the page, and the last good scene keeps rendering.
fn watch(shared: &Shared) {
    loop {
        std::thread::sleep(WATCH_EVERY);
        let now = stamp(&shared.path);
        let mut scene = lock(shared);
        if now == scene.stamp {
            continue;
        }
        scene.stamp = now;
        let Ok(bytes) = flatray_io::read_within(&shared.path, flatray_io::MAX_INPUT_BYTES) else {
            continue;
        };
        let text = String::from_utf8_lossy(&bytes).into_owned();
        if text == scene.on_disk {
            continue;
        }
        scene.on_disk = text.clone();
        match load_text(&text, &shared.path) {
            Ok(loaded) => {
                let before = std::mem::take(&mut scene.text);
                scene.undo.push(before);
                let _ = adopt(shared, &mut scene, text, loaded);
            }
            Err(refusal) => {
                scene.error = Some(refusal.json());
                scene.version += 1;
                shared.worker.note_error(scene.version);
            }
        }
    }
}

async fn page() -> Html<&'static str> {
    Html(PAGE)
}

/// Server-sent events: one per published frame, with what the page
/// shows beside the image.
async fn events(
    State(shared): State<Arc<Shared>>,
) -> Sse<impl tokio_stream::Stream<Item = Result<Event, std::convert::Infallible>>> {
    let stream = WatchStream::new(shared.worker.frames()).map(move |frame| {
        let (version, error) = {
            let scene = lock(&shared);
            (scene.version, scene.error.clone())
        };
        let status = serde_json::json!({
            "frame": frame.number,
            "job": frame.job,
            "version": version,
            "spp": frame.spp,
            "passes": frame.passes,
            "quick": frame.quick,
            "noise": frame.noise,
            "width": frame.width,
            "height": frame.height,
            "seconds": frame.seconds,
            "error": error,
        });
        Ok(Event::default().data(status.to_string()))
    });
    Sse::new(stream).keep_alive(KeepAlive::default())
}

fn png(bytes: Vec<u8>) -> Response {
    (
        [
            (header::CONTENT_TYPE, "image/png"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        bytes,
    )
        .into_response()
}

fn refused(status: StatusCode, body: serde_json::Value) -> Response {
    (status, axum::Json(body)).into_response()
}

async fn frame_png(State(shared): State<Arc<Shared>>) -> Response {
    let frame: Arc<Frame> = shared.worker.frames().borrow().clone();
    match &frame.png {
        Some(bytes) => png(bytes.as_ref().clone()),
        None => refused(
            StatusCode::NOT_FOUND,
            serde_json::json!({"message": "no frame yet"}),
        ),
    }
}

async fn scene_items(State(shared): State<Arc<Shared>>) -> Response {
    let scene = lock(&shared);
    let mut value = scene.items.clone();
    value["version"] = scene.version.into();
    value["error"] = scene.error.clone().unwrap_or_default();
    value["undo"] = scene.undo.len().into();
    value["unsaved"] = (scene.text != scene.on_disk).into();
    axum::Json(value).into_response()
}

/// Makes an edit: refused (422, with the loader's message) when the
/// scene it leaves does not load; nothing changes then.
async fn edit(State(shared): State<Arc<Shared>>, body: axum::body::Bytes) -> Response {
    let edit: Edit = match serde_json::from_slice(&body) {
        Ok(edit) => edit,
        Err(e) => {
            return refused(
                StatusCode::BAD_REQUEST,
                serde_json::json!({"message": format!("not an edit: {e}")}),
            );
        }
    };
    let mut scene = lock(&shared);
    let (edited, loaded) =
        match flatray_io::edit::apply(&scene.text, &edit, &shared.path, &shared.base) {
            Ok(done) => done,
            Err(message) => {
                return refused(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    serde_json::json!({"message": message}),
                );
            }
        };
    let before = scene.text.clone();
    match adopt(&shared, &mut scene, edited, loaded) {
        Ok(()) => {
            scene.undo.push(before);
            axum::Json(serde_json::json!({"version": scene.version})).into_response()
        }
        Err(f) => refused(
            StatusCode::UNPROCESSABLE_ENTITY,
            serde_json::json!({"message": f.message}),
        ),
    }
}

async fn undo(State(shared): State<Arc<Shared>>) -> Response {
    let mut scene = lock(&shared);
    let Some(text) = scene.undo.pop() else {
        return refused(
            StatusCode::CONFLICT,
            serde_json::json!({"message": "nothing to undo"}),
        );
    };
    match load_text(&text, &shared.path) {
        Ok(loaded) => match adopt(&shared, &mut scene, text, loaded) {
            Ok(()) => axum::Json(serde_json::json!({"version": scene.version})).into_response(),
            Err(f) => refused(
                StatusCode::UNPROCESSABLE_ENTITY,
                serde_json::json!({"message": f.message}),
            ),
        },
        Err(r) => refused(StatusCode::UNPROCESSABLE_ENTITY, r.json()),
    }
}

/// Writes the scene being rendered to its file, atomically, the file's
/// previous text kept beside it as `NAME.bak`.
async fn save(State(shared): State<Arc<Shared>>) -> Response {
    let mut scene = lock(&shared);
    let backup = backup_path(&shared.path);
    let previous = std::fs::read(&shared.path).ok();
    if let Some(previous) = &previous
        && let Err(e) = flatray_io::write_bytes(&backup, previous)
    {
        return refused(
            StatusCode::INTERNAL_SERVER_ERROR,
            serde_json::json!({"message": e.to_string()}),
        );
    }
    if let Err(e) = flatray_io::write_text(&shared.path, &scene.text) {
        return refused(
            StatusCode::INTERNAL_SERVER_ERROR,
            serde_json::json!({"message": e.to_string()}),
        );
    }
    scene.on_disk = scene.text.clone();
    scene.stamp = stamp(&shared.path);
    axum::Json(serde_json::json!({
        "saved": shared.path.display().to_string(),
        "backup": previous.map(|_| backup.display().to_string()),
    }))
    .into_response()
}

/// `scene.ron` -> `scene.ron.bak`.
fn backup_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".bak");
    path.with_file_name(name)
}

async fn export_png(State(shared): State<Arc<Shared>>) -> Response {
    let frame: Arc<Frame> = shared.worker.frames().borrow().clone();
    match &frame.full {
        Some((image, tonemap)) => match flatray_io::png_bytes(image, *tonemap) {
            Ok(bytes) => png(bytes),
            Err(e) => refused(
                StatusCode::INTERNAL_SERVER_ERROR,
                serde_json::json!({"message": e}),
            ),
        },
        None => refused(
            StatusCode::NOT_FOUND,
            serde_json::json!({"message": "no full-size image yet"}),
        ),
    }
}

async fn export_exr(State(shared): State<Arc<Shared>>) -> Response {
    let frame: Arc<Frame> = shared.worker.frames().borrow().clone();
    let Some((image, _)) = &frame.full else {
        return refused(
            StatusCode::NOT_FOUND,
            serde_json::json!({"message": "no full-size image yet"}),
        );
    };
    match flatray_io::exr_bytes(image) {
        Ok(bytes) => (
            [
                (header::CONTENT_TYPE, "image/x-exr"),
                (
                    header::CONTENT_DISPOSITION,
                    "attachment; filename=\"render.exr\"",
                ),
            ],
            bytes,
        )
            .into_response(),
        Err(e) => refused(
            StatusCode::INTERNAL_SERVER_ERROR,
            serde_json::json!({"message": e}),
        ),
    }
}

async fn export_noise(State(shared): State<Arc<Shared>>) -> Response {
    let frame: Arc<Frame> = shared.worker.frames().borrow().clone();
    let text = match frame.noise {
        Some(n) => format!(
            "{} spp, about {:.3} % relative RMS error\n",
            frame.spp,
            n * 100.0
        ),
        None => format!("{} spp, noise not estimated yet\n", frame.spp),
    };
    ([(header::CONTENT_TYPE, "text/plain; charset=utf-8")], text).into_response()
}

async fn export_scene(State(shared): State<Arc<Shared>>) -> Response {
    let text = lock(&shared).text.clone();
    (
        [
            (header::CONTENT_TYPE, "text/plain; charset=utf-8"),
            (
                header::CONTENT_DISPOSITION,
                "attachment; filename=\"scene.ron\"",
            ),
        ],
        text,
    )
        .into_response()
}

/// Opens `url` in the desktop's browser, if there is one.
fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else {
        "xdg-open"
    };
    let _ = std::process::Command::new(opener)
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn();
}
