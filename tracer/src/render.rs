//! The render loop, written once: passes of samples (`passes.rs`), tiles
//! in parallel, then pixels, then samples. Integrators only say how one
//! sample is estimated.

use std::ops::Range;

use flatray_geometry::{ArcCandidates, DVec2, Hit, HitLanes, Ray, RayLanes, Skip, hull_candidates};

use flatray_cache::WallMemo;

use crate::caustics::Caustics;
use crate::coherence::{Coherence, FloorCoherence, centre_transmittance};
use crate::film::PixelSums;
use crate::film::{Estimator, Film, Part, run};
use crate::light::{Strata, direct_light_chosen, direct_light_points, numbers_per_point};
use crate::lights::choice::LightTable;
use crate::lights::{Receiver, Visibility};
use crate::memo::build_wall_memo;
use crate::memo::{Onward, OnwardMemo};
use crate::mirror::MirrorArcs;
use crate::options::MemoOptions;
use crate::options::{
    CULL_BLOCK, FINE_CULLING_SAMPLES, FastPath, Integrator, LONG_LIST, RenderOptions, Rendered,
    TILE, TILE_SHADOW_TESTS, image_size,
};
use crate::passes::{Pass, Totals};
use crate::path::{MirrorWalls, Trace, path_begin, path_finish, path_sample};
use crate::plan::Plan;
use crate::run::Limits;
use crate::sampling::{
    ARCS, Stream, StreamKey, arc_points, first_sample_of_arc, sample_arc, sobol_points,
};
use crate::scene::Scene;
use crate::shortcut::memo_bounce;
use crate::strata::{direct_light_chosen_strata, direct_light_strata};
use crate::{Rgb, Stats};

/// Renders `scene`. `progress` is called from worker threads with the
/// number of pixel samples each finished tile took, and with 0, as a
/// heartbeat, before each unit of work; the image does not
/// depend on the number of threads or on their scheduling. The render is
/// the sequence of passes that `passes.rs` describes: the same image as
/// [`crate::Progressive`] driven to the same samples.
pub fn render(scene: &Scene, options: &RenderOptions, progress: &(dyn Fn(u64) + Sync)) -> Rendered {
    let mut passes = Passes::new(scene, options);
    passes.run_to(options.samples, progress);
    passes.rendered()
}

/// Bytes that the per-pass fills (caustic passes, onward memos) of the
/// passes rendered together may take: passes beyond it are rendered
/// after, from the totals (the same image).
const FILLS_BUDGET: u64 = 256 << 20;

/// Floor points per pixel of the passes rendered together, at most (a
/// pass alone takes at most 2^20): each worker thread holds them and
/// their values, about 40 bytes each.
const GROUP_POINTS: u64 = 1 << 21;

/// What every pass of a path-traced render shares, built once.
struct Shared {
    plan: Plan,
    memo: Option<WallMemo>,
    mirror_arcs: Option<MirrorArcs>,
    light_table: Option<LightTable>,
    coherence: Option<FloorCoherence>,
    /// Per wall side, whether a path's last leg from there can meet a
    /// light (`run::last_leg_sides`), where the plan has last legs.
    last_leg_sides: Option<Vec<bool>>,
    tiles: Vec<(u32, u32)>,
}

/// Where the next pass starts: its index, its first sample and its first
/// floor point.
#[derive(Clone, Copy, Debug, Default)]
struct Cursor {
    index: u32,
    samples: u32,
    points: u32,
}

impl Cursor {
    /// The pass from here to `end` samples per pixel.
    fn pass(self, end: u32, options: &RenderOptions) -> Pass {
        Pass::new(
            self.index,
            self.samples..end,
            (self.points, options.memo.floor_samples),
            options.seed,
        )
    }

    /// Where the pass after `pass` starts.
    fn after(pass: &Pass) -> Cursor {
        Cursor {
            index: pass.index + 1,
            samples: pass.samples.end,
            points: pass.points.end,
        }
    }
}

/// A render pass by pass (`passes.rs`): what the passes share, and the
/// running totals.
pub(crate) struct Passes<'a> {
    scene: &'a Scene,
    options: RenderOptions,
    /// `None` for the light tracer, whose passes share nothing.
    shared: Option<Shared>,
    totals: Totals,
    cursor: Cursor,
    /// Whether the last pass ended short of the schedule: no pass may
    /// follow it.
    closed: bool,
}

impl<'a> Passes<'a> {
    pub fn new(scene: &'a Scene, options: &RenderOptions) -> Passes<'a> {
        let (width, height) = image_size(scene, options.scale);
        let mut stats = Stats::default();
        let shared = (options.integrator != Integrator::Light).then(|| {
            let plan = Plan::new(scene, options);
            let memo = plan.wall_memo.then(|| {
                build_wall_memo(
                    scene,
                    &options.memo,
                    options.scale,
                    plan.shadows,
                    &mut stats,
                )
            });
            // Rays off mirrors are culled wherever the floor's are, and so
            // are the onward memo's gathers.
            let mirror_arcs = plan
                .floor_ray_culling
                .then(|| MirrorArcs::build(scene, options.scale, plan.onward))
                .flatten();
            let light_table = light_table_for(scene, options, &plan);
            if let Some(table) = &light_table {
                stats.work.light_table_bytes += table.memory_bytes() as u64;
                stats.work.light_table_rays += table.probe_rays;
            }
            let coherence = plan
                .floor_coherence
                .then(|| FloorCoherence::build(scene, (width, height)))
                .flatten();
            let tiles = (0..height.div_ceil(TILE))
                .flat_map(|ty| (0..width.div_ceil(TILE)).map(move |tx| (tx, ty)))
                .collect();
            let last_leg_sides = plan.last_legs.then(|| crate::run::last_leg_sides(scene));
            Shared {
                plan,
                memo,
                mirror_arcs,
                light_table,
                coherence,
                last_leg_sides,
                tiles,
            }
        });
        Passes {
            scene,
            options: *options,
            shared,
            totals: Totals::new((width, height), stats),
            cursor: Cursor::default(),
            closed: false,
        }
    }

    pub fn samples(&self) -> u32 {
        self.totals.samples
    }

    pub fn size(&self) -> (u32, u32) {
        self.totals.size
    }

    pub fn next_end(&self) -> Option<u32> {
        (!self.closed).then(|| crate::passes::next_pass_end(self.samples()))
    }

    /// Takes the next pass, to `end` samples per pixel, if the schedule
    /// lets one end there.
    pub fn pass(&mut self, end: u32, progress: &(dyn Fn(u64) + Sync)) -> bool {
        let done = self.samples();
        match self.next_end() {
            Some(next) if end > done && end <= next => self.closed = end < next,
            _ => return false,
        }
        let pass = self.cursor.pass(end, &self.options);
        self.run(&[pass], progress);
        true
    }

    /// Takes every pass of the schedule up to `samples`, as many at once
    /// as [`FILLS_BUDGET`] and [`GROUP_POINTS`] allow: each pixel then takes all of them in
    /// turn, sharing its culling lists, floor points and shared shadow
    /// rays. The same sums as pass by pass.
    pub fn run_to(&mut self, samples: u32, progress: &(dyn Fn(u64) + Sync)) {
        let mut group: Vec<Pass> = Vec::new();
        let mut cursor = self.cursor;
        let (mut bytes, mut points) = (0, 0);
        while !self.closed && cursor.samples < samples {
            let next = crate::passes::next_pass_end(cursor.samples);
            let pass = cursor.pass(next.min(samples), &self.options);
            let pass_bytes = self.fill_bytes();
            let pass_points = pass.points.len() as u64;
            if !group.is_empty()
                && (bytes + pass_bytes > FILLS_BUDGET || points + pass_points > GROUP_POINTS)
            {
                self.run(&group, progress);
                group.clear();
                (bytes, points) = (0, 0);
            }
            bytes += pass_bytes;
            points += pass_points;
            self.closed = pass.samples.end < next;
            cursor = Cursor::after(&pass);
            group.push(pass);
        }
        if !group.is_empty() {
            self.run(&group, progress);
        }
    }

    /// About the bytes of a pass's own fills: its caustic pass's floor
    /// (and the first half's) and its onward memo.
    fn fill_bytes(&self) -> u64 {
        let Some(shared) = &self.shared else {
            return 0;
        };
        let (width, height) = self.size();
        let mut bytes = 0u64;
        if shared.plan.caustics {
            bytes += width as u64 * height as u64 * 48;
        }
        if let Some(memo) = shared.memo.as_ref().filter(|_| shared.plan.onward) {
            bytes += crate::onward::onward_bytes(memo.memory_bytes() as u64, self.options.bounces);
        }
        bytes
    }

    /// Renders `group`, consecutive passes from the cursor on, and adds
    /// them to the totals.
    fn run(&mut self, group: &[Pass], progress: &(dyn Fn(u64) + Sync)) {
        let Some(last) = group.last() else {
            return;
        };
        match &self.shared {
            Some(shared) => {
                let (sums, stats) = path_passes(
                    self.scene,
                    &self.options,
                    shared,
                    group,
                    &self.totals.sums,
                    progress,
                );
                self.totals.replace(group, sums, &stats);
            }
            None => {
                for pass in group {
                    let (sums, stats, first) =
                        crate::light_tracer::light_pass(self.scene, &self.options, pass, progress);
                    self.totals.add(pass, sums, &stats, first);
                }
            }
        }
        self.cursor = Cursor::after(last);
    }

    pub fn rendered(&self) -> Rendered {
        self.totals.rendered(self.scene, self.options.exposure)
    }
}

/// What one pass of a path-traced render fills for itself: its caustic
/// pass and its onward memo.
struct Fills {
    caustics: Option<Caustics>,
    onward: Option<OnwardMemo>,
}

impl Fills {
    fn new(
        scene: &Scene,
        options: &RenderOptions,
        shared: &Shared,
        pass: &Pass,
        stats: &mut Stats,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Fills {
        let plan = &shared.plan;
        let (width, height) = image_size(scene, options.scale);
        // Light from points, spots and suns through mirrors and glass,
        // which no path from the floor can find: traced from the lights
        // first, so that next-event estimation at the walls can read it.
        let caustics = if plan.caustics {
            // Photons are no pixel samples: the callback hears of them
            // with 0, as a heartbeat.
            crate::caustics::trace_caustics(
                scene,
                options,
                (Limits::of(options), pass),
                stats,
                &|_| progress(0),
            )
        } else {
            None
        };
        // The rest of a path from each diffuse wall, gathered after the
        // direct light and the caustic pass that its paths read.
        let onward = shared
            .memo
            .as_ref()
            .filter(|_| plan.onward)
            .map(|wall_memo| {
                let trace = trace_for(scene, options, shared, (caustics.as_ref(), None));
                // The first pass's halves read a copy each; a later pass
                // is one half of the noise estimate by itself.
                let copies = if pass.index == 0 { 2 } else { 1 };
                let gathers = crate::onward::gathers(
                    pass.count(),
                    width as u64 * height as u64,
                    (wall_memo.values() as u64, options.bounces.saturating_sub(1)),
                    copies,
                );
                crate::onward::build_onward(&trace, wall_memo, (gathers, copies), pass.seed, stats)
            });
        Fills { caustics, onward }
    }
}

/// Passes `group` of a path-traced render, each with its own fills, every
/// pixel taking them in turn from its totals `previous` (empty before
/// the first pass): the pixels' new totals.
fn path_passes(
    scene: &Scene,
    options: &RenderOptions,
    shared: &Shared,
    group: &[Pass],
    previous: &[PixelSums],
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<PixelSums>, Stats) {
    let (width, height) = image_size(scene, options.scale);
    let plan = &shared.plan;
    let mut stats = Stats::default();
    let fills: Vec<Fills> = group
        .iter()
        .map(|pass| Fills::new(scene, options, shared, pass, &mut stats, progress))
        .collect();
    let contexts = group
        .iter()
        .zip(&fills)
        .map(|(pass, fills)| Context {
            options,
            pass,
            size: (width, height),
            floor_memo: plan.floor_memo,
            coherence: shared.coherence.as_ref(),
            culling: plan.floor_ray_culling,
            trace: trace_for(
                scene,
                options,
                shared,
                (
                    fills.caustics.as_ref(),
                    fills
                        .onward
                        .as_ref()
                        .map(|memo| Onward::of(memo, pass.middle)),
                ),
            ),
            one_bounce_memo: shared.memo.as_ref().filter(|_| {
                plan.indirect && options.bounces == 1 && options.takes(FastPath::Shortcut)
            }),
            render_pixel: if options.takes(FastPath::Avx) {
                pixel_fn()
            } else {
                render_pixel
            },
        })
        .collect();
    let outcome = run(
        &PixelEstimator {
            contexts,
            tiles: &shared.tiles,
            previous,
        },
        stats,
        progress,
    );
    (outcome.output, outcome.stats)
}

/// The path estimators (`Path`, `Original`) as units of the render loop:
/// a tile of pixels each, in blocks of [`CULL_BLOCK`] pixels (which share
/// their culling lists), then pixel by pixel.
struct PixelEstimator<'a> {
    /// One per pass, in order.
    contexts: Vec<Context<'a>>,
    tiles: &'a [(u32, u32)],
    /// The pixels' totals before these passes (empty before the first).
    previous: &'a [PixelSums],
}

impl Estimator for PixelEstimator<'_> {
    type Output = Vec<PixelSums>;

    fn size(&self) -> (u32, u32) {
        self.contexts.first().map_or((0, 0), |c| c.size)
    }

    fn units(&self) -> usize {
        self.tiles.len()
    }

    fn render_unit(&self, unit: usize, stats: &mut Stats, progress: &(dyn Fn(u64) + Sync)) -> Part {
        let contexts = &self.contexts[..];
        let Some(context) = contexts.first() else {
            return Part::Tile {
                x0: 0,
                y0: 0,
                width: 0,
                values: Vec::new(),
            };
        };
        let scene = context.trace.scene;
        let (width, height) = context.size;
        let step = pixel_size(scene, (width, height));
        let (tx, ty) = self.tiles[unit];
        let x0 = tx * TILE;
        let y0 = ty * TILE;
        let x1 = (x0 + TILE).min(width);
        let y1 = (y0 + TILE).min(height);
        let tile_width = x1 - x0;
        let mut values = vec![PixelSums::default(); (tile_width * (y1 - y0)) as usize];
        // The walls each arc of directions can meet, for the tile and
        // then for each block of it (tested against the tile's lists).
        // With few samples a pixel, a block's lists would serve too few
        // rays to repay their filling: the tile's lists serve them all.
        let samples: u32 = contexts.iter().map(|c| c.pass.count()).sum();
        let block_size = if samples < FINE_CULLING_SAMPLES {
            TILE
        } else {
            CULL_BLOCK
        };
        let mut tile_arcs = ArcCandidates::default();
        let mut block = BlockCulling::default();
        let mut batch = Batch::default();
        let corner = |x: u32, y: u32| scene.canvas.origin + DVec2::new(x as f64, y as f64) * step;
        // The shadow lists serve the floor's own shadow rays. Where every
        // light takes a ray from each point (the floor memo's strata, or
        // paths that start with the floor's light), each block has its
        // own. The points of a light table take a few lights each: the
        // tile's lists serve its blocks, for the lights its points take
        // most, within a budget of wall tests.
        let trace = &context.trace;
        let shadow_lists =
            trace.shadows && (trace.floor_direct || trace.force || trace.light_table.is_none());
        let tile_table = trace.light_table.filter(|_| trace.shadows && !shadow_lists);
        if context.culling {
            let (lo, hi) = (corner(x0, y0), corner(x1, y1));
            if let Some(table) = tile_table {
                let listed = &mut batch.listed;
                tile_lights(scene, table, (lo, hi), listed);
                block.fill_shadows_of(scene, lo, hi, |light| listed.get(light) == Some(&true));
                block.drop_long_shadow_lists();
            }
            // A block's lists come from its tile's: the walls its rays
            // can meet, less those that walls opaque to them hide.
            let lists = if block_size == TILE {
                if tile_table.is_none() {
                    block.fill_shadows(scene, lo, hi, shadow_lists);
                }
                &mut block.arcs
            } else {
                &mut tile_arcs
            };
            lists.fill(&scene.segments, lo, hi, ARCS, None);
            lists.drop_blocked(&scene.segments, lo, hi, |i| scene.stops_rays(i));
        }
        for by in (y0..y1).step_by(block_size as usize) {
            for bx in (x0..x1).step_by(block_size as usize) {
                let (bx1, by1) = ((bx + block_size).min(x1), (by + block_size).min(y1));
                let culled = context.culling.then(|| {
                    if block_size != TILE {
                        let (lo, hi) = (corner(bx, by), corner(bx1, by1));
                        block.fill(scene, lo, hi, &tile_arcs, shadow_lists);
                    }
                    &block
                });
                for y in by..by1 {
                    for x in bx..bx1 {
                        let k = (y * width + x) as usize;
                        let total = self.previous.get(k).copied();
                        values[((y - y0) * tile_width + x - x0) as usize] = (context.render_pixel)(
                            contexts,
                            total,
                            (x, y),
                            culled,
                            &mut batch,
                            stats,
                        );
                    }
                }
            }
        }
        let samples: u64 = contexts.iter().map(|c| c.pass.count() as u64).sum();
        progress(values.len() as u64 * samples);
        Part::Tile {
            x0,
            y0,
            width: tile_width,
            values,
        }
    }

    fn finish(&self, film: Film, _stats: &mut Stats) -> Vec<PixelSums> {
        if film.values.is_empty() {
            return vec![PixelSums::default(); film.width as usize * film.height as usize];
        }
        film.values
    }
}

/// The size of one pixel in world units, in x and y.
fn pixel_size(scene: &Scene, (width, height): (u32, u32)) -> DVec2 {
    DVec2::new(
        scene.canvas.width as f64 / width as f64,
        scene.canvas.height as f64 / height as f64,
    )
}

/// What every pixel of one render pass shares.
struct Context<'a> {
    options: &'a RenderOptions,
    pass: &'a Pass,
    size: (u32, u32),
    /// Whether the floor's direct light is estimated once per pixel.
    floor_memo: bool,
    /// Where that estimate's strata can share their shadow rays.
    coherence: Option<&'a FloorCoherence>,
    /// Whether the floor's rays test only their arc's walls.
    culling: bool,
    trace: Trace<'a>,
    /// The wall memo, where paths take the one-bounce shortcut
    /// (`shortcut.rs`: one bounce, the memo, not the reference).
    one_bounce_memo: Option<&'a WallMemo>,
    /// [`render_pixel`], compiled for this processor.
    render_pixel: PixelFn,
}

type PixelFn = fn(
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
fn render_pixel_avx2(
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
fn pixel_fn() -> PixelFn {
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

/// The light table of a render, where its plan chooses lights by one.
fn light_table_for(scene: &Scene, options: &RenderOptions, plan: &Plan) -> Option<LightTable> {
    let mut table = plan
        .light_table
        .then(|| LightTable::build(scene, options.scale, options.seed, plan.shadows))
        .flatten()?;
    if plan.shadows && options.takes(FastPath::DarkCells) {
        table.set_dark(crate::dark::dark_cells(scene, &table));
    }
    Some(table)
}

/// The switches of a path sample, from the plan, with a pass's fills.
fn trace_for<'a>(
    scene: &'a Scene,
    options: &RenderOptions,
    shared: &'a Shared,
    (caustics, onward): (Option<&'a Caustics>, Option<Onward<'a>>),
) -> Trace<'a> {
    trace_with(
        scene,
        options,
        &shared.plan,
        (shared.memo.as_ref(), caustics),
        (
            shared
                .mirror_arcs
                .as_ref()
                .map(|arcs| arcs as &dyn MirrorWalls),
            shared.last_leg_sides.as_deref(),
        ),
        shared.light_table.as_ref(),
        onward,
    )
}

/// The switches of a path sample, from the plan and what it reads.
fn trace_with<'a>(
    scene: &'a Scene,
    options: &RenderOptions,
    plan: &Plan,
    (memo, caustics): (Option<&'a WallMemo>, Option<&'a Caustics>),
    (mirror_arcs, last_leg_sides): (Option<&'a dyn MirrorWalls>, Option<&'a [bool]>),
    light_table: Option<&'a LightTable>,
    onward: Option<Onward<'a>>,
) -> Trace<'a> {
    let force = options.reference;
    Trace {
        scene,
        bounces: options.bounces,
        specular: options.specular,
        indirect: plan.indirect,
        integrator: options.integrator,
        floor_direct: !plan.floor_memo,
        memo,
        memo_checks: true,
        shadows: plan.shadows,
        mirror_emission: plan.mirror_emission,
        last_leg_sides: last_leg_sides.filter(|_| plan.last_legs),
        force,
        tables: options.takes(FastPath::Tables),
        caustics,
        mirror_arcs,
        light_table,
        onward,
    }
}

/// Stream sample indices from here up key the floor memo's points' line
/// light numbers, apart from every path sample's.
const FLOOR_STREAMS: u64 = 1 << 40;

/// The stream sample index that draws a pixel's seeds for its floor
/// points' scrambling.
const FLOOR_SEED_STREAM: u64 = (1 << 41) + 1;

/// One pixel's totals after the passes of `contexts` (one per pass, in
/// order), from its totals `total` before them (`None` before the first
/// pass). Each pass adds the floor's direct light and its path samples,
/// each half weighted by its samples (`passes.rs`). With the floor memo,
/// the floor's direct light is estimated once per pixel over all the
/// passes' floor points, each pass reading its own; without, each sample
/// estimates it anew. A sample whose estimate is not finite is left out
/// and reported in `stats`.
#[inline(always)]
fn render_pixel(
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
    let Context {
        options,
        size,
        floor_memo,
        coherence,
        ref trace,
        ..
    } = *first;
    let scene = trace.scene;
    let pixel = Pixel::new(scene, size, x, y, options.seed);
    let step = pixel.step;
    let corner = scene.canvas.origin + DVec2::new(x as f64, y as f64) * step;
    // The passes' floor points: the direct light at each, filled once.
    let points = first.pass.points.start..last.pass.points.end;
    if floor_memo && !points.is_empty() {
        // Each light's transmittance where the whole pixel shares it.
        let centre = corner + 0.5 * step;
        // The floor's shadow rays, its points' and its centre's, take the
        // pixel's block lists.
        let shadow_walls = culled.map(|c| &c.shadows[..]);
        let receiver = Receiver {
            shadow_walls,
            ..Receiver::FLOOR
        };
        let visibility = &mut batch.visibility;
        batch.shared.clear();
        match coherence {
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
            // batch, not per pixel (a pass over every light).
            None => {
                if visibility.len() != scene.lights.len() {
                    visibility.clear();
                    visibility.resize(scene.lights.len(), Visibility::of(trace.shadows));
                }
            }
        }
        // The pass's points (progressive jitter: the pixel's earlier
        // points are drawn again to place them), and the numbers each line
        // light draws, in the order `direct_light_with` draws them; then
        // the lights one by one over all points (`direct_light_strata`).
        // The pass's points, from the pixel's scrambled Sobol sequence,
        // and the numbers each line light draws, in the order
        // `direct_light_with` draws them; then the lights one by one over
        // all points (`direct_light_strata`).
        let floor = &mut batch.floor;
        floor.points.clear();
        floor.numbers.clear();
        let numbers = numbers_per_point(scene, trace.light_table);
        let bits = pixel.key.stream(FLOOR_SEED_STREAM).bits();
        let seeds = [(bits >> 32) as u32, bits as u32];
        floor.points.resize(points.len(), DVec2::ZERO);
        sobol_points(points.start, seeds, (corner, step), &mut floor.points);
        if numbers > 0 {
            for k in points.clone() {
                let mut stream = pixel.key.stream(FLOOR_STREAMS + k as u64);
                for _ in 0..numbers {
                    floor.numbers.push(stream.uniform());
                }
            }
        }
        match trace.light_table {
            Some(table) => {
                // A light the whole pixel shares is traced once, from the
                // centre, when a point first takes it (the very value each
                // point's own ray would give); a light no point takes
                // costs no ray.
                let shared = &mut batch.shared;
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
                if options.takes(FastPath::StrataLoops) {
                    let strata = (floor, &mut batch.weights);
                    direct_light_chosen_strata(scene, table, receiver, strata, vis, stats);
                } else {
                    direct_light_chosen(scene, table, receiver, floor, vis, stats);
                }
                stats.merge(&centre_stats);
            }
            None if options.takes(FastPath::StrataLoops) => {
                direct_light_strata(scene, floor, visibility, shadow_walls, stats)
            }
            None => direct_light_points(scene, floor, visibility, stats),
        }
    }
    // Every pass's path samples, arc by arc over all of them.
    let mut sums = std::mem::take(&mut batch.sums);
    sums.clear();
    sums.extend(contexts.iter().map(|c| Sums::new(c.pass.middle)));
    match culled {
        Some(culled) => {
            // Unchecked, a sample that is not finite makes the sum not
            // finite; then the pixel's samples are taken again, each
            // checked (a rare case: no test per sample in the common one).
            let before = *stats;
            culled_samples::<false>(contexts, &pixel, culled, &mut sums, stats);
            if !sums.iter().all(|s| s.all.is_finite()) {
                *stats = before;
                for (sum, context) in sums.iter_mut().zip(contexts) {
                    *sum = Sums::new(context.pass.middle);
                }
                checked_culled_samples(contexts, &pixel, culled, &mut sums, stats);
            }
        }
        None => {
            let all = first.pass.samples.start..last.pass.samples.end;
            for (_, of_arc) in sample_order(pixel.arc_offset, all) {
                for sample in of_arc {
                    let pass = pass_of(contexts, sample);
                    let value = sample_with(&contexts[pass], &pixel, sample, stats);
                    add_sample::<true>(&mut sums[pass], value, (x, y, sample), stats);
                }
            }
        }
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

/// The pass of `contexts` (consecutive passes of the schedule) that takes
/// `sample`.
#[inline(always)]
fn pass_of(contexts: &[Context], sample: u32) -> usize {
    let first = contexts.first().map_or(0, |c| c.pass.index);
    (crate::passes::pass_index(sample).saturating_sub(first) as usize)
        .min(contexts.len().saturating_sub(1))
}

/// One pass's sums for one pixel: its path samples' `sums`, its direct
/// light from its own floor points (among `values`, filled from point
/// `first_point` on), and its caustic pass's light on the floor.
#[inline(always)]
fn pass_sums(
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
    if context.floor_memo && !pass.points.is_empty() {
        let from = (pass.points.start - first_point) as usize;
        let to = (pass.points.end - first_point) as usize;
        if let Some(values) = values.get(from..to) {
            let (first, second, all) = strata_halves(values, (x, y), stats);
            (halves, whole) = ((first, second), all);
        }
        stats.work.floor_memo_reuses += pass.count() as u64;
    }
    // The caustic pass's light on the floor, from each half of its
    // photons.
    if let Some(caustics) = context.trace.caustics {
        let k = (y * context.size.0 + x) as usize;
        let (first, second) = caustics.floor_halves(k);
        halves = (halves.0 + first, halves.1 + second);
        whole += caustics.floor_at(k);
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
fn strata_halves(values: &[Rgb], (x, y): (u32, u32), stats: &mut Stats) -> (Rgb, Rgb, Rgb) {
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
struct Pixel {
    position: DVec2,
    key: StreamKey,
    step: DVec2,
    /// Uniform in `0..ARCS`: see [`sample_arc`].
    arc_offset: usize,
}

impl Pixel {
    fn new(scene: &Scene, size: (u32, u32), x: u32, y: u32, seed: u64) -> Pixel {
        let index = y as u64 * size.0 as u64 + x as u64;
        let key = StreamKey::new(seed, index);
        // Exact: 64 times a multiple of 2^-53 below 1.
        let arc_offset = (key.stream(ARC_OFFSET_STREAM).uniform() * ARCS as f64) as usize;
        Pixel {
            position: DVec2::new(x as f64, y as f64),
            key,
            step: pixel_size(scene, size),
            arc_offset,
        }
    }
}

impl Pixel {
    /// A sample's receiver point, jittered uniformly inside the pixel (the
    /// box filter): the first pair of numbers of the sample's stream.
    /// [`arc_in_lanes`] computes the same, component by component.
    #[inline(always)]
    fn receiver(&self, scene: &Scene, stream: &mut Stream) -> DVec2 {
        let (jx, jy) = stream.uniform_pair();
        let jitter = DVec2::new(jx, jy);
        scene.canvas.origin + (self.position + jitter) * self.step
    }
}

/// The stream sample index that draws a pixel's [`Pixel::arc_offset`],
/// apart from every path sample's and the floor memo's.
const ARC_OFFSET_STREAM: u64 = 1 << 41;

/// One sample of a pixel: the receiver is jittered uniformly inside the
/// pixel (the box filter). Deterministic in `(seed, pixel, sample)`.
fn sample_with(context: &Context, pixel: &Pixel, sample: u32, stats: &mut Stats) -> Rgb {
    let trace = &context.trace;
    let scene = trace.scene;
    let mut stream = pixel.key.stream(sample as u64);
    let p = pixel.receiver(scene, &mut stream);
    stats.physics.camera_samples += 1;
    let arc = sample_arc(pixel.arc_offset, sample);
    if context.one_bounce_memo.is_none() {
        return path_sample(trace, p, arc, sample, &mut stream, stats);
    }
    // `path_sample`, with the one-bounce shortcut tried first.
    let begun = path_begin(trace, p, arc, None, &mut stream, stats);
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
fn finish(
    context: &Context,
    fluence: Rgb,
    ray: Ray,
    hit: Option<(u32, Hit)>,
    (line_walls, sample): (Option<&[u32]>, u32),
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    if let (Some(memo), Some((index, h))) = (context.one_bounce_memo, hit)
        && let Some(value) = memo_bounce(&context.trace, memo, fluence, index, h.u, ray.dir, stats)
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
fn sample_order(offset: usize, samples: Range<u32>) -> impl Iterator<Item = (usize, ArcSamples)> {
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
fn chunk_end(first: u32, end: u32) -> u32 {
    (first / CHUNK as u32 + 1)
        .saturating_mul(CHUNK as u32)
        .min(end)
}

/// [`sample_order`]'s state: the chunk `first..last` of the samples up to
/// `end`, and the next arc to look at in it.
struct SampleOrder {
    offset: usize,
    first: u32,
    last: u32,
    end: u32,
    arc: usize,
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
struct ArcSamples {
    next: u32,
    count: u32,
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
fn culled_samples<const CHECKED: bool>(
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
            let begun = path_begin(trace, p, arc, shadow_walls, &mut stream, stats);
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
fn checked_culled_samples(
    contexts: &[Context],
    pixel: &Pixel,
    culled: &BlockCulling,
    sums: &mut [Sums],
    stats: &mut Stats,
) {
    culled_samples::<true>(contexts, pixel, culled, sums, stats);
}

/// A pixel's sum of sample values in one pass, and apart the sum of its
/// first half of samples (those below `half`), whose difference from the
/// second half estimates the pixel's noise. The sum of all is taken in
/// the same order with or without the halves: the image does not change.
#[derive(Clone, Copy, Debug)]
struct Sums {
    all: Rgb,
    first: Rgb,
    half: u32,
}

impl Sums {
    fn new(half: u32) -> Sums {
        Sums {
            all: Rgb::ZERO,
            first: Rgb::ZERO,
            half,
        }
    }

    #[inline(always)]
    fn add(&mut self, sample: u32, value: Rgb) {
        self.all += value;
        if sample < self.half {
            self.first += value;
        }
    }
}

/// Adds a sample's value to its pixel's sum. `CHECKED`, a value that is
/// not finite is left out and reported; unchecked, it is added (and the
/// sum is no longer finite: the caller checks the sum).
#[inline(always)]
fn add_sample<const CHECKED: bool>(
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
fn arc_in_lanes<const CHECKED: bool, const N: usize>(
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
        // In the order `sample_with` draws them: jitter, then direction.
        (jx[k], jy[k]) = stream.uniform_pair();
        fractions[k] = stream.uniform();
    }
    let (origin, position, step) = (scene.canvas.origin, pixel.position, pixel.step);
    let mut rays = RayLanes {
        ox: [0.0; N],
        oy: [0.0; N],
        dx: [0.0; N],
        dy: [0.0; N],
    };
    for k in 0..N {
        // `origin + (position + jitter) * step`, component by component.
        rays.ox[k] = origin.x + (position.x + jx[k]) * step.x;
        rays.oy[k] = origin.y + (position.y + jy[k]) * step.y;
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
        let shortcut = context.one_bounce_memo.and_then(|memo| {
            memo_bounce(trace, memo, Rgb::ZERO, hits.index[k], hits.u[k], dir, stats)
        });
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
const WIDE_LIST: usize = 4;

/// Samples of one arc in one chunk, at most: [`arc_in_lanes`] takes them
/// in this many lanes.
const LANES: usize = CHUNK / ARCS;

/// The samples of one stretch of [`sample_order`]: a whole number of runs
/// of [`ARCS`], so that each arc holds the same number of them, and as
/// many as [`arc_in_lanes`] takes in one go.
const CHUNK: usize = 8 * ARCS;

/// What a block of pixels culls: for each arc of directions, the walls its
/// floor rays can meet; for each light, the walls the shadow rays from its
/// floor points can cross (`None` for a sun: every wall).
#[derive(Default)]
struct BlockCulling {
    arcs: ArcCandidates,
    shadows: Vec<Option<Vec<u32>>>,
}

impl BlockCulling {
    /// The lists for the block `[lo, hi]` of tile `tile`; the shadow lists
    /// only when shadow rays are cast.
    fn fill(&mut self, scene: &Scene, lo: DVec2, hi: DVec2, tile: &ArcCandidates, shadows: bool) {
        self.arcs.fill(&scene.segments, lo, hi, ARCS, Some(tile));
        self.fill_shadows(scene, lo, hi, shadows);
    }

    /// Shadow rays whose list holds more walls than this ask the BVH: the
    /// same answer, for less work than a long list.
    fn drop_long_shadow_lists(&mut self) {
        for list in &mut self.shadows {
            if list.as_ref().is_some_and(|l| l.len() > LONG_LIST) {
                *list = None;
            }
        }
    }

    /// The shadow lists for the block `[lo, hi]` (only when shadow rays
    /// are cast). Without `shadows`, the lists stay as they are: those of
    /// the block's tile, or none.
    fn fill_shadows(&mut self, scene: &Scene, lo: DVec2, hi: DVec2, shadows: bool) {
        self.shadows.resize(scene.lights.len(), None);
        if shadows {
            self.fill_shadows_of(scene, lo, hi, |_| true);
        }
    }

    /// The shadow lists for the block `[lo, hi]` of the lights that
    /// `listed` takes; the other lights have none.
    fn fill_shadows_of(
        &mut self,
        scene: &Scene,
        lo: DVec2,
        hi: DVec2,
        listed: impl Fn(usize) -> bool,
    ) {
        self.shadows.resize(scene.lights.len(), None);
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        for (index, (light, list)) in scene.lights.iter().zip(&mut self.shadows).enumerate() {
            let hull = light.shape.hull().filter(|_| listed(index));
            let Some(hull) = hull else {
                *list = None;
                continue;
            };
            let points = [
                corners[0], corners[1], corners[2], corners[3], hull[0], hull[1], hull[2], hull[3],
            ];
            hull_candidates(&scene.segments, &points, list.get_or_insert_with(Vec::new));
        }
    }
}

/// The buffers of a pixel's floor memo, kept by a tile for all its pixels:
/// no allocation per pixel.
#[derive(Default)]
struct Batch {
    /// Each light's visibility over the pixel (without coherence masks,
    /// the same for every pixel, and filled once).
    visibility: Vec<Visibility>,
    /// Per light, whether the pixel shares its transmittance and it is
    /// not yet traced (with a light table and coherence masks).
    shared: Vec<bool>,
    /// The floor memo's points of one pixel, for all its passes.
    floor: Strata,
    /// The light table's weights of the seen lights at those points.
    weights: Vec<f64>,
    /// The path samples' sums of each pass.
    sums: Vec<Sums>,
    /// Per light, whether the tile's points have its shadow list.
    listed: Vec<bool>,
}

/// Marks in `listed` the lights whose shadow rays from the tile `[lo, hi]`
/// take a list: every light where lights times walls fit
/// [`TILE_SHADOW_TESTS`]; else those that the table's cells under the tile
/// take at every point or by what their probes saw, or else their
/// always-lights alone, as long as they fit; else none (the BVH answers).
fn tile_lights(scene: &Scene, table: &LightTable, tile: (DVec2, DVec2), listed: &mut Vec<bool>) {
    let walls = scene.walls.len().max(1);
    let lights = scene.lights.len();
    listed.clear();
    if lights * walls <= TILE_SHADOW_TESTS {
        listed.resize(lights, true);
        return;
    }
    if table.lights_in_box(tile, true, listed) * walls <= TILE_SHADOW_TESTS
        || table.lights_in_box(tile, false, listed) * walls <= TILE_SHADOW_TESTS
    {
        return;
    }
    listed.clear();
    listed.resize(lights, false);
}

/// One sample of the fluence averaged over pixel `(x, y)` of an image of
/// `size`, without the memo, exactly as a render with the memo off draws
/// it: it can be re-run alone for debugging. The caustic pass's light is
/// not part of a sample (the pass traces it from the lights, for the
/// whole image at once). In a scene whose plan chooses lights by a table,
/// the table is built for each call.
pub fn pixel_sample(
    scene: &Scene,
    options: &RenderOptions,
    size: (u32, u32),
    x: u32,
    y: u32,
    sample: u32,
    stats: &mut Stats,
) -> Rgb {
    let options = RenderOptions {
        memo: MemoOptions {
            enabled: false,
            ..options.memo
        },
        ..*options
    };
    let plan = Plan::new(scene, &options);
    // The render's own table, built again: the same from the same seed.
    let light_table = light_table_for(scene, &options, &plan);
    let last_leg_sides = plan.last_legs.then(|| crate::run::last_leg_sides(scene));
    let pass = Pass::new(0, sample..sample.saturating_add(1), (0, 0), options.seed);
    let context = Context {
        options: &options,
        pass: &pass,
        size,
        floor_memo: false,
        coherence: None,
        culling: false,
        trace: trace_with(
            scene,
            &options,
            &plan,
            (None, None),
            (None, last_leg_sides.as_deref()),
            light_table.as_ref(),
            None,
        ),
        one_bounce_memo: None,
        render_pixel,
    };
    sample_with(
        &context,
        &Pixel::new(scene, size, x, y, options.seed),
        sample,
        stats,
    )
}

/// A render driven pass by pass: the image after any pass is the one a
/// render of that many samples gives, bit for bit, and more samples can
/// be added to it.
pub struct Progressive<'a> {
    inner: Passes<'a>,
}

impl<'a> Progressive<'a> {
    /// Prepares a render of `scene` (`options.samples` is not used: the
    /// passes say how many samples are taken): builds what every pass
    /// shares.
    pub fn new(scene: &'a Scene, options: &RenderOptions) -> Progressive<'a> {
        Progressive {
            inner: Passes::new(scene, options),
        }
    }

    /// Samples per pixel taken so far.
    pub fn samples(&self) -> u32 {
        self.inner.samples()
    }

    /// Where the next pass ends if more are to follow it
    /// ([`next_pass_end`]); `None` once a pass has ended short of that,
    /// since a render of more samples would not have taken that pass.
    pub fn next_end(&self) -> Option<u32> {
        self.inner.next_end()
    }

    /// Takes the next pass, ending at `end` samples per pixel: at most
    /// [`Progressive::next_end`] (a pass that ends short of it is the
    /// last). Returns false, taking nothing, when no such pass may follow.
    /// `progress` is called with pixel samples (or photon paths) done.
    pub fn pass(&mut self, end: u32, progress: &(dyn Fn(u64) + Sync)) -> bool {
        self.inner.pass(end, progress)
    }

    /// The image and statistics so far.
    pub fn rendered(&self) -> Rendered {
        self.inner.rendered()
    }

    /// The image's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.inner.size()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strata_that_are_not_finite_are_left_out_and_counted() {
        let v = |x: f64| Rgb::new(x, 1.0, 2.0);
        let mut stats = Stats::default();
        let finite = [v(1.0), v(3.0), v(2.0), v(6.0)];
        assert_eq!(
            strata_halves(&finite, (4, 5), &mut stats),
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
            strata_halves(&mixed, (4, 5), &mut stats),
            (Rgb::new(2.0, 1.0, 2.0), Rgb::ZERO, Rgb::new(1.0, 0.5, 1.0))
        );
        assert_eq!(stats.physics.nonfinite_samples, 2);
        assert_eq!(stats.physics.first_nonfinite, Some((4, 5, u32::MAX)));
        // One point: its value, for both halves.
        let one = strata_halves(&finite[..1], (4, 5), &mut stats);
        assert_eq!(one, (v(1.0), v(1.0), v(1.0)));
    }
}
