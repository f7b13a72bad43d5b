//! A circle light: a disk whose rim emits outward as a Lambertian emitter
//! of radiance `I`. It is not a wall: it blocks no light, and a point
//! inside it receives nothing from it. Sampled uniformly in the angle it
//! subtends, so an unoccluded disk gives the floor `I` times that angle
//! (`docs/model.md`, closed form 7).

use std::f64::consts::TAU;

use flatray_geometry::{DVec2, Ray, Skip};

use super::PhotonKernel;
use super::{Incident, Photon};
use crate::sampling::{Stream, cosine_half_circle};
use crate::scene::Light;

/// A direction uniform in the angle `2 asin(R / d)` the disk subtends at
/// `x`, to the near point of the rim along it: pdf one over that angle,
/// carrying `G(r') r'` per radian (`Falloff::per_radian`), as a line light.
#[inline]
pub(super) fn incident(
    at: DVec2,
    radius: f64,
    light: &Light,
    x: DVec2,
    u: f64,
    r0: f64,
) -> Option<Incident> {
    let to_centre = at - x;
    let d = to_centre.length();
    if d <= radius {
        // On or inside the rim: the rim emits outward only.
        return None;
    }
    let half = (radius / d).asin();
    let theta = half * (2.0 * u - 1.0);
    let (s, c) = theta.sin_cos();
    let towards = to_centre / d;
    let dir = towards * c + towards.perp() * s;
    // The near crossing of the rim along `dir`: `d cos - sqrt(R^2 - d^2 sin^2)`.
    let off = d * s;
    let t = d * c - (radius * radius - off * off).max(0.0).sqrt();
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    Some(Incident {
        to: dir * t,
        t_max: 1.0,
        length: t,
        value: light.falloff.per_radian(t, r0),
        pdf: 1.0 / (2.0 * half),
    })
}

/// The density per radian of [`incident`]'s directions from `x`: one
/// over the angle the disk subtends, 0 on or inside the rim.
pub(super) fn pdf(at: DVec2, radius: f64, x: DVec2) -> f64 {
    let d = (at - x).length();
    if d <= radius {
        return 0.0;
    }
    1.0 / (2.0 * (radius / d).asin())
}

/// `2 I` per unit length of the rim, outward: `4 pi R I`.
pub(super) fn power(radius: f64) -> f64 {
    2.0 * TAU * radius
}

/// A photon from a uniform point of the rim, cosine-weighted about the
/// outward normal there.
pub(super) fn emit(at: DVec2, radius: f64, light: &Light, stream: &mut Stream) -> Photon {
    let (s, c) = (TAU * stream.uniform()).sin_cos();
    let normal = DVec2::new(c, s);
    Photon {
        origin: at + normal * radius,
        dir: cosine_half_circle(normal, stream.uniform()),
        scale: 1.0,
        kernel: PhotonKernel::Line(light.falloff),
        skip: Skip::NONE,
        unseen: false,
        wavelength: None,
    }
}

/// Where `ray`, starting outside the disk, enters it before `t_max`: the
/// rim there emits towards the ray. A ray from inside sees only the rim's
/// back, which emits nothing inward.
#[inline]
pub(crate) fn met_by(at: DVec2, radius: f64, ray: &Ray, t_max: f64) -> Option<f64> {
    let o = ray.origin - at;
    let a = ray.dir.length_squared();
    let b = o.dot(ray.dir);
    let c = o.length_squared() - radius * radius;
    if c <= 0.0 || b >= 0.0 {
        return None;
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    (t > 0.0 && t < t_max).then_some(t)
}

/// The corners of the square around the disk.
pub(super) fn hull(at: DVec2, radius: f64) -> [DVec2; 4] {
    let (x, y) = (DVec2::new(radius, 0.0), DVec2::new(0.0, radius));
    [at - x - y, at + x - y, at + x + y, at - x + y]
}
