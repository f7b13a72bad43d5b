//! Circular arcs: exact ray-arc crossings, with the crossing rule's
//! watertight joins and an exact rule for rays that leave an arc.
//!
//! # The arc crossing rule
//!
//! An arc's ends are stored exactly, as a segment's are, and the arc is
//! the part of its circle on one side of its chord's line. A ray's line
//! meets a circle at most twice, so it meets the arc 0, 1 or 2 times, and
//! the parity is known from the ends alone: the line crosses the arc once
//! when the ends lie on different sides of the ray's line, by the same
//! signs `cross(d, a - o)` and `cross(d, b - o)` that the segment rule
//! computes. So at an end shared with a segment or another arc, the two
//! shapes see the same sign for the shared point, and the ray crosses one
//! of them: no ray passes between an arc and the wall it joins. When the
//! parity is odd, the root on the arc's side of the chord (the larger
//! margin) is taken, even where rounding puts the line just off the
//! circle (the tangent point then); when it is even, both roots or
//! neither, by the sum of their margins.
//!
//! # Leaving an arc
//!
//! A ray can meet the arc it leaves again (inside a round room it
//! always does). A query given the arc to skip (`Skip`) drops the root at
//! the ray's origin, known to be `t = 0` because the origin lies on the
//! circle, and takes the other from the sum of the roots, `-2 (o - c) . d
//! / |d|^2`; whether it lies on the arc is again the parity: the line
//! crossed the arc at the origin, so a second crossing exists when the
//! ends lie on one side of the ray's line. A shadow ray that ends on an
//! arc (`Skip`'s second index) drops the root at `t_max` the same way. No
//! epsilon is involved.

use crate::{DVec2, Hit, Ray, Segment, Side, cross};

/// A circular arc from `a` to `b`, or a full circle.
///
/// Its `Positive` side is the convex one, away from the centre; its
/// position `u` runs from 0 at `a` to 1 at `b` along its length (the
/// angle from `a`, over the arc's sweep).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    /// The ends; the same point on a full circle.
    pub a: DVec2,
    pub b: DVec2,
    pub center: DVec2,
    pub radius: f64,
    /// +1 when the arc turns counter-clockwise (`cross(a - c, p - c) > 0`
    /// for points just past `a`) from `a` to `b`, -1 when clockwise.
    pub turn: f64,
    /// The angle the arc spans, in `(0, 2 pi]`.
    pub sweep: f64,
    /// Which side of the chord's line (`cross(b - a, p - a)`) the arc lies
    /// on: +1 or -1; 0 for a full circle.
    pub bulge: f64,
}

/// Why three points make no arc.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotAnArc {
    /// Two of the points coincide, or all three lie on one line.
    Collinear,
    /// A coordinate or the radius is not finite, or the radius is not
    /// positive.
    NotFinite,
}

impl Arc {
    /// The arc that starts at `a`, passes through `through` and ends at
    /// `b`. `a` and `b` are kept exactly; the circle is the one through
    /// all three.
    pub fn through(a: DVec2, through: DVec2, b: DVec2) -> Result<Arc, NotAnArc> {
        if !(a.is_finite() && through.is_finite() && b.is_finite()) {
            return Err(NotAnArc::NotFinite);
        }
        let side = cross(b - a, through - a);
        if side == 0.0 || a == b || a == through || b == through {
            return Err(NotAnArc::Collinear);
        }
        let center = circumcentre(a, through, b).ok_or(NotAnArc::Collinear)?;
        let radius = ((a - center).length() + (b - center).length()) * 0.5;
        if !(radius > 0.0 && radius.is_finite() && center.is_finite()) {
            return Err(NotAnArc::NotFinite);
        }
        // Through `through`, the arc turns the way the triangle a, m, b
        // does: counter-clockwise when b lies left of a -> m.
        let turn = if cross(through - a, b - through) > 0.0 {
            1.0
        } else {
            -1.0
        };
        let sweep = angle_from(a - center, b - center, turn);
        Ok(Arc {
            a,
            b,
            center,
            radius,
            turn,
            sweep,
            bulge: side.signum(),
        })
    }

    /// The arc of the circle (`center`, `radius`) from angle `from` to
    /// angle `to` (radians, counter-clockwise in the math frame: x to y),
    /// clockwise where `to < from`. A sweep of `2 pi` or more is the full
    /// circle.
    pub fn from_angles(center: DVec2, radius: f64, from: f64, to: f64) -> Result<Arc, NotAnArc> {
        if !(center.is_finite() && radius > 0.0 && radius.is_finite()) {
            return Err(NotAnArc::NotFinite);
        }
        if !(from.is_finite() && to.is_finite()) {
            return Err(NotAnArc::NotFinite);
        }
        let span = to - from;
        if span.abs() >= std::f64::consts::TAU {
            return Ok(Arc::circle(center, radius, from));
        }
        if span == 0.0 {
            return Err(NotAnArc::Collinear);
        }
        let at = |angle: f64| center + radius * DVec2::new(angle.cos(), angle.sin());
        Arc::through(at(from), at(from + span * 0.5), at(to))
    }

    /// The full circle, starting and ending at angle `start` (radians).
    pub fn circle(center: DVec2, radius: f64, start: f64) -> Arc {
        let a = center + radius * DVec2::new(start.cos(), start.sin());
        Arc {
            a,
            b: a,
            center,
            radius,
            turn: 1.0,
            sweep: std::f64::consts::TAU,
            bulge: 0.0,
        }
    }

    /// Whether it is a whole circle.
    #[inline]
    pub fn is_full(&self) -> bool {
        self.bulge == 0.0
    }

    /// Its length, `radius * sweep`.
    #[inline]
    pub fn length(&self) -> f64 {
        self.radius * self.sweep
    }

    /// The chord from `a` to `b`.
    #[inline]
    pub fn chord(&self) -> Segment {
        Segment::new(self.a, self.b)
    }

    /// The point at position `u` (0 at `a`, 1 at `b`); the ends exactly.
    /// Never inlined: a segment's callers stay small.
    #[inline(never)]
    pub fn point_at(&self, u: f64) -> DVec2 {
        if u <= 0.0 {
            return self.a;
        }
        if u >= 1.0 {
            return self.b;
        }
        let angle = self.turn * self.sweep * u;
        let (s, c) = angle.sin_cos();
        let r = (self.a - self.center).normalize_or_zero() * self.radius;
        self.center + DVec2::new(r.x * c - r.y * s, r.x * s + r.y * c)
    }

    /// The position `u` of a point on (or near) the circle: its angle from
    /// `a` over the sweep, in `[0, 1]`.
    pub fn position_of(&self, p: DVec2) -> f64 {
        let angle = angle_from(self.a - self.center, p - self.center, self.turn);
        if self.is_full() {
            return (angle / self.sweep).clamp(0.0, 1.0);
        }
        if angle <= self.sweep {
            angle / self.sweep
        } else {
            // Past the end: the nearer end (rounding near `a` or `b`).
            let past = angle - self.sweep;
            let before = std::f64::consts::TAU - angle;
            if before < past { 0.0 } else { 1.0 }
        }
    }

    /// The unit normal at `p` on the `Positive` (convex) side: away from
    /// the centre.
    #[inline]
    pub fn normal_at(&self, p: DVec2) -> DVec2 {
        (p - self.center).normalize_or_zero()
    }

    /// The unit normal at `p` pointing into `side`.
    #[inline]
    pub fn normal_on(&self, side: Side, p: DVec2) -> DVec2 {
        self.normal_at(p) * side.sign()
    }

    /// The side of the circle `p` is on: `Positive` outside, `Negative`
    /// inside, `None` on it.
    pub fn side_of(&self, p: DVec2) -> Option<Side> {
        let f = p - self.center;
        Side::of_sign((f.length() - self.radius) * (f.length() + self.radius))
    }

    /// The side from which a ray travelling in `d` arrives at point `p` of
    /// the arc: `Positive` from outside, `Negative` from inside, `None`
    /// along the tangent.
    #[inline]
    pub fn arrival_side(&self, p: DVec2, d: DVec2) -> Option<Side> {
        // Arriving from outside means travelling against the outward
        // normal.
        Side::of_sign(-d.dot(p - self.center))
    }

    /// The bounding box: the ends, and the circle's extreme points that
    /// the arc passes.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let (mut lo, mut hi) = (self.a.min(self.b), self.a.max(self.b));
        for k in [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y] {
            let p = self.center + k * self.radius;
            if self.is_full() || self.holds(p) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }

    /// How far on the arc's side of its chord's line `p` lies (positive
    /// on the arc's side), for a point of the circle.
    #[inline]
    fn margin(&self, p: DVec2) -> f64 {
        self.bulge * cross(self.b - self.a, p - self.a)
    }

    /// Whether a point of the circle lies on the arc.
    #[inline]
    fn holds(&self, p: DVec2) -> bool {
        self.is_full() || self.margin(p) > 0.0
    }

    /// The crossings of the line of `ray` with the arc, by the arc
    /// crossing rule (module docs), whatever their sign: up to two ray
    /// parameters, nearer first. `leaving` drops the root at `t = 0` (the
    /// ray starts on the arc), `arriving` the root at `t = t_end` (it ends
    /// on it).
    pub fn line_crossings(
        &self,
        ray: &Ray,
        leaving: bool,
        arriving: Option<f64>,
    ) -> ([f64; 2], usize) {
        let (o, d) = (ray.origin, ray.dir);
        let dd = d.dot(d);
        if dd.is_nan() || dd <= 0.0 {
            return ([0.0; 2], 0);
        }
        let f = o - self.center;
        let mid = -f.dot(d) / dd;
        // The foot of the perpendicular from the centre, and the half
        // chord there: r^2 - |q|^2 as a product, stable for far origins.
        let q = f + mid * d;
        let ql = q.length();
        let h2 = (self.radius - ql) * (self.radius + ql);
        let odd = if self.is_full() {
            false
        } else {
            let sa = cross(d, self.a - o);
            let sb = cross(d, self.b - o);
            !((sa > 0.0 && sb > 0.0) || (sa < 0.0 && sb < 0.0) || (sa == 0.0 && sb == 0.0))
        };
        let both_zero =
            !self.is_full() && cross(d, self.a - o) == 0.0 && cross(d, self.b - o) == 0.0;
        if leaving || arriving.is_some() {
            // The root at the known end, and the other by the sum of the
            // roots, 2 mid.
            let known = match arriving {
                // Leaving and arriving: the two crossings a line can have.
                Some(_) if leaving => return ([0.0; 2], 0),
                Some(t_end) => t_end,
                None => 0.0,
            };
            let other = 2.0 * mid - known;
            // The line crosses the arc at the known end; a second crossing
            // exists when that crossing leaves the parity even.
            let second = if self.is_full() {
                true
            } else {
                !odd && !both_zero
            };
            return if second && other.is_finite() {
                ([other, 0.0], 1)
            } else {
                ([0.0; 2], 0)
            };
        }
        if self.is_full() {
            if h2.is_nan() || h2 <= 0.0 {
                return ([0.0; 2], 0);
            }
            let s = (h2 / dd).sqrt();
            return ([mid - s, mid + s], 2);
        }
        if both_zero {
            return ([0.0; 2], 0);
        }
        let s = (h2.max(0.0) / dd).sqrt();
        let (t1, t2) = (mid - s, mid + s);
        let (m1, m2) = (self.margin(ray.at(t1)), self.margin(ray.at(t2)));
        if odd {
            let t = if m2 > m1 { t2 } else { t1 };
            ([t, 0.0], 1)
        } else if h2 > 0.0 && m1 + m2 > 0.0 {
            ([t1, t2], 2)
        } else {
            ([0.0; 2], 0)
        }
    }
}

/// The angle from `from` to `to` turning in direction `turn` (+1
/// counter-clockwise), in `[0, 2 pi)`.
fn angle_from(from: DVec2, to: DVec2, turn: f64) -> f64 {
    let angle = (turn * cross(from, to)).atan2(from.dot(to));
    if angle < 0.0 {
        angle + std::f64::consts::TAU
    } else {
        angle
    }
}

/// The centre of the circle through three points, `None` when they lie
/// on one line.
fn circumcentre(a: DVec2, b: DVec2, c: DVec2) -> Option<DVec2> {
    // Relative to `a`, for precision far from the origin.
    let (p, q) = (b - a, c - a);
    let d = 2.0 * cross(p, q);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let (pp, qq) = (p.length_squared(), q.length_squared());
    let x = (q.y * pp - p.y * qq) / d;
    let y = (p.x * qq - q.x * pp) / d;
    Some(a + DVec2::new(x, y))
}

/// The crossings of `ray` with `arc` at `0 < t < t_max`, nearer first,
/// as hits with the arc's position `u`, by the arc crossing rule.
pub fn arc_crossings(
    ray: &Ray,
    arc: &Arc,
    t_max: f64,
    leaving: bool,
    arriving: bool,
) -> ([Hit; 2], usize) {
    let (roots, n) = arc.line_crossings(ray, leaving, arriving.then_some(t_max));
    let mut out = [Hit { t: 0.0, u: 0.0 }; 2];
    let mut k = 0;
    for &t in &roots[..n] {
        if t > 0.0 && t < t_max {
            out[k] = Hit {
                t,
                u: arc.position_of(ray.at(t)),
            };
            k += 1;
        }
    }
    (out, k)
}

/// The nearest crossing of `ray` with `arc` at `0 < t < t_max`.
#[inline]
pub fn intersect_arc(ray: &Ray, arc: &Arc, t_max: f64, leaving: bool) -> Option<Hit> {
    let (hits, n) = arc_crossings(ray, arc, t_max, leaving, false);
    (n > 0).then_some(hits[0])
}
