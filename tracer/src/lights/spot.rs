//! A spot: a point light whose intensity is multiplied by a smooth window
//! around its direction (`Light::spot_window`).

use flatray_geometry::{DVec2, Skip};

use super::PhotonKernel;
use super::{Incident, Photon};
use crate::sampling::Stream;
use crate::scene::{Light, smooth_window};

/// As a point light, times the window at the direction from the light to
/// `x`.
#[inline(always)]
pub(super) fn incident(at: DVec2, light: &Light, x: DVec2, r0: f64) -> Incident {
    let mut incident = super::point::incident(at, light, x, r0);
    if !incident.at_the_light() {
        incident.value *= light.spot_window(-incident.dir());
    }
    incident
}

/// The integral of a spot's window over all directions.
pub(crate) fn spot_integral(cone: f64, softness: f64) -> f64 {
    // Full intensity over 2 (cone - softness), and the smoothstep averages
    // one half over each soft edge of width `softness`.
    2.0 * (cone - softness) + softness
}

/// The window's integral: the intensity over the directions it lights.
pub(super) fn power(cone: f64, softness: f64) -> f64 {
    spot_integral(cone, softness)
}

/// A photon uniform in the cone's angle, weighted by the window so that
/// the mean weight is one.
pub(super) fn emit(
    at: DVec2,
    direction: DVec2,
    cone: f64,
    softness: f64,
    light: &Light,
    stream: &mut Stream,
) -> Photon {
    let theta = cone * (2.0 * stream.uniform() - 1.0);
    let (s, c) = theta.sin_cos();
    Photon {
        origin: at,
        dir: direction * c + direction.perp() * s,
        scale: smooth_window(theta.abs(), cone, softness) * 2.0 * cone
            / spot_integral(cone, softness),
        kernel: PhotonKernel::Point(light.falloff),
        skip: Skip::NONE,
        unseen: false,
        wavelength: None,
    }
}
