//! The film and the render loop: where estimators put what they measure,
//! and the one loop that runs them.
//!
//! An [`Estimator`] splits its work into units (a tile of pixels, a chunk
//! of photons), renders each unit alone into a [`Part`] of the film, and
//! finishes the merged film into an image. [`run`] renders the units in
//! parallel and merges them in unit order, so the image and the
//! statistics are the same for any number of threads. It knows nothing of
//! lights, materials or paths.

use rayon::prelude::*;

use crate::{Rgb, Stats};

/// One pixel's sums over its samples: of all, and of a first half (a
/// pass's own first half of samples; in the totals, the noise estimate's
/// first half: `passes::fold`), whose difference from the rest estimates the
/// noise.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PixelSums {
    pub all: Rgb,
    pub first: Rgb,
}

/// A pixel's sum of sample values in one pass, and apart the sum of its
/// first half of samples (those below `half`), whose difference from the
/// second half estimates the pixel's noise. The sum of all is taken in
/// the same order with or without the halves: the image does not change.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sums {
    pub(crate) all: Rgb,
    pub(crate) first: Rgb,
    pub(crate) half: u32,
}

impl Sums {
    pub(crate) fn new(half: u32) -> Sums {
        Sums {
            all: Rgb::ZERO,
            first: Rgb::ZERO,
            half,
        }
    }

    #[inline(always)]
    pub(crate) fn add(&mut self, sample: u32, value: Rgb) {
        self.all += value;
        if sample < self.half {
            self.first += value;
        }
    }
}

/// What one unit of work measured.
pub(crate) enum Part {
    /// The sums of a tile's pixels for one pass, row by row.
    Tile {
        x0: u32,
        y0: u32,
        width: u32,
        values: Vec<PixelSums>,
    },
    /// Fluence deposited anywhere on the image (a light tracer's track
    /// lengths), and on the walls' bins (the caustic pass's), summed in
    /// the unit's own order. `first_half` says whether the unit belongs to
    /// the first half of the estimator's work, whose floor deposits are
    /// kept apart for the noise estimate.
    Splats {
        fluence: Vec<Rgb>,
        walls: Vec<Rgb>,
        first_half: bool,
    },
}

/// The merged parts of a render.
pub(crate) struct Film {
    pub width: u32,
    pub height: u32,
    /// Pixel sums, from tiles (empty when no unit was a tile).
    pub values: Vec<PixelSums>,
    /// Summed deposits (empty when no unit splatted).
    pub fluence: Vec<Rgb>,
    /// Summed deposits of the units of the first half.
    pub first: Vec<Rgb>,
    /// Summed deposits on the walls (empty when none).
    pub walls: Vec<Rgb>,
}

impl Film {
    fn new(width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            values: Vec::new(),
            fluence: Vec::new(),
            first: Vec::new(),
            walls: Vec::new(),
        }
    }

    /// Adds a part; parts must come in unit order.
    fn add(&mut self, part: Part) {
        let pixels = self.width as usize * self.height as usize;
        match part {
            Part::Tile {
                x0,
                y0,
                width,
                values,
            } => {
                if self.values.is_empty() {
                    self.values = vec![PixelSums::default(); pixels];
                }
                for (k, value) in values.into_iter().enumerate() {
                    let x = x0 + k as u32 % width;
                    let y = y0 + k as u32 / width;
                    self.values[(y * self.width + x) as usize] = value;
                }
            }
            Part::Splats {
                fluence,
                walls,
                first_half,
            } => {
                let add = |sums: &mut Vec<Rgb>, values: &[Rgb]| {
                    sums.resize(values.len(), Rgb::ZERO);
                    for (s, f) in sums.iter_mut().zip(values) {
                        *s += *f;
                    }
                };
                debug_assert_eq!(fluence.len(), pixels);
                add(&mut self.fluence, &fluence);
                if first_half {
                    add(&mut self.first, &fluence);
                }
                if !walls.is_empty() {
                    add(&mut self.walls, &walls);
                }
            }
        }
    }
}

impl Film {
    /// For pixel `k`'s deposits, made by `all` paths (or photons) of which
    /// `first` were in the first half of the units: the estimates of the
    /// two halves, each scaled to the whole; the whole's twice when one
    /// half is empty.
    pub fn split(&self, k: usize, (all, first): (u64, u64)) -> (Rgb, Rgb) {
        split(&self.fluence, &self.first, k, (all, first))
    }
}

/// For pixel `k` of deposits `fluence` made by `all` paths, `first` of
/// them summed apart in `first_sums`: the two halves' estimates, each
/// scaled to the whole, or the whole's twice when a half is empty.
pub(crate) fn split(
    fluence: &[Rgb],
    first_sums: &[Rgb],
    k: usize,
    (all, first): (u64, u64),
) -> (Rgb, Rgb) {
    let whole = fluence.get(k).copied().unwrap_or(Rgb::ZERO);
    if first == 0 || first >= all {
        return (whole, whole);
    }
    let half = first_sums.get(k).copied().unwrap_or(Rgb::ZERO);
    let (p, p1) = (all as f64, first as f64);
    (half * (p / p1), (whole - half) * (p / (p - p1)))
}

/// What the image's pixel `(x, y)` multiplies its mean fluence by: the
/// floor's exact mean albedo over the pixel's square times the exposure,
/// for every estimator.
pub(crate) fn pixel_scale(
    scene: &crate::Scene,
    (width, height): (u32, u32),
    (x, y): (u32, u32),
    exposure: f64,
) -> Rgb {
    let step = scene.canvas.pixel_step((width, height));
    let lo = scene.canvas.origin + flatray_geometry::DVec2::new(x as f64, y as f64) * step;
    scene.floor.mean_albedo(&scene.canvas, lo, lo + step) * exposure
}

/// A way of estimating the image, unit of work by unit of work.
pub(crate) trait Estimator: Sync {
    /// What [`Estimator::finish`] makes of the film: an image, or the
    /// caustic pass's light on the floor and the walls.
    type Output;
    /// The image's size in pixels.
    fn size(&self) -> (u32, u32);
    /// How many units of work; [`run`] merges them in this order.
    fn units(&self) -> usize;
    /// Renders unit `unit` alone, counting into `stats` and reporting
    /// finished samples (or paths) to `progress`.
    fn render_unit(&self, unit: usize, stats: &mut Stats, progress: &(dyn Fn(u64) + Sync)) -> Part;
    /// Turns the merged film into the image (scaling deposits by the floor
    /// albedo and exposure, estimating their noise).
    fn finish(&self, film: Film, stats: &mut Stats) -> Self::Output;
}

/// What [`run`] returns: the estimator's output and everything counted.
pub(crate) struct Outcome<O> {
    pub output: O,
    pub stats: Stats,
}

/// The render loop: every unit in parallel, then the parts merged in unit
/// order into one film, after `stats` (what was counted before the loop,
/// such as filling a cache).
pub(crate) fn run<E: Estimator>(
    estimator: &E,
    mut stats: Stats,
    progress: &(dyn Fn(u64) + Sync),
) -> Outcome<E::Output> {
    // One unit at a time: rayon would otherwise hand a thread a run of
    // units that no other thread can take from, leaving the others idle
    // at the end while it finishes them.
    //
    // A tile's values go into the film as soon as they are made (tiles
    // cover disjoint pixels, so the order of their copies changes no
    // bit), so that the image's sums are held once, not once in the parts
    // and again in the film. Splats are summed, so they wait and are
    // added in unit order, as are the statistics.
    let (width, height) = estimator.size();
    let film = std::sync::Mutex::new(Film::new(width, height));
    let parts: Vec<(Option<Part>, Stats)> = (0..estimator.units())
        .into_par_iter()
        .with_max_len(1)
        .map(|unit| {
            // A heartbeat before each unit: a caller that stops the
            // render from its callback stops it here, before the work.
            progress(0);
            let mut stats = Stats::default();
            let part = match estimator.render_unit(unit, &mut stats, progress) {
                tile @ Part::Tile { .. } => {
                    film.lock()
                        .unwrap_or_else(|poisoned| poisoned.into_inner())
                        .add(tile);
                    None
                }
                splats => Some(splats),
            };
            (part, stats)
        })
        .collect();
    let mut film = film
        .into_inner()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    for (part, unit_stats) in parts {
        stats.merge(&unit_stats);
        if let Some(part) = part {
            film.add(part);
        }
    }
    let output = estimator.finish(film, &mut stats);
    Outcome { output, stats }
}
