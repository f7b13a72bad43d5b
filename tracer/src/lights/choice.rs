//! Which lights next-event estimation sends shadow rays to, in a scene of
//! many lights.
//!
//! With every light sampled at every receiver (the plain estimator of
//! `model.md`), a sample costs a shadow ray per light, though on a floor
//! plan most lights sit behind walls in other rooms. A [`LightTable`]
//! cuts the plan into cells and, per cell, estimates each light's share
//! of the direct light there from a few probe points (shadow rays and
//! all). A receiver in the cell then takes
//!
//! - every light of its cell's *always* list (at most [`ALWAYS`] lights,
//!   those of the largest shares), each by one shadow ray as before;
//! - and, with probability `P(l)`, one more light `l` of the rest, its
//!   contribution divided by `P(l)`; with the remaining probability, none.
//!
//! `P(l)` mixes the light's estimated share (with shadows), its share of
//! what it could bring the cell without shadows (`LightShape::importance`:
//! its intensity and falloff at the cell's nearest point, not sampled, so
//! no probe can miss a bright light next door) and an even share. It is
//! positive for every light: the estimator is unbiased whatever the
//! probes missed (light through a door that no probe saw), and the probes
//! decide only its noise. A lookup is one cell and one binary search over the cell's
//! cumulative table: its cost grows like `log(lights)`.

use flatray_geometry::DVec2;
use rayon::prelude::*;

use crate::light::{Receiver, Visibility, light_contribution};
use crate::sampling::Stream;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// The most lights a cell evaluates at every receiver.
pub(crate) const ALWAYS: usize = 4;

/// The numbers one estimate draws: one per always-light, the choice among
/// the rest, and that light's own number.
pub(crate) const NUMBERS: usize = ALWAYS + 2;

/// The share of the choice's probability given to the lights' shares of
/// importance without shadows, and to an even share of every light: what
/// keeps every light's probability above zero.
const UNSHADOWED: f64 = 0.19;
const EVEN: f64 = 0.01;

/// A light whose estimated share is at least this is always evaluated
/// (if among the [`ALWAYS`] largest).
const ALWAYS_SHARE: f64 = 0.05;

/// At most this many (cell, light) entries: the table's memory, about
/// 16 MiB.
pub(crate) const MAX_ENTRIES: usize = 1 << 20;

/// At most this many probe shadow rays to build a table.
const PROBE_RAYS: usize = 1 << 20;

/// The smallest cell, in pixels of the rendered image per side.
const MIN_CELL_PIXELS: f64 = 8.0;

/// One light of a cell's rest: its index and the cumulative probability
/// up to and including it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    light: u32,
    cumulative: f64,
}

/// The cells' choices of lights (see the module's documentation).
#[derive(Clone, Debug)]
pub(crate) struct LightTable {
    origin: DVec2,
    /// A cell's size in world units, per axis.
    cell: DVec2,
    columns: u32,
    rows: u32,
    /// Per cell, its always-lights (`u32::MAX` past the last).
    always: Vec<[u32; ALWAYS]>,
    /// Per cell, where its entries start in `rest`; one more at the end.
    starts: Vec<u32>,
    rest: Vec<Entry>,
    /// Probe shadow rays cast to build the table.
    pub probe_rays: u64,
}

impl LightTable {
    /// The table for `scene`'s canvas, rendered at `scale` pixels per
    /// world unit; `seed` keys the probes' random numbers. Each cell is
    /// built from its own probes alone, so the table does not depend on
    /// the threads. `None` for a scene without lights.
    pub(crate) fn build(scene: &Scene, scale: f64, seed: u64, shadows: bool) -> Option<LightTable> {
        let lights = scene.lights.len();
        if lights == 0 {
            return None;
        }
        let size = DVec2::new(scene.canvas.width as f64, scene.canvas.height as f64);
        // As many cells as the budget allows, none under the smallest
        // size; about square.
        let min_cell = MIN_CELL_PIXELS / scale.max(f64::MIN_POSITIVE);
        let by_size = (size.x / min_cell).max(1.0) * (size.y / min_cell).max(1.0);
        let cells = by_size.min((MAX_ENTRIES / lights).max(1) as f64).max(1.0);
        let side = (size.x * size.y / cells).sqrt();
        let columns = (size.x / side).ceil().clamp(1.0, 4096.0) as u32;
        let rows = (size.y / side).ceil().clamp(1.0, 4096.0) as u32;
        let cell = DVec2::new(size.x / columns as f64, size.y / rows as f64);
        let count = columns as usize * rows as usize;
        let probes = (PROBE_RAYS / (count * lights)).clamp(1, 8);
        let origin = scene.canvas.origin;
        let per_cell: Vec<([u32; ALWAYS], Vec<Entry>)> = (0..count)
            .into_par_iter()
            .map(|index| {
                let column = (index % columns as usize) as f64;
                let row = (index / columns as usize) as f64;
                let lo = origin + DVec2::new(column, row) * cell;
                cell_choice(scene, lo, cell, probes, (seed, index as u64), shadows)
            })
            .collect();
        let mut always = Vec::with_capacity(count);
        let mut starts = Vec::with_capacity(count + 1);
        let mut rest = Vec::with_capacity(count * lights);
        for (a, r) in per_cell {
            always.push(a);
            starts.push(rest.len() as u32);
            rest.extend(r);
        }
        starts.push(rest.len() as u32);
        Some(LightTable {
            origin,
            cell,
            columns,
            rows,
            always,
            starts,
            rest,
            probe_rays: if shadows {
                (count * lights * probes) as u64
            } else {
                0
            },
        })
    }

    /// Bytes the table holds.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.always.len() * std::mem::size_of::<[u32; ALWAYS]>()
            + self.starts.len() * 4
            + self.rest.len() * std::mem::size_of::<Entry>()
    }

    /// The cell that holds `x`; a point off the canvas takes the nearest.
    #[inline]
    fn cell_of(&self, x: DVec2) -> usize {
        let at = (x - self.origin) / self.cell;
        // NaN clamps to 0 through the cast.
        let column = (at.x.max(0.0) as u64).min(self.columns as u64 - 1);
        let row = (at.y.max(0.0) as u64).min(self.rows as u64 - 1);
        (row * self.columns as u64 + column) as usize
    }

    /// Light from `scene`'s lights arriving at `x` (see
    /// [`crate::light::direct_light_with`]), estimated by the cell's
    /// choice, with the [`NUMBERS`] numbers in `numbers`.
    #[inline]
    pub(crate) fn direct_light(
        &self,
        scene: &Scene,
        x: DVec2,
        receiver: Receiver,
        numbers: &[f64; NUMBERS],
        vis: impl Fn(usize) -> Visibility,
        stats: &mut Stats,
    ) -> Rgb {
        let cell = self.cell_of(x);
        let mut sum = Rgb::ZERO;
        for (k, &light) in self.always[cell].iter().enumerate() {
            if light == u32::MAX {
                break;
            }
            let index = light as usize;
            sum += light_contribution(scene, index, x, receiver, numbers[k], vis(index), stats);
        }
        let rest = &self.rest[self.starts[cell] as usize..self.starts[cell + 1] as usize];
        let u = numbers[ALWAYS];
        // The first entry whose cumulative probability passes `u`; past
        // the last, no light.
        let at = rest.partition_point(|e| e.cumulative <= u);
        if let Some(entry) = rest.get(at) {
            let before = if at == 0 {
                0.0
            } else {
                rest[at - 1].cumulative
            };
            let p = entry.cumulative - before;
            let index = entry.light as usize;
            let v = light_contribution(
                scene,
                index,
                x,
                receiver,
                numbers[ALWAYS + 1],
                vis(index),
                stats,
            );
            stats.work.chosen_lights += 1;
            sum += v / p;
        }
        sum
    }
}

/// One cell's always-lights and the cumulative table of the rest.
fn cell_choice(
    scene: &Scene,
    lo: DVec2,
    size: DVec2,
    probes: usize,
    (seed, index): (u64, u64),
    shadows: bool,
) -> ([u32; ALWAYS], Vec<Entry>) {
    let lights = scene.lights.len();
    let mut stream = Stream::new(seed, index, PROBE_STREAM);
    let points: Vec<(DVec2, f64)> = (0..probes)
        .map(|_| {
            let (jx, jy) = stream.uniform_pair();
            (lo + DVec2::new(jx, jy) * size, stream.uniform())
        })
        .collect();
    let mut stats = Stats::default();
    let mut shadowed = vec![0.0; lights];
    // Without shadows, no probe: a bound that sees every light.
    let unshadowed: Vec<f64> = scene
        .lights
        .iter()
        .map(|l| l.shape.importance(l, (lo, lo + size), scene.small_radius))
        .collect();
    for (light, estimate) in shadowed.iter_mut().enumerate() {
        for &(x, u) in &points {
            let open = light_contribution(
                scene,
                light,
                x,
                Receiver::FLOOR,
                u,
                Visibility::Known(Rgb::ONE),
                &mut stats,
            );
            let open = brightness(open);
            if open > 0.0 {
                *estimate += if shadows {
                    brightness(light_contribution(
                        scene,
                        light,
                        x,
                        Receiver::FLOOR,
                        u,
                        Visibility::Trace,
                        &mut stats,
                    ))
                } else {
                    open
                };
            }
        }
    }
    let share = mixed_shares(&shadowed, &unshadowed);
    // The always-lights: the largest estimated shares, over the threshold.
    let total: f64 = shadowed.iter().sum();
    let mut order: Vec<usize> = (0..lights).collect();
    order.sort_by(|&a, &b| shadowed[b].total_cmp(&shadowed[a]).then(a.cmp(&b)));
    let mut always = [u32::MAX; ALWAYS];
    let mut taken = vec![false; lights];
    for (slot, &light) in always.iter_mut().zip(&order) {
        if !(total > 0.0 && shadowed[light] >= ALWAYS_SHARE * total) {
            break;
        }
        *slot = light as u32;
        taken[light] = true;
    }
    let mut cumulative = 0.0;
    let mut rest = Vec::with_capacity(lights);
    for light in 0..lights {
        if taken[light] {
            continue;
        }
        cumulative += share[light];
        rest.push(Entry {
            light: light as u32,
            cumulative,
        });
    }
    // With no always-light, where the probes saw light, the rest is every
    // light and its shares sum to 1 (up to rounding): one is always chosen.
    if always[0] == u32::MAX
        && total > 0.0
        && let Some(last) = rest.last_mut()
    {
        last.cumulative = 1.0;
    }
    (always, rest)
}

/// Probes draw from stream index `PROBE_STREAM` of their cell's key,
/// apart from every pixel's.
const PROBE_STREAM: u64 = 1 << 41;

/// A colour's brightness for choosing: the mean of its channels.
#[inline]
fn brightness(c: Rgb) -> f64 {
    let b = (c.x + c.y + c.z) / 3.0;
    if b.is_finite() { b.max(0.0) } else { 0.0 }
}

/// Each light's probability of being chosen: its share with shadows,
/// with weight `1 - UNSHADOWED - EVEN`, its share without, with weight
/// `UNSHADOWED`, and an even share, with weight `EVEN`. Where the probes
/// saw no light at all, the first weight goes to no light (the shares sum
/// to `UNSHADOWED + EVEN`: most points there cast no shadow ray); a share
/// without shadows whose total is zero gives its weight to the even one.
fn mixed_shares(shadowed: &[f64], unshadowed: &[f64]) -> Vec<f64> {
    let n = shadowed.len();
    let total_shadowed: f64 = shadowed.iter().sum();
    let total_unshadowed: f64 = unshadowed.iter().sum();
    let mut w_shadowed = 1.0 - UNSHADOWED - EVEN;
    let mut w_unshadowed = UNSHADOWED;
    if !(total_shadowed > 0.0 && total_shadowed.is_finite()) {
        w_shadowed = 0.0;
    }
    let mut w_even = EVEN;
    if !(total_unshadowed > 0.0 && total_unshadowed.is_finite()) {
        w_even += w_unshadowed;
        w_unshadowed = 0.0;
    }
    (0..n)
        .map(|l| {
            let mut p = w_even / n as f64;
            if w_shadowed > 0.0 {
                p += w_shadowed * shadowed[l] / total_shadowed;
            }
            if w_unshadowed > 0.0 {
                p += w_unshadowed * unshadowed[l] / total_unshadowed;
            }
            p
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_light_keeps_a_positive_share_and_the_shares_sum_to_one() {
        for (shadowed, unshadowed) in [
            (vec![0.0, 3.0, 1.0, 0.0], vec![1.0, 3.0, 1.0, 0.0]),
            (vec![0.0; 4], vec![1.0, 0.0, 2.0, 0.0]),
            (vec![0.0; 4], vec![0.0; 4]),
            (vec![f64::INFINITY, 1.0, 0.0, 0.0], vec![1.0; 4]),
        ] {
            let p = mixed_shares(&shadowed, &unshadowed);
            assert!(p.iter().all(|&p| p > 0.0 && p.is_finite()), "{p:?}");
            // Where no probe saw light, most points choose no light.
            let seen: f64 = shadowed.iter().sum();
            let sum = if seen > 0.0 && seen.is_finite() {
                1.0
            } else {
                UNSHADOWED + EVEN
            };
            assert!((p.iter().sum::<f64>() - sum).abs() < 1e-12, "{p:?}");
        }
    }
}
