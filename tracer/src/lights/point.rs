//! An isotropic point light: intensity `I`, falloff `G(r)`; the floor at
//! distance `r` receives `I G(r)` (`docs/model.md`, direct light).

use std::f64::consts::TAU;

use flatray_geometry::{DVec2, Segment, Skip};

use super::PhotonKernel;
use super::{Incident, Photon};
use crate::sampling::{Stream, uniform_circle};
use crate::scene::{Falloff, Light, lies_on_line};

/// The light at `at` seen from `x`: one direction, `G(r)` per unit
/// intensity (the kernel clamped at `r0`).
#[inline(always)]
pub(crate) fn incident(at: DVec2, light: &Light, x: DVec2, r0: f64) -> Incident {
    let to = at - x;
    let length = to.length();
    Incident {
        to,
        t_max: 1.0,
        length,
        value: light.falloff.g(length, r0),
        pdf: 1.0,
    }
}

/// A point (or spot) light on the receiving wall's line reaches it only at
/// grazing incidence, cosine zero. Computed, its shadow ray would run
/// along the wall through the corner, where rounding decides whether it
/// crosses the next wall.
/// What a point light at `at` could bring the box `[lo, hi]` per unit
/// intensity, without shadows: its falloff at the box's nearest point
/// (`LightShape::reach`).
#[inline(always)]
pub(crate) fn reach(at: DVec2, falloff: Falloff, (lo, hi): (DVec2, DVec2), r0: f64) -> f64 {
    falloff.g((at.clamp(lo, hi) - at).length(), r0)
}

pub(super) fn grazes(at: DVec2, wall: &Segment) -> bool {
    lies_on_line(at, wall)
}

/// `2 pi I`: the same intensity in every direction.
pub(super) fn power() -> f64 {
    TAU
}

/// A photon in a uniform direction; the photon density already falls as
/// `1 / r` in the plane, so its first flight carries the kernel's rest.
pub(super) fn emit(at: DVec2, light: &Light, stream: &mut Stream) -> Photon {
    Photon {
        origin: at,
        dir: uniform_circle(stream),
        scale: 1.0,
        kernel: PhotonKernel::Point(light.falloff),
        skip: Skip::NONE,
        unseen: false,
        wavelength: None,
    }
}
