//! The render loop, written once: passes of samples (`passes.rs`), tiles
//! in parallel (`tile.rs`), then pixels (`pixel.rs`), then samples.
//! Integrators only say how one sample is estimated.

use crate::Stats;
use crate::options::{Integrator, RenderOptions, Rendered, image_size};
use crate::passes::{Pass, PointRule, Totals};
use crate::scene::Scene;
use crate::tile::{Shared, path_passes};

/// Renders `scene`. `progress` is called from worker threads with the
/// number of pixel samples each finished tile took, and with 0, as a
/// heartbeat, before each unit of work; the image does not
/// depend on the number of threads or on their scheduling. The render is
/// the sequence of passes that `passes.rs` describes: the same image as
/// [`crate::Progressive`] driven to the same samples.
///
/// ```
/// use flatray_tracer::{Canvas, Falloff, Floor, Light, LightShape, RenderOptions, Rgb, Scene};
/// use glam::DVec2;
///
/// let canvas = Canvas { width: 32, height: 16, origin: DVec2::ZERO };
/// let lamp = Light {
///     shape: LightShape::Point { at: DVec2::new(8.0, 8.0) },
///     color: Rgb::ONE,
///     intensity: 1.0,
///     falloff: Falloff::Flatland,
///     spectrum: None,
///     profile: None,
/// };
/// let scene = Scene::new(canvas, Floor::Color(Rgb::splat(0.5)), 0.5, vec![], vec![lamp])?;
/// let mut options = RenderOptions::default();
/// options.samples = 4;
/// let rendered = flatray_tracer::render(&scene, &options, &|_| {});
/// assert_eq!((rendered.image.width, rendered.image.height), (32, 16));
/// // Nearer the lamp is brighter.
/// assert!(rendered.image.get(9, 8)[0] > rendered.image.get(30, 8)[0]);
/// # Ok::<(), flatray_tracer::InvalidScene>(())
/// ```
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

/// Where the next pass starts: its index, its first sample and its first
/// floor point.
#[derive(Clone, Copy, Debug, Default)]
struct Cursor {
    index: u32,
    samples: u32,
    points: u32,
}

impl Cursor {
    /// The pass from here to `end` samples per pixel, taking floor points
    /// by `rule`.
    fn pass(self, end: u32, options: &RenderOptions, rule: PointRule) -> Pass {
        Pass::new(
            self.index,
            self.samples..end,
            (self.points, options.memo.floor_samples, rule),
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
    /// Floor points per sample of the passes after the first, once the
    /// first has measured it (`passes::point_rate`).
    rate: Option<f64>,
}

impl<'a> Passes<'a> {
    pub fn new(scene: &'a Scene, options: &RenderOptions) -> Passes<'a> {
        let (width, height) = image_size(scene, options.scale);
        let mut stats = Stats::default();
        let shared = (options.integrator != Integrator::Light)
            .then(|| Shared::new(scene, options, &mut stats));
        Passes {
            scene,
            options: *options,
            shared,
            totals: Totals::new((width, height), stats),
            cursor: Cursor::default(),
            closed: false,
            rate: None,
        }
    }

    pub fn samples(&self) -> u32 {
        self.totals.samples
    }

    /// Whether passes are adaptive: asked for, and a path estimator.
    fn adaptive(&self) -> bool {
        self.options.adaptive && self.shared.is_some()
    }

    /// Whether the first pass measures how many floor points the later
    /// ones take: wherever the floor memo takes points.
    fn measures(&self) -> bool {
        self.shared.as_ref().is_some_and(|s| s.plan.floor_memo)
    }

    /// How the pass at `cursor` takes its floor points: the first by
    /// the plan, the later ones by the rate the first measured (a point
    /// per sample where none was).
    fn point_rule(&self, cursor: Cursor) -> PointRule {
        match cursor.index {
            0 => PointRule::First {
                light_table: self.shared.as_ref().is_none_or(|s| s.plan.light_table),
            },
            _ => PointRule::Measured {
                rate: self.rate.unwrap_or(1.0),
            },
        }
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
        let pass = self
            .cursor
            .pass(end, &self.options, self.point_rule(self.cursor));
        self.run(&[pass], progress);
        true
    }

    /// Takes every pass of the schedule up to `samples`, as many at once
    /// as [`FILLS_BUDGET`] and [`GROUP_POINTS`] allow: each pixel then
    /// takes all of them in turn, sharing its culling lists, floor points
    /// and shared shadow rays. The same sums as pass by pass. A first pass
    /// that measures the later passes' floor points goes alone.
    pub fn run_to(&mut self, samples: u32, progress: &(dyn Fn(u64) + Sync)) {
        if self.adaptive() {
            // Each pass's pixels are chosen from the image before it.
            while !self.closed && self.cursor.samples < samples {
                let next = crate::passes::next_pass_end(self.cursor.samples);
                let rule = self.point_rule(self.cursor);
                let pass = self.cursor.pass(next.min(samples), &self.options, rule);
                self.closed = pass.samples.end < next;
                self.run(&[pass], progress);
            }
            return;
        }
        if self.cursor.index == 0 && self.measures() && !self.closed && samples > 0 {
            let next = crate::passes::next_pass_end(0);
            let rule = self.point_rule(self.cursor);
            let pass = self.cursor.pass(next.min(samples), &self.options, rule);
            self.closed = pass.samples.end < next;
            self.run(&[pass], progress);
        }
        let mut group: Vec<Pass> = Vec::new();
        let mut cursor = self.cursor;
        let (mut bytes, mut points) = (0, 0);
        while !self.closed && cursor.samples < samples {
            let next = crate::passes::next_pass_end(cursor.samples);
            let pass = cursor.pass(next.min(samples), &self.options, self.point_rule(cursor));
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
    /// and its lines' (each with the first half's) and its onward memo.
    fn fill_bytes(&self) -> u64 {
        let Some(shared) = &self.shared else {
            return 0;
        };
        let (width, height) = self.size();
        let mut bytes = 0u64;
        if shared.plan.caustics {
            bytes += width as u64 * height as u64 * 48;
        }
        if shared.plan.floor_lines {
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
            Some(shared) if self.options.adaptive => {
                for pass in group {
                    let mask = self.totals.adaptive_mask(pass.index);
                    let (sums, stats) = path_passes(
                        self.scene,
                        &self.options,
                        shared,
                        std::slice::from_ref(pass),
                        (&self.totals.sums, mask.as_deref()),
                        progress,
                    );
                    self.totals
                        .replace_masked(pass, sums, &stats, mask.as_deref());
                }
            }
            Some(shared) => {
                let (sums, stats) = path_passes(
                    self.scene,
                    &self.options,
                    shared,
                    group,
                    (&self.totals.sums, None),
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
        if self.rate.is_none() && self.measures() && group.first().is_some_and(|p| p.index == 0) {
            self.rate = Some(crate::passes::point_rate(&self.totals.stats.split));
        }
    }

    pub fn rendered(&self) -> Rendered {
        self.totals
            .rendered(self.scene, self.options.exposure, self.options.window)
    }
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
