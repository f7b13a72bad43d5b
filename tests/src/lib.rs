//! Helpers shared by flatray's end-to-end tests: scenes from text,
//! temporary folders, renders on a chosen number of threads, and running
//! the command line in-process.
//!
//! What it is for: keeping each test short and about one thing. What it
//! never does: hide an assertion; helpers only build inputs and measure.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use flatray_io::Loaded;
use flatray_tracer::{RenderOptions, Rendered, Scene};

/// A scene from RON text, as if read from `test.ron` in the current folder.
///
/// # Panics
/// When the text is not a valid scene: tests give valid text.
pub fn scene(text: &str) -> Loaded {
    match flatray_io::parse(text, Path::new("test.ron"), Path::new(".")) {
        Ok(loaded) => loaded,
        Err(e) => panic!("test scene does not load: {e}"),
    }
}

/// Renders on a pool of exactly `threads` threads.
pub fn render_on(scene: &Scene, options: &RenderOptions, threads: usize) -> Rendered {
    let pool = rayon_pool(threads);
    pool.install(|| flatray_tracer::render(scene, options, &|_| {}))
}

fn rayon_pool(threads: usize) -> rayon::ThreadPool {
    match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(pool) => pool,
        Err(e) => panic!("cannot build a pool of {threads} threads: {e}"),
    }
}

/// Renders on the global pool.
pub fn render(scene: &Scene, options: &RenderOptions) -> Rendered {
    flatray_tracer::render(scene, options, &|_| {})
}

/// The default options with these samples per pixel, bounces and seed.
pub fn options(samples: u32, bounces: u32, seed: u64) -> RenderOptions {
    let mut options = RenderOptions::default();
    options.samples = samples;
    options.bounces = bounces;
    options.seed = seed;
    options
}

/// A folder under the system's temporary folder, removed on drop.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(name: &str) -> TempDir {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("flatray-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        if let Err(e) = std::fs::create_dir_all(&path) {
            panic!("cannot create {}: {e}", path.display());
        }
        TempDir(path)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }

    /// Writes `text` to `name` inside the folder and returns its path.
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        if let Err(e) = std::fs::write(&path, text) {
            panic!("cannot write {}: {e}", path.display());
        }
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// What a run of the command line returned.
#[derive(Debug)]
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// Runs `flatray ARGS...` in-process.
pub fn flatray(args: &[&str]) -> Run {
    let mut out = Vec::new();
    let mut err = Vec::new();
    let argv = std::iter::once("flatray").chain(args.iter().copied());
    let code = flatray_cli::run(argv, &mut out, &mut err);
    Run {
        code,
        stdout: String::from_utf8_lossy(&out).into_owned(),
        stderr: String::from_utf8_lossy(&err).into_owned(),
    }
}

/// The mean of one channel over the pixels that `keep(x, y)` selects.
pub fn channel_mean(
    image: &flatray_tracer::Image,
    channel: usize,
    keep: impl Fn(u32, u32) -> bool,
) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for y in 0..image.height {
        for x in 0..image.width {
            if keep(x, y) {
                sum += image.get(x, y)[channel] as f64;
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

/// The workspace's root folder.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Channel-summed totals of `block` x `block` pixel squares, row by row.
pub fn block_totals(image: &flatray_tracer::Image, block: u32) -> Vec<f64> {
    let (bw, bh) = (image.width / block, image.height / block);
    let mut totals = vec![0.0; (bw * bh) as usize];
    for y in 0..bh * block {
        for x in 0..bw * block {
            let p = image.get(x, y);
            totals[(y / block * bw + x / block) as usize] += (p[0] + p[1] + p[2]) as f64;
        }
    }
    totals
}

/// Mean and standard error of each block total over `runs` renders with
/// seeds `first_seed..first_seed + runs`. Light tracing spreads one
/// photon over many pixels, so pixels are not independent; runs are.
pub fn block_stats(
    scene: &Scene,
    options: RenderOptions,
    block: u32,
    runs: u64,
    first_seed: u64,
) -> Vec<(f64, f64)> {
    let all: Vec<Vec<f64>> = (0..runs)
        .map(|k| {
            let options = {
                let mut options = options;
                options.seed = first_seed + k;
                options
            };
            block_totals(&render(scene, &options).image, block)
        })
        .collect();
    (0..all[0].len())
        .map(|b| {
            let v: Vec<f64> = all.iter().map(|r| r[b]).collect();
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, (var / n).sqrt())
        })
        .collect()
}

/// Mean and standard deviation of `f` over the unit pixel at `(x, y)`, by
/// an `n` x `n` midpoint rule: the exact mean of a jittered pixel, and
/// the spread of one jittered sample.
pub fn pixel_moments(x: u32, y: u32, n: u32, f: impl Fn(glam::DVec2) -> f64) -> (f64, f64) {
    let (mut s1, mut s2) = (0.0, 0.0);
    for j in 0..n {
        for i in 0..n {
            let p = glam::DVec2::new(
                x as f64 + (i as f64 + 0.5) / n as f64,
                y as f64 + (j as f64 + 0.5) / n as f64,
            );
            let v = f(p);
            s1 += v;
            s2 += v * v;
        }
    }
    let count = (n * n) as f64;
    let mean = s1 / count;
    (mean, (s2 / count - mean * mean).max(0.0).sqrt())
}

/// How light tracing and path tracing are held to each other: block
/// totals of `block` x `block` pixels over `runs` seeds from
/// `first_seed`, within `k` combined standard errors, on at least
/// `min_blocks` blocks.
#[derive(Clone, Copy, Debug)]
pub struct Agreement {
    pub block: u32,
    pub runs: u64,
    pub first_seed: u64,
    pub k: f64,
    pub min_blocks: usize,
}

impl Agreement {
    /// Renders `scene` with `options` by light tracing and by path
    /// tracing (`options.integrator` is replaced) and checks every block
    /// that `keep` keeps; returns the path tracer's block statistics.
    pub fn check(
        &self,
        name: &str,
        scene: &Scene,
        options: RenderOptions,
        keep: impl Fn(usize) -> bool,
    ) -> Vec<(f64, f64)> {
        let at = |integrator| {
            let mut options = options;
            options.integrator = integrator;
            options
        };
        let stats = |integrator| {
            block_stats(
                scene,
                at(integrator),
                self.block,
                self.runs,
                self.first_seed,
            )
        };
        let light = stats(flatray_tracer::Integrator::Light);
        let path = stats(flatray_tracer::Integrator::Path);
        let k = self.k;
        let mut checked = 0;
        for (b, ((ml, sl), (mp, sp))) in light.iter().zip(&path).enumerate() {
            if !keep(b) {
                continue;
            }
            let se = (sl * sl + sp * sp).sqrt();
            assert!(
                (ml - mp).abs() <= k * se + 1e-9 * mp.abs(),
                "{name}, block {b}: light {ml}, path {mp}, {k} SE = {}",
                k * se
            );
            checked += 1;
        }
        assert!(checked >= self.min_blocks, "{name}: only {checked} blocks");
        path
    }
}
