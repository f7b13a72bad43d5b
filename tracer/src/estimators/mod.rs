//! The closed forms: estimators of whole classes of light paths that
//! compute their light rather than sample it. Each module says which
//! classes it counts; `ledger.rs` says which estimator counts each class,
//! and the plan decides (`Plan::ledger`) where each runs.
//!
//! - `exact.rs`: a line or circle light seen directly from a receiver
//!   point, and through one flat mirror (`Ledger::mirror_lights`);
//! - `refracted.rs`: a line or circle light seen from inside a smooth
//!   glass body through one of its edges (`Ledger::glass_lights`);
//! - `square.rs`: a point, spot or sun averaged over a pixel's square of
//!   the floor.
//!
//! What the lights themselves answer (a sample of their light at a point,
//! their power, a photon) is `lights/`; these modules ask it and never
//! sample a light themselves.

pub(crate) mod choice;
mod contribution;
pub(crate) mod exact;
pub(crate) mod refracted;
pub(crate) mod square;

pub(crate) use contribution::{
    Receiver, Visibility, light_contribution, transmittance, weighed_contribution,
};
pub(crate) use exact::{MAX_MIRROR_PAIRS, is_exact, through_mirrors, through_mirrors_of};
pub(crate) use refracted::{MAX_GLASS_PAIRS, glass_pairs, through_glass, through_glass_of};

use flatray_geometry::DVec2;

use crate::ledger::Ledger;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// A receiver's `sampled` direct light with the closed forms the ledger
/// gives it added: line and circle lights seen in one flat mirror
/// (`Ledger::mirror_lights`), then through one edge of the glass body `x`
/// is in (`Ledger::glass_lights`); of every light, or with `light`, of
/// that light alone. The one sum of a receiver's direct light: path
/// vertices, the floor without its memo and the wall memo's bins all
/// take it. (The floor memo's points take the same closed forms, the
/// glass's shared across a half of the points: `pixel.rs`.)
#[inline(always)]
pub(crate) fn with_closed_forms(
    sampled: Rgb,
    ledger: &Ledger,
    scene: &Scene,
    (x, receiver): (DVec2, Receiver),
    light: Option<usize>,
    stats: &mut Stats,
) -> Rgb {
    let mirrors = &scene.flat_mirrors;
    let value = match (ledger.mirror_lights, light) {
        (false, _) => sampled,
        (true, None) => sampled + through_mirrors(scene, mirrors, x, receiver, stats),
        (true, Some(light)) => {
            sampled + through_mirrors_of(scene, mirrors, light, x, receiver, stats)
        }
    };
    match (ledger.glass_lights, light) {
        (false, _) => value,
        (true, None) => value + through_glass(scene, x, receiver, stats),
        (true, Some(light)) => value + through_glass_of(scene, light, x, receiver, stats),
    }
}
