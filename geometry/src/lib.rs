//! Plane geometry for flatray: points, segments, circular arcs, rays,
//! and the ray queries every integrator is built on.
//!
//! What it is for: one vector formula for every orientation of a wall (no
//! special case for vertical, horizontal or diagonal segments), exact
//! endpoint ownership so that closed corners never leak, and reflection;
//! queries that give the same answers faster: a BVH for many segments, AVX
//! kernels for few, and culling by direction ([`ArcCandidates`]) for rays
//! that leave a small box.
//!
//! What it never does: colour, randomness, files or threads. It knows
//! nothing of materials or lights; a shape is identified by its index in
//! a [`SegmentSet`], and callers attach meaning to that index. Its only
//! `unsafe` code is the AVX kernel in `lanes.rs`, run only where the
//! processor reports AVX, and checked bit for bit against the scalar one.
//!
//! # The crossing rule
//!
//! A ray `o + t d` crosses a segment `a b` when the two endpoints are not
//! strictly on the same side of the ray's line. The sides are the signs of
//! `cross(d, a - o)` and `cross(d, b - o)`, and each is computed from the
//! endpoint alone, so two walls that share an endpoint see the *same* sign
//! for it: the ray can pass on one side of the shared corner or the other,
//! or through it, and in every case at least one of the two walls is
//! crossed. No epsilon is involved. A ray that lies exactly along a segment
//! (both signs zero) does not cross it: a grazing ray slides along the wall.
//! Crossings count for `t > 0`: a ray never meets a wall at its own origin,
//! so a wall drawn twice does not trap a ray that leaves one copy.

//!
//! # Arcs
//!
//! A circular arc ([`Arc`]) keeps its ends exactly and meets rays by the
//! same signs at its ends as a segment, so an arc and a wall that share an
//! end leave no gap; a ray can meet an arc twice, and meets the arc it
//! leaves again where the arc curves back (`arc.rs` states both rules).

pub use glam::DVec2;

mod arc;
mod cull;
mod lanes;
pub mod overlap;
mod segment_set;
pub use arc::{Arc, NotAnArc, arc_crossings, intersect_arc};
pub use cull::{ArcCandidates, HitLanes, MAX_HULL_POINTS, RayLanes, convex_hull, hull_candidates};
pub use lanes::{Kernel, portable_forced};
pub use segment_set::{BVH_THRESHOLD, SegmentSet, Skip, Strategy};

/// The 2D cross product (perp dot product) `a.x * b.y - a.y * b.x`.
///
/// Positive when `b` turns counter-clockwise from `a` in a y-up frame (in
/// flatray's y-down image frame that is clockwise on screen).
#[inline]
pub fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Mirror reflection of direction `d` about a line with unit normal `n`.
///
/// Preserves the length of `d`; `n` may point to either side.
#[inline]
pub fn reflect(d: DVec2, n: DVec2) -> DVec2 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction of unit direction `d` at a surface with unit normal `n`
/// (either orientation), by Snell's law with `eta = n1 / n2` (the index the
/// ray leaves over the index it enters). `None` beyond the critical angle:
/// total internal reflection.
#[inline]
pub fn refract(d: DVec2, n: DVec2, eta: f64) -> Option<DVec2> {
    // Orient the normal against the ray.
    let n = if d.dot(n) > 0.0 { -n } else { n };
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * d + (eta * cos_i - cos_t) * n)
}

/// A line segment from `a` to `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub a: DVec2,
    pub b: DVec2,
}

/// One of the two sides of a segment, seen from `a` towards `b`.
///
/// `Positive` is the side where `cross(b - a, p - a) > 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    Positive,
    Negative,
}

impl Side {
    /// The other side.
    #[inline]
    pub fn flip(self) -> Side {
        match self {
            Side::Positive => Side::Negative,
            Side::Negative => Side::Positive,
        }
    }

    /// `+1.0` or `-1.0`.
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Side::Positive => 1.0,
            Side::Negative => -1.0,
        }
    }

    /// `Positive` for a value above zero, `Negative` below, `None` for
    /// zero (either sign) and NaN.
    #[inline]
    pub fn of_sign(value: f64) -> Option<Side> {
        if value > 0.0 {
            Some(Side::Positive)
        } else if value < 0.0 {
            Some(Side::Negative)
        } else {
            None
        }
    }

    /// 0 for `Positive`, 1 for `Negative`: an index for per-side tables.
    #[inline]
    pub fn index(self) -> usize {
        match self {
            Side::Positive => 0,
            Side::Negative => 1,
        }
    }

    /// The side of index `index` (0: `Positive`, anything else:
    /// `Negative`), the inverse of [`Side::index`].
    #[inline]
    pub fn of_index(index: usize) -> Side {
        if index == 0 {
            Side::Positive
        } else {
            Side::Negative
        }
    }
}

impl Segment {
    #[inline]
    pub fn new(a: DVec2, b: DVec2) -> Segment {
        Segment { a, b }
    }

    /// The vector `b - a`.
    #[inline]
    pub fn edge(&self) -> DVec2 {
        self.b - self.a
    }

    #[inline]
    pub fn length(&self) -> f64 {
        self.edge().length()
    }

    /// The point `a + u (b - a)`.
    #[inline]
    pub fn point_at(&self, u: f64) -> DVec2 {
        self.a + u * self.edge()
    }

    /// The unit normal on the `Positive` side, or zero for a degenerate
    /// segment.
    #[inline]
    pub fn normal(&self) -> DVec2 {
        // perp() turns (x, y) into (-y, x): cross(e, perp(e)) = |e|^2 > 0.
        self.edge().perp().normalize_or_zero()
    }

    /// The unit normal pointing into `side`.
    #[inline]
    pub fn normal_on(&self, side: Side) -> DVec2 {
        self.normal() * side.sign()
    }

    /// `cross(b - a, p - a)`: positive on the `Positive` side, negative on
    /// the other, zero on the segment's line.
    #[inline]
    pub fn side_value(&self, p: DVec2) -> f64 {
        cross(self.edge(), p - self.a)
    }

    /// The side of the line that `p` is on, or `None` when `p` is exactly on
    /// the line.
    #[inline]
    pub fn side_of(&self, p: DVec2) -> Option<Side> {
        Side::of_sign(self.side_value(p))
    }

    /// The side from which a ray travelling in direction `d` arrives at
    /// the segment, or `None` when `d` is parallel to it.
    #[inline]
    pub fn arrival_side(&self, d: DVec2) -> Option<Side> {
        // Arriving from the positive side means travelling against the
        // positive normal: cross(e, d) < 0.
        let s = cross(self.edge(), d);
        if s < 0.0 {
            Some(Side::Positive)
        } else if s > 0.0 {
            Some(Side::Negative)
        } else {
            None
        }
    }
}

/// The shape of a wall: a segment or a circular arc.
///
/// A position `u` runs from 0 at its first end to 1 at its last, in
/// proportion to length; its normal on the `Positive` side is the
/// segment's (`cross(b - a, n) > 0`) or, on an arc, away from the centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Segment(Segment),
    Arc(Arc),
}

impl From<Segment> for Shape {
    fn from(segment: Segment) -> Shape {
        Shape::Segment(segment)
    }
}

impl From<Arc> for Shape {
    fn from(arc: Arc) -> Shape {
        Shape::Arc(arc)
    }
}

impl Shape {
    /// The first end.
    #[inline]
    pub fn a(&self) -> DVec2 {
        match self {
            Shape::Segment(s) => s.a,
            Shape::Arc(arc) => arc.a,
        }
    }

    /// The last end.
    #[inline]
    pub fn b(&self) -> DVec2 {
        match self {
            Shape::Segment(s) => s.b,
            Shape::Arc(arc) => arc.b,
        }
    }

    /// The segment from end to end: the segment itself, or an arc's chord.
    #[inline]
    pub fn chord(&self) -> Segment {
        Segment::new(self.a(), self.b())
    }

    #[inline]
    pub fn as_segment(&self) -> Option<&Segment> {
        match self {
            Shape::Segment(s) => Some(s),
            Shape::Arc(_) => None,
        }
    }

    #[inline]
    pub fn as_arc(&self) -> Option<&Arc> {
        match self {
            Shape::Segment(_) => None,
            Shape::Arc(arc) => Some(arc),
        }
    }

    #[inline]
    pub fn length(&self) -> f64 {
        match self {
            Shape::Segment(s) => s.length(),
            Shape::Arc(arc) => arc.length(),
        }
    }

    /// The point at position `u`.
    #[inline]
    pub fn point_at(&self, u: f64) -> DVec2 {
        match self {
            Shape::Segment(s) => s.point_at(u),
            Shape::Arc(arc) => arc.point_at(u),
        }
    }

    /// The unit normal into `side` at point `p` of the shape.
    #[inline]
    pub fn normal_on(&self, side: Side, p: DVec2) -> DVec2 {
        match self {
            Shape::Segment(s) => s.normal_on(side),
            Shape::Arc(arc) => arc.normal_on(side, p),
        }
    }

    /// The side from which a ray travelling in `d` arrives at point `p` of
    /// the shape, or `None` along it (parallel, or tangent).
    #[inline]
    pub fn arrival_side(&self, p: DVec2, d: DVec2) -> Option<Side> {
        match self {
            Shape::Segment(s) => s.arrival_side(d),
            Shape::Arc(arc) => arc.arrival_side(p, d),
        }
    }

    /// The side of the shape `p` is on: of a segment's line, or of an
    /// arc's circle (`Positive` outside); `None` on it.
    #[inline]
    pub fn side_of(&self, p: DVec2) -> Option<Side> {
        match self {
            Shape::Segment(s) => s.side_of(p),
            Shape::Arc(arc) => arc.side_of(p),
        }
    }

    /// The bounding box.
    #[inline]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        match self {
            Shape::Segment(s) => (s.a.min(s.b), s.a.max(s.b)),
            Shape::Arc(arc) => arc.bounds(),
        }
    }
}

/// A ray `origin + t * dir`, `t >= 0`. `dir` need not be unit length; `t`
/// is measured in multiples of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec2,
    pub dir: DVec2,
}

impl Ray {
    #[inline]
    pub fn new(origin: DVec2, dir: DVec2) -> Ray {
        Ray { origin, dir }
    }

    #[inline]
    pub fn at(&self, t: f64) -> DVec2 {
        self.origin + t * self.dir
    }
}

/// Where a ray crosses a segment: the ray parameter `t` and the segment
/// parameter `u` in `[0, 1]` (0 at `a`, 1 at `b`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub u: f64,
}

/// Where the line of `ray` crosses `seg`, by the crossing rule of this
/// crate, whatever the sign of `t`. `None` when both endpoints lie strictly
/// on one side of the line, or the ray lies along the segment.
#[inline]
pub fn line_crossing(ray: &Ray, seg: &Segment) -> Option<Hit> {
    crossing_parts(ray.origin, ray.dir, seg.a, seg.b).map(|(t, sa, sb)| Hit {
        t,
        u: sa / (sa - sb),
    })
}

/// The arithmetic of the crossing rule, written once: `(t, sa, sb)` where
/// `sa` and `sb` are the sides of `a` and `b` relative to the line through
/// `o` along `d`, and `t` the ray parameter of the crossing. The segment
/// parameter is `sa / (sa - sb)`, in `[0, 1]` without clamping because
/// the signs differ or exactly one is zero.
#[inline(always)]
pub(crate) fn crossing_parts(o: DVec2, d: DVec2, a: DVec2, b: DVec2) -> Option<(f64, f64, f64)> {
    let (pa, pb) = (a - o, b - o);
    let sa = d.x * pa.y - d.y * pa.x;
    let sb = d.x * pb.y - d.y * pb.x;
    if (sa > 0.0 && sb > 0.0) || (sa < 0.0 && sb < 0.0) || (sa == 0.0 && sb == 0.0) {
        return None;
    }
    let e = b - a;
    Some(((pa.x * e.y - pa.y * e.x) / (sb - sa), sa, sb))
}

/// The part `[t0, t1]` of the line `o + t d` (for `t` in the given
/// `[t0, t1]`) inside the box `[lo, hi]`, by Liang-Barsky clipping; `None`
/// when nothing of it is inside or an end would not be finite.
pub fn clip_to_box(
    o: DVec2,
    d: DVec2,
    mut t0: f64,
    mut t1: f64,
    lo: DVec2,
    hi: DVec2,
) -> Option<(f64, f64)> {
    for (p, q) in [
        (-d.x, o.x - lo.x),
        (d.x, hi.x - o.x),
        (-d.y, o.y - lo.y),
        (d.y, hi.y - o.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
}

/// Whether two closed segments share a point: they cross, one touches
/// the other, or, lying on one line, they overlap. By the crossing rule's
/// own orientation (`Segment::side_value`): a point exactly on a line is
/// on it, whatever rounding put it there. The loader's test of a glass
/// polygon, the coherence masks and the caustic pass's apertures all ask
/// this one question.
pub fn segments_meet(a: &Segment, b: &Segment) -> bool {
    let straddles = |s: &Segment, t: &Segment| {
        let (p, q) = (s.side_value(t.a), s.side_value(t.b));
        !((p > 0.0 && q > 0.0) || (p < 0.0 && q < 0.0))
    };
    if a.side_value(b.a) == 0.0 && a.side_value(b.b) == 0.0 {
        // On one line: they meet where their extents along it overlap.
        let e = a.edge();
        let (t0, t1) = ((b.a - a.a).dot(e), (b.b - a.a).dot(e));
        return t0.max(t1) >= 0.0 && t0.min(t1) <= e.length_squared();
    }
    straddles(a, b) && straddles(b, a)
}

/// The crossing of `ray` with `seg` at `t > 0`, if any.
#[inline]
pub fn intersect(ray: &Ray, seg: &Segment) -> Option<Hit> {
    line_crossing(ray, seg).filter(|h| h.t > 0.0)
}

#[cfg(test)]
mod tests;
