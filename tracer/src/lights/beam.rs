//! Beams and lasers: parallel light that leaves a segment (a beam: a
//! window's sunlight at noon, a stage light), or a single ray (a laser,
//! a beam of no width). Neither falls off with distance.
//!
//! A beam of intensity `E` sends rays travelling in `direction` from every
//! point of its segment: a receiver downstream of the segment, inside the
//! strip the rays sweep, gets the irradiance `E` across the beam (times
//! its cosine), and nothing outside the strip. Its power is `E` times the
//! strip's width, `|edge x direction|`. Its shadow ray runs from the
//! receiver against the direction, up to the segment: found by
//! next-event estimation, as the sun is.
//!
//! A laser of intensity `P` is one ray of power `P`: a delta in position
//! and direction, which no shadow ray and no path from a receiver finds.
//! Light tracing follows its photons, and so does the caustic pass, which
//! for a laser counts every flight, the first among them, and bins its
//! light at the first diffuse wall it meets (`caustics.rs`).

use flatray_geometry::{DVec2, Segment, Skip};

use super::{Aperture, Incident, Photon, PhotonKernel};
use crate::sampling::Stream;

/// Where the ray from `x` against `direction` meets the line of
/// `segment`: the distance back along it (`t`, in units of `direction`,
/// positive when `x` is downstream) and the point's fraction of the
/// segment (`u`). `None` for a segment along the direction.
#[inline(always)]
fn upstream(segment: &Segment, direction: DVec2, x: DVec2) -> Option<(f64, f64)> {
    let e = segment.edge();
    let denom = direction.perp_dot(e);
    if denom == 0.0 {
        return None;
    }
    let from_a = x - segment.a;
    // x = a + e u + direction t.
    let t = from_a.perp_dot(e) / denom;
    let u = direction.perp_dot(from_a) / denom;
    Some((t, u))
}

/// The beam seen from `x`: its one direction, up to the segment, with the
/// whole irradiance; `None` outside the strip or upstream of the segment.
#[inline(always)]
pub(super) fn incident(segment: &Segment, direction: DVec2, x: DVec2) -> Option<Incident> {
    let (t, u) = upstream(segment, direction, x)?;
    (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(Incident {
        to: -direction,
        t_max: t,
        length: 1.0,
        value: 1.0,
        pdf: 1.0,
    })
}

/// The irradiance times the strip's width.
pub(super) fn power(segment: &Segment, direction: DVec2) -> f64 {
    segment.edge().perp_dot(direction).abs()
}

/// A photon leaving a uniform point of the segment: uniform across the
/// strip.
pub(super) fn emit(segment: &Segment, direction: DVec2, stream: &mut Stream) -> Photon {
    Photon {
        origin: segment.point_at(stream.uniform()),
        dir: direction,
        scale: 1.0,
        kernel: PhotonKernel::None,
        skip: Skip::NONE,
        unseen: false,
        wavelength: None,
    }
}

/// 1 where the box `[lo, hi]` can lie in the strip downstream, 0 where
/// every corner lies on one side of it (the box, convex, then does too).
pub(super) fn reach(segment: &Segment, direction: DVec2, (lo, hi): (DVec2, DVec2)) -> f64 {
    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    let Some(found) = corners
        .iter()
        .map(|&p| upstream(segment, direction, p))
        .collect::<Option<Vec<_>>>()
    else {
        return 0.0;
    };
    let all = |f: &dyn Fn(f64, f64) -> bool| found.iter().all(|&(t, u)| f(t, u));
    if all(&|t, _| t <= 0.0) || all(&|_, u| u < 0.0) || all(&|_, u| u > 1.0) {
        0.0
    } else {
        1.0
    }
}

/// The beam's rays that can reach `target`: the part of the segment whose
/// rays pass between the target's ends; `None` where none does.
pub(super) fn aperture(segment: &Segment, direction: DVec2, target: &Segment) -> Option<Aperture> {
    let (_, ua) = upstream(segment, direction, target.a)?;
    let (_, ub) = upstream(segment, direction, target.b)?;
    let (u0, u1) = (ua.min(ub).max(0.0), ua.max(ub).min(1.0));
    (u1 > u0).then_some(Aperture::Strip {
        start: segment.a,
        edge: segment.edge(),
        direction,
        u0,
        u1,
    })
}

/// The laser's one photon: from `at` along `direction`, never found by a
/// path from a receiver.
pub(super) fn emit_laser(at: DVec2, direction: DVec2) -> Photon {
    Photon {
        origin: at,
        dir: direction,
        scale: 1.0,
        kernel: PhotonKernel::None,
        skip: Skip::NONE,
        unseen: true,
        wavelength: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A beam from a slanted segment lights exactly its strip downstream,
    /// and its power is the strip's width.
    #[test]
    fn a_beam_lights_its_strip_downstream() {
        let segment = Segment::new(DVec2::new(0.0, 0.0), DVec2::new(4.0, 2.0));
        let direction = DVec2::new(0.0, 1.0);
        assert_eq!(power(&segment, direction), 4.0);
        // Downstream, within the strip x in [0, 4]: up to the segment.
        let s = incident(&segment, direction, DVec2::new(1.0, 5.0)).expect("in the strip");
        assert!((s.t_max - 4.5).abs() < 1e-12 && s.to == -direction);
        // Outside the strip, and upstream.
        assert!(incident(&segment, direction, DVec2::new(-0.1, 5.0)).is_none());
        assert!(incident(&segment, direction, DVec2::new(4.1, 5.0)).is_none());
        assert!(incident(&segment, direction, DVec2::new(1.0, 0.4)).is_none());
        // A box that straddles the strip's edge may be reached; one beside
        // it or upstream is not.
        let reached = |lo: (f64, f64), hi: (f64, f64)| {
            reach(&segment, direction, (DVec2::from(lo), DVec2::from(hi)))
        };
        assert_eq!(reached((3.0, 6.0), (5.0, 8.0)), 1.0);
        assert_eq!(reached((4.5, 6.0), (6.0, 8.0)), 0.0);
        assert_eq!(reached((0.0, -5.0), (4.0, -1.0)), 0.0);
    }
}
