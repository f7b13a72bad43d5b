//! How far a path goes: diffuse reflections are counted against
//! `RenderOptions::bounces`, specular events (mirrors, glass) in a row
//! against `RenderOptions::specular`, with Russian roulette on long runs.
//! The path tracer, the light tracer and the caustic pass count alike, so
//! they estimate the same truncated model (`docs/model.md`).
//!
//! It never decides what a material does: it only counts the events the
//! integrators report.

use crate::Rgb;
use crate::sampling::Stream;

/// The default of `RenderOptions::specular`: light crosses glass bodies
/// (two events each), prisms and lenses, and goes to and fro between
/// facing mirrors; Russian roulette ends most long runs well before it.
pub const DEFAULT_SPECULAR: u32 = 32;

/// Specular events in a row up to which a path always goes on; past
/// them, Russian roulette decides.
pub const ROULETTE_FROM: u32 = 8;

/// How far paths go: most diffuse reflections, most specular events in a
/// row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Limits {
    pub bounces: u32,
    pub specular: u32,
}

/// The specular events since a path (or photon) left the floor, a light
/// or its last diffuse wall, and its throughput then.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Run {
    events: u32,
    start: f64,
}

/// What a specular event leaves of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Onward {
    /// The path goes on, its throughput multiplied by this (1 before the
    /// roulette, `1 / q` for a survivor of it).
    Go(f64),
    /// The run is longer than the limit.
    Limit,
    /// Russian roulette ended it.
    Roulette,
}

impl Run {
    /// A run starting at `throughput`.
    #[inline]
    pub fn new(throughput: Rgb) -> Run {
        Run {
            events: 0,
            start: throughput.max_element(),
        }
    }

    /// Whether the run holds specular events.
    #[inline]
    pub fn specular(&self) -> bool {
        self.events > 0
    }

    /// One more specular event, after which the path's throughput is
    /// `throughput`: whether it goes on, at most `limit` events in a row.
    /// Past [`ROULETTE_FROM`] events it survives with probability
    /// `q = min(1, max(throughput) / max(throughput at the run's start))`
    /// and is then weighted by `1 / q`: the expectation is unchanged. A
    /// draw is taken from `stream` only where `q < 1`.
    #[inline]
    pub fn event(&mut self, limit: u32, throughput: Rgb, stream: &mut Stream) -> Onward {
        self.events += 1;
        if self.events > limit {
            return Onward::Limit;
        }
        if self.events <= ROULETTE_FROM {
            return Onward::Go(1.0);
        }
        let q = throughput.max_element() / self.start;
        // Not below 1 (or not a number, from a start of zero): go on.
        if q.partial_cmp(&1.0) != Some(std::cmp::Ordering::Less) {
            return Onward::Go(1.0);
        }
        if q > 0.0 && stream.uniform() < q {
            // A survivor's throughput, times this, peaks at its run's
            // start again.
            Onward::Go(1.0 / q)
        } else {
            Onward::Roulette
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Short runs go on untouched and long ones stop at the limit; past
    /// the roulette's start, the expected weight of a survivor is the
    /// throughput's loss undone: E[survives / q] = 1, within 5 standard
    /// errors over 100,000 fixed-seed trials.
    #[test]
    fn runs_stop_at_the_limit_and_the_roulette_keeps_the_mean() {
        let mut stream = Stream::new(7, 0, 0);
        let mut run = Run::new(Rgb::ONE);
        for _ in 0..ROULETTE_FROM {
            assert_eq!(
                run.event(10, Rgb::splat(0.01), &mut stream),
                Onward::Go(1.0)
            );
        }
        let mut full = Run::new(Rgb::ONE);
        for _ in 0..3 {
            assert_eq!(full.event(3, Rgb::ONE, &mut stream), Onward::Go(1.0));
        }
        assert_eq!(full.event(3, Rgb::ONE, &mut stream), Onward::Limit);

        let q = 0.3;
        let trials = 100_000;
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        for k in 0..trials {
            let mut stream = Stream::new(11, k, 0);
            let mut run = Run::new(Rgb::ONE);
            for _ in 0..ROULETTE_FROM {
                run.event(100, Rgb::ONE, &mut stream);
            }
            let w = match run.event(100, Rgb::new(0.1, q, 0.2), &mut stream) {
                Onward::Go(w) => w,
                _ => 0.0,
            };
            sum += w;
            sum2 += w * w;
        }
        let n = trials as f64;
        let mean = sum / n;
        let se = ((sum2 / n - mean * mean) / n).sqrt();
        assert!((mean - 1.0).abs() < 5.0 * se, "{mean} ± {se}");
        assert!(se > 0.0 && se < 0.01);
    }
}
