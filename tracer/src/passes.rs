//! A render as a sequence of passes, each adding samples to the same
//! pixels: 16 samples per pixel, then as many again, then doubling
//! (16, 32, 64, 128, ...), the last pass ending wherever the render's
//! samples do.
//!
//! A pass draws its own per-render fills (the caustic pass's photons, the
//! onward memo's gathers, a light tracer's photons: as many as its own
//! samples ask for, from its own seed) and adds each pixel's sums to the
//! running totals. So a render of `n` samples is the same sequence of
//! passes however it is driven: [`Progressive`] can stop after any pass,
//! look at the noise, and go on, and the image is bit for bit the one
//! [`crate::render`] gives for the samples reached. What is the same for
//! every pass (the wall memo, the light table, the coherence masks, the
//! culling lists) is built once.

use std::ops::Range;

use rayon::prelude::*;

use crate::film::{PixelSums, pixel_scale};
use crate::options::{Image, Rendered, Window};
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Samples per pixel at the end of the first pass.
pub const FIRST_PASS: u32 = 16;

/// Where the pass that starts at `done` samples per pixel ends, if the
/// render goes on past it: the first pass at [`FIRST_PASS`], each later
/// one at twice the samples it starts from.
pub fn next_pass_end(done: u32) -> u32 {
    if done == 0 {
        FIRST_PASS
    } else {
        done.saturating_mul(2)
    }
}

/// How many of a pass's samples each floor point stands for. Where a
/// light table draws the lights a point takes, its direct light is a
/// random estimate: one point per sample. Elsewhere every light's value
/// at a point is exact, and the points only average it over the pixel's
/// square: a point per 4 samples. (Per 16 the room at one bounce took
/// two thirds of the time for the same noise, but a point light's hard
/// shadow edge stopped converging: a later pass's few points weigh as
/// much as its many samples, `direct_light.rs`.)
pub(crate) fn samples_per_point(light_table: bool) -> u32 {
    if light_table { 1 } else { 4 }
}

/// The fewest floor points a pass takes where a point stands for more
/// than one sample (or its samples, if fewer): a render of a few passes
/// keeps a point per sample, where the direct light's position in the
/// pixel can be most of its noise (the tutorial's flat at 32 spp: 1.86 %
/// with 16 a pass, over 2 % with 4).
pub const FEWEST_EXACT_POINTS: u32 = 16;

/// The floor memo's points in one pixel for a pass of `count` samples,
/// each point standing for `per_point` of them ([`samples_per_point`]):
/// never fewer than [`FEWEST_EXACT_POINTS`] (or the samples, if fewer),
/// and at least `fewest`.
pub(crate) fn pass_points(count: u32, fewest: u32, per_point: u32) -> u32 {
    let wanted = if per_point > 1 {
        (count / per_point).max(count.min(FEWEST_EXACT_POINTS))
    } else {
        count
    };
    wanted.max(fewest)
}

/// The floor memo's points per pixel over the passes of a render of
/// `samples` ([`pass_points`] per pass).
pub(crate) fn floor_points(samples: u32, fewest: u32, per_point: u32) -> u64 {
    let mut done = 0;
    let mut points = 0u64;
    while done < samples {
        let end = next_pass_end(done).min(samples);
        points += pass_points(end - done, fewest, per_point) as u64;
        done = end;
    }
    points
}

/// The index of the pass of the schedule that takes sample `sample`: 0
/// below [`FIRST_PASS`], then one more at each doubling.
#[inline(always)]
pub(crate) fn pass_index(sample: u32) -> u32 {
    const _: () = assert!(FIRST_PASS == 16);
    (u32::BITS - (sample | (FIRST_PASS - 1)).leading_zeros()).saturating_sub(4)
}

/// The passes of a render of `samples` samples per pixel, as ranges of
/// sample indices.
#[cfg(test)]
fn passes(samples: u32) -> impl Iterator<Item = Range<u32>> {
    let mut done = 0;
    std::iter::from_fn(move || {
        (done < samples).then(|| {
            let end = next_pass_end(done).min(samples);
            let pass = done..end;
            done = end;
            pass
        })
    })
}

/// One pass: which it is, its samples, and the seed of its fills.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Pass {
    pub index: u32,
    /// The samples it takes (sample indices of each pixel).
    pub samples: Range<u32>,
    /// Samples below this are in the first half, for the noise estimate
    /// (and read the onward memo's first copy).
    pub middle: u32,
    /// The floor memo's points it draws (point indices of each pixel):
    /// as many as its samples, and at least the memo's fewest.
    pub points: Range<u32>,
    /// The seed of the pass's own photons and gathers: the render's for
    /// the first pass, mixed with the pass's index for the others.
    pub seed: u64,
}

impl Pass {
    /// Pass `index`, of `samples`, whose floor points start at
    /// `first_point`, at least `fewest_points` of them.
    pub fn new(
        index: u32,
        samples: Range<u32>,
        (first_point, fewest_points, per_point): (u32, u32, u32),
        seed: u64,
    ) -> Pass {
        let middle = samples.start + (samples.end - samples.start) / 2;
        let count = samples.end - samples.start;
        let points =
            first_point..first_point.saturating_add(pass_points(count, fewest_points, per_point));
        let seed = match index {
            0 => seed,
            i => crate::sampling::derive_seed(seed, PASS_SEEDS + i as u64),
        };
        Pass {
            index,
            samples,
            middle,
            points,
            seed,
        }
    }

    /// Samples per pixel in the pass.
    pub fn count(&self) -> u32 {
        self.samples.end - self.samples.start
    }

    /// How many of them are in the first half.
    pub fn first_count(&self) -> u32 {
        self.middle - self.samples.start
    }

    /// What a pixel adds for the pass from an estimate of its mean value
    /// made in two independent halves (each scaled to the whole), such as
    /// a pass's photons deposit: each half counted for the pass's samples
    /// in that half.
    pub fn weigh_halves(&self, (first, second): (Rgb, Rgb)) -> PixelSums {
        let (a, b) = (
            self.first_count() as f64,
            (self.count() - self.first_count()) as f64,
        );
        PixelSums {
            all: first * a + second * b,
            first: first * a,
        }
    }
}

/// Offsets the index of a later pass's seed from every pixel's.
const PASS_SEEDS: u64 = 1 << 42;

/// A pixel's totals `total` after one more pass of sums `pass`. The noise
/// estimate's two halves are the first pass's two halves while it is the
/// only one, and then every pass before the last against the last: at 16
/// times a power of two samples, the first and the second half of the
/// samples, each spread evenly over the floor rays' directions
/// (`sampling::sample_arc`).
#[inline]
pub(crate) fn fold(total: PixelSums, pass: PixelSums) -> PixelSums {
    PixelSums {
        all: total.all + pass.all,
        first: total.all,
    }
}

/// The first pass (counted from 0) that adaptive passes take for some
/// pixels only: every pixel takes the first two, 32 samples.
pub const ADAPT_FROM: u32 = 2;

/// A pixel takes an adaptive pass where its estimated squared error,
/// averaged over its 3 x 3 neighbours, is at least this share of the
/// image's mean.
pub const ADAPT_SHARE: f64 = 0.25;

/// The running totals of a render's passes.
pub(crate) struct Totals {
    pub size: (u32, u32),
    /// Per pixel, row by row.
    pub sums: Vec<PixelSums>,
    /// Per pixel, with adaptive passes: its samples and how many of them
    /// are in its noise estimate's first half (every pass it took before
    /// its last, or its first pass's first half).
    pub counts: Option<Vec<(u32, u32)>>,
    /// Samples per pixel so far, and how many are in the noise estimate's
    /// first half (a share of one, for a light tracer's first pass).
    pub samples: u32,
    pub first: f64,
    pub stats: Stats,
}

impl Totals {
    pub fn new(size: (u32, u32), stats: Stats) -> Totals {
        Totals {
            size,
            sums: Vec::new(),
            counts: None,
            samples: 0,
            first: 0.0,
            stats,
        }
    }

    /// Adds a pass's own sums (row by row) and what it counted; `first`
    /// of its samples (a light tracer's share of them) are in its first
    /// half.
    pub fn add(&mut self, pass: &Pass, sums: Vec<PixelSums>, stats: &Stats, first: f64) {
        if self.sums.is_empty() {
            self.sums = sums;
        } else {
            for (total, s) in self.sums.iter_mut().zip(sums) {
                *total = fold(*total, s);
            }
        }
        self.count(pass, first);
        self.stats.merge(stats);
    }

    /// Takes the totals after `passes` (their sums already folded in,
    /// row by row, each pass's first half its first half of samples) and
    /// what they counted.
    pub fn replace(&mut self, passes: &[Pass], sums: Vec<PixelSums>, stats: &Stats) {
        self.sums = sums;
        for pass in passes {
            self.count(pass, pass.first_count() as f64);
        }
        self.stats.merge(stats);
    }

    /// Takes the totals after adaptive pass `pass`, which the pixels of
    /// `mask` took (every pixel, without one), and what it counted.
    pub fn replace_masked(
        &mut self,
        pass: &Pass,
        sums: Vec<PixelSums>,
        stats: &Stats,
        mask: Option<&[bool]>,
    ) {
        let pixels = sums.len();
        let counts = self.counts.get_or_insert_with(|| vec![(0, 0); pixels]);
        for (k, count) in counts.iter_mut().enumerate() {
            if mask.is_none_or(|m| m.get(k) == Some(&true)) {
                *count = match count.0 {
                    0 => (pass.count(), pass.first_count()),
                    n => (n + pass.count(), n),
                };
            }
        }
        self.replace(std::slice::from_ref(pass), sums, stats);
    }

    /// Which pixels take the next adaptive pass: those whose estimated
    /// squared error (the difference of their halves, weighed as the
    /// noise estimate weighs it), averaged over their 3 x 3 neighbours,
    /// is at least [`ADAPT_SHARE`] of the image's mean. `None`: every
    /// pixel (before [`ADAPT_FROM`] passes, or without an estimate).
    pub fn adaptive_mask(&self, passes: u32) -> Option<Vec<bool>> {
        let counts = self.counts.as_ref()?;
        if passes < ADAPT_FROM || self.sums.len() != counts.len() {
            return None;
        }
        let (width, height) = (self.size.0 as usize, self.size.1 as usize);
        let errors: Vec<f64> = self
            .sums
            .iter()
            .zip(counts)
            .map(|(sums, &(n, n1))| {
                let (n, n1) = (n as f64, n1 as f64);
                let n2 = n - n1;
                if n1 <= 0.0 || n2 <= 0.0 {
                    return 0.0;
                }
                let d = sums.first / n1 - (sums.all - sums.first) / n2;
                let e = d.length_squared() * n1 * n2 / (n * n);
                if e.is_finite() { e } else { 0.0 }
            })
            .collect();
        let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
        if mean <= 0.0 || errors.len() != width * height {
            return None;
        }
        let at = |x: usize, y: usize| errors[y * width + x];
        let mask = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let (mut sum, mut count) = (0.0, 0.0);
                for j in y.saturating_sub(1)..(y + 2).min(height) {
                    for i in x.saturating_sub(1)..(x + 2).min(width) {
                        sum += at(i, j);
                        count += 1.0;
                    }
                }
                sum / count >= ADAPT_SHARE * mean
            })
            .collect();
        Some(mask)
    }

    /// Counts `pass`'s samples: in the first half, the first pass's
    /// `first` while it is the only pass, then every pass before the last.
    fn count(&mut self, pass: &Pass, first: f64) {
        self.first = match self.samples {
            0 => first,
            samples => samples as f64,
        };
        self.samples = pass.samples.end;
    }

    /// The image so far: exposure times floor albedo times each pixel's
    /// mean, and the noise estimate from the halves. Rows in parallel,
    /// their noise summed in row order.
    pub fn rendered(&self, scene: &Scene, exposure: f64, window: Option<Window>) -> Rendered {
        let (width, height) = self.size;
        let mut stats = self.stats;
        if self.samples == 0 || self.sums.is_empty() || width == 0 {
            return Rendered {
                image: Image::new(width, height),
                stats,
                samples: vec![self.samples; width as usize * height as usize],
            };
        }
        let n = self.samples as f64;
        let (n1, n2) = (self.first, n - self.first);
        let weight = n1 * n2 / (n * n);
        // Each row is written in place: the image is held once, beside
        // the sums.
        let mut image = Image::new(width, height);
        let counts = self.counts.as_deref();
        let rows: Vec<Stats> = image
            .pixels
            .par_chunks_mut(width as usize)
            .zip(self.sums.par_chunks(width as usize))
            .enumerate()
            .map(|(y, (out, row))| {
                let mut stats = Stats::default();
                for (x, (pixel, sums)) in out.iter_mut().zip(row).enumerate() {
                    let k = y * width as usize + x;
                    let (x, y) = (x as u32, y as u32);
                    if window.is_some_and(|w| !w.contains((x, y))) {
                        continue;
                    }
                    // With adaptive passes, each pixel's own samples.
                    let (n, n1, weight) = match counts.and_then(|c| c.get(k)) {
                        Some(&(m, m1)) => {
                            let (m, m1) = (m as f64, m1 as f64);
                            (m, m1, m1 * (m - m1) / (m * m))
                        }
                        None => (n, n1, weight),
                    };
                    let n2 = n - n1;
                    let scale = pixel_scale(scene, self.size, (x, y), exposure);
                    let value = sums.all / n * scale;
                    if n1 > 0.0 && n2 > 0.0 {
                        let difference = sums.first / n1 - (sums.all - sums.first) / n2;
                        stats.noise.add(difference * scale, value, weight);
                    }
                    *pixel = if value.is_finite() {
                        [value.x as f32, value.y as f32, value.z as f32]
                    } else {
                        stats.record_nonfinite(x, y, u32::MAX);
                        [0.0; 3]
                    };
                }
                stats
            })
            .collect();
        for row_stats in rows {
            stats.merge(&row_stats);
        }
        let samples = match counts {
            Some(counts) => counts.iter().map(|c| c.0).collect(),
            None => vec![self.samples; self.sums.len()],
        };
        Rendered {
            image,
            stats,
            samples,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_double_from_the_first_and_end_at_the_samples() {
        let ends = |n| passes(n).map(|p| (p.start, p.end)).collect::<Vec<_>>();
        assert_eq!(ends(0), vec![]);
        assert_eq!(ends(1), vec![(0, 1)]);
        assert_eq!(ends(16), vec![(0, 16)]);
        assert_eq!(ends(17), vec![(0, 16), (16, 17)]);
        assert_eq!(ends(100), vec![(0, 16), (16, 32), (32, 64), (64, 100)]);
        assert_eq!(next_pass_end(u32::MAX), u32::MAX);
        assert_eq!(floor_points(100, 1, 1), 100);
        assert_eq!(floor_points(100, 20, 1), 20 + 20 + 32 + 36);
        assert_eq!(floor_points(0, 20, 1), 0);
        // Passes of 16, 16, 32 and 36 samples: a quarter or a sixteenth
        // of each, but at least 16; or 20 at least.
        assert_eq!(floor_points(100, 1, 4), 16 + 16 + 16 + 16);
        assert_eq!(floor_points(100, 1, 16), 16 + 16 + 16 + 16);
        assert_eq!(floor_points(1024, 1, 4), 16 + 16 + 16 + 16 + 32 + 64 + 128);
        assert_eq!(floor_points(100, 20, 16), 20 + 20 + 20 + 20);
        assert_eq!(floor_points(2, 1, 16), 2);
    }

    #[test]
    fn a_sample_knows_its_pass() {
        for (index, pass) in passes(1 << 20).enumerate() {
            for sample in [pass.start, pass.end - 1] {
                assert_eq!(pass_index(sample), index as u32, "sample {sample}");
            }
        }
        assert_eq!(pass_index(u32::MAX), 28);
    }

    #[test]
    fn halves_weigh_each_half_by_its_samples() {
        let pass = Pass::new(1, 16..21, (36, 36, 1), 7);
        assert_eq!(pass.points, 36..72);
        assert_eq!((pass.count(), pass.first_count()), (5, 2));
        let sums = pass.weigh_halves((Rgb::splat(1.0), Rgb::splat(3.0)));
        assert_eq!(sums.all, Rgb::splat(2.0 + 9.0));
        assert_eq!(sums.first, Rgb::splat(2.0));
        assert_ne!(pass.seed, 7);
        assert_eq!(Pass::new(0, 0..16, (0, 1, 1), 7).seed, 7);
        assert_eq!(Pass::new(0, 0..16, (0, 1, 1), 7).points, 0..16);
        assert_eq!(Pass::new(6, 512..1024, (0, 1, 16), 7).points, 0..32);
    }
}
