//! Light that path tracing cannot find: from a point, a spot or the sun
//! through one or more mirrors or glass edges, to the floor or to a
//! diffuse wall. A path from the floor meets such a light only by hitting
//! a point (a path of probability zero), so the path tracer leaves it to
//! this pass, and the two split the paths between them with no overlap:
//!
//! - next-event estimation (the path tracer) takes light that reaches a
//!   receiver straight from a light, through panes at most;
//! - the caustic pass takes light from a light of one direction per point
//!   that reaches the receiver after at least one mirror or glass event,
//!   and all the light of a laser (a delta in position and direction,
//!   which no path finds).
//!
//! Photons leave each such light towards the mirrors and glass edges only
//! (`Aperture`: the directions, or the sun's rays, that meet each of
//! them), so none is wasted on the rest of the room. Each is followed by
//! the light tracer's code (`light_tracer::follow_photon`): its flights
//! after its first specular event add their exact track length to the
//! floor's pixels, and at its first diffuse wall it stops, its power
//! added to that wall's bins. The path tracer's next-event estimation at
//! a diffuse wall adds them ([`Caustics::wall`]): a photon's run of
//! specular events ends at that wall, as the path's diffuse reflection
//! starts one, so every bin is within the limits (`run.rs`).
//!
//! The floor's part is unbiased, as the light tracer's is. The walls' part
//! averages each bin (one pixel long at the wall memo's default): a bias
//! like the wall memo's, where the caustic on a wall has an edge. Their
//! values stay within [`MAX_WALL_VALUES`] per chunk of work (coarser bins;
//! a scene of more diffuse walls than that holds leaves the caustic light
//! on walls out).

use flatray_geometry::{Ray, Segment, Side, Skip, segments_meet};

use crate::film::{Estimator, Film, Part, run};
use crate::ledger::Ledger;
use crate::light_tracer::{Deposits, Grid, WallDeposits, follow_photon};
use crate::lights::aimed::Aim;
use crate::lights::{Aperture, Photon};
use crate::options::{RenderOptions, image_size};
use crate::passes::Pass;
use crate::run::Limits;
use crate::sampling::Stream;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Caustic photons per pixel sample of the render where the mirrors and
/// glass take a large share of the lights' power ([`photon_rate`]). Every
/// photon is aimed at a mirror or glass edge, and a photon's track covers
/// many pixels.
pub const PHOTONS_PER_SAMPLE: f64 = 0.0625;
/// The share of the lights' power heading for mirrors and glass from which
/// the caustic pass takes its full rate, [`PHOTONS_PER_SAMPLE`].
pub const FULL_RATE_SHARE: f64 = 0.25;
/// The least fraction of the full rate that a scene's caustic pass takes.
pub const LEAST_RATE: f64 = 1.0 / 16.0;

/// Caustic photons per pixel sample, for a scene whose mirrors and glass
/// edges take `share` of its lights' power (`intensity` times the
/// measure of the directions, or sun rays, that meet them, over
/// `intensity` times the whole): [`PHOTONS_PER_SAMPLE`] times
/// `(share / FULL_RATE_SHARE)^2`, from [`LEAST_RATE`] of it up to all of it.
///
/// Where a small share of the light meets mirrors, their light adds
/// little to the image's error, and photons spent there buy less than
/// path samples; the square is the rate that, measured on scenes with
/// mirrors or glass, came nearest the best error per second. Any photon
/// count gives an unbiased caustic estimate; the rate only moves noise
/// between the pass and the path samples (`docs/performance.md`,
/// "Caustic photons by the mirrors' share").
pub fn photon_rate(share: f64) -> f64 {
    let ratio = share / FULL_RATE_SHARE;
    let factor = ratio * ratio;
    // NaN (a scene of no power) takes the least rate.
    PHOTONS_PER_SAMPLE
        * if factor.is_nan() {
            LEAST_RATE
        } else {
            factor.clamp(LEAST_RATE, 1.0)
        }
}

/// Fixed work chunks, as the light tracer's: at least two (the noise
/// estimate compares halves), at most sixteen.
const MAX_CHUNKS: usize = 16;
/// The fewest photons a chunk takes beyond the first two chunks.
const MIN_CHUNK_PHOTONS: u64 = 1 << 15;
/// Bytes the chunks' floor and wall buffers may take together (beyond the
/// two chunks that every pass has).
const CHUNK_BUDGET: usize = 32 << 20;
/// At most this many values in the walls' bins, over every wall and side
/// (24 bytes each, per chunk of work).
pub const MAX_WALL_VALUES: usize = 1 << 20;
/// Stream sample index of caustic photons, apart from every other stream.
const CAUSTIC_STREAM: u64 = 1 << 42;
/// Photons between two progress reports within a chunk.
const PROGRESS_STEP: u64 = 4096;

/// The layout of the diffuse walls' bins: per wall, its first value, its
/// number of bins along it and its spans; per bin, a value per side. As
/// the wall memo's, a wall's bins stop at every junction (where
/// another wall meets or crosses it): the two sides of a junction can lie
/// in different rooms, and a bin across it would carry light from one
/// into the other.
#[derive(Clone, Debug, Default)]
pub(crate) struct WallBins {
    walls: Vec<BinLayout>,
    spans: Vec<BinSpan>,
    len: usize,
}

/// A wall's bins: its first value, its bins along it, its spans, and
/// one over a bin's length where it has one span (most walls), which a
/// lookup then reads without its span.
#[derive(Clone, Copy, Debug, Default)]
struct BinLayout {
    first: usize,
    bins: usize,
    spans: (u32, u32),
    per_length: f64,
}

/// A stretch `[u0, u1]` of a wall between junctions, cut into `bins` bins
/// from the wall's bin `offset`; `scale` is `bins / (u1 - u0)` (exactly
/// `bins` for a span of the whole wall), `per_length` one over a bin's
/// length.
#[derive(Clone, Copy, Debug)]
struct BinSpan {
    u0: f64,
    u1: f64,
    offset: usize,
    bins: usize,
    scale: f64,
    per_length: f64,
}

impl WallBins {
    /// Bins of about `bin_length` world units on every diffuse wall, cut
    /// at the `junctions` along each (positions in `(0, 1)`), where
    /// `wanted` (a path reads them); coarser where the walls are long,
    /// within [`MAX_WALL_VALUES`] (and a bin more per junction). With more
    /// diffuse walls than that allows one bin each, no bins: the caustic
    /// light on walls is then left out (`docs/robustness.md`).
    fn new(scene: &Scene, junctions: &[Vec<f64>], bin_length: f64, wanted: bool) -> WallBins {
        let lengths = scene.diffuse_lengths();
        let walls = lengths.iter().filter(|&&l| l > 0.0).count();
        if !wanted || 4 * walls > MAX_WALL_VALUES {
            return WallBins {
                walls: vec![BinLayout::default(); lengths.len()],
                ..WallBins::default()
            };
        }
        // Half the values for bins along the walls, the other half for
        // the one each wall has at least.
        let most = MAX_WALL_VALUES / 4;
        let total: f64 = lengths.iter().sum();
        let bin_length = bin_length.max(total / most as f64);
        let mut bins = WallBins::default();
        for (wall, length) in lengths.into_iter().enumerate() {
            let first_span = bins.spans.len() as u32;
            let mut n = 0;
            if length > 0.0 {
                let bounds =
                    flatray_cache::span_bounds(junctions.get(wall).map_or(&[], Vec::as_slice));
                for pair in bounds.windows(2) {
                    let span_length = (pair[1] - pair[0]) * length;
                    let count = ((span_length / bin_length).ceil() as usize).clamp(1, most);
                    bins.spans.push(BinSpan {
                        u0: pair[0],
                        u1: pair[1],
                        offset: n,
                        bins: count,
                        scale: count as f64 / (pair[1] - pair[0]),
                        per_length: count as f64 / span_length,
                    });
                    n += count;
                }
            }
            let spans = (first_span, bins.spans.len() as u32);
            bins.walls.push(BinLayout {
                first: bins.len,
                bins: n,
                spans,
                per_length: if spans.1 - spans.0 == 1 {
                    bins.spans[first_span as usize].per_length
                } else {
                    0.0
                },
            });
            bins.len += n * 2;
        }
        bins
    }

    /// Where `u` on wall `wall` falls among the centres of its span's
    /// bins ([`Found`]); `None` for a wall without bins.
    #[inline]
    fn locate(&self, wall: u32, u: f64) -> Option<Found> {
        let layout = self.walls.get(wall as usize)?;
        let (first, end) = (layout.spans.0 as usize, layout.spans.1 as usize);
        let (offset, bins, x, per_length) = match end.checked_sub(first)? {
            0 => return None,
            // The whole wall, u in [0, 1].
            1 => (0, layout.bins, u * layout.bins as f64, layout.per_length),
            n => {
                let spans = self.spans.get(first..end)?;
                let span = &spans[spans[..n - 1].partition_point(|s| s.u1 <= u)];
                let x = (u - span.u0) * span.scale;
                (span.offset, span.bins, x, span.per_length)
            }
        };
        // From the first bin's centre, in bins; NaN takes the first bin.
        let x = x - 0.5;
        let last = bins.checked_sub(1)?;
        let (a, share) = if x.is_nan() || x <= 0.0 {
            (0, 0.0)
        } else if x >= last as f64 {
            (last, 0.0)
        } else {
            let a = x as usize;
            (a, x - a as f64)
        };
        let b = (a + 1).min(last);
        Some(Found {
            first: layout.first,
            bins: layout.bins,
            pair: (offset + a, offset + b),
            share,
            per_length,
        })
    }
}

impl WallDeposits for WallBins {
    /// Adds `power` arriving on side `side` of diffuse wall `wall` at `u`,
    /// as irradiance, shared between the two bins about `u` as a read
    /// there takes them ([`Found`]), so that what a photon leaves on a wall
    /// is centred where it hit.
    fn add(&self, values: &mut [Rgb], (wall, side, u): (u32, Side, f64), power: Rgb) {
        if let Some(found) = self.locate(wall, u) {
            found.deposit(values, 0, side, power);
        }
    }

    /// After the bins' values, where a buffer holds a second set.
    fn add_late(&self, values: &mut [Rgb], (wall, side, u): (u32, Side, f64), power: Rgb) {
        if let Some(found) = self.locate(wall, u) {
            found.deposit(values, self.len, side, power);
        }
    }
}

/// Where a position along a wall falls among its bins: between the
/// centres of two bins of its span (the same bin twice beyond the span's
/// outer centres, or in a span of one bin), `share` of the way from the
/// first to the second. A deposit gives each bin its share of the power
/// (the second `share`, the first the rest) and a read blends the two by
/// the same shares: the power is kept, and a photon's light, as the
/// bins give it back, is centred where it hit (a bin's whole deposit
/// would be centred on the bin, up to half a bin away).
#[derive(Clone, Copy, Debug)]
struct Found {
    /// The wall's first value and its bins along it.
    first: usize,
    bins: usize,
    pair: (usize, usize),
    share: f64,
    /// One over a bin's length.
    per_length: f64,
}

impl Found {
    /// The indices of the two bins' values on side `side`, in a set of
    /// values from `set`.
    #[inline]
    fn indices(&self, set: usize, side: Side) -> (usize, usize) {
        let base = set + self.first + side.index() * self.bins;
        (base + self.pair.0, base + self.pair.1)
    }

    fn deposit(&self, values: &mut [Rgb], set: usize, side: Side, power: Rgb) {
        let (a, b) = self.indices(set, side);
        let density = power * self.per_length;
        if let Some(value) = values.get_mut(a) {
            *value += density * (1.0 - self.share);
        }
        if self.share > 0.0
            && let Some(value) = values.get_mut(b)
        {
            *value += density * self.share;
        }
    }

    #[inline]
    fn read(&self, values: &[Rgb], set: usize, side: Side) -> Rgb {
        let (a, b) = self.indices(set, side);
        let at = |k: usize| values.get(k).copied().unwrap_or(Rgb::ZERO);
        if self.share > 0.0 {
            at(a) * (1.0 - self.share) + at(b) * self.share
        } else {
            at(a)
        }
    }
}

/// What the caustic pass measured: the fluence on the floor per pixel,
/// and the irradiance on the diffuse walls.
pub(crate) struct Caustics {
    floor: Vec<Rgb>,
    /// The floor deposits of the first half of the photons, and how many
    /// photons that half and the whole traced.
    first: Vec<Rgb>,
    photons: (u64, u64),
    bins: WallBins,
    walls: Vec<Rgb>,
}

impl Caustics {
    /// The fluence on pixel `k`, from all the photons.
    pub fn floor_at(&self, k: usize) -> Rgb {
        self.floor.get(k).copied().unwrap_or(Rgb::ZERO)
    }

    /// The fluence on pixel `k` as the two halves of the photons estimate
    /// it, each scaled to the whole.
    pub fn floor_halves(&self, k: usize) -> (Rgb, Rgb) {
        crate::film::split(&self.floor, &self.first, k, self.photons)
    }

    /// The irradiance from caustic light on side `side` of wall `wall` at
    /// `u`.
    #[inline]
    pub fn wall(&self, wall: u32, side: Side, u: f64) -> Rgb {
        self.bins
            .locate(wall, u)
            .map_or(Rgb::ZERO, |found| found.read(&self.walls, 0, side))
    }

    /// Whether the pass kept light that took a glossy reflection after a
    /// mirror or glass on its way to a diffuse wall ([`Caustics::wall_late`]).
    pub fn has_late(&self) -> bool {
        self.walls.len() > self.bins.len
    }

    /// The irradiance on side `side` of diffuse wall `wall` at `u` of
    /// light that took one glossy reflection on its way there: it counts
    /// one reflection more than [`Caustics::wall`]'s, so a path reads it
    /// only where it has a reflection left.
    pub fn wall_late(&self, wall: u32, side: Side, u: f64) -> Rgb {
        self.bins.locate(wall, u).map_or(Rgb::ZERO, |found| {
            found.read(&self.walls, self.bins.len, side)
        })
    }
}

/// One light's apertures towards the specular walls; for a line or
/// circle light, its aim at them.
struct Emitter {
    light: usize,
    apertures: Vec<Aperture>,
    /// Their measures, summed as they are listed.
    cumulative: Vec<f64>,
    area: Option<Aim>,
}

/// Segments whose apertures hold every direction that meets `shape`: the
/// segment itself; for an arc, the two tangents of each piece of at most
/// an eighth of a turn, from its ends to where they meet (the piece lies
/// in that triangle, so a ray that meets it crosses them). Apertures may
/// overlap: a photon's density counts every aperture that holds it.
fn covering(shape: &flatray_geometry::Shape) -> impl Iterator<Item = Segment> + use<> {
    use flatray_geometry::Shape;
    let mut out = Vec::new();
    match shape {
        Shape::Segment(s) => out.push(*s),
        Shape::Arc(arc) => {
            let pieces = (arc.sweep / std::f64::consts::FRAC_PI_4).ceil().max(1.0) as usize;
            let half = 0.5 * arc.sweep / pieces as f64;
            for k in 0..pieces {
                let (u0, u1) = (k as f64 / pieces as f64, (k + 1) as f64 / pieces as f64);
                let (p, q) = (arc.point_at(u0), arc.point_at(u1));
                let mid = arc.point_at(0.5 * (u0 + u1));
                // Where the tangents at `p` and `q` meet: along the
                // middle's radius, at `r / cos(half)`.
                let apex = arc.center + (mid - arc.center) / half.cos();
                out.push(Segment::new(p, apex));
                out.push(Segment::new(apex, q));
            }
        }
    }
    out.into_iter()
}

/// Most segments that line and circle lights aim their photons at
/// (`Plan::area_photons`): each photon looks at every one.
pub const MAX_AREA_TARGETS: usize = 256;

/// The segments line and circle lights aim their photons at: every
/// mirror and glass edge (arcs by the segments that cover them).
pub(crate) fn area_targets(scene: &Scene) -> Vec<Segment> {
    scene
        .walls
        .iter()
        .filter(|w| w.material.turns_specularly())
        .flat_map(|w| covering(&w.shape))
        .collect()
}

/// Parts of an aperture tested for whether a diffuse wall hides the target.
const APERTURE_PARTS: usize = 64;

/// The parts of `aperture` (towards wall `target`) whose photons can meet
/// the target or another specular wall before a diffuse one, merged into
/// runs: a part is left out only where one diffuse wall stands in front of
/// the target across the whole part. Its photons would all stop there
/// before any specular event, adding nothing, so leaving them out changes
/// no expected value, and spares the photons that a room's walls hide
/// from its mirrors. A direction that meets another specular wall first
/// lies in that wall's aperture, which keeps it.
fn reaching(scene: &Scene, aperture: &Aperture, target: u32) -> Vec<Aperture> {
    let hidden = |k: usize| {
        let (u0, u1) = (
            k as f64 / APERTURE_PARTS as f64,
            (k + 1) as f64 / APERTURE_PARTS as f64,
        );
        let edge = |u: f64| {
            let (origin, dir) = aperture.ray(u);
            let ray = Ray::new(origin, dir);
            let (wall, hit) = scene
                .segments
                .closest_hit(&ray, f64::INFINITY, Skip::NONE)?;
            // Where the ray meets the target's line (an edge ray aims at
            // its end, and may pass it by a rounding).
            let s = &scene.walls[target as usize].shape.chord();
            let (e, denom) = (s.edge(), dir.perp_dot(s.edge()));
            let beyond = (s.a - origin).perp_dot(e) / denom;
            if !(beyond.is_finite() && beyond > 0.0) {
                return None;
            }
            let diffuse = scene.walls[wall as usize].material.is_diffuse();
            // Well inside the wall, and well in front of the target.
            (diffuse
                && wall != target
                && hit.u > 1e-6
                && hit.u < 1.0 - 1e-6
                && hit.t < beyond * (1.0 - 1e-9))
                .then(|| (wall, ray.at(hit.t), ray.at(beyond)))
        };
        match (edge(u0), edge(u1)) {
            (Some((w0, a0, b0)), Some((w1, a1, b1))) => {
                // The same wall, and its chord across the part never meets
                // the target's: it is in front all the way.
                w0 == w1 && !segments_meet(&Segment::new(a0, a1), &Segment::new(b0, b1))
            }
            _ => false,
        }
    };
    let mut parts = Vec::new();
    let mut start = None;
    for k in 0..=APERTURE_PARTS {
        let keep = k < APERTURE_PARTS && !hidden(k);
        match (keep, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                parts.push(aperture.part(
                    s as f64 / APERTURE_PARTS as f64,
                    k as f64 / APERTURE_PARTS as f64,
                ));
                start = None;
            }
            _ => {}
        }
    }
    parts
}

/// The caustic pass as units of the render loop: chunks of photons, each
/// summed into buffers of the floor and the walls.
struct CausticPass<'a> {
    scene: &'a Scene,
    size: (u32, u32),
    limits: Limits,
    emitters: Vec<Emitter>,
    /// The emitters' cumulative shares: intensity times their apertures'
    /// measure.
    shares: Vec<f64>,
    /// Their total, and each photon's share of it.
    total: f64,
    photons: u64,
    chunks: usize,
    per_chunk: u64,
    grid: Grid,
    bins: WallBins,
    /// The length of a chunk's buffer of the bins' values: the bins, and
    /// again for late light where it can come.
    values: usize,
    /// The seed of the photons: the render pass's.
    seed: u64,
    /// Who counts which path: what line and circle lights' photons leave
    /// to closed forms, and where photons stop.
    ledger: Ledger,
}

/// Runs the caustic pass for a path-traced render of `scene`; `None` when
/// the scene has no mirror or glass, or no light of one direction per
/// point (the plan says so).
///
/// With `ledger.area_photons` (`Plan::area_photons`), line and circle
/// lights send photons too, aimed at the mirror and glass edges
/// (`lights::aimed`): they count after a run of specular events but those
/// the ledger says receivers take in closed form, and path rays leave that
/// light to them.
pub(crate) fn trace_caustics(
    scene: &Scene,
    options: &RenderOptions,
    (limits, pass): (Limits, &Pass),
    ledger: Ledger,
    stats: &mut Stats,
    progress: &(dyn Fn(u64) + Sync),
) -> Option<Caustics> {
    let targets: Vec<u32> = (0..scene.walls.len() as u32)
        .filter(|&i| {
            let material = &scene.walls[i as usize].material;
            material.turns_specularly() || (material.is_glossy() && options.bounces > 0)
        })
        .collect();
    // What line and circle lights aim at, where they send photons.
    let aimed_at = ledger.area_photons.then(|| area_targets(scene));
    let emitters: Vec<Emitter> = scene
        .lights
        .iter()
        .enumerate()
        .filter_map(|(index, light)| {
            if crate::estimators::is_exact(&light.shape) {
                let aim = Aim::new(light.shape, aimed_at.clone()?)?;
                return (light.intensity > 0.0).then_some(Emitter {
                    light: index,
                    apertures: Vec::new(),
                    cumulative: vec![aim.measure()],
                    area: Some(aim),
                });
            }
            // A light no path finds (a laser) is traced whole; any other
            // towards the specular walls.
            let apertures: Vec<Aperture> = match light.shape.whole_aperture() {
                Some(whole) => vec![whole],
                None => targets
                    .iter()
                    .flat_map(|&t| {
                        let shape = scene.walls[t as usize].shape;
                        covering(&shape).filter_map(move |target| {
                            let aperture = light.shape.aperture(scene, &target)?;
                            Some((aperture, t, shape.as_arc().is_some()))
                        })
                    })
                    .flat_map(|(a, t, arc)| {
                        // An arc's apertures are kept whole: the test of
                        // what hides a target takes its line.
                        if arc { vec![a] } else { reaching(scene, &a, t) }
                    })
                    .collect(),
            };
            let mut sum = 0.0;
            let cumulative: Vec<f64> = apertures
                .iter()
                .map(|a| {
                    sum += a.measure();
                    sum
                })
                .collect();
            (sum > 0.0 && light.intensity > 0.0).then_some(Emitter {
                light: index,
                apertures,
                cumulative,
                area: None,
            })
        })
        .collect();
    if emitters.is_empty() || limits.specular == 0 {
        return None;
    }
    let mut total = 0.0;
    let shares: Vec<f64> = emitters
        .iter()
        .map(|e| {
            total += scene.lights[e.light].intensity * e.cumulative.last().copied().unwrap_or(0.0);
            total
        })
        .collect();
    let (width, height) = image_size(scene, options.scale);
    let pixels = width as usize * height as usize;
    let power: f64 = scene
        .lights
        .iter()
        .map(|l| l.intensity * l.shape.power(scene))
        .sum();
    let rate = photon_rate(total / power);
    let photons = ((pass.count() as f64 * pixels as f64 * rate).ceil() as u64).max(1);
    // A path reads the walls' bins at a diffuse reflection: none without.
    let junctions = scene.junctions();
    let bins = WallBins::new(
        scene,
        &junctions,
        options.memo.bin_length / options.scale,
        limits.bounces > 0,
    );
    // A second set of the bins' values, for light off a rough mirror
    // after a mirror or glass, where one can come.
    let late = limits.bounces >= 2 && scene.walls.iter().any(|w| w.material.is_glossy());
    let values = bins.len * (1 + usize::from(late));
    let chunk_bytes = (pixels + values) * 24;
    // As many chunks as the budget holds, but not so many that a chunk's
    // buffers cost more to clear and merge than its photons to trace.
    let by_photons = (photons / MIN_CHUNK_PHOTONS) as usize;
    let chunks = (CHUNK_BUDGET / chunk_bytes.max(1))
        .min(by_photons)
        .clamp(2, MAX_CHUNKS);
    let pass = CausticPass {
        scene,
        size: (width, height),
        limits,
        emitters,
        shares,
        total,
        photons,
        chunks,
        per_chunk: photons.div_ceil(chunks as u64),
        grid: Grid::new(scene, options.scale, width, height),
        bins,
        values,
        seed: pass.seed,
        ledger,
    };
    let outcome = run(&pass, Stats::default(), progress);
    stats.merge(&outcome.stats);
    Some(outcome.output)
}

impl Estimator for CausticPass<'_> {
    type Output = Caustics;

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn units(&self) -> usize {
        self.chunks
    }

    fn render_unit(
        &self,
        chunk: usize,
        stats: &mut Stats,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Part {
        let scene = self.scene;
        let mut floor = vec![Rgb::ZERO; self.size.0 as usize * self.size.1 as usize];
        let mut walls = vec![Rgb::ZERO; self.values];
        let first = chunk as u64 * self.per_chunk;
        let last = ((chunk as u64 + 1) * self.per_chunk).min(self.photons);
        let weight = self.total / self.photons as f64;
        let mut scratch = Vec::new();
        let pick = |list: &[f64], u: f64| {
            let u = u * list.last().copied().unwrap_or(0.0);
            list.iter().position(|&c| u < c).unwrap_or(list.len() - 1)
        };
        for index in first..last {
            // Progress in steps, so that a caller hears from a long chunk.
            if (index - first) % PROGRESS_STEP == PROGRESS_STEP - 1 {
                progress(PROGRESS_STEP);
            }
            let mut stream = Stream::new(self.seed, index, CAUSTIC_STREAM);
            stats.physics.caustic_photons += 1;
            let emitter = &self.emitters[pick(&self.shares, stream.uniform())];
            let light = &scene.lights[emitter.light];
            let colour = |stream: &mut Stream| match scene
                .spectra
                .photon(emitter.light, || stream.uniform())
            {
                Some((wavelength, colour)) => (Some(wavelength), colour),
                None => (None, light.color),
            };
            let (photon, power, area) = if let Some(aim) = &emitter.area {
                // Its share of the photons stands for its aimed power as
                // measured; each carries what its own point sees.
                let Some(aimed) = aim.draw(&mut stream, &mut scratch) else {
                    continue;
                };
                let (wavelength, colour) = colour(&mut stream);
                let photon = Photon {
                    origin: aimed.origin,
                    dir: aimed.dir,
                    scale: 1.0,
                    kernel: light.shape.kernel(light),
                    skip: scene.light_wall[emitter.light].map_or(Skip::NONE, Skip::one),
                    unseen: false,
                    wavelength,
                };
                // Its light arrives at receivers from `-dir`.
                let factor = aimed.factor * light.profile_at(-aimed.dir);
                let power = colour * (weight * factor / aim.measure());
                (photon, power, true)
            } else {
                let aperture = &emitter.apertures[pick(&emitter.cumulative, stream.uniform())];
                let (origin, dir) = aperture.ray(stream.uniform());
                // The density of this ray among the light's apertures:
                // every aperture that holds it could have drawn it.
                let holding = emitter
                    .apertures
                    .iter()
                    .filter(|a| a.contains(origin, dir))
                    .count()
                    .max(1);
                let window = light.spot_window(dir);
                let (wavelength, colour) = colour(&mut stream);
                let photon = Photon {
                    origin,
                    dir,
                    scale: 1.0,
                    kernel: light.shape.kernel(light),
                    skip: scene
                        .laser_wall(emitter.light)
                        .map_or(Skip::NONE, Skip::one),
                    unseen: !light.shape.found_by_paths(),
                    wavelength,
                };
                (photon, colour * (weight * window / holding as f64), false)
            };
            if power == Rgb::ZERO {
                continue;
            }
            let mut deposits = Deposits {
                grid: &self.grid,
                floor: &mut floor,
                walls: Some((&self.bins, &mut walls)),
                ledger: self.ledger,
                area,
            };
            follow_photon(
                scene,
                photon,
                power,
                self.limits,
                &mut deposits,
                &mut stream,
                stats,
            );
        }
        progress(last.saturating_sub(first) % PROGRESS_STEP);
        Part::Splats {
            fluence: floor,
            walls,
            first_half: chunk < self.chunks / 2,
        }
    }

    fn finish(&self, film: Film, _stats: &mut Stats) -> Caustics {
        let (width, height) = self.size;
        let first_photons = ((self.chunks / 2) as u64 * self.per_chunk).min(self.photons);
        let floor = if film.fluence.is_empty() {
            vec![Rgb::ZERO; width as usize * height as usize]
        } else {
            film.fluence
        };
        let walls = if film.walls.is_empty() {
            vec![Rgb::ZERO; self.values]
        } else {
            film.walls
        };
        Caustics {
            floor,
            first: film.first,
            photons: (self.photons, first_photons),
            bins: self.bins.clone(),
            walls,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The full rate from a quarter on, the square of the share below,
    /// a sixteenth at least, and the least rate where the share is not a
    /// number.
    #[test]
    fn the_photon_rate_at_its_ends() {
        for (share, factor) in [
            (0.25, 1.0),
            (0.5, 1.0),
            (f64::INFINITY, 1.0),
            (0.125, 0.25),
            (0.0625, LEAST_RATE),
            (0.01, LEAST_RATE),
            (0.0, LEAST_RATE),
            (f64::NAN, LEAST_RATE),
        ] {
            assert_eq!(photon_rate(share), PHOTONS_PER_SAMPLE * factor, "{share}");
        }
    }
}
