//! The floor's indirect light gathered along lines across the image.
//!
//! A floor point's indirect fluence is `∫ L(x, φ) dφ` over the circle:
//! what reaches it from every direction after walls, mirrors and glass.
//! In the plane, every point of a line between two walls that the line
//! crosses looks along it at the same two wall points: one in each
//! direction. So one line across the image, cut at the walls it crosses,
//! gives every pixel it passes two directions' radiance for two path
//! continuations per piece, where a pixel's own path sample gives one
//! pixel one direction. These are global lines (Sbert 1996, for
//! radiosity), read here as a gather: the track-length estimator of the
//! light tracer (`light_tracer::Grid`) with the radiance that a path from
//! the floor would bring in place of a photon's power.
//!
//! A pass draws `n` directions `θ_k` ([`DIRECTIONS_PER_SAMPLE`] per pixel
//! sample) in two halves, each stratified over a half turn. A direction's
//! lines cross the pixel grid's axis nearer to their normal once a pixel,
//! all at one random shift, `Δs` apart across their direction; a line's
//! piece of track length `ℓ` in a pixel adds
//! `(L(θ) + L(θ + π)) ℓ π Δs / n`, divided by the pixel's area. For any
//! point, the lines of one direction pass within `ds` of it with
//! probability `ds / Δs`, so the sum estimates the pixel's mean fluence
//! without bias; and every column (or row) of pixels holds exactly one
//! line's worth of track in each pixel, so the track lengths add no
//! noise of their own. The radiance of each
//! piece is what [`path_finish`] returns from the piece's middle, the
//! same continuation (wall memo, onward memo, mirrors, glass, caustic
//! bins, the closed forms' exclusions) that a pixel's path sample takes
//! after its first ray: along a piece it does not change, as no kernel
//! acts after the floor and the scenes this runs in have no absorbing
//! glass (`Plan::floor_lines`).
//!
//! The noise estimate's two halves are two independent sets of
//! directions, each over the whole half turn. The work is cut into
//! chunks of directions, each summed in order into its own buffer and
//! merged in chunk order (`film::run`), so the result does not depend on
//! the number of threads. It never samples per pixel: the floor memo
//! takes the direct light, and pixels take no path samples where lines
//! run.

use flatray_geometry::{DVec2, Ray, Skip};

use crate::film::{Estimator, Film, Part, run};
use crate::light_tracer::Grid;
use crate::options::{RenderOptions, Window, image_size};
use crate::passes::Pass;
use crate::path::{Trace, path_finish};
use crate::sampling::Stream;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Directions of lines per pixel sample of a pass: each gives every
/// pixel two directions (`θ` and `θ + π`).
pub const DIRECTIONS_PER_SAMPLE: f64 = 8.0;
/// Lines of one direction per pixel, across the pixel grid's axis nearer
/// to the lines' normal: each pixel's square holds exactly this many
/// lines' worth of track, whatever their shift.
pub const LINES_PER_PIXEL: u32 = 1;

/// Where lines run, they report this fraction (one over it) of a pass's
/// pixel samples to the progress callback as their directions are done,
/// and the pixels' tiles the rest: the lines take most of the time.
pub(crate) const LINE_PROGRESS: u64 = 2;

/// The stream index of a direction's numbers, apart from every other
/// stream of the pass.
const LINES_STREAM: u64 = (1 << 44) + (1 << 30);
/// Buffers of all chunks together stay within this many bytes.
const CHUNK_BUDGET: usize = 64 << 20;
/// The most chunks a pass is cut into.
const MAX_CHUNKS: usize = 16;

/// Lines run where a direction's lines are cut into at most this many
/// pieces per pixel, on average over directions ([`pieces_per_pixel`]).
/// A piece costs three ray queries and two path continuations, and serves
/// the pixels along it: in a plan of walls a few pixels apart (a maze)
/// each piece serves a pixel or two, and a pixel's own path samples cost
/// less for the same noise.
pub const MAX_PIECES_PER_PIXEL: f64 = 0.1;

/// The pieces that one direction's lines are cut into, on average over
/// directions, per pixel of a `size` image of `scene`: the lines, and the
/// crossings with the walls that meet the canvas (a wall of length `ℓ`
/// crosses `2ℓ / (π s)` lines `s` apart, on average over directions).
pub(crate) fn pieces_per_pixel(scene: &Scene, (width, height): (u32, u32)) -> f64 {
    let step = scene.canvas.pixel_step((width, height));
    let spacing = step.x.min(step.y) / LINES_PER_PIXEL as f64;
    let lo = scene.canvas.origin;
    let hi = lo + DVec2::new(width as f64, height as f64) * step;
    let crossings: f64 = scene
        .walls
        .iter()
        .filter(|w| {
            let (l, h) = w.shape.bounds();
            l.x <= hi.x && l.y <= hi.y && h.x >= lo.x && h.y >= lo.y
        })
        .map(|w| 2.0 * w.shape.length() / (std::f64::consts::PI * spacing))
        .sum();
    let lines = (hi - lo).length() / spacing;
    let pixels = (width as f64 * height as f64).max(1.0);
    (lines + crossings) / pixels
}

/// What the lines of one pass gathered: the mean indirect fluence of each
/// pixel, and that of the first half of the directions.
pub(crate) struct Lines {
    floor: Vec<Rgb>,
    first: Vec<Rgb>,
}

impl Lines {
    /// Pixel `k`'s indirect fluence, from all the directions.
    pub fn floor_at(&self, k: usize) -> Rgb {
        self.floor.get(k).copied().unwrap_or(Rgb::ZERO)
    }

    /// Pixel `k`'s indirect fluence as each half of the directions
    /// estimates it, each scaled to the whole.
    pub fn floor_halves(&self, k: usize) -> (Rgb, Rgb) {
        crate::film::split(&self.floor, &self.first, k, (2, 1))
    }
}

/// One pass's lines as units of the render loop: a chunk of directions
/// each.
struct LinePass<'a> {
    trace: Trace<'a>,
    size: (u32, u32),
    grid: Grid,
    /// The canvas, in world units (lower and upper corners): lines are
    /// laid out over it and walked across it whole, so that a window's
    /// pixels take exactly what the whole image's do.
    lo: DVec2,
    hi: DVec2,
    /// The window's part of the canvas (all of it without one): lines
    /// that miss it are left out.
    window: (DVec2, DVec2),
    /// Directions per half, and the chunks of each half.
    per_half: u64,
    chunks_per_half: usize,
    /// A pixel's width and height, in world units.
    pixel: DVec2,
    seed: u64,
    /// The sample indices whose onward memo copy each half reads.
    samples: (u32, u32),
    /// The pixel samples the lines report as done, over all directions.
    work: u64,
}

/// Gathers one pass's indirect light on the floor along lines, for the
/// pixels of `window` (the whole image without one).
pub(crate) fn gather_lines(
    trace: Trace,
    options: &RenderOptions,
    pass: &Pass,
    stats: &mut Stats,
    progress: &(dyn Fn(u64) + Sync),
) -> Lines {
    let scene = trace.scene;
    let (width, height) = image_size(scene, options.scale);
    let step = scene.canvas.pixel_step((width, height));
    let corner = |x: u32, y: u32| scene.canvas.origin + DVec2::new(x as f64, y as f64) * step;
    let (lo, hi) = (corner(0, 0), corner(width, height));
    // The first pass measures the split of its noise at probe pixels all
    // over the image (`passes::is_probe`), outside a window too: its lines
    // cover the whole canvas, so that a window takes the whole render's
    // floor points.
    let window = match options.window.filter(|_| pass.index > 0) {
        Some(Window { x0, y0, x1, y1 }) => (corner(x0, y0), corner(x1, y1)),
        None => (lo, hi),
    };
    let per_half = ((pass.count() as f64 * DIRECTIONS_PER_SAMPLE / 2.0).ceil() as u64).max(1);
    let pixels = width as usize * height as usize;
    let chunks_per_half = (CHUNK_BUDGET / (2 * pixels * 24).max(1))
        .clamp(1, MAX_CHUNKS / 2)
        .min(per_half as usize);
    // The pixels whose samples the progress counts: the tiles' that meet
    // the window (whole tiles, as the pixels' tiles count them).
    let pixels_counted = match options.window {
        Some(Window { x0, y0, x1, y1 }) => {
            let tile = crate::options::TILE;
            let (x0, y0) = (x0 / tile * tile, y0 / tile * tile);
            let x1 = x1.div_ceil(tile).saturating_mul(tile).min(width);
            let y1 = y1.div_ceil(tile).saturating_mul(tile).min(height);
            x1.saturating_sub(x0) as u64 * y1.saturating_sub(y0) as u64
        }
        None => pixels as u64,
    };
    let line_pass = LinePass {
        trace,
        size: (width, height),
        grid: Grid::new(scene, options.scale, width, height),
        lo,
        hi,
        window,
        per_half,
        chunks_per_half,
        pixel: step,
        seed: pass.seed,
        samples: (pass.samples.start, pass.middle),
        work: pixels_counted * pass.count() as u64 / LINE_PROGRESS,
    };
    let outcome = run(&line_pass, Stats::default(), progress);
    stats.merge(&outcome.stats);
    outcome.output
}

impl LinePass<'_> {
    /// The radiance reaching `x` from direction `-dir` (looking along
    /// `dir`): a path sample's value after its first ray, less the `2π`
    /// of its direction's density. `hit` is where that ray meets the
    /// walls.
    fn radiance(
        &self,
        ray: Ray,
        hit: Option<(u32, flatray_geometry::Hit)>,
        sample: u32,
        stream: &mut Stream,
        stats: &mut Stats,
    ) -> Rgb {
        let value = path_finish(
            &self.trace,
            Rgb::ZERO,
            ray,
            hit,
            None,
            sample,
            stream,
            stats,
        );
        value / std::f64::consts::TAU
    }

    /// Walks the line `base + t dir` across the canvas,
    /// adding `weight` times the radiance both ways of each piece between
    /// walls to the pixels it crosses.
    #[allow(clippy::too_many_arguments)]
    fn walk(
        &self,
        (base, dir): (DVec2, DVec2),
        weight: f64,
        sample: u32,
        floor: &mut [Rgb],
        stream: &mut Stream,
        stats: &mut Stats,
    ) {
        let segments = &self.trace.scene.segments;
        let Some((t0, t1)) = clip(base, dir, self.lo, self.hi) else {
            return;
        };
        // A crossing found at `t` is stepped over by this much (far below
        // a pixel, far above rounding): any other within it (a corner) is
        // left out, with the track it would cut.
        let eps = 1e-9 * (base.abs().max_element() + t0.abs().max(t1.abs()))
            + 1e-6 * self.pixel.min_element();
        let mut t = t0;
        // A line crosses a segment once and an arc at most twice; a few
        // more for a crossing found again past the step by rounding.
        let most = 2 * self.trace.scene.walls.len() + 8;
        for _ in 0..most {
            let start = base + dir * t;
            let ahead = segments.closest_hit(&Ray::new(start, dir), f64::INFINITY, Skip::NONE);
            let t_hit = ahead.map_or(f64::INFINITY, |(_, h)| t + h.t);
            let end = t_hit.min(t1);
            if end > t {
                stats.work.line_pieces += 1;
                let middle = 0.5 * (t + end);
                let x = base + dir * middle;
                let forward = self.radiance(
                    Ray::new(x, dir),
                    ahead.map(|(i, h)| {
                        (
                            i,
                            flatray_geometry::Hit {
                                t: t_hit - middle,
                                u: h.u,
                            },
                        )
                    }),
                    sample,
                    stream,
                    stats,
                );
                // Looked for, not taken from the last crossing: a wall
                // stepped over within `eps` of it may be the nearer.
                let back = Ray::new(x, -dir);
                let back_hit = segments.closest_hit(&back, f64::INFINITY, Skip::NONE);
                let backward = self.radiance(back, back_hit, sample, stream, stats);
                let power = (forward + backward) * weight;
                if !power.is_finite() {
                    // Left out and counted, as a path sample would be
                    // (at the piece's middle's pixel).
                    let (px, py) = self.grid.pixel_at(x);
                    stats.record_nonfinite(px, py, sample);
                } else if power != Rgb::ZERO {
                    self.grid
                        .deposit_flat(&Ray::new(start, dir), end - t, power, floor);
                }
            }
            if ahead.is_none() || t_hit >= t1 {
                break;
            }
            t = t_hit + eps;
        }
    }
}

/// The range of `t` for which `base + t dir` lies in the rectangle
/// `lo..hi`, if any of it does.
fn clip(base: DVec2, dir: DVec2, lo: DVec2, hi: DVec2) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for (o, d, l, h) in [(base.x, dir.x, lo.x, hi.x), (base.y, dir.y, lo.y, hi.y)] {
        let (l, h) = (l.min(h), l.max(h));
        if d == 0.0 {
            if o < l || o > h {
                return None;
            }
            continue;
        }
        let (a, b) = ((l - o) / d, (h - o) / d);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 < t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
}

impl Estimator for LinePass<'_> {
    type Output = Lines;

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn units(&self) -> usize {
        2 * self.chunks_per_half
    }

    fn render_unit(
        &self,
        chunk: usize,
        stats: &mut Stats,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Part {
        let mut floor = vec![Rgb::ZERO; self.size.0 as usize * self.size.1 as usize];
        let half = (chunk >= self.chunks_per_half) as u64;
        let within = chunk % self.chunks_per_half;
        let sample = if half == 0 {
            self.samples.0
        } else {
            self.samples.1
        };
        // Both halves' directions weigh alike: each half's sum is half
        // the estimate, and `Lines::floor_halves` scales each to the whole.
        let n = 2 * self.per_half;
        let (lo, hi) = (self.lo, self.hi);
        let centre = 0.5 * (lo + hi);
        let directions = 2 * self.per_half;
        for k in (within as u64..self.per_half).step_by(self.chunks_per_half) {
            let direction = half * self.per_half + k;
            // This direction's share of the work, so that the shares sum
            // to the whole; reported before the walk, as a heartbeat too.
            let share = |d: u64| (self.work as u128 * d as u128 / directions as u128) as u64;
            progress(share(direction + 1) - share(direction));
            let mut stream = Stream::new(self.seed, direction, LINES_STREAM);
            let angle = std::f64::consts::PI * (k as f64 + stream.uniform()) / self.per_half as f64;
            let dir = DVec2::new(angle.cos(), angle.sin());
            // The lines cross the axis nearer to their normal at a fixed
            // step, `LINES_PER_PIXEL` to a pixel, from a random shift:
            // every column (or row) of pixels then holds exactly that many
            // lines' worth of track in each pixel's square, so the lines
            // cover each pixel exactly, whatever the shift and direction.
            let shift = stream.uniform();
            let across_y = dir.x.abs() >= dir.y.abs();
            // The axis the lines are spaced along, a pixel's size on it,
            // and how far a line drifts along it across half the canvas.
            let (axis, size, drift) = if across_y {
                (1, self.pixel.y, (dir.y / dir.x).abs())
            } else {
                (0, self.pixel.x, (dir.x / dir.y).abs())
            };
            let other = 1 - axis;
            let h = size / LINES_PER_PIXEL as f64;
            // The spacing across the lines, for the weight.
            let spacing = h * if across_y { dir.x.abs() } else { dir.y.abs() };
            let weight = std::f64::consts::PI * spacing / n as f64;
            // Line `j` crosses the centre's line along the other axis at
            // `centre + (j + shift) h`; those that can meet the canvas,
            // and of them those that can meet the window.
            let at = |v: f64| (v - centre[axis]) / h - shift;
            let reach = |l: DVec2, u: DVec2| {
                let span = drift
                    * (u[other] - centre[other])
                        .abs()
                        .max((l[other] - centre[other]).abs());
                (
                    at(l[axis] - span).floor() as i64,
                    at(u[axis] + span).ceil() as i64,
                )
            };
            let (first, _) = reach(lo, hi);
            let (from, to) = reach(self.window.0, self.window.1);
            for j in from..=to {
                let mut base = centre;
                base[axis] = centre[axis] + (j as f64 + shift) * h;
                // Each line draws from its own stream, numbered from the
                // canvas's first line, so that a window changes no bit.
                let line = (j - first).max(0) as u64;
                let mut stream = Stream::new(self.seed, direction, LINES_STREAM + 1 + line);
                stats.work.lines += 1;
                self.walk((base, dir), weight, sample, &mut floor, &mut stream, stats);
            }
        }
        Part::Splats {
            fluence: floor,
            walls: Vec::new(),
            first_half: half == 0,
        }
    }

    fn finish(&self, film: Film, _stats: &mut Stats) -> Lines {
        // Every chunk splats the whole floor, and each half has one, so
        // both sums are whole; `Lines` reads them by `get` all the same.
        Lines {
            floor: film.fluence,
            first: film.first,
        }
    }
}
