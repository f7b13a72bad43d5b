//! One pixel's estimate over the passes of a render: the floor's direct
//! light (once per pixel with the floor memo, its strata sharing shadow
//! rays where the coherence masks allow), then its path samples in the
//! order of their arcs, the floor's rays culled by block and arc and
//! traced in lanes where the plan says so.

use std::ops::Range;

use flatray_geometry::{DVec2, Hit, HitLanes, Ray, RayLanes, Skip};

use flatray_cache::WallMemo;

use crate::accel::coherence::{Coherence, FloorCoherence, centre_transmittance};
use crate::accel::culling::BlockCulling;
use crate::accel::shortcut::memo_bounce;
use crate::accel::strata::{direct_light_chosen_strata, direct_light_strata};
use crate::direct::{Strata, direct_light_chosen, direct_light_points, numbers_per_point};
use crate::estimators::choice::LightTable;
use crate::estimators::square::{Square, square_light, takes_square};
use crate::estimators::{Receiver, Visibility, at_point, through_glass};
use crate::film::{PixelSums, Sums};
use crate::lines::Lines;
use crate::options::{LONG_LIST, RenderOptions};
use crate::passes::Pass;
use crate::path::{Trace, path_begin, path_finish, path_sample};
use crate::sampling::{
    ARCS, Stream, StreamKey, arc_points, first_sample_of_arc, sample_arc, sobol_points,
};
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// The buffers of a pixel's floor memo, kept by a tile for all its pixels:
/// no allocation per pixel.
#[derive(Default)]
pub(crate) struct Batch {
    /// Each light's visibility over the pixel (without coherence masks,
    /// the same for every pixel, and filled once).
    pub(crate) visibility: Vec<Visibility>,
    /// Per light, whether the pixel shares its transmittance and it is
    /// not yet traced (with a light table and coherence masks).
    pub(crate) shared: Vec<bool>,
    /// The floor memo's points of one pixel, for all its passes.
    pub(crate) floor: Strata,
    /// The light table's weights of the seen lights at those points.
    pub(crate) weights: Vec<f64>,
    /// The path samples' sums of each pass.
    pub(crate) sums: Vec<Sums>,
    /// Per light, whether the tile's points have its shadow list.
    pub(crate) listed: Vec<bool>,
}

/// What every pixel of one render pass shares.
pub(crate) struct Context<'a> {
    pub(crate) options: &'a RenderOptions,
    pub(crate) pass: &'a Pass,
    pub(crate) size: (u32, u32),
    /// Whether the floor's direct light is estimated once per pixel.
    pub(crate) floor_memo: bool,
    /// Whether that estimate takes points, spots and suns over the
    /// pixel's square in closed form (`Plan::floor_squares`).
    pub(crate) floor_squares: bool,
    /// Whether the pass measures its noise's split at the probe pixels
    /// (the first pass, with the floor memo: `passes::point_rate`).
    pub(crate) measures: bool,
    /// Where that estimate's strata can share their shadow rays.
    pub(crate) coherence: Option<&'a FloorCoherence>,
    /// Whether the floor's rays test only their arc's walls.
    pub(crate) culling: bool,
    pub(crate) trace: Trace<'a>,
    /// The wall memo, where paths take the one-bounce shortcut
    /// (`accel/shortcut.rs`: one bounce, the memo, not the reference).
    pub(crate) one_bounce_memo: Option<&'a WallMemo>,
    /// Whether the floor memo's points are taken light by light
    /// (`accel::strata`).
    pub(crate) strata_loops: bool,
    /// The pass's lines (`lines.rs`): where the render has them, they
    /// take the floor's indirect light, and pixels take no path samples.
    pub(crate) lines: Option<&'a Lines>,
    /// [`render_pixel`], compiled for this processor.
    pub(crate) render_pixel: PixelFn,
}

pub(crate) type PixelFn = fn(
    &[Context],
    Option<PixelSums>,
    (u32, u32),
    Option<&BlockCulling>,
    &mut Batch,
    &mut Stats,
) -> PixelSums;

/// [`render_pixel`] compiled with AVX2 (the same operations, so the same
/// bits: no fused multiply-add is enabled).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) fn render_pixel_avx2(
    contexts: &[Context],
    total: Option<PixelSums>,
    (x, y): (u32, u32),
    culled: Option<&BlockCulling>,
    batch: &mut Batch,
    stats: &mut Stats,
) -> PixelSums {
    render_pixel(contexts, total, (x, y), culled, batch, stats)
}

/// The fastest [`render_pixel`] this processor runs.
pub(crate) fn pixel_fn() -> PixelFn {
    #[cfg(target_arch = "x86_64")]
    if !flatray_geometry::portable_forced() && is_x86_feature_detected!("avx2") {
        return |contexts, total, xy, culled, batch, stats| {
            // SAFETY: the processor has AVX2, checked just above.
            unsafe { render_pixel_avx2(contexts, total, xy, culled, batch, stats) }
        };
    }
    // Out of line, compiled for any x86-64 processor (or any other).
    render_pixel
}

/// Stream sample indices from here up key the floor memo's points' line
/// light numbers, apart from every path sample's.
pub(crate) const FLOOR_STREAMS: u64 = 1 << 40;

/// The stream sample index that draws a pixel's seeds for its floor
/// points' scrambling.
pub(crate) const FLOOR_SEED_STREAM: u64 = (1 << 41) + 1;

/// One pixel's totals after the passes of `contexts` (one per pass, in
/// order), from its totals `total` before them (`None` before the first
/// pass). Each pass adds the floor's direct light and its path samples,
/// each half weighted by its samples (`passes.rs`). With the floor memo,
/// the floor's direct light is estimated once per pixel over all the
/// passes' floor points, each pass reading its own; without, each sample
/// estimates it anew. A sample whose estimate is not finite is left out
/// and reported in `stats`.
#[inline(always)]
pub(crate) fn render_pixel(
    contexts: &[Context],
    mut total: Option<PixelSums>,
    (x, y): (u32, u32),
    culled: Option<&BlockCulling>,
    batch: &mut Batch,
    stats: &mut Stats,
) -> PixelSums {
    let (Some(first), Some(last)) = (contexts.first(), contexts.last()) else {
        return total.unwrap_or_default();
    };
    let scene = first.trace.scene;
    let pixel = Pixel::new(scene, first.size, x, y, first.options.seed);
    // The passes' floor points: the direct light at each, filled once.
    let points = first.pass.points.start..last.pass.points.end;
    if first.floor_memo && !points.is_empty() {
        floor_direct(
            contexts,
            &pixel,
            (x, y),
            points.clone(),
            culled,
            batch,
            stats,
        );
    }
    // Every pass's path samples, arc by arc over all of them.
    let mut sums = std::mem::take(&mut batch.sums);
    sums.clear();
    sums.extend(contexts.iter().map(|c| Sums::new(c.pass.middle)));
    // The lines took the floor's indirect light: no path samples.
    if first.lines.is_none() {
        path_samples(contexts, &pixel, (x, y), culled, &mut sums, stats);
    }
    for (context, sum) in contexts.iter().zip(&sums) {
        let pass_sums = pass_sums(
            context,
            *sum,
            (x, y),
            &batch.floor.values,
            points.start,
            stats,
        );
        total = Some(match total {
            None => pass_sums,
            Some(t) => crate::passes::fold(t, pass_sums),
        });
    }
    batch.sums = sums;
    total.unwrap_or_default()
}

/// The floor's direct light at the passes' floor `points` of pixel
/// `(x, y)`, into `batch.floor.values`: each light's visibility over the
/// pixel where the coherence masks know it, the lights taken over the
/// pixel's square in closed form, the sampled estimate at each point, and
/// the closed forms through one flat mirror and one glass edge.
#[inline(always)]
fn floor_direct(
    contexts: &[Context],
    pixel: &Pixel,
    (x, y): (u32, u32),
    points: Range<u32>,
    culled: Option<&BlockCulling>,
    batch: &mut Batch,
    stats: &mut Stats,
) {
    let Some(first) = contexts.first() else {
        return;
    };
    let trace = &first.trace;
    let scene = trace.scene;
    let step = pixel.step;
    let corner = scene.canvas.origin + pixel.position * step;
    // Each light's transmittance where the whole pixel shares it.
    let centre = corner + 0.5 * step;
    // The floor's shadow rays, its points' and its centre's, take the
    // pixel's block lists.
    let receiver = Receiver {
        shadow_walls: culled.map(|c| &c.shadows[..]),
        ..Receiver::FLOOR
    };
    pixel_visibility(first, (x, y), centre, receiver, batch, stats);
    let square = if first.floor_squares {
        square_lights(
            scene,
            (corner, step),
            receiver,
            &mut batch.visibility,
            stats,
        )
    } else {
        Rgb::ZERO
    };
    floor_points(
        scene,
        trace.light_table,
        (pixel, (corner, step)),
        points.clone(),
        &mut batch.floor,
    );
    sampled_direct(first, centre, receiver, batch, stats);
    if square != Rgb::ZERO {
        for value in &mut batch.floor.values {
            *value += square;
        }
    }
    closed_forms_at_points(contexts, points.start, &mut batch.floor, stats);
}

/// Each light's visibility over the pixel, into `batch.visibility`, and
/// with a light table, whether the pixel shares it untraced, into
/// `batch.shared`.
#[inline(always)]
fn pixel_visibility(
    first: &Context,
    (x, y): (u32, u32),
    centre: DVec2,
    receiver: Receiver,
    batch: &mut Batch,
    stats: &mut Stats,
) {
    let trace = &first.trace;
    let scene = trace.scene;
    let visibility = &mut batch.visibility;
    batch.shared.clear();
    match first.coherence {
        // With a light table, each point takes a few lights: a shared
        // transmittance is traced when a point first takes its light.
        Some(coherence) if trace.light_table.is_some() => {
            visibility.clear();
            for state in coherence.pixel(x, y) {
                let (vis, shared) = match state {
                    Coherence::Varies => (Visibility::Trace, false),
                    Coherence::Same => (Visibility::Trace, true),
                    Coherence::Clear => {
                        stats.work.floor_shared_visibility += 1;
                        (Visibility::Known(Rgb::ONE), false)
                    }
                };
                visibility.push(vis);
                batch.shared.push(shared);
            }
        }
        Some(coherence) => {
            visibility.clear();
            visibility.extend(
                coherence
                    .pixel(x, y)
                    .iter()
                    .enumerate()
                    .map(|(light, state)| match state {
                        Coherence::Varies => Visibility::Trace,
                        Coherence::Same => {
                            stats.work.floor_shared_visibility += 1;
                            Visibility::Known(centre_transmittance(
                                scene,
                                light,
                                centre,
                                receiver.walls_towards(light),
                                stats,
                            ))
                        }
                        Coherence::Clear => {
                            stats.work.floor_shared_visibility += 1;
                            Visibility::Known(Rgb::ONE)
                        }
                    }),
            )
        }
        // The same for every pixel of the render: filled once per
        // batch, not per pixel (a pass over every light), unless the
        // pixel's squares change it.
        None => {
            if visibility.len() != scene.lights.len() || first.floor_squares {
                visibility.clear();
                visibility.resize(scene.lights.len(), Visibility::of(trace.shadows));
            }
        }
    }
}

/// Points, spots and suns whose shadows cover some of the pixel's square
/// `area`, or whose kernel varies steeply across it, over the whole square
/// in closed form: every point of the pixel takes their mean (returned),
/// and none of them takes their light again (their `visibility` becomes
/// zero). Elsewhere the light reaches the whole pixel and only its kernel
/// varies, gently: the points take it, with nothing in the way. The
/// coherence masks' transmittance, where they know it, saves looking at
/// the walls; the answer is the same.
#[inline(always)]
fn square_lights(
    scene: &Scene,
    area: (DVec2, DVec2),
    receiver: Receiver,
    visibility: &mut [Visibility],
    stats: &mut Stats,
) -> Rgb {
    let mut square = Rgb::ZERO;
    for (light, vis) in visibility.iter_mut().enumerate() {
        if !takes_square(&scene.lights[light].shape) {
            continue;
        }
        let known = match *vis {
            Visibility::Trace => None,
            Visibility::Known(known) => Some(known),
        };
        match square_light(scene, light, area, receiver, known, stats) {
            Some(Square::Uniform) => *vis = Visibility::Known(Rgb::ONE),
            Some(Square::Mean(mean)) => {
                square += mean;
                *vis = Visibility::Known(Rgb::ZERO);
            }
            None => {}
        }
    }
    square
}

/// The passes' floor `points` over the pixel's square `area`, from its
/// scrambled Sobol sequence, and the numbers each line light draws, in the
/// order `direct_light_with` draws them, into `floor`.
#[inline(always)]
fn floor_points(
    scene: &Scene,
    light_table: Option<&LightTable>,
    (pixel, area): (&Pixel, (DVec2, DVec2)),
    points: Range<u32>,
    floor: &mut Strata,
) {
    floor.points.clear();
    floor.numbers.clear();
    let numbers = numbers_per_point(scene, light_table);
    let bits = pixel.key.stream(FLOOR_SEED_STREAM).bits();
    let seeds = [(bits >> 32) as u32, bits as u32];
    floor.points.resize(points.len(), DVec2::ZERO);
    sobol_points(points.start, seeds, area, &mut floor.points);
    if numbers > 0 {
        for k in points {
            let mut stream = pixel.key.stream(FLOOR_STREAMS + k as u64);
            for _ in 0..numbers {
                floor.numbers.push(stream.uniform());
            }
        }
    }
}

/// The sampled direct light at the floor's points, into
/// `batch.floor.values`: with a light table, the lights it chooses; else
/// every light, light by light over all points (`direct_light_strata`)
/// where the plan says so, else point by point.
#[inline(always)]
fn sampled_direct(
    first: &Context,
    centre: DVec2,
    receiver: Receiver,
    batch: &mut Batch,
    stats: &mut Stats,
) {
    let scene = first.trace.scene;
    let Batch {
        visibility,
        shared,
        floor,
        weights,
        ..
    } = batch;
    match first.trace.light_table {
        Some(table) => {
            // A light the whole pixel shares is traced once, from the
            // centre, when a point first takes it (the very value each
            // point's own ray would give); a light no point takes costs
            // no ray.
            let mut centre_stats = Stats::default();
            let vis = |light: usize| {
                if shared.get(light).copied().unwrap_or(false) {
                    shared[light] = false;
                    centre_stats.work.floor_shared_visibility += 1;
                    visibility[light] = Visibility::Known(centre_transmittance(
                        scene,
                        light,
                        centre,
                        receiver.walls_towards(light),
                        &mut centre_stats,
                    ));
                }
                visibility[light]
            };
            if first.strata_loops {
                direct_light_chosen_strata(scene, table, receiver, (floor, weights), vis, stats);
            } else {
                direct_light_chosen(scene, table, receiver, floor, vis, stats);
            }
            stats.merge(&centre_stats);
        }
        None if first.strata_loops => {
            direct_light_strata(scene, floor, visibility, receiver.shadow_walls, stats)
        }
        None => direct_light_points(scene, floor, visibility, stats),
    }
}

/// The closed forms of the floor's direct light, those each point takes
/// on its own and those through one glass edge, added at the passes'
/// floor points (filled
/// from point `first_point` on) where the render takes them.
#[inline(always)]
fn closed_forms_at_points(
    contexts: &[Context],
    first_point: u32,
    floor: &mut Strata,
    stats: &mut Stats,
) {
    let Some(first) = contexts.first() else {
        return;
    };
    let trace = &first.trace;
    let scene = trace.scene;
    if trace.ledger.takes_at_point() {
        // The closed forms each point takes on its own: lights seen in
        // one flat mirror (`estimators::at_point`).
        for (value, &x) in floor.values.iter_mut().zip(&floor.points) {
            if let Some(v) = at_point(&trace.ledger, scene, (x, Receiver::FLOOR), None, stats) {
                *value += v;
            }
        }
    }
    if trace.ledger.glass_lights {
        // Lines and circles seen through one glass edge, in closed form
        // (`estimators::refracted`): their mean over some of each half's
        // points, given to every point of the half.
        for context in contexts {
            let from = (context.pass.points.start - first_point) as usize;
            for half in glass_halves(from, context.pass.points.len()) {
                let (Some(values), Some(xs)) = (
                    floor.values.get_mut(half.all.clone()),
                    floor.points.get(half.taken),
                ) else {
                    continue;
                };
                let mut mean = Rgb::ZERO;
                for &x in xs {
                    mean += through_glass(scene, x, Receiver::FLOOR, stats);
                }
                let mean = mean / xs.len().max(1) as f64;
                for value in values {
                    *value += mean;
                }
            }
        }
    }
}

/// Every pass's path samples of a pixel, arc by arc over all of them,
/// into `sums` (one per pass): culled by the pixel's block where the
/// render culls, else traced one by one.
#[inline(always)]
fn path_samples(
    contexts: &[Context],
    pixel: &Pixel,
    (x, y): (u32, u32),
    culled: Option<&BlockCulling>,
    sums: &mut [Sums],
    stats: &mut Stats,
) {
    let (Some(first), Some(last)) = (contexts.first(), contexts.last()) else {
        return;
    };
    match culled {
        Some(culled) => {
            // Unchecked, a sample that is not finite makes the sum not
            // finite; then the pixel's samples are taken again, each
            // checked (a rare case: no test per sample in the common one).
            let before = *stats;
            culled_samples::<false>(contexts, pixel, culled, sums, stats);
            if !sums.iter().all(|s| s.all.is_finite()) {
                *stats = before;
                for (sum, context) in sums.iter_mut().zip(contexts) {
                    *sum = Sums::new(context.pass.middle);
                }
                checked_culled_samples(contexts, pixel, culled, sums, stats);
            }
        }
        None => {
            let all = first.pass.samples.start..last.pass.samples.end;
            for (_, of_arc) in sample_order(pixel.arc_offset, all) {
                for sample in of_arc {
                    let pass = pass_of(contexts, sample);
                    let value = sample_with(&contexts[pass], pixel, sample, stats);
                    add_sample::<true>(&mut sums[pass], value, (x, y, sample), stats);
                }
            }
        }
    }
}

/// One floor point in this many takes the light through glass edges
/// (`estimators::refracted`) for its half of the pass's points: the light
/// inside glass varies gently across a pixel, and each look costs several
/// path samples (`docs/performance.md` has the study that chose 8).
pub(crate) const GLASS_POINT_SHARE: usize = 8;

/// One half of a pass's floor points ([`noise_halves`]): all its points,
/// and the first of them, one in [`GLASS_POINT_SHARE`] and at least one,
/// whose mean light through glass edges every point of the half takes.
/// The half's mean stays an unbiased estimate over the pixel (each point
/// is uniform over it), and its points differ only as they did.
pub(crate) struct GlassHalf {
    pub all: std::ops::Range<usize>,
    pub taken: std::ops::Range<usize>,
}

/// The halves of a pass's `count` floor points from index `from`.
pub(crate) fn glass_halves(from: usize, count: usize) -> impl Iterator<Item = GlassHalf> {
    let middle = count / 2;
    [(from, middle), (from + middle, count - middle)]
        .into_iter()
        .filter(|&(_, n)| n > 0)
        .map(|(start, n)| GlassHalf {
            all: start..start + n,
            taken: start..start + (n / GLASS_POINT_SHARE).max(1),
        })
}

/// The pass of `contexts` (consecutive passes of the schedule) that takes
/// `sample`.
#[inline(always)]
pub(crate) fn pass_of(contexts: &[Context], sample: u32) -> usize {
    let first = contexts.first().map_or(0, |c| c.pass.index);
    (crate::passes::pass_index(sample).saturating_sub(first) as usize)
        .min(contexts.len().saturating_sub(1))
}

/// One pass's sums for one pixel: its path samples' `sums`, its direct
/// light from its own floor points (among `values`, filled from point
/// `first_point` on), and its caustic pass's light on the floor.
#[inline(always)]
pub(crate) fn pass_sums(
    context: &Context,
    sums: Sums,
    (x, y): (u32, u32),
    values: &[Rgb],
    first_point: u32,
    stats: &mut Stats,
) -> PixelSums {
    let pass = context.pass;
    // Each half's estimates, and the whole's.
    let (mut halves, mut whole) = ((Rgb::ZERO, Rgb::ZERO), Rgb::ZERO);
    let mut point_halves = ((Rgb::ZERO, Rgb::ZERO), (0, 0));
    if context.floor_memo && !pass.points.is_empty() {
        let from = (pass.points.start - first_point) as usize;
        let to = (pass.points.end - first_point) as usize;
        if let Some(values) = values.get(from..to) {
            let (first, second, all) = noise_halves(values, (x, y), stats);
            (halves, whole) = ((first, second), all);
            if context.measures && crate::passes::is_probe((x, y)) {
                let measured = &values[..values.len().min(crate::passes::MEASURED_POINTS)];
                let middle = measured.len() / 2;
                let (first, second, _) = noise_halves(measured, (x, y), &mut Stats::default());
                point_halves = ((first, second), (middle, measured.len() - middle));
            }
        }
        stats.work.floor_memo_reuses += pass.count() as u64;
        if context.lines.is_some() {
            // The pass's samples of the pixel are its points and its share
            // of the lines: counted as its samples, as paths would be.
            stats.physics.camera_samples += pass.count() as u64;
        }
        stats.work.floor_points += pass.points.len() as u64;
    }
    // The caustic pass's light on the floor, from each half of its
    // photons, and the lines' indirect light, from each half of their
    // directions: both are "the rest", beside the floor points.
    let mut rest_halves = (Rgb::ZERO, Rgb::ZERO);
    let k = (y * context.size.0 + x) as usize;
    let caustics = context
        .trace
        .caustics
        .map(|c| (c.floor_halves(k), c.floor_at(k)));
    let lines = context.lines.map(|l| (l.floor_halves(k), l.floor_at(k)));
    for ((a, b), all) in caustics.into_iter().chain(lines) {
        rest_halves = (rest_halves.0 + a, rest_halves.1 + b);
        halves = (halves.0 + a, halves.1 + b);
        whole += all;
    }
    if context.measures && crate::passes::is_probe((x, y)) {
        // The points' halves against the rest's: the paths' means over
        // each half of the samples, and the photons'.
        let (a, b) = (pass.first_count(), pass.count() - pass.first_count());
        if a > 0 && b > 0 {
            let scale = crate::film::pixel_scale(
                context.trace.scene,
                context.size,
                (x, y),
                context.options.exposure,
            );
            let ((p1, p2), (m1, m2)) = point_halves;
            let paths = sums.first / a as f64 - (sums.all - sums.first) / b as f64
                + (rest_halves.0 - rest_halves.1);
            stats.split.add(
                ((p1 - p2) * scale, m1 as u32, m2 as u32),
                (paths * scale, a, b),
            );
        }
    }
    // A pass of one sample has no halves: its points and photons all
    // count, for the whole.
    let mut pixel_sums = match pass.count() {
        1 => PixelSums {
            all: whole,
            first: Rgb::ZERO,
        },
        _ => pass.weigh_halves(halves),
    };
    pixel_sums.all += sums.all;
    pixel_sums.first += sums.first;
    pixel_sums
}

/// The means of a pass's floor points over the first and the second half
/// of them (two estimates of the pixel's direct light, each over the
/// whole pixel; the mean of all, twice, for a single point), and over all.
/// Points that are not finite count as zero, and are reported (as sample
/// `u32::MAX` of pixel `(x, y)`).
pub(crate) fn noise_halves(
    values: &[Rgb],
    (x, y): (u32, u32),
    stats: &mut Stats,
) -> (Rgb, Rgb, Rgb) {
    let middle = values.len() / 2;
    let mut sums = [Rgb::ZERO; 2];
    for (k, &value) in values.iter().enumerate() {
        if value.is_finite() {
            sums[(k >= middle) as usize] += value;
        } else {
            stats.record_nonfinite(x, y, u32::MAX);
        }
    }
    let all = (sums[0] + sums[1]) / values.len().max(1) as f64;
    if middle == 0 {
        return (all, all, all);
    }
    (
        sums[0] / middle as f64,
        sums[1] / (values.len() - middle) as f64,
        all,
    )
}

/// A pixel's position, stream key, size and the turn of its samples'
/// arcs, computed once for all its samples.
pub(crate) struct Pixel {
    pub(crate) position: DVec2,
    pub(crate) key: StreamKey,
    pub(crate) step: DVec2,
    /// Uniform in `0..ARCS`: see [`sample_arc`].
    pub(crate) arc_offset: usize,
}

impl Pixel {
    pub(crate) fn new(scene: &Scene, size: (u32, u32), x: u32, y: u32, seed: u64) -> Pixel {
        let index = y as u64 * size.0 as u64 + x as u64;
        let key = StreamKey::new(seed, index);
        // Exact: 64 times a multiple of 2^-53 below 1.
        let arc_offset = (key.stream(ARC_OFFSET_STREAM).uniform() * ARCS as f64) as usize;
        Pixel {
            position: DVec2::new(x as f64, y as f64),
            key,
            step: scene.canvas.pixel_step(size),
            arc_offset,
        }
    }
}

impl Pixel {
    /// A sample's receiver point, jittered uniformly inside the pixel (the
    /// box filter): the first pair of numbers of the sample's stream.
    /// [`arc_in_lanes`] computes the same, component by component.
    #[inline(always)]
    pub(crate) fn receiver(&self, scene: &Scene, stream: &mut Stream) -> DVec2 {
        let (jx, jy) = stream.uniform_pair();
        self.point(scene, (jx, jy))
    }

    /// The point at `jitter` (each in `[0, 1)`) across the pixel's square.
    #[inline(always)]
    pub(crate) fn point(&self, scene: &Scene, (jx, jy): (f64, f64)) -> DVec2 {
        scene.canvas.origin + (self.position + DVec2::new(jx, jy)) * self.step
    }
}

/// The stream sample index that draws a pixel's [`Pixel::arc_offset`],
/// apart from every path sample's and the floor memo's.
pub(crate) const ARC_OFFSET_STREAM: u64 = 1 << 41;

/// Stream sample indices from here up draw, per pass and arc, the turn of
/// that pass's samples inside that arc ([`arc_fraction`]).
pub(crate) const ARC_TURN_STREAMS: u64 = (1 << 41) + (1 << 20);

/// How far through its arc (`sampling::sample_arc`) sample `sample`'s
/// floor direction lies. A pass's runs of [`ARCS`] samples each take the
/// arc once; the `r`-th run of the pass takes the van der Corput point
/// `r` turned by one number drawn for the pass and the arc, so that a
/// pass's samples in each arc are spread evenly through it (`2^k` runs
/// take one each of its `2^k` equal parts), and each alone is uniform in
/// it. Passes turn apart: they stay independent estimates, as the noise
/// estimate's halves require.
#[inline(always)]
pub(crate) fn arc_fraction(key: StreamKey, arc: usize, sample: u32) -> f64 {
    let pass = crate::passes::pass_index(sample);
    let run = (sample - crate::passes::pass_start(pass)) / ARCS as u32;
    let turn = key
        .stream(ARC_TURN_STREAMS + pass as u64 * ARCS as u64 + arc as u64)
        .uniform();
    let fraction = turn + crate::sampling::radical_inverse(run);
    if fraction >= 1.0 {
        fraction - 1.0
    } else {
        fraction
    }
}

/// One sample of a pixel: the receiver is jittered uniformly inside the
/// pixel (the box filter). Deterministic in `(seed, pixel, sample)`.
pub(crate) fn sample_with(context: &Context, pixel: &Pixel, sample: u32, stats: &mut Stats) -> Rgb {
    let trace = &context.trace;
    let scene = trace.scene;
    let mut stream = pixel.key.stream(sample as u64);
    let p = pixel.receiver(scene, &mut stream);
    stats.physics.camera_samples += 1;
    let arc = sample_arc(pixel.arc_offset, sample);
    let direction = (arc, arc_fraction(pixel.key, arc, sample));
    if context.one_bounce_memo.is_none() {
        return path_sample(trace, p, direction, sample, &mut stream, stats);
    }
    // `path_sample`, with the one-bounce shortcut tried first.
    let begun = path_begin(trace, p, direction, None, &mut stream, stats);
    let Some(ray) = begun.ray else {
        return begun.fluence;
    };
    let hit = scene.segments.closest_hit(&ray, f64::INFINITY, Skip::NONE);
    finish(
        context,
        begun.fluence,
        ray,
        hit,
        (None, sample),
        &mut stream,
        stats,
    )
}

/// [`path_finish`], after the one-bounce shortcut where the render takes
/// it: the same value.
#[inline(always)]
pub(crate) fn finish(
    context: &Context,
    fluence: Rgb,
    ray: Ray,
    hit: Option<(u32, Hit)>,
    (line_walls, sample): (Option<&[u32]>, u32),
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    if let (Some(memo), Some((index, h))) = (context.one_bounce_memo, hit)
        && let Some(value) = memo_bounce(
            &context.trace,
            memo,
            fluence,
            index,
            h.u,
            ray.dir,
            stream.key(),
            stats,
        )
    {
        return value;
    }
    path_finish(
        &context.trace,
        fluence,
        ray,
        hit,
        line_walls,
        sample,
        stream,
        stats,
    )
}

/// The order in which a pixel's samples `samples` are taken and summed,
/// whether culled or not: chunk by chunk of [`CHUNK`] samples (from a
/// multiple of it to the next), in each arc by arc (see [`sample_arc`]),
/// in each by index. Yields each arc that has samples in the chunk, with
/// them (at most [`LANES`]). The samples of any pass are taken in the
/// same order whether it is rendered alone or with others.
pub(crate) fn sample_order(
    offset: usize,
    samples: Range<u32>,
) -> impl Iterator<Item = (usize, ArcSamples)> {
    SampleOrder {
        offset,
        first: samples.start,
        last: chunk_end(samples.start, samples.end),
        end: samples.end,
        arc: 0,
    }
}

/// Where the chunk that holds sample `first` ends, within `end`.
#[inline(always)]
pub(crate) fn chunk_end(first: u32, end: u32) -> u32 {
    (first / CHUNK as u32 + 1)
        .saturating_mul(CHUNK as u32)
        .min(end)
}

/// [`sample_order`]'s state: the chunk `first..last` of the samples up to
/// `end`, and the next arc to look at in it.
pub(crate) struct SampleOrder {
    pub(crate) offset: usize,
    pub(crate) first: u32,
    pub(crate) last: u32,
    pub(crate) end: u32,
    pub(crate) arc: usize,
}

impl Iterator for SampleOrder {
    type Item = (usize, ArcSamples);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, ArcSamples)> {
        while self.first < self.end {
            while self.arc < ARCS {
                let arc = self.arc;
                self.arc += 1;
                // The arc's first sample from `first` on: its samples are
                // `ARCS` apart. A chunk of fewer samples than arcs leaves
                // arcs empty.
                let residue = first_sample_of_arc(self.offset, arc);
                let start = self.first + (residue.wrapping_sub(self.first) & (ARCS as u32 - 1));
                if start < self.last {
                    let count = (self.last - start - 1) / ARCS as u32 + 1;
                    return Some((arc, ArcSamples { next: start, count }));
                }
            }
            self.first = self.last;
            self.last = chunk_end(self.first, self.end);
            self.arc = 0;
        }
        None
    }
}

/// The samples of one arc in one chunk: `count` of them from `next`,
/// [`ARCS`] apart.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ArcSamples {
    pub(crate) next: u32,
    pub(crate) count: u32,
}

impl Iterator for ArcSamples {
    type Item = u32;

    #[inline(always)]
    fn next(&mut self) -> Option<u32> {
        (self.count > 0).then(|| {
            let sample = self.next;
            self.next = self.next.wrapping_add(ARCS as u32);
            self.count -= 1;
            sample
        })
    }

    #[inline(always)]
    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.count as usize, Some(self.count as usize))
    }
}

impl ExactSizeIterator for ArcSamples {}

/// The samples of a pixel's passes `contexts` whose floor rays are culled
/// by direction, in [`sample_order`] over all of them: the samples of one
/// arc test the same walls and their paths branch alike. Each value is
/// exactly what [`sample_with`] gives with its pass's fills, added to its
/// pass's sum in `sums` in the same order as without culling.
///
/// Without the floor's direct light in the paths (the memo holds it), a
/// path whose first ray escapes adds exactly nothing: where an arc meets
/// no wall, its samples are known to be zero and are not drawn at all.
#[inline(always)]
pub(crate) fn culled_samples<const CHECKED: bool>(
    contexts: &[Context],
    pixel: &Pixel,
    culled: &BlockCulling,
    sums: &mut [Sums],
    stats: &mut Stats,
) {
    let (Some(first), Some(last)) = (contexts.first(), contexts.last()) else {
        return;
    };
    let trace = &first.trace;
    let scene = trace.scene;
    let samples = first.pass.samples.start..last.pass.samples.end;
    let (arcs, shadow_walls) = (&culled.arcs, Some(&culled.shadows[..]));
    let empty_arcs_add_nothing = !trace.floor_direct && !trace.force;
    stats.physics.camera_samples += samples.len() as u64;
    let (x, y) = (pixel.position.x as u32, pixel.position.y as u32);
    for (arc, of_arc) in sample_order(pixel.arc_offset, samples) {
        let walls = arcs.arc(arc);
        stats.work.culled_rays += of_arc.len() as u64;
        if empty_arcs_add_nothing {
            // Paths start with nothing and leave the floor at once.
            if walls.is_empty() {
                stats.work.culled_empty += of_arc.len() as u64;
                stats.physics.paths_escaped += of_arc.len() as u64;
                continue;
            }
            // As many lanes as the arc has samples, rounded up to a power
            // of two: few samples per arc draw no idle lanes.
            let count = of_arc.len();
            let args = (contexts, pixel, arc, walls, of_arc);
            match count {
                1 => arc_in_lanes::<CHECKED, 1>(args, sums, stats),
                2 => arc_in_lanes::<CHECKED, 2>(args, sums, stats),
                3 | 4 => arc_in_lanes::<CHECKED, 4>(args, sums, stats),
                _ => arc_in_lanes::<CHECKED, LANES>(args, sums, stats),
            }
            continue;
        }
        for sample in of_arc {
            let pass = pass_of(contexts, sample);
            let context = &contexts[pass];
            let trace = &context.trace;
            let mut stream = pixel.key.stream(sample as u64);
            let p = pixel.receiver(scene, &mut stream);
            let direction = (arc, arc_fraction(pixel.key, arc, sample));
            let begun = path_begin(trace, p, direction, shadow_walls, &mut stream, stats);
            // The plan culls only when paths bounce: every sample has a ray.
            let value = match begun.ray {
                Some(ray) => {
                    let walls = Some(walls).filter(|w| w.len() <= LONG_LIST);
                    stats.work.culled_walls_tested += walls.map_or(0, |w| w.len() as u64);
                    let hit =
                        scene
                            .segments
                            .closest_hit_within(&ray, f64::INFINITY, Skip::NONE, walls);
                    finish(
                        context,
                        begun.fluence,
                        ray,
                        hit,
                        (walls, sample),
                        &mut stream,
                        stats,
                    )
                }
                None => begun.fluence,
            };
            add_sample::<CHECKED>(&mut sums[pass], value, (x, y, sample), stats);
        }
    }
}

/// [`culled_samples`] with every sample checked, out of line: for the
/// rare pixel whose unchecked sums are not all finite.
#[inline(never)]
pub(crate) fn checked_culled_samples(
    contexts: &[Context],
    pixel: &Pixel,
    culled: &BlockCulling,
    sums: &mut [Sums],
    stats: &mut Stats,
) {
    culled_samples::<true>(contexts, pixel, culled, sums, stats);
}

/// Adds a sample's value to its pixel's sum. `CHECKED`, a value that is
/// not finite is left out and reported; unchecked, it is added (and the
/// sum is no longer finite: the caller checks the sum).
#[inline(always)]
pub(crate) fn add_sample<const CHECKED: bool>(
    sum: &mut Sums,
    value: Rgb,
    (x, y, sample): (u32, u32, u32),
    stats: &mut Stats,
) {
    if !CHECKED || value.is_finite() {
        sum.add(sample, value);
    } else {
        stats.record_nonfinite(x, y, sample);
    }
}

/// The samples `of_arc` (at most `N`, of [`LANES`] at most), all of arc
/// `arc`, whose paths start with nothing (no floor light of their own):
/// drawn, their first rays built and tested against `walls` in `N` lanes,
/// one lane per sample, then each path finished alone, with its pass's
/// fills, and added to its pass's sum in order. The same values as [`sample_with`] gives.
#[inline(always)]
pub(crate) fn arc_in_lanes<const CHECKED: bool, const N: usize>(
    (contexts, pixel, arc, walls, of_arc): (&[Context], &Pixel, usize, &[u32], ArcSamples),
    sums: &mut [Sums],
    stats: &mut Stats,
) {
    let Some(context) = contexts.first() else {
        return;
    };
    let scene = context.trace.scene;
    let count = of_arc.len();
    // Every lane is drawn, those past the chunk's end for samples that
    // are not taken: the loops below have a fixed length.
    let Some(start) = of_arc.clone().next() else {
        return;
    };
    let mut streams: [Stream; N] =
        std::array::from_fn(|k| pixel.key.stream(start as u64 + (k * ARCS) as u64));
    let (mut jx, mut jy, mut fractions) = ([0.0; N], [0.0; N], [0.0; N]);
    for (k, stream) in streams.iter_mut().enumerate() {
        // As `sample_with` draws them: the jitter from the sample's
        // stream, the direction's fraction from its pass's turn.
        (jx[k], jy[k]) = stream.uniform_pair();
        fractions[k] = arc_fraction(pixel.key, arc, start.saturating_add((k * ARCS) as u32));
    }
    let mut rays = RayLanes {
        ox: [0.0; N],
        oy: [0.0; N],
        dx: [0.0; N],
        dy: [0.0; N],
    };
    for k in 0..N {
        let p = pixel.point(scene, (jx[k], jy[k]));
        (rays.ox[k], rays.oy[k]) = (p.x, p.y);
    }
    (rays.dx, rays.dy) = arc_points(arc, &fractions);
    let hits = if walls.len() <= LONG_LIST {
        stats.work.culled_walls_tested += (walls.len() * count) as u64;
        if N == 1 && walls.len() >= WIDE_LIST {
            // One sample of the arc: its walls in lanes instead.
            let hit = scene.segments.closest_hit_among_wide(&rays.ray(0), walls);
            HitLanes {
                index: [hit.index[0]; N],
                t: [hit.t[0]; N],
                u: [hit.u[0]; N],
            }
        } else {
            scene.segments.closest_hits_among(&rays, walls)
        }
    } else {
        // A long list costs more than the BVH: each lane asks the BVH.
        let mut hits = HitLanes {
            index: [u32::MAX; N],
            t: [f64::INFINITY; N],
            u: [0.0; N],
        };
        for k in 0..count.min(N) {
            if let Some((index, hit)) =
                scene
                    .segments
                    .closest_hit(&rays.ray(k), f64::INFINITY, Skip::NONE)
            {
                (hits.index[k], hits.t[k], hits.u[k]) = (index, hit.t, hit.u);
            }
        }
        hits
    };
    let walls = Some(walls).filter(|w| w.len() <= LONG_LIST);
    let (x, y) = (pixel.position.x as u32, pixel.position.y as u32);
    for ((k, sample), stream) in of_arc.enumerate().zip(&mut streams) {
        let pass = pass_of(contexts, sample);
        let trace = &contexts[pass].trace;
        // `path_finish`'s common case first, from the lanes as they are.
        let dir = DVec2::new(rays.dx[k], rays.dy[k]);
        // A `match`, not a closure: the closure is a function of its own,
        // which the compiler may leave out of line, and then it is
        // compiled without the AVX2 of the loop around it.
        let shortcut = match context.one_bounce_memo {
            Some(memo) => {
                let path = stream.key();
                memo_bounce(
                    trace,
                    memo,
                    Rgb::ZERO,
                    hits.index[k],
                    hits.u[k],
                    dir,
                    path,
                    stats,
                )
            }
            None => None,
        };
        let value = match shortcut {
            Some(value) => value,
            None => path_finish(
                trace,
                Rgb::ZERO,
                rays.ray(k),
                hits.hit(k),
                walls,
                sample,
                stream,
                stats,
            ),
        };
        add_sample::<CHECKED>(&mut sums[pass], value, (x, y, sample), stats);
    }
}

/// A ray alone in its arc whose list holds at least this many walls tests
/// them four at a time (`SegmentSet::closest_hit_among_wide`); a shorter
/// list costs less one wall at a time.
pub(crate) const WIDE_LIST: usize = 4;

/// Samples of one arc in one chunk, at most: [`arc_in_lanes`] takes them
/// in this many lanes.
pub(crate) const LANES: usize = CHUNK / ARCS;

/// The samples of one stretch of [`sample_order`]: a whole number of runs
/// of [`ARCS`], so that each arc holds the same number of them, and as
/// many as [`arc_in_lanes`] takes in one go.
pub(crate) const CHUNK: usize = 8 * ARCS;

#[cfg(test)]
mod tests {
    use super::*;

    /// A pass's runs spread each arc's samples evenly through it: pass
    /// 5 (samples 256 to 511) takes 4 runs, one in each quarter of every
    /// arc; another pass turns apart.
    #[test]
    fn a_passs_runs_spread_through_each_arc() {
        let key = StreamKey::new(3, 77);
        for arc in [0, 9, 63] {
            let first = 256 + crate::sampling::first_sample_of_arc(0, arc);
            let mut quarters: Vec<usize> = (0..4)
                .map(|run| (arc_fraction(key, arc, first + 64 * run) * 4.0) as usize)
                .collect();
            quarters.sort();
            assert_eq!(quarters, [0, 1, 2, 3], "arc {arc}");
            assert_ne!(
                arc_fraction(key, arc, first),
                arc_fraction(key, arc, first - 128)
            );
        }
    }

    #[test]
    fn strata_that_are_not_finite_are_left_out_and_counted() {
        let v = |x: f64| Rgb::new(x, 1.0, 2.0);
        let mut stats = Stats::default();
        let finite = [v(1.0), v(3.0), v(2.0), v(6.0)];
        assert_eq!(
            noise_halves(&finite, (4, 5), &mut stats),
            (
                Rgb::new(2.0, 1.0, 2.0),
                Rgb::new(4.0, 1.0, 2.0),
                Rgb::new(3.0, 1.0, 2.0)
            )
        );
        assert_eq!(stats.physics.nonfinite_samples, 0);
        // An infinity and a NaN count as zero, and are counted.
        let mixed = [v(1.0), v(3.0), v(f64::INFINITY), v(f64::NAN)];
        assert_eq!(
            noise_halves(&mixed, (4, 5), &mut stats),
            (Rgb::new(2.0, 1.0, 2.0), Rgb::ZERO, Rgb::new(1.0, 0.5, 1.0))
        );
        assert_eq!(stats.physics.nonfinite_samples, 2);
        assert_eq!(stats.physics.first_nonfinite, Some((4, 5, u32::MAX)));
        // One point: its value, for both halves.
        let one = noise_halves(&finite[..1], (4, 5), &mut stats);
        assert_eq!(one, (v(1.0), v(1.0), v(1.0)));
    }
}
