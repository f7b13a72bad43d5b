//! A line light: a segment emitting from both sides (or its `Positive`
//! side only, when one-sided) as a Lambertian emitter of radiance `I`,
//! sampled uniformly in the angle it subtends at the receiver.

use flatray_geometry::{DVec2, Ray, Segment, Side, Skip, intersect};

use super::PhotonKernel;
use super::{Incident, Photon};
use crate::sampling::{Stream, cosine_half_circle, sample_subtended_angle, subtended_angle};
use crate::scene::{EMITTING_SIDE, Light, lies_on_line};

/// A direction uniform in the angle the segment subtends at `x`: pdf one
/// over that angle, carrying `G(r') r'` per radian (`Falloff::per_radian`).
#[inline]
pub(super) fn incident(
    segment: &Segment,
    one_sided: bool,
    light: &Light,
    x: DVec2,
    u: f64,
    r0: f64,
) -> Option<Incident> {
    if !lights(segment, one_sided, x) {
        return None;
    }
    let s = sample_subtended_angle(x, segment, u)?;
    Some(incident_of(
        light,
        x,
        (s.point, s.distance, s.subtended),
        r0,
    ))
}

/// Whether the segment sends light to `x`: both sides, or the emitting
/// one.
#[inline(always)]
pub(crate) fn lights(segment: &Segment, one_sided: bool, x: DVec2) -> bool {
    !one_sided || segment.side_of(x) == Some(EMITTING_SIDE)
}

/// [`incident`] for the angle sample at `point`, `distance` from `x`, of
/// a segment that subtends `subtended` there: also what the floor memo's
/// lanes of angle samples take (`accel::strata`).
#[inline(always)]
pub(crate) fn incident_of(
    light: &Light,
    x: DVec2,
    (point, distance, subtended): (DVec2, f64, f64),
    r0: f64,
) -> Incident {
    let to = point - x;
    Incident {
        to,
        t_max: 1.0,
        length: distance,
        value: light.falloff.per_radian(distance, r0) * light.profile_at(to),
        pdf: 1.0 / subtended,
    }
}

/// The density per radian of [`incident`]'s directions from `x`: one
/// over the angle the segment subtends, 0 where it draws none.
pub(super) fn pdf(segment: &Segment, one_sided: bool, x: DVec2) -> f64 {
    if one_sided && segment.side_of(x) != Some(EMITTING_SIDE) {
        return 0.0;
    }
    let angle = subtended_angle(x, segment);
    if angle > 0.0 { 1.0 / angle } else { 0.0 }
}

/// A wall never receives its own light, nor a line light along its own
/// line: all of it arrives at grazing incidence, cosine zero. Computed, the
/// receiver point is rounded off the line and the light would subtend
/// about pi at a cosine that is not zero.
pub(super) fn grazes(segment: &Segment, own: Option<u32>, index: u32, wall: &Segment) -> bool {
    own == Some(index) || (lies_on_line(segment.a, wall) && lies_on_line(segment.b, wall))
}

/// A Lambertian emitter of radiance `I`: `2 I` per unit length and side.
pub(super) fn power(segment: &Segment, one_sided: bool) -> f64 {
    let sides = if one_sided { 1.0 } else { 2.0 };
    2.0 * segment.length() * sides
}

/// A photon from a uniform point of the segment, on a side drawn evenly
/// (or the emitting one), in a cosine-weighted direction.
pub(super) fn emit(
    segment: &Segment,
    one_sided: bool,
    wall: Option<u32>,
    light: &Light,
    stream: &mut Stream,
) -> Photon {
    let origin = segment.point_at(stream.uniform());
    let side = if one_sided || stream.uniform() < 0.5 {
        Side::Positive
    } else {
        Side::Negative
    };
    let dir = cosine_half_circle(segment.normal_on(side), stream.uniform());
    Photon {
        origin,
        dir,
        // A receiver in its path sees the light arrive from `-dir`.
        scale: light.profile_at(-dir),
        kernel: PhotonKernel::Line(light.falloff),
        skip: wall.map_or(Skip::NONE, Skip::one),
        unseen: false,
        wavelength: None,
    }
}

/// Where `ray` meets the segment before `t_max`, from a side it emits
/// towards.
#[inline]
pub(super) fn met_by(segment: &Segment, one_sided: bool, ray: &Ray, t_max: f64) -> Option<f64> {
    let h = intersect(ray, segment)?;
    let side = segment.arrival_side(ray.dir)?;
    (h.t < t_max && (!one_sided || side == EMITTING_SIDE)).then_some(h.t)
}

/// What a path ray that meets line light `light` from `side`, at total
/// distance `r`, carries back: `I G(r') r'` per radian (the radiance `I`
/// for `Flatland`), nothing from the dark side of a one-sided light. A
/// wall's light has no profile (`Light::profile`).
pub(crate) fn emitted(light: &Light, one_sided: bool, side: Side, r: f64, r0: f64) -> f64 {
    if one_sided && side != EMITTING_SIDE {
        return 0.0;
    }
    light.intensity * light.falloff.per_radian(r, r0)
}
