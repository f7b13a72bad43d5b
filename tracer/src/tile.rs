//! The path estimators (`Path`, `Original`) as units of the render loop:
//! what every pass of a render shares (the plan and the structures it
//! builds once), what each pass fills for itself (the list [`FILLS`]:
//! caustic photons, onward memo, lines), and a tile of pixels per unit,
//! in blocks of [`CULL_BLOCK`] pixels that share their culling lists.

use flatray_geometry::{ArcCandidates, DVec2};

use flatray_cache::WallMemo;

use crate::accel::coherence::FloorCoherence;
use crate::accel::culling::{BlockCulling, tile_lights};
use crate::accel::mirror::MirrorArcs;
use crate::caustics::Caustics;
use crate::estimators::choice::LightTable;
use crate::film::PixelSums;
use crate::film::{Estimator, Film, Part, run};
use crate::lines::Lines;
use crate::memo::build_wall_memo;
use crate::memo::{Onward, OnwardMemo};
use crate::options::MemoOptions;
use crate::options::{CULL_BLOCK, FINE_CULLING_SAMPLES, RenderOptions, TILE, Window, image_size};
use crate::passes::{Pass, PointRule};
use crate::path::{MirrorWalls, Trace};
use crate::pixel::Batch;
use crate::pixel::{Context, Pixel, pixel_fn, render_pixel, sample_with};
use crate::plan::Plan;
use crate::run::Limits;
use crate::sampling::ARCS;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// What every pass of a path-traced render shares, built once.
pub(crate) struct Shared {
    pub(crate) plan: Plan,
    pub(crate) memo: Option<WallMemo>,
    pub(crate) mirror_arcs: Option<MirrorArcs>,
    pub(crate) light_table: Option<LightTable>,
    pub(crate) coherence: Option<FloorCoherence>,
    /// Per wall side, whether a path's last leg from there can meet a
    /// light (`run::last_leg_sides`), where the plan has last legs.
    pub(crate) last_leg_sides: Option<Vec<bool>>,
    /// The tiles that meet the window (all of them, without one).
    pub(crate) tiles: Vec<(u32, u32)>,
    /// Every tile of the image, where a window leaves some out: the first
    /// pass measures its probe pixels in all of them (`passes::is_probe`).
    pub(crate) all_tiles: Option<Vec<(u32, u32)>>,
}

impl Shared {
    /// What every pass of a path-traced render of `scene` shares, built
    /// once; what building it cost is counted in `stats`.
    pub(crate) fn new(scene: &Scene, options: &RenderOptions, stats: &mut Stats) -> Shared {
        let (width, height) = image_size(scene, options.scale);
        let plan = Plan::new(scene, options);
        let memo = plan.wall_memo.then(|| {
            let shadows = (plan.shadows, &plan.ledger());
            build_wall_memo(scene, &options.memo, options.scale, shadows, stats)
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
        // Only the tiles that meet the window, where there is one: each
        // tile's pixels do not depend on which other tiles are rendered.
        let every: Vec<(u32, u32)> = (0..height.div_ceil(TILE))
            .flat_map(|ty| (0..width.div_ceil(TILE)).map(move |tx| (tx, ty)))
            .collect();
        let (tiles, all_tiles) = match options.window {
            Some(window) => (
                every
                    .iter()
                    .copied()
                    .filter(|&tile| tile_meets(window, tile))
                    .collect(),
                Some(every),
            ),
            None => (every, None),
        };
        let last_leg_sides = plan.last_legs.then(|| crate::run::last_leg_sides(scene));
        Shared {
            plan,
            memo,
            mirror_arcs,
            light_table,
            coherence,
            last_leg_sides,
            tiles,
            all_tiles,
        }
    }
}

/// Whether tile `(tx, ty)` meets `window`.
fn tile_meets(window: Window, (tx, ty): (u32, u32)) -> bool {
    window.meets((tx * TILE, ty * TILE), ((tx + 1) * TILE, (ty + 1) * TILE))
}

/// What one pass of a path-traced render fills for itself before its
/// pixels, each built by one step of [`FILLS`] where the plan runs it.
#[derive(Default)]
pub(crate) struct Fills {
    caustics: Option<Caustics>,
    onward: Option<OnwardMemo>,
    /// The floor's indirect light along lines (`Plan::floor_lines`).
    lines: Option<Lines>,
}

/// What a step of [`FILLS`] builds from.
struct FillInput<'a> {
    scene: &'a Scene,
    options: &'a RenderOptions,
    shared: &'a Shared,
    pass: &'a Pass,
    progress: &'a (dyn Fn(u64) + Sync),
}

/// One step of a pass's fills: builds its part of `fills` where the plan
/// runs it, reading the parts the steps before it built.
type FillStep = fn(&FillInput<'_>, &mut Fills, &mut Stats);

/// A pass's fills in the order they read each other: the caustic photons
/// first (light through mirrors and glass that next-event estimation at
/// the walls reads), then the onward memo (whose gathers read them), then
/// the floor's lines (whose paths read both). A new fill is one step
/// here and one field of [`Fills`]; the render loop walks the list.
const FILLS: [FillStep; 3] = [caustic_photons, onward_memo, floor_lines];

/// Light from points, spots and suns through mirrors and glass, which no
/// path from the floor can find, traced from the lights.
fn caustic_photons(input: &FillInput<'_>, fills: &mut Fills, stats: &mut Stats) {
    let plan = &input.shared.plan;
    if !plan.caustics {
        return;
    }
    // Photons are no pixel samples: the callback hears of them with 0,
    // as a heartbeat.
    fills.caustics = crate::caustics::trace_caustics(
        input.scene,
        input.options,
        (Limits::of(input.options), input.pass),
        plan.ledger(),
        stats,
        &|_| (input.progress)(0),
    );
}

/// The rest of a path from each diffuse wall, gathered after the direct
/// light and the caustic photons its paths read.
fn onward_memo(input: &FillInput<'_>, fills: &mut Fills, stats: &mut Stats) {
    let FillInput {
        scene,
        options,
        shared,
        pass,
        ..
    } = *input;
    let Some(wall_memo) = shared.memo.as_ref().filter(|_| shared.plan.onward) else {
        return;
    };
    let (width, height) = image_size(scene, options.scale);
    let trace = fills.trace(scene, options, shared, pass);
    // The first pass's halves read a copy each; a later pass is one half
    // of the noise estimate by itself.
    let copies = if pass.index == 0 { 2 } else { 1 };
    let gathers = crate::onward::gathers(
        pass.count(),
        width as u64 * height as u64,
        (wall_memo.values() as u64, options.bounces.saturating_sub(1)),
        copies,
    );
    let memo = crate::onward::build_onward(&trace, wall_memo, (gathers, copies), pass.seed, stats);
    fills.onward = Some(memo);
}

/// The floor's indirect light along lines, whose paths read the fills
/// before it.
fn floor_lines(input: &FillInput<'_>, fills: &mut Fills, stats: &mut Stats) {
    if !input.shared.plan.floor_lines {
        return;
    }
    let mut trace = fills.trace(input.scene, input.options, input.shared, input.pass);
    trace.floor_direct = false;
    let lines = crate::lines::gather_lines(trace, input.options, input.pass, stats, input.progress);
    fills.lines = Some(lines);
}

impl Fills {
    /// Pass `pass`'s fills: every step of [`FILLS`] in turn.
    fn new(
        scene: &Scene,
        options: &RenderOptions,
        shared: &Shared,
        pass: &Pass,
        stats: &mut Stats,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Fills {
        let input = FillInput {
            scene,
            options,
            shared,
            pass,
            progress,
        };
        let mut fills = Fills::default();
        for step in FILLS {
            step(&input, &mut fills, stats);
        }
        fills
    }

    /// The switches of pass `pass`'s path samples, reading what is
    /// filled so far.
    fn trace<'a>(
        &'a self,
        scene: &'a Scene,
        options: &RenderOptions,
        shared: &'a Shared,
        pass: &Pass,
    ) -> Trace<'a> {
        let onward = self
            .onward
            .as_ref()
            .map(|memo| Onward::of(memo, pass.middle));
        trace_for(scene, options, shared, (self.caustics.as_ref(), onward))
    }
}

/// Passes `group` of a path-traced render, each with its own fills, every
/// pixel taking them in turn from its totals `previous` (empty before
/// the first pass): the pixels' new totals.
pub(crate) fn path_passes(
    scene: &Scene,
    options: &RenderOptions,
    shared: &Shared,
    group: &[Pass],
    (previous, mask): (&[PixelSums], Option<&[bool]>),
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<PixelSums>, Stats) {
    let (width, height) = image_size(scene, options.scale);
    let plan = &shared.plan;
    let mut stats = Stats::default();
    // A first pass measures its probe pixels in every tile, also those
    // outside the window.
    let measures = plan.floor_memo && group.first().is_some_and(|p| p.index == 0);
    let tiles = match &shared.all_tiles {
        Some(all) if measures => all,
        _ => &shared.tiles,
    };
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
            floor_squares: plan.floor_squares,
            measures: measures && pass.index == 0,
            coherence: shared.coherence.as_ref(),
            culling: plan.floor_ray_culling,
            trace: fills.trace(scene, options, shared, pass),
            one_bounce_memo: shared.memo.as_ref().filter(|_| plan.fast.shortcut.runs),
            lines: fills.lines.as_ref(),
            strata_loops: plan.fast.strata_loops.runs,
            render_pixel: if plan.fast.avx.runs {
                pixel_fn()
            } else {
                render_pixel
            },
        })
        .collect();
    let outcome = run(
        &PixelEstimator {
            contexts,
            tiles,
            window: options.window,
            previous,
            mask,
        },
        stats,
        progress,
    );
    (outcome.output, outcome.stats)
}

/// The path estimators (`Path`, `Original`) as units of the render loop:
/// a tile of pixels each, in blocks of [`CULL_BLOCK`] pixels (which share
/// their culling lists), then pixel by pixel.
pub(crate) struct PixelEstimator<'a> {
    /// One per pass, in order.
    pub(crate) contexts: Vec<Context<'a>>,
    pub(crate) tiles: &'a [(u32, u32)],
    /// The render's window: a tile outside it renders only its probe
    /// pixels, for their measure, and adds no values.
    pub(crate) window: Option<Window>,
    /// The pixels' totals before these passes (empty before the first).
    pub(crate) previous: &'a [PixelSums],
    /// With adaptive passes, the pixels that take them; the others keep
    /// their totals.
    pub(crate) mask: Option<&'a [bool]>,
}

impl Estimator for PixelEstimator<'_> {
    type Output = Vec<PixelSums>;

    fn size(&self) -> (u32, u32) {
        self.contexts.first().map_or((0, 0), |c| c.size)
    }

    fn units(&self) -> usize {
        self.tiles.len()
    }

    fn render_unit(&self, unit: usize, outer: &mut Stats, progress: &(dyn Fn(u64) + Sync)) -> Part {
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
        let step = scene.canvas.pixel_step((width, height));
        let (tx, ty) = self.tiles[unit];
        let x0 = tx * TILE;
        let y0 = ty * TILE;
        let x1 = (x0 + TILE).min(width);
        let y1 = (y0 + TILE).min(height);
        let tile_width = x1 - x0;
        let mut values = vec![PixelSums::default(); (tile_width * (y1 - y0)) as usize];
        // Outside the window, only the first pass's probes, measured. Their
        // work is counted apart and only their measure kept: the window's
        // counts are its own pixels'.
        let probes_only = self.window.is_some_and(|w| !tile_meets(w, (tx, ty)));
        let mut probe_stats = Stats::default();
        let stats = if probes_only {
            &mut probe_stats
        } else {
            &mut *outer
        };
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
                        if self.mask.is_some_and(|m| m.get(k) == Some(&false)) {
                            values[((y - y0) * tile_width + x - x0) as usize] =
                                total.unwrap_or_default();
                            continue;
                        }
                        if probes_only && !crate::passes::is_probe((x, y)) {
                            continue;
                        }
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
        if probes_only {
            outer.split.merge(&probe_stats.split);
            return Part::Tile {
                x0,
                y0,
                width: 0,
                values: Vec::new(),
            };
        }
        let samples: u64 = contexts.iter().map(|c| c.pass.count() as u64).sum();
        // Where lines run, they report half of the pixels' samples as
        // their directions are walked (`lines::LINE_PROGRESS`).
        let work = values.len() as u64 * samples;
        progress(match context.lines {
            Some(_) => work - work / crate::lines::LINE_PROGRESS,
            None => work,
        });
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

/// The light table of a render, where its plan chooses lights by one.
pub(crate) fn light_table_for(
    scene: &Scene,
    options: &RenderOptions,
    plan: &Plan,
) -> Option<LightTable> {
    let mut table = plan
        .light_table
        .then(|| LightTable::build(scene, options.scale, options.seed, plan.shadows))
        .flatten()?;
    if plan.fast.dark_cells.runs {
        table.set_dark(crate::accel::dark::dark_cells(scene, &table));
    }
    Some(table)
}

/// The switches of a path sample, from the plan, with a pass's fills.
pub(crate) fn trace_for<'a>(
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
pub(crate) fn trace_with<'a>(
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
        ledger: crate::ledger::Ledger {
            caustics: caustics.is_some(),
            ..plan.ledger()
        },
        last_leg_sides: last_leg_sides.filter(|_| plan.last_legs),
        force,
        tables: plan.fast.tables.runs,
        caustics,
        mirror_arcs,
        light_table,
        onward,
    }
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
    let pass = Pass::new(
        0,
        sample..sample.saturating_add(1),
        (0, 0, PointRule::First { light_table: true }),
        options.seed,
    );
    let context = Context {
        options: &options,
        pass: &pass,
        size,
        floor_memo: false,
        floor_squares: false,
        measures: false,
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
        strata_loops: false,
        lines: None,
        render_pixel,
    };
    sample_with(
        &context,
        &Pixel::new(scene, size, x, y, options.seed),
        sample,
        stats,
    )
}
