//! The direct-light memo of flatray (the original project's "dynamic
//! programming"): direct irradiance on walls, binned along each wall, per
//! side, so that a path landing on a wall reads it instead of casting
//! shadow rays.
//!
//! What it is for: a compact table keyed by (wall, side, bin along the
//! wall), filled once before a render from a function of (wall, side,
//! position, light) summed over the lights in their order, and read by
//! linear interpolation between bin centres. Only the sums are kept, so
//! its memory grows with the walls' length, not with the lights. The
//! tracer's onward memo fills more tables on the same bins
//! (`WallMemo::build_like`), each term a gather direction. Because
//! every stored value is a pure function of its key, the table is the same
//! whatever the number of threads that filled it.
//!
//! It also tells its caller which reads to check against an exact
//! estimate, so that the memo's bias can be taken out by whoever knows the
//! physics ([`Check`]): one read in [`CHECK_RATE`] (by a hash of the wall
//! and the read's position along it); one in 8, 4 or 2 between bins whose
//! values say the interpolation may be further off, so that the check
//! still cannot go below zero; and every read where even that cannot be
//! promised.
//!
//! What it never does: decide physics. It does not know what irradiance
//! is; the tracer hands it a fill function and reads numbers back. It reads
//! no files and keeps no state that depends on scheduling.

use rayon::prelude::*;

/// An RGB triple as stored: three `f32`, enough for a cached irradiance.
pub type Value = [f32; 3];

/// The memo of direct irradiance on walls.
///
/// Each wall is cut into spans at the points where other walls meet or
/// cross it (a T-junction, a crossing), and each span into bins. A bin
/// never straddles a junction and a lookup never interpolates across one:
/// the two sides of a junction can see different light (one may be inside
/// a closed room, the other outside), and blending them would leak light.
#[derive(Clone, Debug, Default)]
pub struct WallMemo {
    lights: usize,
    /// For each wall, its first span, its number of spans, and what a
    /// lookup finds its span with.
    walls: Vec<SpanRange>,
    spans: Vec<Span>,
    /// Per (span, side, bin): the sum over lights, what a lookup reads.
    /// Only the sum is kept, so the memory does not grow with the lights.
    total: Vec<Value>,
    /// Per (span, side, bin): how the reads interpolated from this bin
    /// are checked, as the base-2 logarithm of their check rate: 0 for
    /// [`Check::Always`], [`CHECK_RATE_LOG2`] where the bins are smooth
    /// enough for the usual rate; empty for a memo that is never checked
    /// ([`WallMemo::build_like`]).
    rates: Vec<u8>,
}

/// How the caller takes a read ([`WallMemo::read`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Check {
    /// The memo's value as it is.
    No,
    /// One read in `rate` (a power of two, at most [`CHECK_RATE`]): the
    /// caller reads `m + rate (e - m)` for the memo's `m` and an exact
    /// estimate `e`, which is on average the exact value whatever the memo
    /// holds, and is not below zero wherever `e >= m (1 - 1 / rate)`. The
    /// rate is lower where the bins may be further off ([`uneven_bins`]).
    Sampled { rate: u64 },
    /// The memo's value may be off by more than a check of one read in 2
    /// can take out without going below zero (a shadow's edge of a light
    /// that gives most of the bins' value, a lamp very close to the wall,
    /// a span of one bin): the caller takes the exact estimate alone.
    Always,
}

/// A wall of at most this many spans finds a lookup's span without a
/// branch.
const SHORT_SPANS: usize = 4;

/// A wall's first span and number of spans, and the ends of its first
/// spans but the last (`+inf` past them): the span holding `u` is the
/// first plus the number of these ends before `u`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SpanRange {
    first: u32,
    count: u32,
    ends: [f64; SHORT_SPANS - 1],
}

/// A stretch of a wall between junctions: `[u0, u1]` along the wall, cut
/// into `bins` bins whose entries start at `offset` (side 0, then side 1).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Span {
    u0: f64,
    u1: f64,
    bins: u32,
    offset: usize,
    /// `bins / (u1 - u0)` and `bins - 1`, as a lookup computes with them.
    scale: f64,
    last: f64,
}

impl Span {
    fn new(u0: f64, u1: f64, bins: u32, offset: usize) -> Span {
        Span {
            u0,
            u1,
            bins,
            offset,
            // Through i64: the same values, as bins < 2^32. For a span of
            // the whole wall (most are) the division is by 1: exact.
            scale: bins as i64 as f64 / (u1 - u0),
            last: (bins as i64 - 1) as f64,
        }
    }
}

/// Where a lookup lands: a wall, a side (0 or 1) and a position `u` in
/// `[0, 1]` along the wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    pub wall: u32,
    pub side: usize,
    pub u: f64,
}

/// One read in this many is marked for checking ([`checked`]).
pub const CHECK_RATE: u64 = 16;

/// The base-2 logarithm of [`CHECK_RATE`].
const CHECK_RATE_LOG2: u8 = CHECK_RATE.trailing_zeros() as u8;

/// Cells along a wall, as a share of its length, within which [`checked`]
/// decides alike: far finer than a bin, and far coarser than the rounding
/// of a position along a wall far from the origin (a scene translated by
/// 1e9 units moves `u` by about 1e-8 of a wall's length), so that a
/// translated scene checks the same reads.
const CHECK_CELLS: f64 = (1u64 << 16) as f64;

/// Whether the read at `u` on wall `wall`, by a path keyed `path`, is one
/// the caller checks: one in [`CHECK_RATE`], by a hash of the three (a
/// random number keyed by the path, as its own random stream is, and by
/// the read's cell along the wall, so that every caller that holds the
/// path's key decides alike, and a far-off scene decides as one at the
/// origin). A caller that estimates the exact value `e` there and reads
/// `m + CHECK_RATE (e - m)` instead of the memo's `m` has, on average, the
/// exact value, whatever the memo holds.
#[inline(always)]
pub fn checked(wall: u32, u: f64, path: u64) -> bool {
    checked_at(wall, u, path, CHECK_RATE)
}

/// [`checked`] for one read in `rate`, a power of two at most
/// [`CHECK_RATE`]: of the same hash, so that a read checked at one rate
/// is checked at every lower one.
#[inline(always)]
pub fn checked_at(wall: u32, u: f64, path: u64, rate: u64) -> bool {
    // NaN and the ends map to cells 0 and CHECK_CELLS, as the cast saturates.
    let cell = (u * CHECK_CELLS) as u64;
    let mut z =
        cell ^ ((wall as u64) << 32).rotate_left(17) ^ path.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)).is_multiple_of(rate)
}

/// The ends of a wall's spans between its `junctions` (positions along
/// it, any order; those outside `(0, 1)` left out): 0, the junctions in
/// increasing order without repeats, 1.
pub fn span_bounds(junctions: &[f64]) -> Vec<f64> {
    let mut cuts: Vec<f64> = junctions
        .iter()
        .copied()
        .filter(|u| *u > 0.0 && *u < 1.0)
        .collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    std::iter::once(0.0)
        .chain(cuts)
        .chain(std::iter::once(1.0))
        .collect()
}

impl WallMemo {
    /// Builds the memo for walls of the given lengths, each cut at the
    /// positions `junctions[wall]` (in `(0, 1)`, any order) into spans, and
    /// each span into `ceil(span length / bin_length)` bins (at least one),
    /// for `lights` lights. `fill(wall, side, u, light)` gives the value at
    /// the centre `u` of a bin; it is called once per entry, from several
    /// threads.
    pub fn build(
        lengths: &[f64],
        junctions: &[Vec<f64>],
        bin_length: f64,
        lights: usize,
        fill: impl Fn(u32, usize, f64, usize) -> Value + Sync,
    ) -> WallMemo {
        let mut walls = Vec::with_capacity(lengths.len());
        let mut spans = Vec::new();
        let mut next = 0usize;
        for (wall, &length) in lengths.iter().enumerate() {
            let first = spans.len() as u32;
            let bounds = span_bounds(junctions.get(wall).map_or(&[], Vec::as_slice));
            for pair in bounds.windows(2) {
                let n = ((pair[1] - pair[0]) * length / bin_length).ceil();
                let bins = if n.is_finite() && n >= 1.0 {
                    n.min(u32::MAX as f64) as u32
                } else {
                    1
                };
                spans.push(Span::new(pair[0], pair[1], bins, next));
                next += 2 * bins as usize;
            }
            let count = spans.len() as u32 - first;
            let mut ends = [f64::INFINITY; SHORT_SPANS - 1];
            // The last span's end is never needed: a u beyond every other
            // end lies in the last span.
            let inner = &spans[first as usize..spans.len() - 1];
            for (end, span) in ends.iter_mut().zip(inner) {
                *end = span.u1;
            }
            walls.push(SpanRange { first, count, ends });
        }
        let total = fill_bins(&walls, &spans, lights, fill);
        let rates = uneven_bins(&spans, &total);
        WallMemo {
            lights,
            walls,
            spans,
            total,
            rates,
        }
    }

    /// Marks the reads about `u` on `wall` as checked more often: `u` is a
    /// place where the light the memo holds may jump (the edge of a shadow
    /// that a wall casts), which the bins' values do not show where it
    /// falls between two centres that see the same light. `jump` bounds,
    /// on each side, the light that may be missing past the edge; the
    /// reads interpolated from the bins about `u` are checked at the
    /// highest rate at which a check of a read that misses it cannot go
    /// below zero ([`uneven_bins`]), or always.
    pub fn mark_edge(&mut self, wall: u32, u: f64, jump: [Value; 2]) {
        if self.rates.is_empty() || wall as usize >= self.walls.len() || !u.is_finite() {
            return;
        }
        let span = self.spans[self.span_of(wall, u)];
        let n = span.bins as usize;
        let x = (u - span.u0) * span.scale - 0.5;
        // The bin a read at `u` starts from, and the one before where `u`
        // is within rounding of a centre.
        let i = x.clamp(0.0, span.last) as usize;
        let before = (x - 1e-6).clamp(0.0, span.last) as usize;
        for (side, jump) in jump.iter().enumerate() {
            let base = span.offset + side * n;
            for k in [i, before] {
                let (a, b) = (self.total[base + k], self.total[base + (k + 1).min(n - 1)]);
                let rate = (0..3)
                    .map(|c| rate_log2(a[c].min(b[c]), ERROR_MARGIN * jump[c]))
                    .min()
                    .unwrap_or(0);
                let flag = &mut self.rates[base + k];
                *flag = (*flag).min(rate);
            }
        }
    }

    /// A memo on the same walls, spans and bins as `self`, filled as
    /// [`WallMemo::build`] fills one, from `fill(wall, side, u, term)`
    /// summed over `terms` terms at each bin's centre.
    pub fn build_like(
        &self,
        terms: usize,
        fill: impl Fn(u32, usize, f64, usize) -> Value + Sync,
    ) -> WallMemo {
        WallMemo {
            lights: terms,
            walls: self.walls.clone(),
            spans: self.spans.clone(),
            total: fill_bins(&self.walls, &self.spans, terms, fill),
            rates: Vec::new(),
        }
    }

    /// The number of walls.
    pub fn walls(&self) -> usize {
        self.walls.len()
    }

    /// The number of bins of `wall`, over all its spans.
    pub fn bins(&self, wall: u32) -> u32 {
        let SpanRange { first, count, .. } = self.walls[wall as usize];
        self.spans[first as usize..(first + count) as usize]
            .iter()
            .map(|s| s.bins)
            .sum()
    }

    /// The number of spans of `wall`.
    pub fn spans(&self, wall: u32) -> u32 {
        self.walls[wall as usize].count
    }

    /// Values filled: (wall, side, bin, light) keys.
    pub fn entries(&self) -> usize {
        self.total.len() * self.lights
    }

    /// Values held: one per (span, side, bin), whatever the lights.
    pub fn values(&self) -> usize {
        self.total.len()
    }

    /// Bytes held by the tables: per bin, not per light.
    pub fn memory_bytes(&self) -> usize {
        self.total.len() * std::mem::size_of::<Value>()
            + self.rates.len()
            + self.spans.len() * std::mem::size_of::<Span>()
            + self.walls.len() * std::mem::size_of::<SpanRange>()
    }

    /// The value stored in bin `bin` of span `span` of `wall`: the sum
    /// over lights.
    pub fn bin_value(&self, wall: u32, span: u32, side: usize, bin: u32) -> Value {
        let s = self.spans[(self.walls[wall as usize].first + span) as usize];
        self.total[s.offset + side * s.bins as usize + bin as usize]
    }

    /// The span of `wall` that holds `u`: the first whose end is not
    /// before `u`, or else the last.
    #[inline(always)]
    fn span_of(&self, wall: u32, u: f64) -> usize {
        let wall = &self.walls[wall as usize];
        if wall.count as usize <= SHORT_SPANS && !u.is_nan() {
            // The ends ascend, and the padding is never passed: count
            // them, without a branch that a mispredicted lookup pays for.
            let passed: u32 = wall.ends.iter().map(|&end| (u > end) as u32).sum();
            (wall.first + passed) as usize
        } else {
            // A linear scan.
            let (mut s, last) = (wall.first, wall.first + wall.count - 1);
            while s < last && (u > self.spans[s as usize].u1 || u.is_nan()) {
                s += 1;
            }
            s as usize
        }
    }

    /// The summed value over all lights at `key`, linearly interpolated
    /// between the centres of the two nearest bins of its span (constant
    /// beyond the span's first and last centre).
    #[inline(always)]
    pub fn lookup(&self, key: Key) -> Value {
        self.interpolate(key).0
    }

    /// [`WallMemo::lookup`], and how the caller checks the read ([`Check`])
    /// for a path keyed `path` ([`checked`]).
    #[inline(always)]
    pub fn read(&self, key: Key, path: u64) -> (Value, Check) {
        let (value, i) = self.interpolate(key);
        let check = match self.rate_of(i) {
            // A memo that is never checked.
            None => Check::No,
            Some(1) => Check::Always,
            Some(rate) => {
                if checked_at(key.wall, key.u, path, rate) {
                    Check::Sampled { rate }
                } else {
                    Check::No
                }
            }
        };
        (value, check)
    }

    /// The rate at which [`WallMemo::read`] checks reads at `key`: 1 where
    /// it checks every read, [`CHECK_RATE`] where the bins are smooth, 0
    /// for a memo that checks none ([`WallMemo::build_like`]).
    pub fn check_rate(&self, key: Key) -> u64 {
        self.rate_of(self.interpolate(key).1).unwrap_or(0)
    }

    /// [`WallMemo::read`] for a caller that takes no sampled checks (and so
    /// carries the memo's bias where the bins are smooth): every read that
    /// a check at the usual rate, [`CHECK_RATE`], could take below zero is
    /// [`Check::Always`], and the rest [`Check::No`].
    #[inline(always)]
    pub fn read_unsampled(&self, key: Key) -> (Value, Check) {
        let (value, i) = self.interpolate(key);
        let check = match self.rate_of(i) {
            Some(rate) if rate < CHECK_RATE => Check::Always,
            _ => Check::No,
        };
        (value, check)
    }

    /// The check rate of the reads interpolated from bin entry `i`, or
    /// none for a memo that is never checked.
    #[inline(always)]
    fn rate_of(&self, i: usize) -> Option<u64> {
        self.rates
            .get(i)
            .map(|&log2| 1 << log2.min(CHECK_RATE_LOG2))
    }

    /// The interpolated value at `key`, and the index of the bin it
    /// starts from.
    #[inline(always)]
    fn interpolate(&self, key: Key) -> (Value, usize) {
        let span = &self.spans[self.span_of(key.wall, key.u)];
        let n = span.bins as usize;
        let base = span.offset + key.side * n;
        // No division: the span's bins per unit of `u` are kept (exactly
        // its bin count for a span of the whole wall, as most are).
        // Conversions through i64 (one instruction each; usize takes a
        // sequence of them on x86-64). x is at most `last`, so is i.
        let x = ((key.u - span.u0) * span.scale - 0.5).clamp(0.0, span.last);
        let i = x as i64;
        let j = (i + 1).min(n as i64 - 1);
        let f = (x - i as f64) as f32;
        let (i, j) = (i as usize, j as usize);
        let (a, b) = (self.total[base + i], self.total[base + j]);
        let value = [
            a[0] + (b[0] - a[0]) * f,
            a[1] + (b[1] - a[1]) * f,
            a[2] + (b[2] - a[2]) * f,
        ];
        (value, base + i)
    }
}

/// How far past its own estimate of the interpolation's error a bin is
/// taken to be off (the estimate is from the bins' second differences,
/// exact for a parabola).
const ERROR_MARGIN: f32 = 2.0;

/// Per (span, side, bin): the base-2 logarithm of the highest check rate
/// `R` (a power of two, at most [`CHECK_RATE`]) at which the reads
/// interpolated from the bin are off by at most `1 / R` of the smaller of
/// the values they blend, so that a check at that rate cannot go below
/// zero there; 0 (every read checked) where even `R = 2` is too high. Between
/// centres `h` apart, where the light is smooth, a linear interpolation is
/// off by at most `h² |f''| / 8`, `h² f''` estimated by the second
/// differences of the bins about it; where the light jumps between the two
/// centres (a shadow's edge), by up to the jump, which shows as second
/// differences of opposite signs at the two ends, half their difference
/// the jump. Beyond a span's first and last centre the read is constant
/// (the end bin's value, checked at the end bin's rate), off by about half
/// the first difference more, and the first interval of
/// a span can't tell a jump from a slope: its first difference counts
/// whole. A span of one bin has no estimate, and is always checked.
fn uneven_bins(spans: &[Span], total: &[Value]) -> Vec<u8> {
    let mut rates = vec![CHECK_RATE_LOG2; total.len()];
    for span in spans {
        let n = span.bins as usize;
        for side in 0..2 {
            let base = span.offset + side * n;
            let m = &total[base..base + n];
            let flags = &mut rates[base..base + n];
            if n == 1 {
                flags[0] = 0;
                continue;
            }
            // Each colour channel is checked on its own.
            #[allow(clippy::needless_range_loop)]
            for c in 0..3 {
                let v = |k: usize| m[k][c];
                // The second difference about centre k, where it has one.
                let second =
                    |k: usize| (k >= 1 && k + 1 < n).then(|| v(k - 1) - 2.0 * v(k) + v(k + 1));
                for (i, flag) in flags.iter_mut().enumerate() {
                    let j = (i + 1).min(n - 1);
                    let k = i.min(n - 2);
                    let first = (v(k + 1) - v(k)).abs();
                    let (si, sj) = (second(i), second(j));
                    // The end bins take the curve of the nearest centre
                    // that has a second difference.
                    let near = |k: usize| second(k.clamp(1, n.saturating_sub(2).max(1)));
                    let curve = near(i)
                        .unwrap_or(0.0)
                        .abs()
                        .max(near(j).unwrap_or(0.0).abs())
                        / 8.0;
                    let jump = match (si, sj) {
                        (Some(a), Some(b)) if i != j => (a - b).abs() / 2.0,
                        _ => first,
                    };
                    // Held constant over the half bin past the end centre:
                    // off by half a bin's slope there, which is the first
                    // difference's (at the interval's middle) and up to
                    // one and a half second differences more.
                    let end = if i == 0 || i == n - 1 {
                        first / 2.0 + 3.0 * curve
                    } else {
                        0.0
                    };
                    let error = (ERROR_MARGIN * curve).max(jump).max(ERROR_MARGIN * end);
                    *flag = (*flag).min(rate_log2(v(i).min(v(j)), error));
                }
            }
        }
    }
    rates
}

/// The base-2 logarithm of the highest power of two `R` at most
/// [`CHECK_RATE`] with `error <= least / R`, or 0 (every read checked)
/// where `R = 2` fails or either is NaN.
fn rate_log2(least: f32, error: f32) -> u8 {
    let mut log2 = CHECK_RATE_LOG2;
    let within = |log2: u8| error <= least / (1u64 << log2) as f32;
    while log2 > 0 && !within(log2) {
        log2 -= 1;
    }
    log2
}

/// Every (span, side, bin) value: `fill` at the bin's centre, summed over
/// `lights` in their order, the spans in parallel.
fn fill_bins(
    walls: &[SpanRange],
    spans: &[Span],
    lights: usize,
    fill: impl Fn(u32, usize, f64, usize) -> Value + Sync,
) -> Vec<Value> {
    let owner: Vec<u32> = walls
        .iter()
        .enumerate()
        .flat_map(|(w, range)| std::iter::repeat_n(w as u32, range.count as usize))
        .collect();
    spans
        .par_iter()
        .zip(owner.par_iter())
        .flat_map_iter(|(span, &wall)| {
            let fill = &fill;
            let span = *span;
            (0..2usize).flat_map(move |side| {
                (0..span.bins).map(move |bin| {
                    let u = span.u0 + (span.u1 - span.u0) * (bin as f64 + 0.5) / span.bins as f64;
                    (0..lights).fold([0.0f32; 3], |acc, light| {
                        let v = fill(wall, side, u, light);
                        [acc[0] + v[0], acc[1] + v[1], acc[2] + v[2]]
                    })
                })
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_are_about_one_length_unit_and_keyed_exactly() {
        let memo = WallMemo::build(&[10.0, 2.5, 0.1], &[], 1.0, 2, |w, s, u, l| {
            [w as f32, s as f32 + u as f32, l as f32]
        });
        assert_eq!((memo.bins(0), memo.bins(1), memo.bins(2)), (10, 3, 1));
        assert_eq!(memo.entries(), (10 + 3 + 1) * 2 * 2);
        // Two lights, 0 and 1, summed.
        let u = (2.5 / 3.0) as f32;
        assert_eq!(memo.bin_value(1, 0, 1, 2), [2.0, 2.0 * (1.0 + u), 1.0]);
        assert_eq!(memo.bin_value(0, 0, 0, 0), [0.0, 0.1, 1.0]);
    }

    #[test]
    fn lookups_interpolate_between_bin_centres_and_sum_lights() {
        // Value = u at the bin centre, for each of 3 lights.
        let memo = WallMemo::build(&[4.0], &[], 1.0, 3, |_, _, u, _| [u as f32, 1.0, 0.0]);
        for u in [0.125, 0.3, 0.5, 0.61, 0.875] {
            let v = memo.lookup(Key {
                wall: 0,
                side: 0,
                u,
            });
            assert!((v[0] - 3.0 * u as f32).abs() < 1e-6, "u {u}: {v:?}");
            assert_eq!(v[1], 3.0);
        }
        // Beyond the outer centres the value is held constant.
        assert!(
            (memo.lookup(Key {
                wall: 0,
                side: 1,
                u: 0.0
            })[0]
                - 0.375)
                .abs()
                < 1e-6
        );
        assert!(
            (memo.lookup(Key {
                wall: 0,
                side: 1,
                u: 1.0
            })[0]
                - 2.625)
                .abs()
                < 1e-6
        );
    }

    #[test]
    fn lookups_never_interpolate_across_a_junction() {
        // Value 1 left of the junction at u = 0.37, 0 right of it: a lookup
        // just right of the junction reads 0, just left reads 1.
        let memo = WallMemo::build(&[10.0], &[vec![0.37]], 1.0, 1, |_, _, u, _| {
            [if u < 0.37 { 1.0 } else { 0.0 }; 3]
        });
        assert_eq!(memo.spans(0), 2);
        assert_eq!(
            memo.lookup(Key {
                wall: 0,
                side: 0,
                u: 0.3700001
            }),
            [0.0; 3]
        );
        assert_eq!(
            memo.lookup(Key {
                wall: 0,
                side: 0,
                u: 0.3699999
            }),
            [1.0; 3]
        );
        assert_eq!(
            memo.lookup(Key {
                wall: 0,
                side: 1,
                u: 0.99
            }),
            [0.0; 3]
        );
        assert_eq!(
            memo.lookup(Key {
                wall: 0,
                side: 1,
                u: 0.0
            }),
            [1.0; 3]
        );
    }

    #[test]
    fn a_lookup_finds_the_span_a_linear_scan_finds() {
        // Walls of 1 to 7 spans: up to SHORT_SPANS without a branch, more
        // by the scan. u at every junction, a hair either side of it, the
        // ends, beyond them, and NaN.
        let junctions: Vec<Vec<f64>> = (0..7)
            .map(|k| (1..=k).map(|j| j as f64 / (k + 1) as f64 - 0.01).collect())
            .collect();
        let memo = WallMemo::build(&[10.0; 7], &junctions, 1.0, 1, |_, _, _, _| [0.0; 3]);
        for (wall, cuts) in junctions.iter().enumerate() {
            let wall = wall as u32;
            assert_eq!(memo.spans(wall), cuts.len() as u32 + 1);
            let range = memo.walls[wall as usize];
            let spans = &memo.spans[range.first as usize..(range.first + range.count) as usize];
            let mut us = vec![0.0, 1.0, -0.5, 1.5, f64::NAN, 0.5];
            for &c in cuts {
                us.extend([c, c.next_down(), c.next_up()]);
            }
            for u in us {
                let scan = spans
                    .iter()
                    .position(|s| u <= s.u1)
                    .unwrap_or(spans.len() - 1);
                assert_eq!(
                    memo.span_of(wall, u),
                    range.first as usize + scan,
                    "wall {wall}, u {u}"
                );
            }
        }
    }

    #[test]
    fn the_table_does_not_depend_on_the_thread_count() {
        let lengths: Vec<f64> = (0..200).map(|k| 1.0 + k as f64 * 0.37).collect();
        let fill = |w: u32, s: usize, u: f64, l: usize| [(w as f64 * u) as f32, s as f32, l as f32];
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let four = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let junctions: Vec<Vec<f64>> = (0..200).map(|k| vec![0.3 + k as f64 * 1e-3]).collect();
        let a = one.install(|| WallMemo::build(&lengths, &junctions, 0.5, 2, fill));
        let b = four.install(|| WallMemo::build(&lengths, &junctions, 0.5, 2, fill));
        assert_eq!(a.total, b.total);
    }

    #[test]
    fn memory_is_proportional_to_wall_length_not_lights() {
        let fill = |_: u32, _: usize, _: f64, _: usize| [0.0; 3];
        let small = WallMemo::build(&[100.0; 10], &[], 1.0, 2, fill);
        let long = WallMemo::build(&[100.0; 20], &[], 1.0, 2, fill);
        let lit = WallMemo::build(&[100.0; 10], &[], 1.0, 4, fill);
        assert_eq!(small.entries() * 2, long.entries());
        assert_eq!(small.entries() * 2, lit.entries());
        assert_eq!(small.memory_bytes() * 2, long.memory_bytes());
        assert_eq!(small.memory_bytes(), lit.memory_bytes());
        // A value and the flag of its reads, and a share of the spans.
        let per_bin = small.memory_bytes() as f64 / (10 * 100 * 2) as f64;
        assert!(
            per_bin < std::mem::size_of::<Value>() as f64 + 2.0,
            "{per_bin}"
        );
    }

    fn check_at(memo: &WallMemo, side: usize, u: f64) -> Check {
        memo.read(Key { wall: 0, side, u }, 0).1
    }

    #[test]
    fn reads_are_checked_alike_within_a_cell_and_one_in_the_rate() {
        let mut checked_cells = 0;
        let cells = 1 << 16;
        for k in 0..cells {
            let centre = (k as f64 + 0.5) / CHECK_CELLS;
            // Anywhere in the cell decides as its centre does: a position
            // that rounds differently in its last bits checks alike.
            let near = [
                centre - 0.4 / CHECK_CELLS,
                centre * (1.0 + 1e-12),
                centre + 0.4 / CHECK_CELLS,
            ];
            for u in near {
                assert_eq!(checked(3, u, 7), checked(3, centre, 7), "cell {k}, u {u}");
            }
            checked_cells += checked(3, centre, 7) as u32;
        }
        // One cell in 16, within 5 standard errors of the binomial count.
        let expected = cells as f64 / CHECK_RATE as f64;
        let sd = (expected * (1.0 - 1.0 / CHECK_RATE as f64)).sqrt();
        assert!(
            (checked_cells as f64 - expected).abs() < 5.0 * sd,
            "{checked_cells}"
        );
        // Another wall, or another path, checks other cells.
        for (wall, path) in [(4, 7), (3, 8)] {
            let other = (0..cells)
                .filter(|&k| {
                    let u = (k as f64 + 0.5) / CHECK_CELLS;
                    checked(3, u, 7) != checked(wall, u, path)
                })
                .count();
            assert!(other > cells / 16, "{other}");
        }
    }

    #[test]
    fn smooth_bins_are_sampled_and_jumps_and_short_spans_always_checked() {
        // A smooth light along a wall of 20 bins: inside the outer
        // centres, only sampled checks.
        let smooth = WallMemo::build(&[20.0], &[], 1.0, 1, |_, _, u, _| {
            [(1.0 + u + 0.5 * u * u) as f32; 3]
        });
        for k in 1..39 {
            let u = (k as f64 + 0.5) / 40.0;
            assert_ne!(check_at(&smooth, 0, u), Check::Always, "u {u}");
        }
        // Beyond the first and last centre the read is held constant, and
        // checked at the end bin's rate, which allows for it: here the
        // usual one.
        for u in [0.001, 0.01, 0.99, 0.999] {
            assert_eq!(rate_at(&smooth, 1, u), CHECK_RATE, "u {u}");
        }
        // A shadow's edge at u = 0.51, between centres 9 and 10 (at 0.475
        // and 0.525): the interval between them is always checked (its
        // neighbours may be, as their second differences show half the
        // jump), and no other inner one.
        let step = WallMemo::build(&[20.0], &[], 1.0, 1, |_, _, u, _| {
            [if u < 0.51 { 2.0 } else { 1.0 }; 3]
        });
        for k in 2..38 {
            let u = (k as f64 + 0.5) / 40.0;
            let always = check_at(&step, 0, u) == Check::Always;
            if u > 0.475 && u < 0.525 {
                assert!(always, "u {u}");
            } else if !(0.425..=0.575).contains(&u) {
                assert!(!always, "u {u}");
            }
        }
        // A span of one bin: always.
        let short = WallMemo::build(&[0.5], &[], 1.0, 1, |_, _, _, _| [1.0; 3]);
        assert_eq!(check_at(&short, 0, 0.5), Check::Always);
        // Nothing the onward memo's tables read is checked.
        let like = smooth.build_like(1, |_, _, _, _| [0.0; 3]);
        assert_eq!(
            like.read(
                Key {
                    wall: 0,
                    side: 0,
                    u: 0.01
                },
                0
            )
            .1,
            Check::No
        );
    }

    fn rate_at(memo: &WallMemo, side: usize, u: f64) -> u64 {
        memo.check_rate(Key { wall: 0, side, u })
    }

    #[test]
    fn a_marked_edge_checks_the_reads_about_it_as_its_jump_asks() {
        let mut memo = WallMemo::build(&[20.0], &[], 1.0, 1, |_, _, _, _| [1.0; 3]);
        for k in 1..39 {
            assert_eq!(rate_at(&memo, 0, (k as f64 + 0.5) / 40.0), CHECK_RATE);
        }
        // A thin shadow at u = 0.3 between centres 5 and 6 (at 0.275 and
        // 0.325), which the bins' equal values do not show, of a light
        // that may give all of the bins' value on side 0 and a twentieth
        // of it on side 1 (in green): every read about it is checked on
        // side 0, and one in 8 on side 1 (twice the twentieth, 0.1, is
        // within an eighth of 1, so that `1 + 8 (0.95 - 1) >= 0`).
        memo.mark_edge(0, 0.3, [[1.0; 3], [0.0, 0.05, 0.0]]);
        for (side, rate) in [(0, 1), (1, 8)] {
            for k in 1..39 {
                let u = (k as f64 + 0.5) / 40.0;
                let about = u > 0.275 && u < 0.325;
                let expected = if about { rate } else { CHECK_RATE };
                assert_eq!(rate_at(&memo, side, u), expected, "side {side}, u {u}");
            }
        }
        // An edge at no wall, at no place, or of no light, marks nothing;
        // one of a jump that is not a number marks every read.
        let marked = memo.rates.clone();
        memo.mark_edge(7, 0.5, [[1.0; 3]; 2]);
        memo.mark_edge(0, f64::NAN, [[1.0; 3]; 2]);
        memo.mark_edge(0, 0.7, [[0.0; 3]; 2]);
        assert_eq!(memo.rates, marked);
        memo.mark_edge(0, 0.7, [[f32::NAN; 3]; 2]);
        assert_eq!(rate_at(&memo, 1, 0.69), 1);
    }

    #[test]
    fn a_check_at_each_reads_rate_cannot_go_below_zero_where_the_bins_show_the_light() {
        // Lamps at several heights above a wall of 40 bins, by its middle,
        // by and past its ends, and a shadow's edge wider than a bin:
        // wherever the light is smooth between centres (and past the end
        // centres, where reads are held constant), or its jumps show in
        // the bins, a read `m` checked at its rate `R` against the exact
        // `e` gives `m + R (e - m) >= 0`.
        let mut rates_seen = [0usize; 5];
        for height in [0.05, 0.2, 0.5, 1.0, 3.0, 10.0] {
            for (at, edge) in [
                (0.5, 2.0),
                (0.97, 2.0),
                (0.02, 2.0),
                (1.01, 2.0),
                (0.31, 0.62),
            ] {
                let exact = |u: f64| {
                    let d = (u - at) * 40.0;
                    let lamp = height / (height * height + d * d);
                    let lit = if u < edge { lamp } else { 0.1 * lamp };
                    lit + 0.001
                };
                let memo = WallMemo::build(&[40.0], &[], 1.0, 1, |_, _, u, _| [exact(u) as f32; 3]);
                for k in 0..4000 {
                    let u = (k as f64 + 0.5) / 4000.0;
                    let rate = rate_at(&memo, 0, u);
                    rates_seen[rate.trailing_zeros() as usize] += 1;
                    let m = memo.lookup(Key {
                        wall: 0,
                        side: 0,
                        u,
                    })[0] as f64;
                    let checked = m + rate as f64 * (exact(u) - m);
                    assert!(
                        checked >= -1e-6 * m,
                        "height {height}, lamp at {at}, u {u}: rate {rate}, {m} -> {checked}"
                    );
                }
            }
        }
        // Every rate is met, so each is tested.
        assert!(rates_seen.iter().all(|&n| n > 0), "{rates_seen:?}");
    }
}
