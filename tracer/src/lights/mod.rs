//! The light interface: what every kind of light tells the integrators.
//!
//! Each kind of light lives in a module of its own (`point.rs`,
//! `spot.rs`, `line.rs`, `sun.rs`, `circle.rs`, `beam.rs` for beams and
//! lasers) with the same functions:
//!
//! - `incident`: a sample of the light arriving at a receiver point, as a
//!   shadow ray to test, the value it carries per radian (or, for a light
//!   of one direction, in total) and the probability density of the
//!   direction it came from;
//! - `grazes`: whether a wall can receive it only at grazing incidence
//!   (robustness rule 4b), so receives nothing;
//! - `power` and `emit`: its total power and a photon leaving it, for the
//!   light tracer;
//! - `met_by`: where a path ray meets light it emits, for lights that are
//!   not walls and can be seen (after a mirror);
//! - `hull`: points whose convex hull holds every point that shadow rays
//!   aim at, for culled shadow rays;
//! - `aperture`: for a light of one direction per point (a point, a spot,
//!   the sun), the photons it sends that reach a given wall, for the
//!   caustic pass (`caustics.rs`).
//!
//! The methods on [`LightShape`] below dispatch to them; each `match` is
//! exhaustive, so a new kind of light is a compiler error in this file
//! until every function is given, and nowhere else in the model.
//! Fast paths that treat a light specially ask where its light comes
//! from ([`Emitter`]: the coherence masks' `draws`, the strata loops'
//! point and line lanes), matching it exhaustively, and fall back to these
//! functions for every other.

pub(crate) mod aimed;
mod arc;
mod beam;
mod kernel;
pub(crate) use kernel::PhotonKernel;
pub(crate) mod circle;
pub(crate) mod line;
pub(crate) mod point;
mod spot;
mod sun;

use flatray_geometry::{DVec2, Ray, Segment, Shape, Side, Skip};

use crate::sampling::Stream;
use crate::scene::{Light, LightShape, Scene};
pub(crate) use sun::sun_line;

pub(crate) use point::incident as point_incident;

/// A sample of the light that reaches a receiver point from one light,
/// before occlusion, the receiver's cosine, the light's colour and its
/// intensity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Incident {
    /// The shadow ray's direction vector from the receiver: `t` runs over
    /// `0 < t < t_max`. Zero when the receiver sits on the light itself
    /// (no direction, nothing in between).
    pub to: DVec2,
    pub t_max: f64,
    /// `|to|` for a ray to a point (1 for a direction): `to / length` is
    /// the unit direction towards the light.
    pub length: f64,
    /// What arrives per unit intensity: per radian of direction for a
    /// light with an area (a line, a circle), in total for a point, a
    /// spot or the sun. The kernel and the spot window included.
    pub value: f64,
    /// The probability density of the sampled direction, per radian; 1
    /// for a light of one direction (a point, a spot, the sun), whose
    /// value is then already the whole.
    pub pdf: f64,
}

impl Incident {
    /// Whether the receiver sits on the light: no direction to it.
    #[inline]
    pub fn at_the_light(&self) -> bool {
        self.length == 0.0
    }

    /// The unit direction towards the light.
    #[inline]
    pub fn dir(&self) -> DVec2 {
        self.to / self.length
    }
}

/// What arrives from a light of `intensity`, given an [`Incident`]'s
/// value and pdf and the receiver's cosine: one expression, so that every
/// path through the code that estimates it gives the same bits.
#[inline(always)]
pub(crate) fn arriving(intensity: f64, value: f64, cosine: f64, pdf: f64) -> f64 {
    intensity * value * (cosine / pdf)
}

/// A photon leaving a light: where, which way, its power relative to the
/// light's mean photon, the kernel its first flight reproduces, and the
/// wall it leaves (if the light is solid).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Photon {
    pub origin: DVec2,
    pub dir: DVec2,
    pub scale: f64,
    pub kernel: PhotonKernel,
    pub skip: Skip,
    /// Whether no path from a receiver finds this photon's light (a
    /// laser's): the caustic pass then counts its every flight, not only
    /// those after a specular event.
    pub unseen: bool,
    /// The wavelength (micrometres) a photon of a lamp with a spectrum
    /// carries from the lamp, where glass disperses.
    pub wavelength: Option<f64>,
}

impl LightShape {
    /// How many numbers [`LightShape::incident`] takes from the stream.
    #[inline]
    pub(crate) fn numbers(&self) -> usize {
        match self {
            LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => 0,
            LightShape::Line { .. } | LightShape::Arc { .. } | LightShape::Circle { .. } => 1,
        }
    }

    /// A sample of light `light` (of this shape) arriving at `x`, with `u`
    /// in `[0, 1)` where the shape takes a number; `None` where none
    /// arrives (the dark side of a one-sided line, inside a circle).
    #[inline(always)]
    pub(crate) fn incident(&self, light: &Light, x: DVec2, u: f64, r0: f64) -> Option<Incident> {
        match *self {
            LightShape::Point { at } => Some(point::incident(at, light, x, r0)),
            LightShape::Spot { at, .. } => Some(spot::incident(at, light, x, r0)),
            LightShape::Line {
                segment, one_sided, ..
            } => line::incident(&segment, one_sided, light, x, u, r0),
            LightShape::Arc { arc, .. } => arc::incident(&arc, light, x, u, r0),
            LightShape::Directional { direction } => Some(sun::incident(direction)),
            LightShape::Circle { at, radius } => circle::incident(at, radius, light, x, u, r0),
            LightShape::Beam { segment, direction } => beam::incident(&segment, direction, x),
            // A delta in position and direction: no receiver's sample finds it.
            LightShape::Laser { .. } => None,
        }
    }

    /// The density per radian with which [`LightShape::incident`] draws
    /// the direction from `x` that meets the light at `at`: for a light
    /// with an area, what multiple importance sampling weighs a BSDF's
    /// sample that met it against. 0 for a light of one direction (no ray
    /// meets it), and where `incident` draws nothing.
    #[inline]
    pub(crate) fn pdf_towards(&self, x: DVec2, at: DVec2) -> f64 {
        match *self {
            LightShape::Line {
                segment, one_sided, ..
            } => line::pdf(&segment, one_sided, x),
            LightShape::Arc { arc, .. } => arc::pdf_at(&arc, x, at),
            LightShape::Circle { at, radius } => circle::pdf(at, radius, x),
            LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => 0.0,
        }
    }

    /// What a path ray meeting this light's wall (a solid line light)
    /// from `side`, at total distance `r`, carries back; nothing for a
    /// light that is no wall.
    #[inline]
    pub(crate) fn emitted_at_wall(&self, light: &Light, side: Side, r: f64, r0: f64) -> f64 {
        match *self {
            LightShape::Line { one_sided, .. } => line::emitted(light, one_sided, side, r, r0),
            LightShape::Arc { .. } => line::emitted(light, false, side, r, r0),
            LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Circle { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => 0.0,
        }
    }

    /// Whether wall `index` (of segment `wall`) can receive this light
    /// only at grazing incidence, so receives nothing from it.
    pub(crate) fn grazes(&self, index: u32, wall: &Shape) -> bool {
        // An arc curves away from every line: no light lies along it.
        let Shape::Segment(wall) = wall else {
            return false;
        };
        match *self {
            LightShape::Point { at } | LightShape::Spot { at, .. } => point::grazes(at, wall),
            LightShape::Line {
                segment, wall: own, ..
            } => line::grazes(&segment, own, index, wall),
            LightShape::Directional { direction } | LightShape::Beam { direction, .. } => {
                sun::grazes(direction, wall)
            }
            // A straight wall sees an arc's light at grazing incidence
            // only at one point of it.
            LightShape::Arc { .. } | LightShape::Circle { .. } | LightShape::Laser { .. } => false,
        }
    }

    /// The light's power per unit intensity (per unit time, integrated
    /// over the circle of directions), before colour.
    pub(crate) fn power(&self, scene: &Scene) -> f64 {
        match *self {
            LightShape::Directional { direction } => sun::power(scene, direction),
            _ => self.lamp_power().unwrap_or(0.0),
        }
    }

    /// A lamp's power per unit intensity in world units (per unit time,
    /// integrated over the circle of directions), before colour: what
    /// turns a luminous flux into an intensity. `None` for a sun, whose
    /// power is the scene's frame's.
    pub fn lamp_power(&self) -> Option<f64> {
        Some(match *self {
            LightShape::Directional { .. } => return None,
            LightShape::Point { .. } => point::power(),
            LightShape::Spot { cone, softness, .. } => spot::power(cone, softness),
            LightShape::Line {
                segment, one_sided, ..
            } => line::power(&segment, one_sided),
            LightShape::Arc { arc, .. } => arc::power(&arc),
            LightShape::Circle { radius, .. } => circle::power(radius),
            LightShape::Beam { segment, direction } => beam::power(&segment, direction),
            // Its intensity is its power.
            LightShape::Laser { .. } => 1.0,
        })
    }

    /// A photon leaving light `light` (of this shape), drawn from `stream`.
    pub(crate) fn emit(&self, light: &Light, scene: &Scene, stream: &mut Stream) -> Photon {
        match *self {
            LightShape::Point { at } => point::emit(at, light, stream),
            LightShape::Spot {
                at,
                direction,
                cone,
                softness,
            } => spot::emit(at, direction, cone, softness, light, stream),
            LightShape::Line {
                segment,
                one_sided,
                wall,
            } => line::emit(&segment, one_sided, wall, light, stream),
            LightShape::Arc { arc, wall } => arc::emit(&arc, wall, light, stream),
            LightShape::Directional { direction } => sun::emit(scene, direction, stream),
            LightShape::Circle { at, radius } => circle::emit(at, radius, light, stream),
            LightShape::Beam { segment, direction } => beam::emit(&segment, direction, stream),
            LightShape::Laser { at, direction } => beam::emit_laser(at, direction),
        }
    }

    /// Where `ray` first meets light this shape emits towards it, before
    /// `t_max`, for a light a path ray can see that is not a wall (a
    /// solid line light is found as its wall): the distance along the ray.
    #[inline]
    pub(crate) fn met_by(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        match *self {
            LightShape::Line {
                segment,
                one_sided,
                wall: None,
            } => line::met_by(&segment, one_sided, ray, t_max),
            LightShape::Circle { at, radius } => circle::met_by(at, radius, ray, t_max),
            LightShape::Line { wall: Some(_), .. }
            // An arc light is found as its wall.
            | LightShape::Arc { .. }
            | LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => None,
        }
    }

    /// Whether a path ray can meet the light (it has an area): what the
    /// plan's "lights seen in mirrors" needs.
    /// Whether a light with an area reaches into the half-plane in front
    /// of the line through `origin` with normal `normal` (unit), counting
    /// points within `tolerance` of the line: where a ray in that
    /// half-plane could meet it. False for the lights a ray never meets.
    pub(crate) fn reaches_in_front(&self, origin: DVec2, normal: DVec2, tolerance: f64) -> bool {
        match self {
            LightShape::Line { segment, .. } => {
                (segment.a - origin)
                    .dot(normal)
                    .max((segment.b - origin).dot(normal))
                    > -tolerance
            }
            LightShape::Circle { at, radius } => (*at - origin).dot(normal) + radius > -tolerance,
            LightShape::Arc { arc, .. } => {
                let (lo, hi) = arc.bounds();
                [lo, hi, DVec2::new(lo.x, hi.y), DVec2::new(hi.x, lo.y)]
                    .iter()
                    .any(|&p| (p - origin).dot(normal) > -tolerance)
            }
            LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => false,
        }
    }

    pub(crate) fn has_area(&self) -> bool {
        match self {
            LightShape::Line { .. } | LightShape::Arc { .. } | LightShape::Circle { .. } => true,
            LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => false,
        }
    }

    /// About the most that light `light` (of this shape) brings a floor
    /// point of the box `[lo, hi]`, without shadows or one side: its
    /// intensity times its falloff at the box's nearest point (for a light
    /// with an area, times the largest angle it can subtend there; for a
    /// spot, times its window when the box is a point). For choosing lights (`choice.rs`), never for an
    /// estimate: zero only where the light can bring nothing.
    pub(crate) fn importance(&self, light: &Light, bounds: (DVec2, DVec2), r0: f64) -> f64 {
        let v = light.intensity
            * self.reach(light, bounds, r0)
            * (light.color.x + light.color.y + light.color.z)
            / 3.0;
        if v.is_finite() { v.max(0.0) } else { 0.0 }
    }

    /// [`LightShape::importance`] per unit intensity, without the light's
    /// colour.
    #[inline]
    pub(crate) fn reach(&self, light: &Light, (lo, hi): (DVec2, DVec2), r0: f64) -> f64 {
        let distance = |p: DVec2| (p.clamp(lo, hi) - p).length();
        let falloff = light.falloff;
        let value = match *self {
            LightShape::Point { at } => point::reach(at, falloff, (lo, hi), r0),
            LightShape::Spot { at, .. } => {
                // At a point (a box of no size), the spot's window there.
                let window = if lo == hi && lo != at {
                    light.spot_window((lo - at).normalize())
                } else {
                    1.0
                };
                falloff.g(distance(at), r0) * window
            }
            LightShape::Line { segment, .. } => {
                // The nearest of the box to the segment, at most: the
                // nearer of the segment's ends and middle to the box.
                let d = [segment.a, segment.b, segment.point_at(0.5)]
                    .map(distance)
                    .into_iter()
                    .fold(f64::INFINITY, f64::min)
                    - 0.5 * segment.length();
                let d = d.max(r0);
                let most = light.profile.as_ref().map_or(1.0, |p| p.max());
                falloff.per_radian(d, r0) * (segment.length() / d).min(std::f64::consts::PI) * most
            }
            LightShape::Circle { at, radius } => {
                let d = (distance(at) - radius).max(r0);
                falloff.per_radian(d + radius, r0) * (2.0 * radius / d).min(std::f64::consts::PI)
            }
            LightShape::Arc { arc, .. } => {
                // As a line light as long as the arc, from the nearest of
                // its box: at most the whole circle of directions.
                let (a_lo, a_hi) = arc.bounds();
                let gap = (a_lo - hi).max(lo - a_hi).max(DVec2::ZERO).length();
                let d = gap.max(r0);
                falloff.per_radian(d, r0) * (arc.length() / d).min(std::f64::consts::TAU)
            }
            LightShape::Directional { .. } => 1.0,
            LightShape::Beam { segment, direction } => beam::reach(&segment, direction, (lo, hi)),
            // No receiver's sample finds a laser.
            LightShape::Laser { .. } => 0.0,
        };
        usable(value)
    }

    /// Points whose convex hull holds every point a shadow ray towards the
    /// light aims at; `None` for light from a direction.
    pub(crate) fn hull(&self) -> Option<[DVec2; 4]> {
        match *self {
            LightShape::Point { at } | LightShape::Spot { at, .. } => Some([at; 4]),
            LightShape::Line { segment, .. } => Some([segment.a, segment.b, segment.a, segment.b]),
            LightShape::Arc { arc, .. } => Some(arc::hull(&arc)),
            LightShape::Directional { .. } | LightShape::Laser { .. } => None,
            LightShape::Circle { at, radius } => Some(circle::hull(at, radius)),
            LightShape::Beam { segment, .. } => Some([segment.a, segment.b, segment.a, segment.b]),
        }
    }
}

/// A reach as the light table uses it: not below 0, and 0 where it is not
/// a number.
#[inline(always)]
pub(crate) fn usable(value: f64) -> f64 {
    if value.is_finite() {
        value.max(0.0)
    } else {
        0.0
    }
}

/// The photons a light of one direction per point sends towards a wall:
/// an interval of directions from a point (a point light or a spot), or of
/// positions across the sun's beam.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Aperture {
    /// Directions from `at` turning from unit `from` by up to `angle`
    /// radians (`< pi`) to unit `to`, counterclockwise when `turn` is 1,
    /// clockwise when it is -1.
    Angle {
        at: DVec2,
        from: DVec2,
        to: DVec2,
        angle: f64,
        turn: f64,
    },
    /// Rays of the sun's beam entering at `start + across * s` for `s` in
    /// `s0..s1`, travelling in `direction`.
    Beam {
        start: DVec2,
        across: DVec2,
        direction: DVec2,
        s0: f64,
        s1: f64,
    },
    /// Rays of a beam light leaving `start + edge * u` for `u` in
    /// `u0..u1`, travelling in `direction`; measured across the beam.
    Strip {
        start: DVec2,
        edge: DVec2,
        direction: DVec2,
        u0: f64,
        u1: f64,
    },
    /// A laser's one ray, of measure 1.
    Ray { origin: DVec2, direction: DVec2 },
}

/// Unit `from` turned by `angle` radians, counterclockwise for `turn` 1.
fn turned(from: DVec2, angle: f64, turn: f64) -> DVec2 {
    let (s, c) = angle.sin_cos();
    from * c + from.perp() * (turn * s)
}

impl Aperture {
    /// The part of the aperture from fraction `u0` to `u1` of it.
    pub fn part(&self, u0: f64, u1: f64) -> Aperture {
        match *self {
            Aperture::Angle {
                at,
                from,
                angle,
                turn,
                ..
            } => {
                let start = turned(from, angle * u0, turn);
                Aperture::Angle {
                    at,
                    from: start,
                    to: turned(from, angle * u1, turn),
                    angle: angle * (u1 - u0),
                    turn,
                }
            }
            Aperture::Beam {
                start,
                across,
                direction,
                s0,
                s1,
            } => Aperture::Beam {
                start,
                across,
                direction,
                s0: s0 + (s1 - s0) * u0,
                s1: s0 + (s1 - s0) * u1,
            },
            Aperture::Strip {
                start,
                edge,
                direction,
                u0: a,
                u1: b,
            } => Aperture::Strip {
                start,
                edge,
                direction,
                u0: a + (b - a) * u0,
                u1: a + (b - a) * u1,
            },
            Aperture::Ray { .. } => *self,
        }
    }

    /// Its measure: radians, or units of the beam's width.
    pub fn measure(&self) -> f64 {
        match *self {
            Aperture::Angle { angle, .. } => angle,
            Aperture::Beam { s0, s1, .. } => s1 - s0,
            Aperture::Strip {
                edge,
                direction,
                u0,
                u1,
                ..
            } => (u1 - u0) * edge.perp_dot(direction).abs(),
            Aperture::Ray { .. } => 1.0,
        }
    }

    /// The ray at fraction `u` of the aperture: origin and direction.
    pub fn ray(&self, u: f64) -> (DVec2, DVec2) {
        match *self {
            Aperture::Angle {
                at,
                from,
                angle,
                turn,
                ..
            } => (at, turned(from, angle * u, turn)),
            Aperture::Beam {
                start,
                across,
                direction,
                s0,
                s1,
            } => (start + across * (s0 + (s1 - s0) * u), direction),
            Aperture::Strip {
                start,
                edge,
                direction,
                u0,
                u1,
            } => (start + edge * (u0 + (u1 - u0) * u), direction),
            Aperture::Ray { origin, direction } => (origin, direction),
        }
    }

    /// Whether the aperture holds the ray from `origin` along `dir` (one
    /// that [`Aperture::ray`] of this light's apertures gave).
    pub fn contains(&self, origin: DVec2, dir: DVec2) -> bool {
        match *self {
            Aperture::Angle { from, to, turn, .. } => {
                turn * from.perp_dot(dir) >= 0.0 && turn * dir.perp_dot(to) >= 0.0
            }
            Aperture::Beam {
                start,
                across,
                s0,
                s1,
                ..
            } => {
                let s = (origin - start).dot(across);
                s >= s0 && s <= s1
            }
            Aperture::Strip {
                start,
                edge,
                u0,
                u1,
                ..
            } => {
                let u = (origin - start).dot(edge) / edge.length_squared();
                u >= u0 && u <= u1
            }
            Aperture::Ray { .. } => true,
        }
    }
}

/// Where every shadow ray of a light goes, from any point: to a point
/// light's or a spot's position, or against the sun's direction. Lights
/// with an area (lines, circles) have no one source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Source {
    /// To this point.
    At(DVec2),
    /// Against this direction of travel, without end.
    Sun(DVec2),
}

impl Source {
    /// The shadow ray's direction from `x` and its `t_max`: up to the point
    /// (`t = 1`), or without end towards the sun.
    #[inline]
    pub(crate) fn way_from(self, x: DVec2) -> (DVec2, f64) {
        match self {
            Source::At(p) => (p - x, 1.0),
            Source::Sun(direction) => (-direction, f64::INFINITY),
        }
    }
}

/// Where a light's light comes from, as the fast paths may know it: the
/// geometry they specialise on (the coherence masks draw its shadow
/// edges, the strata loops sample it in lanes). Matched exhaustively
/// outside this module, so that a new kind of light is mapped here to one
/// of these, or a new one that the compiler then asks every fast path
/// about.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Emitter {
    /// From one point; `windowed` where the light is a spot, whose
    /// intensity depends on the direction.
    Point { at: DVec2, windowed: bool },
    /// From one direction of travel, without end (the sun).
    Direction(DVec2),
    /// From a segment, on one side or both.
    Segment { segment: Segment, one_sided: bool },
    /// From the rim of a disk.
    Disk { at: DVec2, radius: f64 },
    /// From both sides of a circular arc.
    Arc(flatray_geometry::Arc),
    /// Parallel rays in `direction` from a segment (a beam), or from one
    /// point (a laser: `edge` zero).
    Parallel {
        start: DVec2,
        edge: DVec2,
        direction: DVec2,
    },
}

/// How many lights of each kind a scene holds: what the plan counts and
/// names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct LightCounts {
    pub points: usize,
    pub spots: usize,
    pub lines: usize,
    pub circles: usize,
    pub suns: usize,
    pub beams: usize,
    pub lasers: usize,
    /// Lights of one direction per point (points, spots, suns, beams,
    /// lasers): the caustic pass aims their photons at mirrors and glass.
    pub aimed: usize,
}

impl LightCounts {
    pub(crate) fn of(lights: &[Light]) -> LightCounts {
        let mut counts = LightCounts::default();
        for light in lights {
            match light.shape {
                LightShape::Point { .. } => counts.points += 1,
                LightShape::Spot { .. } => counts.spots += 1,
                LightShape::Line { .. } | LightShape::Arc { .. } => counts.lines += 1,
                LightShape::Circle { .. } => counts.circles += 1,
                LightShape::Directional { .. } => counts.suns += 1,
                LightShape::Beam { .. } => counts.beams += 1,
                LightShape::Laser { .. } => counts.lasers += 1,
            }
            counts.aimed += usize::from(light.shape.aims_photons());
        }
        counts
    }
}

impl LightShape {
    /// Where the light comes from, for the fast paths ([`Emitter`]).
    #[inline]
    pub(crate) fn emitter(&self) -> Emitter {
        match *self {
            LightShape::Point { at } => Emitter::Point {
                at,
                windowed: false,
            },
            LightShape::Spot { at, .. } => Emitter::Point { at, windowed: true },
            LightShape::Directional { direction } => Emitter::Direction(direction),
            LightShape::Line {
                segment, one_sided, ..
            } => Emitter::Segment { segment, one_sided },
            LightShape::Arc { arc, .. } => Emitter::Arc(arc),
            LightShape::Circle { at, radius } => Emitter::Disk { at, radius },
            LightShape::Beam { segment, direction } => Emitter::Parallel {
                start: segment.a,
                edge: segment.edge(),
                direction,
            },
            LightShape::Laser { at, direction } => Emitter::Parallel {
                start: at,
                edge: DVec2::ZERO,
                direction,
            },
        }
    }

    /// Whether the light sends one direction per point, so that the
    /// caustic pass can aim its photons at a wall ([`LightShape::aperture`]).
    #[inline]
    pub(crate) fn aims_photons(&self) -> bool {
        match self {
            LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => true,
            LightShape::Line { .. } | LightShape::Arc { .. } | LightShape::Circle { .. } => false,
        }
    }

    /// Whether a path from a receiver can find this light's light at
    /// all: not a laser's (a delta in position and direction), which only
    /// light tracing and the caustic pass see.
    #[inline]
    pub(crate) fn found_by_paths(&self) -> bool {
        !matches!(self, LightShape::Laser { .. })
    }

    /// For a light that no path finds, the one aperture that holds all
    /// its photons, which the caustic pass traces whatever they meet.
    pub(crate) fn whole_aperture(&self) -> Option<Aperture> {
        match *self {
            LightShape::Laser { at, direction } => Some(Aperture::Ray {
                origin: at,
                direction,
            }),
            _ => None,
        }
    }

    /// The one place this light's shadow rays all go, if it has one.
    pub(crate) fn source(&self) -> Option<Source> {
        match *self {
            LightShape::Point { at } | LightShape::Spot { at, .. } => Some(Source::At(at)),
            LightShape::Directional { direction } => Some(Source::Sun(direction)),
            // A beam's shadow rays end at its segment, and only inside its
            // strip; a laser has none.
            LightShape::Line { .. }
            | LightShape::Arc { .. }
            | LightShape::Circle { .. }
            | LightShape::Beam { .. }
            | LightShape::Laser { .. } => None,
        }
    }

    /// Where this light sends photons that can reach `target` first: for
    /// lights of one direction per point; `None` for lights with an area
    /// (path tracing sees those in mirrors) and where the target subtends
    /// nothing.
    pub(crate) fn aperture(&self, scene: &Scene, target: &Segment) -> Option<Aperture> {
        match *self {
            LightShape::Point { at } | LightShape::Spot { at, .. } => {
                let (va, vb) = (target.a - at, target.b - at);
                let cross = va.perp_dot(vb);
                if cross == 0.0 || va == DVec2::ZERO || vb == DVec2::ZERO {
                    return None;
                }
                let angle = cross.abs().atan2(va.dot(vb));
                let (from, turn) = (va.normalize(), cross.signum());
                (angle > 0.0).then(|| Aperture::Angle {
                    at,
                    from,
                    to: turned(from, angle, turn),
                    angle,
                    turn,
                })
            }
            LightShape::Directional { direction } => {
                let (start, across, width) = sun_line(scene, direction);
                let across = across.normalize();
                let (sa, sb) = (
                    (target.a - start).dot(across),
                    (target.b - start).dot(across),
                );
                let (s0, s1) = (sa.min(sb).max(0.0), sa.max(sb).min(width));
                (s1 > s0).then_some(Aperture::Beam {
                    start,
                    across,
                    direction,
                    s0,
                    s1,
                })
            }
            LightShape::Beam { segment, direction } => beam::aperture(&segment, direction, target),
            // All of a laser's photons are traced (`whole_aperture`).
            LightShape::Line { .. }
            | LightShape::Arc { .. }
            | LightShape::Circle { .. }
            | LightShape::Laser { .. } => None,
        }
    }

    /// The kernel a photon of this light carries on its first flight.
    pub(crate) fn kernel(&self, light: &Light) -> PhotonKernel {
        match self {
            LightShape::Point { .. } | LightShape::Spot { .. } => {
                PhotonKernel::Point(light.falloff)
            }
            LightShape::Line { .. } | LightShape::Arc { .. } | LightShape::Circle { .. } => {
                PhotonKernel::Line(light.falloff)
            }
            LightShape::Directional { .. } | LightShape::Beam { .. } | LightShape::Laser { .. } => {
                PhotonKernel::None
            }
        }
    }
}
