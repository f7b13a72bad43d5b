//! Sunlight: parallel rays travelling in one direction from outside the
//! scene; the intensity is the irradiance across the beam, with no
//! falloff.

use flatray_geometry::{DVec2, Segment, Skip};

use super::PhotonKernel;
use super::{Incident, Photon};
use crate::sampling::Stream;
use crate::scene::Scene;

/// Towards the sun, unbounded: the whole intensity.
#[inline(always)]
pub(super) fn incident(direction: DVec2) -> Incident {
    Incident {
        to: -direction,
        t_max: f64::INFINITY,
        length: 1.0,
        value: 1.0,
        pdf: 1.0,
    }
}

/// Sunlight along the receiving wall reaches it only at grazing incidence
/// (to within the rounding of their cross product).
pub(super) fn grazes(direction: DVec2, wall: &Segment) -> bool {
    let e = wall.edge();
    e.perp_dot(direction).abs() <= 16.0 * f64::EPSILON * e.length()
}

/// Where sunlight enters: a line across the beam, upstream of everything,
/// and its width.
pub(crate) fn sun_line(scene: &Scene, direction: DVec2) -> (DVec2, DVec2, f64) {
    let mut min = scene.canvas.origin;
    let mut max =
        scene.canvas.origin + DVec2::new(scene.canvas.width as f64, scene.canvas.height as f64);
    for wall in &scene.walls {
        let (lo, hi) = wall.shape.bounds();
        min = min.min(lo);
        max = max.max(hi);
    }
    let centre = (min + max) * 0.5;
    let radius = (max - min).length() * 0.5 + 1.0;
    let across = direction.perp();
    let start = centre - direction * radius - across * radius;
    (start, across, 2.0 * radius)
}

/// The irradiance times the width of the beam that covers the scene.
pub(super) fn power(scene: &Scene, direction: DVec2) -> f64 {
    sun_line(scene, direction).2
}

/// A photon entering uniformly across the beam.
pub(super) fn emit(scene: &Scene, direction: DVec2, stream: &mut Stream) -> Photon {
    let (start, across, width) = sun_line(scene, direction);
    Photon {
        origin: start + across * (width * stream.uniform()),
        dir: direction,
        scale: 1.0,
        kernel: PhotonKernel::None,
        skip: Skip::NONE,
        unseen: false,
        wavelength: None,
    }
}
