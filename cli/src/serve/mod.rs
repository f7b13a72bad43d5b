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
//!
//! Every request passes `guard` first (only this server's own page may
//! change anything), and the file is read and written through `disk`
//! (regular files only, never a read-only one, backups kept). Edits made
//! in the page are never replaced without the user's word: a change on
//! disk while the page has unsaved edits is held as a conflict that the
//! page shows, and a save refuses to overwrite a file that changed since
//! it was loaded unless told to.

mod disk;
mod guard;
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
use guard::Guard;
use tokio_stream::StreamExt;
use tokio_stream::wrappers::WatchStream;

use crate::{Failure, stamp};
use render::{Frame, Job, Worker};

/// The page, served with its token in place of [`TOKEN_SLOT`].
const PAGE: &str = include_str!("page.html");

/// Where the page holds the token it sends with every change.
const TOKEN_SLOT: &str = "{{TOKEN}}";

/// How often the scene file is looked at for changes made elsewhere.
const WATCH_EVERY: Duration = Duration::from_millis(250);

#[derive(Debug, clap::Args)]
pub(crate) struct ServeArgs {
    /// The scene file (RON): rendered, edited, saved back. Or a Universal
    /// VTT map (.dd2vtt, .uvtt, .df2vtt): imported first into MAP.ron
    /// beside it (with its floor image), which is then served; where
    /// MAP.ron exists, it is served as it is.
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
    /// The scene file as the user named it, for messages.
    shown: PathBuf,
    /// The file itself, read, watched and saved (a symbolic link resolved
    /// once, when the server starts, so that a save replaces the file it
    /// points at, and a link put in its place later is never followed).
    path: PathBuf,
    /// The folder that the scene's own paths (its floor image) are taken
    /// from.
    base: PathBuf,
    guard: Arc<Guard>,
    state: Mutex<Scene>,
    worker: Worker,
}

/// The scene as the page sees it.
struct Scene {
    /// The text being rendered: the file's, with the edits made since.
    text: String,
    /// Texts before each edit, for undo.
    undo: Vec<String>,
    /// The file's identity: the text the page's edits start from (the
    /// file's as last loaded, when it loaded, or as saved), and the file's
    /// modification time and length when last looked at.
    on_disk: String,
    stamp: Option<(SystemTime, u64)>,
    /// The file's text when it changed on disk while the page had edits
    /// not saved: shown on the page, applied only when the user says so.
    conflict: Option<String>,
    /// The last good scene and its items, as JSON.
    items: serde_json::Value,
    /// What is wrong with the file on disk, when a change made there does
    /// not load (the last good scene keeps rendering).
    error: Option<serde_json::Value>,
    /// Raised at each new scene, so the page reloads its items.
    version: u64,
}

pub(crate) fn serve(
    args: ServeArgs,
    out: &mut dyn std::io::Write,
    err: &mut dyn std::io::Write,
) -> Result<(), Failure> {
    let shown = scene_of(&args.scene, out, err)?;
    let base = shown.parent().unwrap_or(Path::new(".")).to_path_buf();
    let path = std::fs::canonicalize(&shown).unwrap_or_else(|_| shown.clone());
    let (text, loaded) = read_scene(&path, &shown).map_err(|e| Failure::usage(e.message))?;
    let items = items_json(&text, &loaded)?;

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
    let guard = Arc::new(Guard::new(bound.port()).map_err(Failure::other)?);

    let worker = Worker::start();
    let shared = Arc::new(Shared {
        shown: shown.clone(),
        path: path.clone(),
        base,
        guard: Arc::clone(&guard),
        state: Mutex::new(Scene {
            on_disk: text.clone(),
            stamp: stamp(&path),
            text,
            undo: Vec::new(),
            conflict: None,
            items,
            error: None,
            version: 1,
        }),
        worker,
    });
    shared.worker.submit(Job::new(1, loaded));

    let url = format!("http://{bound}/");
    if !args.host.is_loopback() {
        let _ = writeln!(
            out,
            "WARNING: listening on {bound}, not on loopback: anyone who can reach this machine can see {} and, with the page, edit it and save it",
            shown.display()
        );
    }
    let _ = writeln!(out, "serving {} at {url} (Ctrl-C to stop)", shown.display());
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
        .route("/api/resolve", post(resolve))
        .route("/api/export.png", get(export_png))
        .route("/api/export.exr", get(export_exr))
        .route("/api/noise.txt", get(export_noise))
        .route("/api/scene.ron", get(export_scene))
        .route("/api/measure.png", post(measure_png))
        .layer(DefaultBodyLimit::max(guard::MAX_BODY))
        .layer(axum::middleware::from_fn_with_state(guard, guard::check))
        .with_state(shared);
    runtime.block_on(guard::run(listener, app));
    Ok(())
}

/// The scene file to serve for `given`: the file itself, or for a
/// Universal VTT map the scene imported from it beside it (imported now
/// unless it exists, so that edits saved from an earlier session are
/// never replaced).
fn scene_of(
    given: &Path,
    out: &mut dyn std::io::Write,
    err: &mut dyn std::io::Write,
) -> Result<PathBuf, Failure> {
    let is_map = given
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["dd2vtt", "uvtt", "df2vtt"].contains(&e.to_ascii_lowercase().as_str()));
    if !is_map {
        return Ok(given.to_path_buf());
    }
    let scene = given.with_extension("ron");
    if std::fs::symlink_metadata(&scene).is_ok() {
        let _ = writeln!(
            out,
            "{} exists: serving it as it is (to import {} again: flatray import {} -o {} --force)",
            scene.display(),
            given.display(),
            given.display(),
            scene.display()
        );
        return Ok(scene);
    }
    let options = flatray_io::import::ImportOptions::default();
    let imported = crate::import_to(given, &options, &scene, false, err)?;
    let _ = writeln!(
        out,
        "imported {} into {} ({imported})",
        given.display(),
        scene.display()
    );
    Ok(scene)
}

/// The text of the scene file at `path` (named `shown` in messages) and
/// what it loads as.
fn read_scene(path: &Path, shown: &Path) -> Result<(String, Loaded), Refusal> {
    let text = disk::read_text(path)
        .map_err(|m| {
            Refusal::plain(m.replace(&path.display().to_string(), &shown.display().to_string()))
        })?
        .ok_or_else(|| Refusal::plain(format!("{}: no such file", shown.display())))?;
    let base = shown.parent().unwrap_or(Path::new("."));
    let loaded = flatray_io::parse(&text, shown, base).map_err(|e| Refusal::of(&e))?;
    Ok((text, loaded))
}

fn load_text(text: &str, shared: &Shared) -> Result<Loaded, Refusal> {
    flatray_io::parse(text, &shared.shown, &shared.base).map_err(|e| Refusal::of(&e))
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

/// Tells the pages that the state changed without a new render.
fn announce(shared: &Shared, scene: &mut Scene) {
    scene.version += 1;
    shared.worker.announce();
}

/// Looks at the scene file every [`WATCH_EVERY`]. A change made elsewhere
/// (an editor's save) is loaded and rendered when the page has no edits
/// of its own to lose; when it has, the change is held as a conflict for
/// the user to settle on the page. A change that does not load is shown
/// on the page, and the last good scene keeps rendering. The file is read
/// with no lock held.
fn watch(shared: &Shared) {
    loop {
        std::thread::sleep(WATCH_EVERY);
        let now = stamp(&shared.path);
        if now == lock(shared).stamp {
            continue;
        }
        let read = disk::read_text(&shared.path);
        // Loaded (its floor image read) with no lock held, and only when
        // it is to be taken: a new text while the page has no edits.
        let parsed = match &read {
            Ok(Some(text))
                if {
                    let scene = lock(shared);
                    *text != scene.on_disk && *text != scene.text && scene.text == scene.on_disk
                } =>
            {
                Some(load_text(text, shared))
            }
            _ => None,
        };
        let mut scene = lock(shared);
        scene.stamp = now;
        let text = match read {
            Ok(Some(text)) => text,
            // Removed, or being replaced: the next look sees the new file.
            Ok(None) => continue,
            Err(message) => {
                scene.error = Some(Refusal::plain(message).json());
                announce(shared, &mut scene);
                continue;
            }
        };
        take_from_disk(shared, &mut scene, text, parsed);
    }
}

/// What the watcher does with the file's new `text`, which loads as
/// `parsed` where it was loaded (when it is to be taken).
fn take_from_disk(
    shared: &Shared,
    scene: &mut Scene,
    text: String,
    parsed: Option<Result<Loaded, Refusal>>,
) {
    let unsaved = scene.text != scene.on_disk;
    if text == scene.on_disk {
        // Back to what the page started from: nothing to settle.
        if scene.conflict.take().is_some() || scene.error.take().is_some() {
            announce(shared, scene);
        }
        return;
    }
    if text == scene.text {
        // The file now holds just what the page shows.
        scene.on_disk = text;
        scene.conflict = None;
        announce(shared, scene);
        return;
    }
    if unsaved {
        scene.conflict = Some(text);
        announce(shared, scene);
        return;
    }
    // A text that does not load is shown as an error, and not taken as
    // what the page follows: the last good scene stays, with no edits of
    // the page's own, and the fixed file is taken when it comes.
    let Some(parsed) = parsed else {
        // The page's state changed between the look and now: look again.
        scene.stamp = None;
        return;
    };
    match parsed {
        Ok(loaded) => {
            scene.on_disk = text.clone();
            let before = std::mem::take(&mut scene.text);
            scene.undo.push(before);
            let _ = adopt(shared, scene, text, loaded);
        }
        Err(refusal) => {
            scene.error = Some(refusal.json());
            announce(shared, scene);
        }
    }
}

/// The page, with this server's token in it. It may not be shown inside
/// another site's frame (where a click could be stolen).
async fn page(State(shared): State<Arc<Shared>>) -> Response {
    (
        [
            (header::CACHE_CONTROL, "no-store"),
            (header::X_FRAME_OPTIONS, "DENY"),
            (header::CONTENT_SECURITY_POLICY, "frame-ancestors 'none'"),
        ],
        Html(PAGE.replace(TOKEN_SLOT, shared.guard.token())),
    )
        .into_response()
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
    value["conflict"] = match &scene.conflict {
        Some(file) => serde_json::json!({"file": file, "mine": scene.text}),
        None => serde_json::Value::Null,
    };
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
    // The edit is made and loaded (its floor image read) with no lock
    // held, then taken if the scene is still the one it was made on.
    let before = lock(&shared).text.clone();
    let (edited, loaded) =
        match flatray_io::edit::apply(&before, &edit, &shared.shown, &shared.base) {
            Ok(done) => done,
            Err(message) => {
                return refused(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    serde_json::json!({"message": message}),
                );
            }
        };
    let mut scene = lock(&shared);
    if scene.text != before {
        return changed_meanwhile();
    }
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

/// A change refused because another came first (from a second page, or
/// the file): the page makes it again on the new scene if it still wants.
fn changed_meanwhile() -> Response {
    refused(
        StatusCode::CONFLICT,
        serde_json::json!({"message": "the scene changed while this change was made (another page, or the file); look, and make it again"}),
    )
}

async fn undo(State(shared): State<Arc<Shared>>) -> Response {
    let (before, last) = {
        let scene = lock(&shared);
        (scene.text.clone(), scene.undo.last().cloned())
    };
    let Some(text) = last else {
        return refused(
            StatusCode::CONFLICT,
            serde_json::json!({"message": "nothing to undo"}),
        );
    };
    // Loaded with no lock held; the undo is taken only once it loads.
    let loaded = load_text(&text, &shared);
    let mut scene = lock(&shared);
    if scene.text != before || scene.undo.last() != Some(&text) {
        return changed_meanwhile();
    }
    match loaded {
        Ok(loaded) => match adopt(&shared, &mut scene, text, loaded) {
            Ok(()) => {
                scene.undo.pop();
                axum::Json(serde_json::json!({"version": scene.version})).into_response()
            }
            Err(f) => refused(
                StatusCode::UNPROCESSABLE_ENTITY,
                serde_json::json!({"message": f.message}),
            ),
        },
        Err(r) => refused(StatusCode::UNPROCESSABLE_ENTITY, r.json()),
    }
}

/// What a save may be told.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SaveRequest {
    /// Replace the file even though it changed on disk since it was
    /// loaded.
    #[serde(default)]
    overwrite: bool,
}

/// Writes the scene being rendered to its file, atomically, the file's
/// previous texts kept beside it (`disk::keep_backup`). Refused, with
/// nothing written, when the file is read-only or not a regular file, and
/// (409) when it changed on disk since it was loaded and the request does
/// not say `overwrite`.
async fn save(State(shared): State<Arc<Shared>>, body: axum::body::Bytes) -> Response {
    let request: SaveRequest = if body.iter().all(u8::is_ascii_whitespace) {
        SaveRequest::default()
    } else {
        match serde_json::from_slice(&body) {
            Ok(request) => request,
            Err(e) => {
                return refused(
                    StatusCode::BAD_REQUEST,
                    serde_json::json!({"message": format!("not a save: {e}")}),
                );
            }
        }
    };
    let shown = |m: String| {
        m.replace(
            &shared.path.display().to_string(),
            &shared.shown.display().to_string(),
        )
    };
    if let Err(message) = disk::check_writable(&shared.path) {
        return refused(
            StatusCode::FORBIDDEN,
            serde_json::json!({"message": shown(message)}),
        );
    }
    // Read with no lock held: the checks above do not rule out a file
    // replaced in between, and a read that waits must not stop the rest.
    let current = match disk::read_text(&shared.path) {
        Ok(current) => current,
        Err(message) => {
            return refused(
                StatusCode::FORBIDDEN,
                serde_json::json!({"message": shown(message)}),
            );
        }
    };
    let mut scene = lock(&shared);
    if let Some(current) = &current
        && *current != scene.on_disk
        && *current != scene.text
        && !request.overwrite
    {
        if scene.conflict.as_ref() != Some(current) {
            scene.conflict = Some(current.clone());
            announce(&shared, &mut scene);
        }
        return refused(
            StatusCode::CONFLICT,
            serde_json::json!({
                "message": format!(
                    "{} changed on disk since it was loaded: saving would lose that change. Keep yours or take the file's, or save with overwrite",
                    shared.shown.display()
                ),
                "changed": true,
            }),
        );
    }
    let backup = match &current {
        Some(previous) => match disk::keep_backup(&shared.path, previous) {
            Ok(path) => Some(path),
            Err(message) => {
                return refused(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    serde_json::json!({"message": shown(message)}),
                );
            }
        },
        None => None,
    };
    if let Err(e) = flatray_io::write_text(&shared.path, &scene.text) {
        return refused(
            StatusCode::INTERNAL_SERVER_ERROR,
            serde_json::json!({"message": shown(e.to_string())}),
        );
    }
    scene.on_disk = scene.text.clone();
    scene.stamp = stamp(&shared.path);
    if scene.conflict.take().is_some() {
        announce(&shared, &mut scene);
    }
    axum::Json(serde_json::json!({
        "saved": shared.shown.display().to_string(),
        "backup": backup.map(|b| b.display().to_string()),
    }))
    .into_response()
}

/// Which side of a conflict the user keeps.
#[derive(Debug, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
enum Side {
    /// The page's edits: they stay, unsaved, and a save may replace the
    /// file's change.
    Mine,
    /// The file's text: it is loaded and rendered; the page's edits can
    /// be had back with undo.
    File,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ResolveRequest {
    keep: Side,
}

/// Settles a conflict between the page's unsaved edits and a change made
/// to the file on disk.
async fn resolve(State(shared): State<Arc<Shared>>, body: axum::body::Bytes) -> Response {
    let request: ResolveRequest = match serde_json::from_slice(&body) {
        Ok(request) => request,
        Err(e) => {
            return refused(
                StatusCode::BAD_REQUEST,
                serde_json::json!({"message": format!("not a choice (expected {{\"keep\": \"mine\"}} or {{\"keep\": \"file\"}}): {e}")}),
            );
        }
    };
    let Some(file) = lock(&shared).conflict.clone() else {
        return refused(
            StatusCode::CONFLICT,
            serde_json::json!({"message": "the file has not changed on disk: there is nothing to choose"}),
        );
    };
    // The file's text is loaded (when it is to be taken) with no lock held.
    let loaded = match request.keep {
        Side::File => Some(load_text(&file, &shared)),
        Side::Mine => None,
    };
    let mut scene = lock(&shared);
    if scene.conflict.as_ref() != Some(&file) {
        return changed_meanwhile();
    }
    match request.keep {
        Side::Mine => {
            scene.on_disk = file;
            scene.conflict = None;
            announce(&shared, &mut scene);
        }
        Side::File => {
            let loaded = match loaded {
                Some(Ok(loaded)) => loaded,
                None => return changed_meanwhile(),
                Some(Err(r)) => {
                    let mut body = r.json();
                    body["message"] = format!(
                        "the file's text does not load, so it cannot be taken (fix it in your editor, or keep yours): {}",
                        r.message
                    )
                    .into();
                    return refused(StatusCode::UNPROCESSABLE_ENTITY, body);
                }
            };
            let before = scene.text.clone();
            if let Err(f) = adopt(&shared, &mut scene, file.clone(), loaded) {
                return refused(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    serde_json::json!({"message": f.message}),
                );
            }
            scene.undo.push(before);
            scene.on_disk = file;
            scene.conflict = None;
        }
    }
    axum::Json(serde_json::json!({"version": scene.version})).into_response()
}

/// The live view's measure of the rooms: `flatray measure`'s figures and
/// map from this many batches of this many samples per pixel in all, a
/// quick look (each figure's error is on the map's labels' scale, not a
/// report's).
const MEASURE_BATCHES: u32 = 4;
const MEASURE_SPP: u32 = 16;

/// The false-colour map of each room's illuminance (`flatray measure
/// --map`: the plan at the canvas's size, then its legend) of the scene as
/// the page has it, edits included; 422 with the reason where it has no
/// room or does not load. Measured apart from the render, on a blocking
/// thread. A `POST`, as a change is: it costs renders, so it is taken only
/// from the page itself, with its token (`guard.rs`).
async fn measure_png(State(shared): State<Arc<Shared>>) -> Response {
    let text = lock(&shared).text.clone();
    let own = Arc::clone(&shared);
    match tokio::task::spawn_blocking(move || measure_map(&text, &own)).await {
        Ok(Ok(bytes)) => png(bytes),
        Ok(Err(message)) => refused(
            StatusCode::UNPROCESSABLE_ENTITY,
            serde_json::json!({"message": message}),
        ),
        Err(_) => refused(
            StatusCode::INTERNAL_SERVER_ERROR,
            serde_json::json!({"message": "the measure stopped"}),
        ),
    }
}

fn measure_map(text: &str, shared: &Shared) -> Result<Vec<u8>, String> {
    let loaded = load_text(text, shared).map_err(|r| r.message)?;
    let request = flatray_io::measure::Request {
        spp: Some(MEASURE_SPP),
        batches: MEASURE_BATCHES,
        scale: 1.0,
        door_width: None,
        target_error: None,
    };
    let (rooms, measured) = flatray_io::measure::run(&loaded, &request, |options| {
        flatray_tracer::render(&loaded.scene, options, &|_| {}).image
    })?;
    flatray_io::measure::map_png(&measured, &rooms, &loaded.scene)
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
            "{} spp, about {:.3} % relMSE (each pixel's error relative to its value)\n",
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
