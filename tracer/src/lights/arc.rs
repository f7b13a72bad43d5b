//! An arc light: a curved wall that emits from both sides as a
//! Lambertian emitter of radiance `I`, sampled uniformly along its length.
//!
//! Seen from a receiver an arc can fold over itself (from outside a
//! round column, its far side lies behind its near side), so it is
//! sampled by length, not by the angle it subtends: a point of it, with
//! the density per radian `r / (L |cos|)` of the direction towards it
//! (`r` the distance, `cos` the angle to the arc's normal there, `L` its
//! length). The arc's own wall is in the way of the points it hides: the
//! shadow ray ends on it and meets it before only where it curves across
//! (`docs/robustness.md`, rule 9).

use flatray_geometry::{Arc, DVec2, Side, Skip};

use super::PhotonKernel;
use super::{Incident, Photon};
use crate::sampling::{Stream, cosine_half_circle};
use crate::scene::Light;

/// A point drawn uniformly along the arc, seen from `x`: `None` where the
/// direction to it grazes the arc there, or `x` is the point.
#[inline]
pub(super) fn incident(arc: &Arc, light: &Light, x: DVec2, u: f64, r0: f64) -> Option<Incident> {
    let point = arc.point_at(u);
    let to = point - x;
    let distance = to.length();
    let pdf = pdf_at(arc, x, point);
    if pdf == 0.0 {
        return None;
    }
    Some(Incident {
        to,
        t_max: 1.0,
        length: distance,
        value: light.falloff.per_radian(distance, r0),
        pdf,
    })
}

/// The density per radian, from `x`, of the direction towards `point` of
/// the arc: `r / (L |cos|)`; 0 where it grazes or `x` is the point.
#[inline]
pub(super) fn pdf_at(arc: &Arc, x: DVec2, point: DVec2) -> f64 {
    let to = point - x;
    let distance = to.length();
    let cosine = arc.normal_at(point).dot(to).abs() / distance;
    let length = arc.length();
    let pdf = distance / (length * cosine);
    if pdf.is_finite() && pdf > 0.0 {
        pdf
    } else {
        0.0
    }
}

/// A Lambertian emitter of radiance `I` on both sides: `2 I` per unit
/// length and side.
pub(super) fn power(arc: &Arc) -> f64 {
    4.0 * arc.length()
}

/// A photon from a uniform point of the arc, on a side drawn evenly, in a
/// cosine-weighted direction about the normal there.
pub(super) fn emit(arc: &Arc, wall: Option<u32>, light: &Light, stream: &mut Stream) -> Photon {
    let origin = arc.point_at(stream.uniform());
    let side = if stream.uniform() < 0.5 {
        Side::Positive
    } else {
        Side::Negative
    };
    Photon {
        origin,
        dir: cosine_half_circle(arc.normal_on(side, origin), stream.uniform()),
        scale: 1.0,
        kernel: PhotonKernel::Line(light.falloff),
        // Leaving the arc: its root at the origin is dropped, and the
        // photon meets it again where it curves across.
        skip: wall.map_or(Skip::NONE, Skip::one),
        unseen: false,
        wavelength: None,
    }
}

/// The box corners of the arc: their hull holds every point of it.
pub(super) fn hull(arc: &Arc) -> [DVec2; 4] {
    let (lo, hi) = arc.bounds();
    [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rgb;
    use crate::scene::{Falloff, LightShape};

    /// Under `Flatland` every point inside a full circle that emits `I`
    /// sees it all around: the mean of `I value cos / pdf` over the
    /// light's samples is `2 pi I`, at the centre and off it, to 0.5 %
    /// over 20,000 stratified samples.
    #[test]
    fn a_circle_of_light_gives_two_pi_inside() {
        let arc = Arc::circle(DVec2::new(3.0, -2.0), 5.0, 0.4);
        let light = Light {
            profile: None,
            shape: LightShape::Arc { arc, wall: None },
            color: Rgb::ONE,
            intensity: 1.0,
            falloff: Falloff::Flatland,
            spectrum: None,
        };
        for x in [
            DVec2::new(3.0, -2.0),
            DVec2::new(6.5, -1.0),
            DVec2::new(0.0, -5.5),
        ] {
            let n = 20_000;
            let mut sum = 0.0;
            for k in 0..n {
                let u = (k as f64 + 0.5) / n as f64;
                if let Some(s) = incident(&arc, &light, x, u, 1e-6) {
                    sum += s.value / s.pdf;
                }
            }
            let mean = sum / n as f64;
            assert!(
                (mean / std::f64::consts::TAU - 1.0).abs() < 5e-3,
                "{x}: {mean}"
            );
        }
    }
}
