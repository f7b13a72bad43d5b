//! The live view's render worker: one thread that renders the newest
//! scene it is given and publishes each frame to every open page.
//!
//! For each scene: first a quick frame (at most [`QUICK_SIDE`] pixels a
//! side, [`QUICK_SPP`] samples), then the full size pass after pass, as
//! `render --target-error` takes them (16 spp, then doubling): after each
//! pass the image is exactly the single render of the samples reached. A
//! new scene stops the pass being rendered at once. The worker stops at
//! [`TARGET_NOISE`] or [`MAX_SPP`] and waits for the next scene.

use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use flatray_io::{Loaded, ToneMap};
use flatray_tracer::Image;
use tokio::sync::watch;

/// The quick first frame's longest side, in pixels, and its samples.
const QUICK_SIDE: u32 = 128;
const QUICK_SPP: u32 = 2;
/// Where the worker stops refining: the estimated noise (the root of
/// relMSE, each pixel's error relative to its own value), or the samples
/// per pixel.
const TARGET_NOISE: f64 = 0.01;
const MAX_SPP: u32 = 1 << 16;

/// A scene to render, with the version of the page's state it is.
pub(crate) struct Job {
    version: u64,
    loaded: Arc<Loaded>,
}

impl Job {
    pub(crate) fn new(version: u64, loaded: Loaded) -> Job {
        Job {
            version,
            loaded: Arc::new(loaded),
        }
    }
}

/// What the pages show: the latest image and how far it has come.
#[derive(Clone, Default)]
pub(crate) struct Frame {
    /// Raised at every frame.
    pub number: u64,
    /// The version of the scene it shows.
    pub job: u64,
    /// The image as PNG, tone-mapped.
    pub png: Option<Arc<Vec<u8>>>,
    /// The full-size image, linear, and its tone map (none for the quick
    /// frame).
    pub full: Option<(Arc<Image>, ToneMap)>,
    pub spp: u32,
    /// Full-size passes taken.
    pub passes: u32,
    pub quick: bool,
    pub noise: Option<f64>,
    pub width: u32,
    pub height: u32,
    /// Seconds from the scene's arrival to this frame.
    pub seconds: f64,
}

pub(crate) struct Worker {
    jobs: Mutex<Sender<Job>>,
    frames: Arc<watch::Sender<Arc<Frame>>>,
    latest: Arc<AtomicU64>,
}

impl Worker {
    pub(crate) fn start() -> Worker {
        let (jobs, incoming) = channel();
        let (frames, _) = watch::channel(Arc::new(Frame::default()));
        let frames = Arc::new(frames);
        let latest = Arc::new(AtomicU64::new(0));
        let (out, newest) = (Arc::clone(&frames), Arc::clone(&latest));
        std::thread::spawn(move || run(&incoming, &out, &newest));
        Worker {
            jobs: Mutex::new(jobs),
            frames,
            latest,
        }
    }

    /// Renders `job` from now on, dropping whatever was being rendered.
    pub(crate) fn submit(&self, job: Job) {
        self.latest.store(job.version, Ordering::SeqCst);
        if let Ok(jobs) = self.jobs.lock() {
            let _ = jobs.send(job);
        }
    }

    /// The frames, newest first; a new receiver sees the current one.
    pub(crate) fn frames(&self) -> watch::Receiver<Arc<Frame>> {
        self.frames.subscribe()
    }

    /// Tells the pages that the state changed without a new frame (a
    /// scene on disk that does not load, a conflict with the file): they
    /// are sent the last frame again, with the state's news.
    pub(crate) fn announce(&self) {
        self.frames.send_modify(|frame| {
            let mut next = Frame::clone(frame);
            next.number += 1;
            *frame = Arc::new(next);
        });
    }
}

/// Why a render stopped midway: its scene was replaced.
struct Replaced;

fn run(incoming: &Receiver<Job>, frames: &watch::Sender<Arc<Frame>>, latest: &AtomicU64) {
    let mut number = 0u64;
    let mut next = incoming.recv().ok();
    while let Some(job) = next.take() {
        next = show(&job, incoming, frames, latest, &mut number);
        if next.is_none() {
            // Refined as far as it goes: wait for the next scene.
            next = incoming.recv().ok();
        }
    }
}

/// The newest job waiting, if any.
fn newest(incoming: &Receiver<Job>) -> Option<Job> {
    let mut newest = None;
    while let Ok(job) = incoming.try_recv() {
        newest = Some(job);
    }
    newest
}

/// Renders `job`, the quick frame and then pass after pass, publishing
/// each; returns a newer job as soon as one comes.
fn show(
    job: &Job,
    incoming: &Receiver<Job>,
    frames: &watch::Sender<Arc<Frame>>,
    latest: &AtomicU64,
    number: &mut u64,
) -> Option<Job> {
    let started = Instant::now();
    let loaded = &job.loaded;
    let version = job.version;
    let mut publish = |image: Image, spp: u32, passes: u32, noise: Option<f64>, quick: bool| {
        *number += 1;
        let (width, height) = (image.width, image.height);
        let png = flatray_io::png_bytes(&image, loaded.tonemap)
            .ok()
            .map(Arc::new);
        frames.send_replace(Arc::new(Frame {
            number: *number,
            job: version,
            png,
            full: (!quick).then(|| (Arc::new(image), loaded.tonemap)),
            spp,
            passes,
            quick,
            noise,
            width,
            height,
            seconds: started.elapsed().as_secs_f64(),
        }));
    };
    // The quick frame, without the cache: for so few samples, filling it
    // would cost more than the shadow rays it saves.
    let quick = {
        let mut options = loaded.options;
        options.scale = quick_scale(loaded);
        options.samples = QUICK_SPP;
        options.memo.enabled = false;
        options
    };
    let rendered = stoppable(version, latest, |progress| {
        flatray_tracer::render(&loaded.scene, &quick, progress)
    });
    match rendered {
        Some(r) => publish(r.image, QUICK_SPP, 0, r.stats.noise.relmse(), true),
        None => return newest(incoming),
    }
    if let Some(newer) = newest(incoming) {
        return Some(newer);
    }
    let options = {
        let mut options = loaded.options;
        options.scale = 1.0;
        options
    };
    let mut progressive = flatray_tracer::Progressive::new(&loaded.scene, &options);
    let mut passes = 0;
    loop {
        let done = progressive.samples();
        // The schedule's end: nothing more to refine.
        let end = progressive.next_end().map(|e| e.min(MAX_SPP))?;
        if end <= done {
            return None;
        }
        let taken = stoppable(version, latest, |progress| progressive.pass(end, progress));
        if taken.is_none() {
            return newest(incoming);
        }
        passes += 1;
        let rendered = progressive.rendered();
        let noise = rendered.stats.noise.relmse();
        publish(rendered.image, progressive.samples(), passes, noise, false);
        if noise.is_some_and(|n| n <= TARGET_NOISE) {
            return None;
        }
        if let Some(newer) = newest(incoming) {
            return Some(newer);
        }
    }
}

/// The scale at which the canvas's longest side is at most [`QUICK_SIDE`].
fn quick_scale(loaded: &Loaded) -> f64 {
    let side = loaded
        .scene
        .canvas()
        .width
        .max(loaded.scene.canvas().height)
        .max(1);
    (QUICK_SIDE as f64 / side as f64).min(1.0)
}

/// Runs `work` (a render given a progress callback), or stops it and
/// returns `None` once a newer scene than `version` has come. The
/// library's render cannot be asked to stop; its progress callback,
/// called before and after each unit of work, unwinds out of the render
/// with a private payload when the scene is replaced, and that unwinding
/// is caught here (no message, and nothing of the stopped render is used
/// again).
fn stoppable<T>(
    version: u64,
    latest: &AtomicU64,
    work: impl FnOnce(&(dyn Fn(u64) + Sync)) -> T,
) -> Option<T> {
    let progress = |_: u64| {
        if latest.load(Ordering::SeqCst) != version {
            std::panic::resume_unwind(Box::new(Replaced));
        }
    };
    if latest.load(Ordering::SeqCst) != version {
        return None;
    }
    match std::panic::catch_unwind(AssertUnwindSafe(|| work(&progress))) {
        Ok(done) if latest.load(Ordering::SeqCst) == version => Some(done),
        Ok(_) => None,
        Err(payload) if payload.is::<Replaced>() => None,
        Err(payload) => std::panic::resume_unwind(payload),
    }
}
