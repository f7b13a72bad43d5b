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

/// The first pass's floor points where each point's value is exact (or
/// its samples, if fewer). Where a light table draws the lights a point
/// takes, its direct light is a random estimate, and the first pass takes
/// a point per sample.
pub const FIRST_EXACT_POINTS: u32 = 8;

/// The first pass measures its points' error from its first this many
/// points, half against half ([`point_rate`]): a later pass takes few
/// points, and this many, stratified as the first of a pixel's Sobol
/// sequence are, have about the error per point that those few have. (A
/// measure from all of the first pass's points would read their finer
/// stratification as a smaller error per point.)
pub const MEASURED_POINTS: usize = 4;

/// What [`point_rate`] divides the ratio of the points' error to the
/// rest's by. The first pass measures the rest's error from halves of 8
/// samples, each on 8 of the 64 arcs of directions; a later pass takes
/// whole runs of the arcs, and stratifies each arc over its runs, so its
/// paths' error per sample is several times smaller than measured. The
/// value is set from the time each scene of `scenes/` takes to reach a
/// given error (`docs/model.md`, "The direct-light memo").
pub const POINT_SHARE: f64 = 1.0 / 32.0;

/// Probe pixels, where the first pass measures its noise's split
/// ([`crate::stats::Split`]): one in each square of this many pixels a
/// side, the same pixels whatever the window, so that a window of a render
/// takes the same points as the whole.
pub const PROBE_SPACING: u32 = 4;

/// Whether pixel `(x, y)` is a probe pixel ([`PROBE_SPACING`]).
#[inline(always)]
pub(crate) fn is_probe((x, y): (u32, u32)) -> bool {
    x % PROBE_SPACING == PROBE_SPACING / 2 && y % PROBE_SPACING == PROBE_SPACING / 2
}

/// How many floor points a pass takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum PointRule {
    /// The first pass's: a point per sample where a light table draws
    /// each point's lights, [`FIRST_EXACT_POINTS`] elsewhere.
    First { light_table: bool },
    /// `rate` points per sample, at least one a pass: the later passes',
    /// measured by the first ([`point_rate`]).
    Measured { rate: f64 },
}

/// Points per sample for the passes after the first, from the first
/// pass's noise at its probe pixels (`split`). Each part's squared error
/// falls as its count grows, the points' as `K_points / points` and the
/// rest's as `K_paths / samples`; a pass takes `K_points / (POINT_SHARE
/// K_paths)` points per sample, at most one. Where the paths carry most
/// of the noise (a bounce) a point, which takes every light's closed
/// form, would buy little: the samples take the time. Where the points
/// carry it (a hard shadow, many lights), every sample takes one. Where
/// the paths measured no noise at all, one per sample.
pub(crate) fn point_rate(split: &crate::stats::Split) -> f64 {
    if split.probes == 0 || split.paths <= 0.0 {
        return 1.0;
    }
    let rate = split.points / (POINT_SHARE * split.paths);
    if rate.is_finite() {
        rate.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// The floor memo's points in one pixel for a pass of `count` samples, by
/// `rule`, and at least `fewest`.
pub(crate) fn pass_points(count: u32, fewest: u32, rule: PointRule) -> u32 {
    let wanted = match rule {
        PointRule::First { light_table: true } => count,
        PointRule::First { light_table: false } => count.min(FIRST_EXACT_POINTS),
        // At least one point a pass: each pass is an estimate of the
        // pixel by itself.
        PointRule::Measured { rate } => ((count as f64 * rate).ceil() as u32).clamp(1, count),
    };
    wanted.max(fewest)
}

/// The index of the pass of the schedule that takes sample `sample`: 0
/// below [`FIRST_PASS`], then one more at each doubling.
#[inline(always)]
pub(crate) fn pass_index(sample: u32) -> u32 {
    const _: () = assert!(FIRST_PASS == 16);
    (u32::BITS - (sample | (FIRST_PASS - 1)).leading_zeros()).saturating_sub(4)
}

/// The first sample of pass `index` of the schedule.
#[inline(always)]
pub(crate) fn pass_start(index: u32) -> u32 {
    match index {
        0 => 0,
        i => FIRST_PASS.checked_shl(i - 1).unwrap_or(u32::MAX),
    }
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
    /// `first_point`, at least `fewest_points` of them, as many as `rule`
    /// says.
    pub fn new(
        index: u32,
        samples: Range<u32>,
        (first_point, fewest_points, rule): (u32, u32, PointRule),
        seed: u64,
    ) -> Pass {
        let middle = samples.start + (samples.end - samples.start) / 2;
        let count = samples.end - samples.start;
        let taken = pass_points(count, fewest_points, rule);
        let points = first_point..first_point.saturating_add(taken);
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
    }

    #[test]
    fn a_pass_takes_its_points_by_its_rule() {
        let table = PointRule::First { light_table: true };
        let exact = PointRule::First { light_table: false };
        assert_eq!(pass_points(16, 1, table), 16);
        assert_eq!(pass_points(16, 1, exact), FIRST_EXACT_POINTS);
        assert_eq!(pass_points(3, 1, exact), 3);
        assert_eq!(pass_points(16, 20, exact), 20);
        // A measured rate, rounded up, at least one a pass and at most
        // one a sample.
        let rate = |rate| PointRule::Measured { rate };
        assert_eq!(pass_points(256, 1, rate(0.04)), 11);
        assert_eq!(pass_points(16, 1, rate(0.0)), 1);
        assert_eq!(pass_points(16, 1, rate(1.0)), 16);
        assert_eq!(pass_points(16, 5, rate(0.01)), 5);
    }

    /// The rate follows the split of the first pass's noise: points
    /// twice as noisy against the same paths take twice as many; paths
    /// with no noise, or nothing measured, one a sample; never more.
    #[test]
    fn the_rate_follows_the_measured_split() {
        let split = |points, paths| crate::stats::Split {
            probes: 10,
            points,
            paths,
        };
        let r1 = point_rate(&split(1.0, 1000.0));
        let r2 = point_rate(&split(2.0, 1000.0));
        assert!((r1 - 1.0 / (POINT_SHARE * 1000.0)).abs() < 1e-15);
        assert!((r2 - 2.0 * r1).abs() < 1e-15);
        assert_eq!(point_rate(&split(1.0, 0.0)), 1.0);
        assert_eq!(point_rate(&split(500.0, 1.0)), 1.0);
        assert_eq!(point_rate(&crate::stats::Split::default()), 1.0);
        assert_eq!(point_rate(&split(f64::NAN, 1.0)), 1.0);
    }

    #[test]
    fn probes_are_one_in_each_square() {
        let probes = (0..64)
            .flat_map(|y| (0..64).map(move |x| (x, y)))
            .filter(|&p| is_probe(p))
            .count();
        assert_eq!(probes, 64 * 64 / (PROBE_SPACING * PROBE_SPACING) as usize);
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
        let pass = Pass::new(1, 16..21, (36, 36, PointRule::Measured { rate: 1.0 }), 7);
        assert_eq!(pass.points, 36..72);
        assert_eq!((pass.count(), pass.first_count()), (5, 2));
        let sums = pass.weigh_halves((Rgb::splat(1.0), Rgb::splat(3.0)));
        assert_eq!(sums.all, Rgb::splat(2.0 + 9.0));
        assert_eq!(sums.first, Rgb::splat(2.0));
        assert_ne!(pass.seed, 7);
        let table = PointRule::First { light_table: true };
        assert_eq!(Pass::new(0, 0..16, (0, 1, table), 7).seed, 7);
        assert_eq!(Pass::new(0, 0..16, (0, 1, table), 7).points, 0..16);
        let rate = PointRule::Measured { rate: 1.0 / 16.0 };
        assert_eq!(Pass::new(6, 512..1024, (0, 1, rate), 7).points, 0..32);
        assert_eq!(pass_start(6), 512);
        assert_eq!(pass_start(0), 0);
    }
}
