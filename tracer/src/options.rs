//! What a render is asked to do, and what it gives back: the options,
//! the integrators, the fast paths, the image. A leaf: every other module
//! may read these, and this module reads none of theirs but the scene's
//! size and the statistics' type.

use crate::Stats;
use crate::scene::Scene;

/// The default of `RenderOptions::specular`: light crosses glass bodies
/// (two events each), prisms and lenses, and goes to and fro between
/// facing mirrors; Russian roulette ends most long runs well before it.
pub const DEFAULT_SPECULAR: u32 = 32;

/// How the memo is used. Start from [`MemoOptions::default`] and set the
/// fields you need: more may be added without a breaking release.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct MemoOptions {
    /// Whether a render uses the memo at all.
    pub enabled: bool,
    /// Length of a wall bin, in pixels of the rendered image.
    pub bin_length: f64,
    /// The fewest receiver points per pixel and render pass for the
    /// floor's direct light. A later pass's points grow with its samples
    /// at the rate the first pass measures (`passes::point_rate`), so the
    /// error keeps falling as the samples grow.
    pub floor_samples: u32,
    /// Whether, with the memo on and more than one bounce, paths end at
    /// their first diffuse wall and read the rest of their light from the
    /// onward memo (`onward.rs`), rather than being followed from wall to
    /// wall.
    pub onward: bool,
}

impl MemoOptions {
    /// The cache's mode, as `--cache` says it: "on", "direct" (the wall
    /// and floor memos, paths followed from wall to wall) or "off".
    pub fn mode(&self) -> &'static str {
        match (self.enabled, self.onward) {
            (false, _) => "off",
            (true, true) => "on",
            (true, false) => "direct",
        }
    }
}

impl Default for MemoOptions {
    fn default() -> MemoOptions {
        MemoOptions {
            enabled: true,
            bin_length: 1.0,
            floor_samples: 1,
            onward: true,
        }
    }
}

/// Which estimator a render uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Integrator {
    /// Path tracing with next-event estimation at every diffuse vertex and
    /// cosine-weighted bounces: the sound default.
    #[default]
    Path,
    /// The original project's estimator, kept as a baseline: uniform
    /// random bounce directions, each diffuse vertex aimed at the lights
    /// (for one bounce, exactly its light-directed last bounce).
    Original,
    /// Light tracing: photon paths from the lights, each free flight added
    /// to the pixels it crosses by its track length. Sees point lights in
    /// mirrors, which path tracing cannot.
    Light,
}

impl Integrator {
    /// The integrator's name, as `--integrator` and the scene format's
    /// `render` block say it (lower case).
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Path => "path",
            Integrator::Original => "original",
            Integrator::Light => "light",
        }
    }
}

/// Everything about a render that is not the scene.
///
/// Start from [`RenderOptions::default`] and set the fields you need:
/// more may be added without a breaking release.
///
/// ```
/// use flatray_tracer::{Integrator, RenderOptions};
///
/// let mut options = RenderOptions::default();
/// options.samples = 64;
/// options.bounces = 2;
/// options.integrator = Integrator::Path;
/// assert_eq!(options.seed, 0);
/// ```
///
/// A struct expression outside this crate does not compile, so that a
/// new field breaks no caller:
///
/// ```compile_fail
/// let options = flatray_tracer::RenderOptions { samples: 4, ..Default::default() };
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RenderOptions {
    /// Samples per pixel.
    pub samples: u32,
    /// Most diffuse reflections (off walls) between a light and the
    /// floor. Mirrors, glass and panes do not count: see `specular`.
    pub bounces: u32,
    /// Most specular events (mirror reflections, glass refractions and
    /// reflections) in a row: between a light, a diffuse wall or the
    /// floor and the next of them. Past [`ROULETTE_FROM`] events in a
    /// row, a path goes on with the probability of its run's throughput
    /// (Russian roulette, unbiased); at `specular` it stops.
    pub specular: u32,
    pub seed: u64,
    /// Multiplies every pixel value.
    pub exposure: f64,
    /// Pixels per world unit.
    pub scale: f64,
    pub integrator: Integrator,
    /// The direct-light memo.
    pub memo: MemoOptions,
    /// The caustic pass (on by default): the light of points, spots and
    /// suns through mirrors and glass, which path tracing alone cannot
    /// see. Off, that light is missing from the image.
    pub caustics: bool,
    /// The plain model: every effect computed wherever it could add
    /// light, even where the plan would skip it, and no fast path (no
    /// culling, lanes, shared shadow rays, tables or shortcuts, and the
    /// pixel loop compiled for any processor). The same image, bit for
    /// bit (`tests/tests/identity.rs`), more slowly: for tests, debugging
    /// and benchmarks ([`RenderOptions::with_reference`]).
    pub(crate) reference: bool,
    /// The fast paths a render may take (all, by default); `reference`
    /// takes none. Each computes what the model computes, bit for bit: a
    /// fast path is left out only to measure what it buys.
    pub(crate) fast_paths: FastPaths,
    /// How next-event estimation picks its lights.
    pub light_choice: LightChoice,
    /// Only the pixels of this window are rendered (all of them when
    /// `None`); the others are 0 and take no part in the noise estimate.
    /// A window's pixels have the whole render's bits, so a render split
    /// into windows and put back together is the whole render, bit for
    /// bit. The path estimators skip the tiles outside the window; the
    /// light tracer traces every path and keeps the window's pixels.
    pub window: Option<Window>,
    /// Adaptive passes (path estimators): from the third pass on, a pass
    /// takes only the pixels whose estimated error, averaged over their
    /// 3 x 3 neighbours, is at least a quarter of the image's mean
    /// (`passes::ADAPT_FROM`, `passes::adaptive_mask`); the others keep
    /// the samples they have. Passes are then taken one at a time.
    pub adaptive: bool,
    /// The floor's indirect light gathered along lines across the image
    /// (on by default, where the plan allows: `Plan::floor_lines`), rather
    /// than by each pixel's own path samples. Both estimate the same
    /// image; the lines' noise is lower for the time.
    pub floor_lines: bool,
}

/// A rectangle of an image's pixels: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Window {
    /// Whether pixel `(x, y)` is in the window.
    #[inline]
    pub fn contains(&self, (x, y): (u32, u32)) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// Whether the window and the rectangle `x0..x1`, `y0..y1` share a
    /// pixel.
    #[inline]
    pub fn meets(&self, (x0, y0): (u32, u32), (x1, y1): (u32, u32)) -> bool {
        self.x0 < x1 && x0 < self.x1 && self.y0 < y1 && y0 < self.y1
    }
}

impl RenderOptions {
    /// These options with the plain model on or off: every effect
    /// computed wherever it could add light, and no fast path. The same
    /// image, bit for bit, more slowly; for tests, debugging and
    /// benchmarks.
    #[doc(hidden)]
    pub fn with_reference(mut self, on: bool) -> RenderOptions {
        self.reference = on;
        self
    }

    /// Whether the plain model is on ([`RenderOptions::with_reference`]).
    #[doc(hidden)]
    pub fn is_reference(&self) -> bool {
        self.reference
    }

    /// These options taking only the fast paths `paths`, to measure what
    /// each buys. Every fast path computes the model's bits.
    #[doc(hidden)]
    pub fn with_fast_paths(mut self, paths: FastPaths) -> RenderOptions {
        self.fast_paths = paths;
        self
    }

    /// The fast paths a render may take.
    #[doc(hidden)]
    pub fn fast_paths(&self) -> FastPaths {
        self.fast_paths
    }

    /// Whether the render takes fast path `path`.
    #[inline]
    pub fn takes(&self, path: FastPath) -> bool {
        !self.reference && self.fast_paths.contains(path)
    }
}

/// A fast path beside the model (`ARCHITECTURE.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FastPath {
    /// The floor's rays, the rays off mirrors and the floor's shadow rays
    /// test only the walls their block of pixels (or piece of mirror) and
    /// arc of directions can meet, where the walls are few.
    Culling,
    /// The floor memo's strata share one shadow ray per light where no
    /// shadow edge crosses their pixel (`accel/coherence.rs`).
    Coherence,
    /// The floor memo's light-by-light loops, with line lights' angle
    /// samples in lanes (`accel::strata::direct_light_strata`).
    StrataLoops,
    /// One bounce read straight from the wall memo (`accel/shortcut.rs`).
    Shortcut,
    /// The floor's albedo along walls read from a table.
    Tables,
    /// The pixel loop compiled a second time with AVX2.
    Avx,
    /// No shadow ray to a chosen light that a wall hides from the whole
    /// cell of the light table (`accel/dark.rs`).
    DarkCells,
}

impl FastPath {
    /// Every fast path, in a fixed order.
    pub const ALL: [FastPath; 7] = [
        FastPath::Culling,
        FastPath::Coherence,
        FastPath::StrataLoops,
        FastPath::Shortcut,
        FastPath::Tables,
        FastPath::Avx,
        FastPath::DarkCells,
    ];

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// A set of fast paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FastPaths(u8);

impl FastPaths {
    /// Every fast path.
    pub const ALL: FastPaths = FastPaths(0b111_1111);

    /// All but `path`.
    pub fn without(self, path: FastPath) -> FastPaths {
        FastPaths(self.0 & !path.bit())
    }

    pub fn contains(self, path: FastPath) -> bool {
        self.0 & path.bit() != 0
    }
}

impl Default for FastPaths {
    fn default() -> FastPaths {
        FastPaths::ALL
    }
}

/// Which lights next-event estimation sends shadow rays to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightChoice {
    /// The plan decides: a light table for scenes of more than
    /// [`MANY_LIGHTS`] lights, every light otherwise.
    #[default]
    Auto,
    /// One shadow ray to every light at every receiver.
    Every,
    /// The lights a table of the plan's cells chooses
    /// (`estimators::choice`): the brightest there always, one of the rest
    /// at random.
    Table,
}

/// Over this many lights, the plan chooses lights by a table.
pub const MANY_LIGHTS: usize = 8;

impl Default for RenderOptions {
    fn default() -> RenderOptions {
        RenderOptions {
            samples: 16,
            bounces: 1,
            specular: DEFAULT_SPECULAR,
            seed: 0,
            exposure: 1.0,
            scale: 1.0,
            integrator: Integrator::Path,
            memo: MemoOptions::default(),
            caustics: true,
            reference: false,
            fast_paths: FastPaths::ALL,
            light_choice: LightChoice::Auto,
            window: None,
            adaptive: false,
            floor_lines: true,
        }
    }
}

/// A linear RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }
}

/// The result of a render.
#[derive(Clone, Debug)]
pub struct Rendered {
    pub image: Image,
    pub stats: Stats,
    /// The samples each pixel took, row by row: all the same but with
    /// [`RenderOptions::adaptive`].
    pub samples: Vec<u32>,
}

/// The side of a square tile in pixels.
pub const TILE: u32 = 16;
/// The side of the square blocks of pixels whose floor rays share lists
/// of the walls each arc of directions can meet.
pub const CULL_BLOCK: u32 = 4;

/// Scenes of more walls than this leave their floor rays to the BVH: a
/// tile's lists test every wall, and in a large plan an arc's list grows
/// long.
pub const MAX_CULLED_WALLS: usize = 512;

/// With a light table, each tile lists the walls its floor's shadow rays
/// to each light can cross where lights times walls are at most this: that
/// many wall tests per tile (16 x 16 pixels).
pub const TILE_SHADOW_TESTS: usize = 8192;

/// Pixels rendered with fewer samples than this (over the passes rendered
/// together) take their culling lists from their whole tile, not from
/// their block: a block's list of one arc would serve fewer than
/// `CULL_BLOCK^2 * FINE_CULLING_SAMPLES / ARCS` = 16 rays.
pub const FINE_CULLING_SAMPLES: u32 = 64;

/// The image size for `scene` at `scale`: at least one pixel each way.
pub fn image_size(scene: &Scene, scale: f64) -> (u32, u32) {
    let w = (scene.canvas.width as f64 * scale).round().max(1.0) as u32;
    let h = (scene.canvas.height as f64 * scale).round().max(1.0) as u32;
    (w, h)
}

/// The image size for `scene` at `scale`, or, where it is more than
/// flatray renders, what it would be and the bounds it passes.
pub fn checked_image_size(scene: &Scene, scale: f64) -> Result<(u32, u32), String> {
    use crate::scene::{MAX_CANVAS_PIXELS, MAX_CANVAS_SIDE};
    // In floats first: a size past u32 is said as it would be, not as
    // the largest u32.
    let side = |units: u32| (units as f64 * scale).round().max(1.0);
    let (w, h) = (side(scene.canvas.width), side(scene.canvas.height));
    if w > MAX_CANVAS_SIDE as f64 || h > MAX_CANVAS_SIDE as f64 || w * h > MAX_CANVAS_PIXELS as f64
    {
        return Err(format!(
            "the image would be {w:.0} x {h:.0} pixels, more than flatray renders (at most {MAX_CANVAS_SIDE} a side and {MAX_CANVAS_PIXELS} in all)"
        ));
    }
    Ok(image_size(scene, scale))
}

/// Rays whose arc lists more walls than this ask the whole set instead
/// (its BVH, or in a set of a few dozen walls its scan in lanes): the
/// same answers, for less work than a long list.
pub(crate) const LONG_LIST: usize = 16;
