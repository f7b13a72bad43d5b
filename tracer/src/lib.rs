//! flatray's renderer: the in-memory scene, the integrators, the samplers
//! and random streams, and the parallel render loop with its statistics.
//!
//! What it is for: estimating, for every floor pixel, the quantity that
//! `docs/model.md` defines (exposure times floor albedo times the
//! pixel's mean fluence), reproducibly: every sample draws from a stream
//! keyed by (seed, pixel, sample), so an image is bit-identical for any
//! number of threads.
//!
//! The model, which reads like `docs/model.md`: the lights (`lights/`, a
//! module per kind), the materials (`material/`), who counts which light
//! path (`ledger.rs`), a light's light at a receiver and the closed forms
//! (`estimators/`), next-event estimation (`direct.rs`), the path tracer (`path.rs`), the light tracer
//! (`light_tracer.rs`), the caustic pass (`caustics.rs`) and the one
//! render loop (`film.rs`). Above it, fast paths that compute the same
//! bits (`accel/`, one file each, `tests/tests/identity.rs`): culled rays,
//! shared shadow rays, lanes, tables; `RenderOptions::reference` turns
//! them all off. The memos (`memo.rs`, `onward.rs`) are estimators of
//! their own.
//!
//! What it never does: read or write files, parse text, or print. Scenes
//! come in as plain data ([`Scene`]); images go out as linear floats
//! ([`Image`]); progress goes out through a callback. Its one `unsafe`
//! block calls the pixel loop compiled with AVX2, after checking that the
//! processor has it (`pixel.rs::pixel_fn`).

mod accel;
mod caustics;
mod decision;
mod direct;
mod estimators;
mod film;
mod ledger;
mod light_tracer;
mod lights;
mod lines;
mod material;
mod memo;
pub mod metrics;
mod onward;
pub mod optics;
mod options;
mod passes;
mod path;
mod pixel;
pub mod plan;
mod render;
mod run;
pub mod sampling;
pub mod scene;
pub mod spectrum;
mod stats;
mod tile;

pub use caustics::{FULL_RATE_SHARE, LEAST_RATE, PHOTONS_PER_SAMPLE, photon_rate};
pub use options::{
    DEFAULT_SPECULAR, Image, Integrator, LightChoice, MANY_LIGHTS, MAX_CULLED_WALLS, MemoOptions,
    RenderOptions, Rendered, TILE, TILE_SHADOW_TESTS, Window, checked_image_size, image_size,
};
/// The fast paths, to measure what each buys
/// ([`RenderOptions::with_fast_paths`]); every one computes the model's
/// bits.
#[doc(hidden)]
pub use options::{FastPath, FastPaths};
pub use passes::{ADAPT_FROM, ADAPT_SHARE, FIRST_PASS, next_pass_end};
pub use plan::Plan;
pub use render::{Progressive, render};
pub use run::ROULETTE_FROM;
pub use scene::{
    Canvas, Falloff, Floor, GlassBody, InvalidScene, Light, LightShape, Material, Parts, Scene,
    Wall,
};
pub use spectrum::Rgb;
pub use stats::{Noise, Physics, Stats, Work};
pub use tile::pixel_sample;
