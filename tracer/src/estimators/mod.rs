//! The closed forms: estimators of whole classes of light paths that
//! compute their light rather than sample it. Each module says which
//! classes it counts; `ledger.rs` says which estimator counts each class,
//! and the plan decides (`Plan::ledger`) where each runs.
//!
//! - `exact.rs`: a line or circle light seen directly from a receiver
//!   point, and through one flat mirror (`ClosedForms::mirror_lights`);
//! - `refracted.rs`: a line or circle light seen from inside a smooth
//!   glass body through one of its edges (`ClosedForms::glass_lights`);
//! - `square.rs`: a point, spot or sun averaged over a pixel's square of
//!   the floor;
//! - `mirrored.rs`: a point, spot, sun or beam seen from a receiver point
//!   through one flat mirror (`ClosedForms::aimed_mirrors`).
//!
//! Each closed form through a mirror or glass has an entry in
//! [`ClosedForms`]: its decision, made by its own module's `decide`, which
//! the ledger reads and the plan's wording lists, and its term in
//! [`at_point`] or [`with_closed_forms`].
//!
//! What the lights themselves answer (a sample of their light at a point,
//! their power, a photon) is `lights/`; these modules ask it and never
//! sample a light themselves.

pub(crate) mod choice;
mod contribution;
pub(crate) mod exact;
pub(crate) mod mirrored;
pub(crate) mod refracted;
pub(crate) mod square;

pub(crate) use contribution::{
    Receiver, Visibility, light_contribution, transmittance, weighed_contribution,
};
pub(crate) use exact::{is_exact, through_mirrors, through_mirrors_of};
pub(crate) use refracted::{through_glass, through_glass_of};

use flatray_geometry::DVec2;

use crate::decision::Decision;
use crate::ledger::Ledger;
use crate::options::RenderOptions;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// The closed forms through mirrors and glass, each with its decision of
/// where it runs and the reason for it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ClosedForms {
    /// Line and circle lights seen in one flat mirror, taken at every
    /// receiver and left out of path rays that meet them right after
    /// that mirror (`exact::through_mirrors`).
    pub mirror_lights: Decision,
    /// Line and circle lights seen through one edge of the glass body a
    /// receiver is in, left out of path rays that meet them right after
    /// that one refraction (`refracted::through_glass`).
    pub glass_lights: Decision,
    /// Points, spots, suns and beams seen in one flat mirror
    /// (`mirrored.rs`).
    pub aimed_mirrors: Decision,
}

impl ClosedForms {
    /// Each closed form's decision for `scene` rendered with `options`,
    /// where the plan casts shadow rays if `shadows`.
    pub(crate) fn of(scene: &Scene, options: &RenderOptions, shadows: bool) -> ClosedForms {
        ClosedForms {
            mirror_lights: exact::decide(scene, options, shadows),
            glass_lights: refracted::decide(scene, options, shadows),
            aimed_mirrors: mirrored::decide(scene, options, shadows),
        }
    }

    /// Whether the closed forms count every path of points, spots, suns
    /// and beams through mirrors and glass in `scene`: there, the caustic
    /// pass has none of their light left to carry (rough mirrors and
    /// lasers aside, which the plan asks about).
    pub(crate) fn take_aimed_runs(&self, scene: &Scene) -> bool {
        self.aimed_mirrors.runs && mirrored::takes_every_run(scene)
    }

    /// Each closed form's name, as the plan lists it, and its decision.
    pub(crate) fn named(&self) -> [(&'static str, &Decision); 3] {
        [
            (
                "lines and circles in a mirror, closed form",
                &self.mirror_lights,
            ),
            (
                "lines and circles through one glass edge, closed form",
                &self.glass_lights,
            ),
            (
                "points, spots and suns in a mirror, closed form",
                &self.aimed_mirrors,
            ),
        ]
    }
}

/// What a closed form through mirrors or glass says of itself, for
/// [`decide`]: its pairs of a specular wall and a light, its budget of
/// them, and its words.
struct Terms {
    pairs: usize,
    most: usize,
    /// One pair, as in "flat mirror and light pair".
    pair: &'static str,
    /// Why there are none: "no flat mirror and ... in the scene".
    none: &'static str,
    /// What `specular = 0` stops: "reflected" or "refracted".
    event: &'static str,
    /// Who takes the light where the closed form does not.
    otherwise: &'static str,
    /// What the closed form does where it runs.
    runs: &'static str,
}

/// Where a closed form through mirrors or glass runs, and why: with its
/// pairs within budget, light reflected or refracted, shadow rays cast,
/// and no reason of its own against it (`held`, checked before shadows).
/// Light tracing takes none of them.
fn decide(options: &RenderOptions, shadows: bool, terms: Terms, held: Option<&str>) -> Decision {
    let counted = |n: usize| match n {
        1 => format!("1 {}", terms.pair),
        n => format!("{n} {}s", terms.pair),
    };
    if options.integrator == crate::options::Integrator::Light {
        Decision::skipped("light tracing does not take it")
    } else if terms.pairs == 0 {
        Decision::skipped(terms.none)
    } else if options.specular == 0 {
        Decision::skipped(format!("specular = 0: no light is {}", terms.event))
    } else if terms.pairs > terms.most {
        Decision::skipped(format!(
            "{}, over {}: {}",
            counted(terms.pairs),
            terms.most,
            terms.otherwise
        ))
    } else if let Some(held) = held {
        Decision::skipped(held)
    } else if !shadows {
        Decision::skipped("no shadow rays are cast")
    } else {
        Decision::runs(format!("{}: {}", counted(terms.pairs), terms.runs))
    }
}

/// Whether any wall of `scene` is an arc: the closed forms through a
/// mirror or a glass edge take the walls around it as segments.
fn has_arcs(scene: &Scene) -> bool {
    scene.walls.iter().any(|w| w.shape.as_arc().is_some())
}

/// The closed forms that a receiver point `x` takes at that point alone,
/// as the `ledger` gives them, of every light or with `light` of that
/// light alone: line and circle lights in one flat mirror
/// (`Ledger::mirror_lights`), points, spots, suns and beams in one
/// (`Ledger::aimed_mirrors`). `None` where the ledger gives none.
#[inline(always)]
pub(crate) fn at_point(
    ledger: &Ledger,
    scene: &Scene,
    (x, receiver): (DVec2, Receiver),
    light: Option<usize>,
    stats: &mut Stats,
) -> Option<Rgb> {
    let mirrors = &scene.flat_mirrors;
    let lines = match (ledger.mirror_lights, light) {
        (false, _) => None,
        (true, None) => Some(through_mirrors(scene, mirrors, x, receiver, stats)),
        (true, Some(light)) => Some(through_mirrors_of(
            scene, mirrors, light, x, receiver, stats,
        )),
    };
    if !ledger.aimed_mirrors {
        return lines;
    }
    let aimed = mirrored::aimed_in_mirrors(scene, light, x, receiver, stats);
    Some(lines.map_or(aimed, |lines| lines + aimed))
}

/// A receiver's `sampled` direct light with the closed forms the ledger
/// gives it added: those it takes at its point ([`at_point`]), then line
/// and circle lights through one edge of the glass body `x` is in
/// (`Ledger::glass_lights`); of every light, or with `light`, of that
/// light alone. The one sum of a receiver's direct light: path
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
    let value = match at_point(ledger, scene, (x, receiver), light, stats) {
        None => sampled,
        Some(at_point) => sampled + at_point,
    };
    match (ledger.glass_lights, light) {
        (false, _) => value,
        (true, None) => value + through_glass(scene, x, receiver, stats),
        (true, Some(light)) => value + through_glass_of(scene, light, x, receiver, stats),
    }
}
