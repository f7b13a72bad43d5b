//! Which lights next-event estimation sends shadow rays to, in a scene of
//! many lights.
//!
//! With every light sampled at every receiver (the plain estimator of
//! `model.md`), a sample costs a shadow ray per light, though on a floor
//! plan most lights sit behind walls in other rooms. A [`LightTable`]
//! cuts the plan into cells and casts, from a few probe points per cell, a
//! shadow ray to every light. Each cell reads its own probes and its eight
//! neighbours' and keeps
//!
//! - its *always-lights*: at most [`ALWAYS`], those of the largest shares
//!   of the light the probes received, each at least 5 % of it;
//! - its *seen* lights: the others that reached a probe, each with the
//!   fraction of its light (without shadows) that got through;
//! - a *defensive* share of every other light, by what it could bring the
//!   cell without shadows (`LightShape::importance`: intensity and falloff
//!   at the cell's nearest point, not sampled, so nothing next door is
//!   missed), and a little evenly.
//!
//! A receiver `x` in the cell takes every always-light (a shadow ray each,
//! as without the table) and, with probability `P(l | x)`, one more light
//! `l`, its contribution divided by `P(l | x)`; with the remaining
//! probability, none. `P(l | x)` is [`SEEN`] times `l`'s part of the seen
//! lights' weights at `x` (fraction through, times intensity, times
//! falloff at `x`: `LightShape::reach`), plus [`DEFENSIVE`] times its
//! defensive share. Every light but the always-lights has a defensive
//! share above zero, so the estimator is unbiased whatever the probes
//! missed (light through a door that no probe saw); the probes decide
//! only its noise.
//! A choice costs a pass over the cell's seen lights and a binary search
//! over its defensive table: a shadow ray or two per point, whatever the
//! number of lights.
//!
//! Most lights chosen by their defensive share lie in other rooms. Beside
//! the model, a fast path (`accel/dark.rs`) marks per cell the lights that one
//! opaque wall hides from the whole cell ([`LightTable::set_dark`]): such
//! a light brings exactly nothing, and a point that chooses it casts no
//! ray. The choice and its probabilities stay as they are, so the image
//! does too.

use flatray_geometry::DVec2;
use rayon::prelude::*;

use super::{Receiver, Visibility, light_contribution};
use crate::sampling::Stream;
use crate::scene::{LightShape, Scene};
use crate::{Rgb, Stats};

/// The most lights a cell evaluates at every receiver.
pub(crate) const ALWAYS: usize = 4;

/// The numbers one estimate draws: one per always-light, the choice among
/// the rest, and that light's own number.
pub(crate) const NUMBERS: usize = ALWAYS + 2;

/// The probability that a point chooses among the lights its cell's
/// probes saw (beside the always-lights), where there are any.
const SEEN: f64 = 0.8;

/// The probability that a point chooses from the cell's defensive share
/// of every light: what keeps every light's probability above zero.
const DEFENSIVE: f64 = 0.2;

/// Of the defensive share, the part spread evenly over the lights (the
/// rest goes by importance).
const EVEN: f64 = 0.1;

/// A light whose estimated share is at least this is always evaluated
/// (if among the [`ALWAYS`] largest).
const ALWAYS_SHARE: f64 = 0.05;

/// The most lights a cell keeps as seen, the brightest first; the others
/// are chosen by the defensive share alone.
const MAX_SEEN: usize = 64;

/// At most this many (cell, light) entries: the table's memory, about
/// 8 MiB.
pub(crate) const MAX_ENTRIES: usize = 1 << 20;

/// At most this many probe shadow rays to build a table.
const PROBE_RAYS: usize = 1 << 20;

/// The smallest cell, in pixels of the rendered image per side.
const MIN_CELL_PIXELS: f64 = 8.0;

/// A light that a cell's probes saw: its index, and the fraction of its
/// light (without shadows) that reached them times its intensity and
/// brightness: its weight at a point is this times its reach there.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Seen {
    light: u32,
    scale: f64,
}

/// One cell's choice, as built.
struct Cell {
    always: [u32; ALWAYS],
    seen: Vec<Seen>,
    /// The defensive share, cumulative over every light in index order
    /// (the always-lights take none): ends at 1, or is all zero.
    defensive: Vec<f64>,
}

/// The cells' choices of lights (see the module's documentation).
#[derive(Clone, Debug)]
pub(crate) struct LightTable {
    origin: DVec2,
    /// A cell's size in world units, per axis.
    cell: DVec2,
    columns: u32,
    rows: u32,
    lights: usize,
    /// Per cell, its always-lights (`u32::MAX` past the last).
    always: Vec<[u32; ALWAYS]>,
    /// Per cell, where its seen lights start in `seen`; one more at the
    /// end.
    seen_starts: Vec<u32>,
    seen: Vec<Seen>,
    /// Per cell, `lights` cumulative defensive shares.
    defensive: Vec<f64>,
    /// Per cell, a bit per light: set where one opaque wall hides the
    /// light from every point of the cell ([`LightTable::set_dark`]);
    /// empty where none was looked for.
    dark: Vec<u64>,
    /// Probe shadow rays cast to build the table (and to mark its dark
    /// lights).
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
        let corner = |index: usize| {
            let column = (index % columns as usize) as f64;
            let row = (index / columns as usize) as f64;
            origin + DVec2::new(column, row) * cell
        };
        // Each cell's probes: per light, what they received without and
        // with shadows.
        let probed: Vec<Vec<(f64, f64)>> = (0..count)
            .into_par_iter()
            .map(|index| {
                probe_cell(
                    scene,
                    corner(index),
                    cell,
                    probes,
                    (seed, index as u64),
                    shadows,
                )
            })
            .collect();
        // Each cell chooses from its own probes and its neighbours' (the
        // 3 x 3 cells around it): nine times the probes, where the light
        // changes little from cell to cell.
        let per_cell: Vec<Cell> = (0..count)
            .into_par_iter()
            .map(|index| {
                let (column, row) = (index % columns as usize, index / columns as usize);
                let mut sums = vec![(0.0, 0.0); lights];
                for r in row.saturating_sub(1)..(row + 2).min(rows as usize) {
                    for c in column.saturating_sub(1)..(column + 2).min(columns as usize) {
                        for (sum, &(open, shadowed)) in
                            sums.iter_mut().zip(&probed[r * columns as usize + c])
                        {
                            sum.0 += open;
                            sum.1 += shadowed;
                        }
                    }
                }
                choose_cell(scene, corner(index), cell, &sums)
            })
            .collect();
        let mut always = Vec::with_capacity(count);
        let mut seen_starts = Vec::with_capacity(count + 1);
        let mut seen = Vec::new();
        let mut defensive = Vec::with_capacity(count * lights);
        for c in per_cell {
            always.push(c.always);
            seen_starts.push(seen.len() as u32);
            seen.extend(c.seen);
            defensive.extend(c.defensive);
        }
        seen_starts.push(seen.len() as u32);
        Some(LightTable {
            origin,
            cell,
            columns,
            rows,
            lights,
            always,
            seen_starts,
            seen,
            defensive,
            dark: Vec::new(),
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
            + self.seen_starts.len() * 4
            + self.seen.len() * std::mem::size_of::<Seen>()
            + self.defensive.len() * 8
            + self.dark.len() * 8
    }

    /// The words of a cell's bits in [`LightTable::dark`].
    pub(crate) fn dark_words(&self) -> usize {
        self.lights.div_ceil(64)
    }

    /// Cell `cell`'s box, closed: where `accel/dark.rs` proves a light dark.
    pub(crate) fn cell_box(&self, cell: usize) -> (DVec2, DVec2) {
        let columns = self.columns as usize;
        let lo =
            self.origin + DVec2::new((cell % columns) as f64, (cell / columns) as f64) * self.cell;
        (lo, lo + self.cell)
    }

    /// Takes the marks of the lights that one opaque wall hides from the
    /// whole of each cell (`accel/dark.rs`: a bit per light, cell by cell, as
    /// [`LightTable::dark_words`] words a cell), and the rays cast to
    /// find them. [`LightTable::chosen_light`] then casts no shadow ray
    /// to such a light: its contribution is exactly 0.
    pub(crate) fn set_dark(&mut self, (dark, rays): (Vec<u64>, u64)) {
        if dark.len() == self.always.len() * self.dark_words() {
            self.dark = dark;
            self.probe_rays += rays;
        }
    }

    /// The number of cells.
    pub(crate) fn cells(&self) -> usize {
        self.always.len()
    }

    /// The number of lights.
    pub(crate) fn lights(&self) -> usize {
        self.lights
    }

    /// Whether `light` was marked dark at `x`, a point of cell `cell`.
    #[inline]
    pub(crate) fn dark_at(&self, cell: usize, light: usize, x: DVec2) -> bool {
        let Some(&word) = self.dark.get(cell * self.dark_words() + light / 64) else {
            return false;
        };
        if word & (1 << (light % 64)) == 0 {
            return false;
        }
        // A point off the canvas takes the nearest cell, whose proof does
        // not hold there.
        let (lo, hi) = self.cell_box(cell);
        x.cmpge(lo).all() && x.cmple(hi).all()
    }

    /// Marks in `taken` (one flag per light) the lights that points of the
    /// box `[lo, hi]` take most: the always-lights of every cell the box
    /// meets, and with `seen` their seen lights too. Other lights are
    /// taken only by their defensive share. Returns how many are marked.
    pub(crate) fn lights_in_box(
        &self,
        (lo, hi): (DVec2, DVec2),
        seen: bool,
        taken: &mut Vec<bool>,
    ) -> usize {
        taken.clear();
        taken.resize(self.lights, false);
        let (first, last) = (self.cell_of(lo), self.cell_of(hi));
        let columns = self.columns as usize;
        let (c0, r0) = (first % columns, first / columns);
        let (c1, r1) = (last % columns, last / columns);
        let mut count = 0;
        let mut mark = |light: usize| {
            if let Some(t) = taken.get_mut(light)
                && !*t
            {
                *t = true;
                count += 1;
            }
        };
        for row in r0.min(r1)..=r0.max(r1) {
            for column in c0.min(c1)..=c0.max(c1) {
                let cell = row * columns + column;
                self.always(cell).for_each(&mut mark);
                if seen {
                    let range =
                        self.seen_starts[cell] as usize..self.seen_starts[cell + 1] as usize;
                    self.seen[range].iter().for_each(|s| mark(s.light as usize));
                }
            }
        }
        count
    }

    /// The cell that holds `x`; a point off the canvas takes the nearest.
    #[inline]
    pub(crate) fn cell_of(&self, x: DVec2) -> usize {
        let at = (x - self.origin) / self.cell;
        // NaN clamps to 0 through the cast.
        let column = (at.x.max(0.0) as u64).min(self.columns as u64 - 1);
        let row = (at.y.max(0.0) as u64).min(self.rows as u64 - 1);
        (row * self.columns as u64 + column) as usize
    }

    /// Light from `scene`'s lights arriving at `x` (see
    /// [`crate::direct::direct_light_with`]), estimated by the cell's
    /// choice, with the [`NUMBERS`] numbers in `numbers`.
    #[inline]
    pub(crate) fn direct_light(
        &self,
        scene: &Scene,
        x: DVec2,
        receiver: Receiver,
        numbers: &[f64; NUMBERS],
        mut vis: impl FnMut(usize) -> Visibility,
        stats: &mut Stats,
    ) -> Rgb {
        let cell = self.cell_of(x);
        let mut sum = Rgb::ZERO;
        for (k, index) in self.always(cell).enumerate() {
            sum += light_contribution(scene, index, x, receiver, numbers[k], vis(index), stats);
        }
        sum + self.chosen_light(scene, (cell, x), receiver, numbers, vis, stats)
    }

    /// The always-lights of `cell`, in the order [`LightTable::direct_light`]
    /// takes them (the `k`-th takes the point's number `k`).
    #[inline]
    pub(crate) fn always(&self, cell: usize) -> impl Iterator<Item = usize> + '_ {
        self.always
            .get(cell)
            .into_iter()
            .flatten()
            .take_while(|&&l| l != u32::MAX)
            .map(|&l| l as usize)
    }

    /// The part of [`LightTable::direct_light`] at `x` in `cell` beyond the
    /// always-lights: the light chosen among the rest, its contribution
    /// divided by its probability, or zero where none is chosen.
    #[inline]
    pub(crate) fn chosen_light(
        &self,
        scene: &Scene,
        (cell, x): (usize, DVec2),
        receiver: Receiver,
        numbers: &[f64; NUMBERS],
        vis: impl FnMut(usize) -> Visibility,
        stats: &mut Stats,
    ) -> Rgb {
        let seen = self.seen_of(cell);
        let mut weights = [0.0; MAX_SEEN];
        for (w, s) in weights.iter_mut().zip(seen) {
            *w = seen_weight(scene, s, x);
        }
        let weights = (&weights[..seen.len()], 1);
        self.chosen_light_weighed(scene, (cell, x), weights, receiver, numbers, vis, stats)
    }

    /// [`LightTable::chosen_light`], with the weights of the cell's seen
    /// lights at `x` given: the `j`-th at `weights.0[j * weights.1]`, as
    /// [`LightTable::seen_weights`] leaves them.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn chosen_light_weighed(
        &self,
        scene: &Scene,
        (cell, x): (usize, DVec2),
        weights: (&[f64], usize),
        receiver: Receiver,
        numbers: &[f64; NUMBERS],
        mut vis: impl FnMut(usize) -> Visibility,
        stats: &mut Stats,
    ) -> Rgb {
        let Some((index, p)) = self.choose(cell, weights, numbers[ALWAYS]) else {
            return Rgb::ZERO;
        };
        // A light that a wall hides from the whole cell brings exactly
        // nothing: no ray needed.
        if self.dark_at(cell, index, x) {
            stats.work.chosen_lights += 1;
            stats.work.chosen_dark += 1;
            return Rgb::ZERO;
        }
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
        v / p
    }

    /// The seen lights of `cell`.
    #[inline]
    fn seen_of(&self, cell: usize) -> &[Seen] {
        &self.seen[self.seen_starts[cell] as usize..self.seen_starts[cell + 1] as usize]
    }

    /// The weight of each seen light of `cell` at each of `points`, light
    /// by light: the `j`-th light's at point `k` in
    /// `weights[j * points.len() + k]`, each the very value
    /// [`LightTable::chosen_light`] computes there (a point light's over
    /// all points in one loop, which the compiler vectorises: inlined
    /// always, for the caller's target features).
    #[inline(always)]
    pub(crate) fn seen_weights(
        &self,
        scene: &Scene,
        cell: usize,
        points: &[DVec2],
        weights: &mut Vec<f64>,
    ) {
        let seen = self.seen_of(cell);
        weights.clear();
        weights.resize(seen.len() * points.len(), 0.0);
        if points.is_empty() {
            return;
        }
        let r0 = scene.small_radius;
        for (column, s) in weights.chunks_exact_mut(points.len()).zip(seen) {
            let light = &scene.lights[s.light as usize];
            match light.shape {
                LightShape::Point { at } => {
                    // `LightShape::reach` of a point light, at a point,
                    // with the kind looked at once for all the points (a
                    // point light's falloff is finite and positive past
                    // `r0`: `usable` would change nothing).
                    let falloff = light.falloff;
                    for (w, &x) in column.iter_mut().zip(points) {
                        *w = s.scale * crate::lights::point::reach(at, falloff, (x, x), r0);
                    }
                }
                _ => {
                    for (w, &x) in column.iter_mut().zip(points) {
                        *w = seen_weight(scene, s, x);
                    }
                }
            }
        }
    }

    /// The light that the number `u` chooses in cell `cell`, with the
    /// probability of choosing it there, or none; `weights` as in
    /// [`LightTable::chosen_light_weighed`].
    #[inline]
    fn choose(
        &self,
        cell: usize,
        (weights, stride): (&[f64], usize),
        u: f64,
    ) -> Option<(usize, f64)> {
        let seen = self.seen_of(cell);
        let defensive = &self.defensive[cell * self.lights..(cell + 1) * self.lights];
        let a = if seen.is_empty() { 0.0 } else { SEEN };
        let b = if defensive.last().is_some_and(|&c| c > 0.0) {
            DEFENSIVE
        } else {
            0.0
        };
        // Each seen light's weight at the point: its visibility in the
        // cell times what it could bring the point without shadows.
        let weight = |k: usize| weights.get(k * stride).copied().unwrap_or(0.0);
        let mut total = 0.0;
        for k in 0..seen.len() {
            total += weight(k);
        }
        let chosen = if u < a {
            let target = u / a * total;
            let mut cumulative = 0.0;
            let mut found = None;
            for (k, s) in seen.iter().enumerate() {
                cumulative += weight(k);
                if target < cumulative {
                    found = Some(s.light as usize);
                    break;
                }
            }
            found?
        } else if u < a + b {
            let v = (u - a) / b;
            defensive.partition_point(|&c| c <= v).min(self.lights - 1)
        } else {
            return None;
        };
        // Its probability, by either way.
        let mut p = 0.0;
        if total > 0.0
            && let Some(k) = seen.iter().position(|s| s.light as usize == chosen)
        {
            p += a * weight(k) / total;
        }
        let before = if chosen == 0 {
            0.0
        } else {
            defensive[chosen - 1]
        };
        p += b * (defensive[chosen] - before);
        (p > 0.0).then_some((chosen, p))
    }
}

/// Seen light `s`'s weight at `x`: its visibility in the cell times what
/// it could bring `x` without shadows.
#[inline(always)]
fn seen_weight(scene: &Scene, s: &Seen, x: DVec2) -> f64 {
    let light = &scene.lights[s.light as usize];
    s.scale * light.shape.reach(light, (x, x), scene.small_radius)
}

/// Per light, what a cell's probes received from it without shadows and
/// with them.
fn probe_cell(
    scene: &Scene,
    lo: DVec2,
    size: DVec2,
    probes: usize,
    (seed, index): (u64, u64),
    shadows: bool,
) -> Vec<(f64, f64)> {
    let mut stream = Stream::new(seed, index, PROBE_STREAM);
    let points: Vec<(DVec2, f64)> = (0..probes)
        .map(|_| {
            let (jx, jy) = stream.uniform_pair();
            (lo + DVec2::new(jx, jy) * size, stream.uniform())
        })
        .collect();
    let mut stats = Stats::default();
    (0..scene.lights.len())
        .map(|light| {
            let (mut open, mut shadowed) = (0.0, 0.0);
            for &(x, u) in &points {
                let unblocked = brightness(light_contribution(
                    scene,
                    light,
                    x,
                    Receiver::FLOOR,
                    u,
                    Visibility::Known(Rgb::ONE),
                    &mut stats,
                ));
                open += unblocked;
                if unblocked > 0.0 {
                    shadowed += if shadows {
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
                        unblocked
                    };
                }
            }
            (open, shadowed)
        })
        .collect()
}

/// One cell's always-lights, seen lights and defensive shares, from the
/// probes' sums per light (without shadows, with them) around it.
fn choose_cell(scene: &Scene, lo: DVec2, size: DVec2, sums: &[(f64, f64)]) -> Cell {
    let lights = scene.lights.len();
    let shadowed = |l: usize| sums[l].1;
    // The always-lights: the largest estimated shares, over the threshold.
    let total: f64 = sums.iter().map(|s| s.1).sum();
    let mut order: Vec<usize> = (0..lights).collect();
    order.sort_by(|&a, &b| shadowed(b).total_cmp(&shadowed(a)).then(a.cmp(&b)));
    let mut always = [u32::MAX; ALWAYS];
    let mut taken = vec![false; lights];
    for (slot, &light) in always.iter_mut().zip(&order) {
        if !(total > 0.0 && shadowed(light) >= ALWAYS_SHARE * total) {
            break;
        }
        *slot = light as u32;
        taken[light] = true;
    }
    let seen: Vec<Seen> = order
        .iter()
        .filter(|&&l| !taken[l] && sums[l].1 > 0.0 && sums[l].0 > 0.0)
        .take(MAX_SEEN)
        .map(|&l| {
            let light = &scene.lights[l];
            let visibility = (sums[l].1 / sums[l].0).min(1.0);
            let brightness = (light.color.x + light.color.y + light.color.z) / 3.0;
            let scale = visibility * light.intensity * brightness;
            Seen {
                light: l as u32,
                scale: if scale.is_finite() {
                    scale.max(0.0)
                } else {
                    0.0
                },
            }
        })
        .collect();
    // Without shadows, no probe: a bound that sees every light.
    let importance: Vec<f64> = scene
        .lights
        .iter()
        .map(|l| l.shape.importance(l, (lo, lo + size), scene.small_radius))
        .collect();
    let defensive = defensive_shares(&importance, &taken);
    Cell {
        always,
        seen,
        defensive,
    }
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

/// The cumulative defensive shares over every light: `1 - EVEN` by
/// importance and `EVEN` evenly, over the lights not `taken` (which get
/// none). The last is exactly 1; all are 0 when every light is taken.
fn defensive_shares(importance: &[f64], taken: &[bool]) -> Vec<f64> {
    let free = taken.iter().filter(|&&t| !t).count();
    if free == 0 {
        return vec![0.0; taken.len()];
    }
    let total: f64 = importance
        .iter()
        .zip(taken)
        .filter(|(_, t)| !**t)
        .map(|(i, _)| i)
        .sum();
    let by_importance = total > 0.0 && total.is_finite();
    let even = if by_importance { EVEN } else { 1.0 };
    let mut cumulative = 0.0;
    let mut shares: Vec<f64> = importance
        .iter()
        .zip(taken)
        .map(|(&i, &t)| {
            if !t {
                cumulative += even / free as f64;
                if by_importance {
                    cumulative += (1.0 - EVEN) * i / total;
                }
            }
            cumulative
        })
        .collect();
    // The last free light ends the table at exactly 1.
    if let Some(last) = taken.iter().rposition(|&t| !t) {
        for share in &mut shares[last..] {
            *share = 1.0;
        }
    }
    shares
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box marks the always-lights (and with `seen`, the seen lights)
    /// of exactly the cells it meets, also where it reaches past the
    /// canvas.
    #[test]
    fn a_box_marks_the_lights_of_the_cells_it_meets() {
        let (columns, rows, lights) = (5u32, 3u32, 11usize);
        let count = (columns * rows) as usize;
        let seen: Vec<Seen> = (0..count)
            .flat_map(|c| {
                (0..c % 3).map(move |k| Seen {
                    light: ((c * 3 + k + 4) % lights) as u32,
                    scale: 1.0,
                })
            })
            .collect();
        let mut seen_starts = vec![0u32];
        for c in 0..count {
            seen_starts.push(seen_starts[c] + (c % 3) as u32);
        }
        let table = LightTable {
            origin: DVec2::new(-3.0, 7.0),
            cell: DVec2::new(2.0, 0.5),
            columns,
            rows,
            lights,
            always: (0..count)
                .map(|c| {
                    [
                        (c % lights) as u32,
                        ((c + 2) % lights) as u32,
                        u32::MAX,
                        u32::MAX,
                    ]
                })
                .collect(),
            seen_starts,
            seen,
            defensive: vec![0.0; count * lights],
            dark: Vec::new(),
            probe_rays: 0,
        };
        let mut stream = Stream::new(7, 0, 0);
        let mut taken = Vec::new();
        for _ in 0..2000 {
            // Corners from before the canvas to past it.
            let mut point =
                || DVec2::new(-5.0 + 14.0 * stream.uniform(), 6.0 + 2.5 * stream.uniform());
            let (a, b) = (point(), point());
            let (lo, hi) = (a.min(b), a.max(b));
            for with_seen in [false, true] {
                let mut expected = vec![false; lights];
                let (end_x, end_y) = (-3.0 + 10.0, 7.0 + 1.5);
                let (lo_c, hi_c) = (
                    lo.max(DVec2::new(-3.0, 7.0)).min(DVec2::new(end_x, end_y)),
                    hi.max(DVec2::new(-3.0, 7.0)).min(DVec2::new(end_x, end_y)),
                );
                for c in 0..count {
                    let (column, row) = ((c % 5) as f64, (c / 5) as f64);
                    let cell_lo = DVec2::new(-3.0 + 2.0 * column, 7.0 + 0.5 * row);
                    let cell_hi = cell_lo + DVec2::new(2.0, 0.5);
                    let meets = lo_c.x <= cell_hi.x
                        && hi_c.x >= cell_lo.x
                        && lo_c.y <= cell_hi.y
                        && hi_c.y >= cell_lo.y;
                    if meets {
                        for &l in table.always[c].iter().filter(|&&l| l != u32::MAX) {
                            expected[l as usize] = true;
                        }
                        if with_seen {
                            let range =
                                table.seen_starts[c] as usize..table.seen_starts[c + 1] as usize;
                            for s in &table.seen[range] {
                                expected[s.light as usize] = true;
                            }
                        }
                    }
                }
                let marked = table.lights_in_box((lo, hi), with_seen, &mut taken);
                assert_eq!(taken, expected, "{lo} {hi} seen {with_seen}");
                assert_eq!(marked, expected.iter().filter(|&&t| t).count());
            }
        }
    }

    #[test]
    fn every_free_light_keeps_a_positive_defensive_share_and_they_end_at_one() {
        for (importance, taken) in [
            (vec![0.0, 3.0, 1.0, 0.0], vec![false, false, true, false]),
            (vec![0.0; 4], vec![false; 4]),
            (vec![f64::INFINITY, 1.0, 0.0, 0.0], vec![false; 4]),
            (vec![1.0, 2.0, 3.0, 4.0], vec![false, false, false, true]),
        ] {
            let c = defensive_shares(&importance, &taken);
            let mut before = 0.0;
            for (l, &cumulative) in c.iter().enumerate() {
                let p = cumulative - before;
                if taken[l] {
                    assert_eq!(p, 0.0, "{c:?}");
                } else {
                    assert!(p > 0.0, "{c:?}");
                }
                before = cumulative;
            }
            assert_eq!(c[c.len() - 1], 1.0, "{c:?}");
        }
        assert_eq!(defensive_shares(&[1.0, 2.0], &[true, true]), vec![0.0, 0.0]);
    }
}
