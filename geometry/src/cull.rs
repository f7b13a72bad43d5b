//! Culling by direction: which segments rays that leave a box can meet,
//! for each of `n` equal arcs of directions.
//!
//! Arc `k` of `n` holds the directions at angles `2 pi k / n` to
//! `2 pi (k + 1) / n` from `+x` towards `+y`. A ray from a point of the box
//! whose direction lies in arc `k` can only cross the segments listed for
//! `k`: the list is every segment that meets the region such rays sweep,
//! grown by a margin far beyond rounding (a relative `1e-9` in distance,
//! `1e-9` radians in angle). So [`SegmentSet::closest_hit_among`] over the
//! list returns exactly what [`SegmentSet::closest_hit`] returns.
//!
//! [`hull_candidates`] does the same for segments between two convex
//! sets, shadow rays from a box of receivers to a light: the segments that
//! meet the convex hull of the given points.
//!
//! The region is the Minkowski sum of the box and the arc's cone, a convex
//! set bounded by the two rays of the cone drawn from the box's outermost
//! corners and by the box edges that face away from the cone. A segment
//! misses it exactly when one of those lines, or the segment's own line,
//! separates the two (the separating axis theorem).
//!
//! A circular arc among the walls is listed in every list: a superset, as
//! the lists need, without a geometric test of its own; it never counts as
//! blocking in [`ArcCandidates::drop_blocked`].

use crate::lanes::{Best, visit_crossings};
use crate::{DVec2, Hit, Ray, Segment, SegmentSet, Skip, cross, crossing_parts};

/// The angular margin of an arc, in radians, on each side.
const ARC_MARGIN: f64 = 1e-9;
/// The distance margin, relative to the largest coordinate involved.
const DISTANCE_MARGIN: f64 = 1e-9;

/// For each arc of directions, the indices (ascending) of the segments
/// that rays leaving one box can meet. Filled again for each box within a
/// larger one's lists without allocating, once its buffers have grown.
#[derive(Clone, Debug, Default)]
pub struct ArcCandidates {
    /// `indices[starts[k]..starts[k + 1]]` is arc `k`'s list.
    starts: Vec<u32>,
    indices: Vec<u32>,
    /// Each arc's edge directions, widened by the margin: computed once
    /// for a number of arcs, kept for every box after.
    edges: Vec<(DVec2, DVec2)>,
    /// The segments of each arc while the lists are filled.
    buckets: Vec<Vec<u32>>,
}

impl ArcCandidates {
    /// Fills the lists for rays leaving the box `[lo, hi]` in `arcs` arcs.
    /// With `within`, only the segments of its lists (for a box that holds
    /// this one) are tested.
    ///
    /// Without `within`, a segment is tested only against the arcs of the
    /// directions from the box to it ([`arc_range`]: a few arcs for a
    /// segment far from the box), then by the exact test against each of
    /// those. The lists are those of testing every arc, for far less
    /// work on many segments.
    pub fn fill(
        &mut self,
        set: &SegmentSet,
        lo: DVec2,
        hi: DVec2,
        arcs: usize,
        within: Option<&ArcCandidates>,
    ) {
        self.starts.clear();
        self.indices.clear();
        self.starts.push(0);
        let scale = lo.abs().max(hi.abs()).max_element();
        if self.edges.len() != arcs {
            let angle = std::f64::consts::TAU / arcs as f64;
            let direction = |a: f64| {
                let (sin, cos) = a.sin_cos();
                DVec2::new(cos, sin)
            };
            self.edges = (0..arcs)
                .map(|k| {
                    (
                        direction(angle * k as f64 - ARC_MARGIN),
                        direction(angle * (k + 1) as f64 + ARC_MARGIN),
                    )
                })
                .collect();
        }
        if let Some(parent) = within {
            // A few segments per arc: each tested against its arc alone.
            for (k, &(d0, d1)) in self.edges.iter().enumerate() {
                let wedge = Wedge::new(lo, hi, d0, d1);
                for &index in parent.arc(k) {
                    if set.arc(index).is_some() {
                        // Arcs stay in every list (below).
                        self.indices.push(index);
                        continue;
                    }
                    let segment = set.get(index);
                    let extent = scale.max(segment.a.abs().max(segment.b.abs()).max_element());
                    if wedge.meets(segment.a, segment.b, DISTANCE_MARGIN * (1.0 + extent)) {
                        self.indices.push(index);
                    }
                }
                self.starts.push(self.indices.len() as u32);
            }
            return;
        }
        // Every segment of the set: each tested only against the arcs of
        // the directions towards it, into one list per arc.
        self.buckets.resize_with(arcs, Vec::new);
        for bucket in &mut self.buckets {
            bucket.clear();
        }
        for index in 0..set.len() as u32 {
            if set.arc(index).is_some() {
                // A circular arc is listed in every arc of directions: a
                // superset, as culling needs, without a wedge test of its
                // own.
                for bucket in &mut self.buckets[..arcs] {
                    bucket.push(index);
                }
                continue;
            }
            let segment = set.get(index);
            let extent = scale.max(segment.a.abs().max(segment.b.abs()).max_element());
            let margin = DISTANCE_MARGIN * (1.0 + extent);
            let (first, count) = arc_range(lo, hi, segment.a, segment.b, arcs, margin);
            for j in first..first + count {
                let k = j % arcs;
                let (d0, d1) = self.edges[k];
                if Wedge::new(lo, hi, d0, d1).meets(segment.a, segment.b, margin) {
                    self.buckets[k].push(index);
                }
            }
        }
        for bucket in &self.buckets[..arcs] {
            self.indices.extend_from_slice(bucket);
            self.starts.push(self.indices.len() as u32);
        }
    }

    /// Drops from each arc's list the segments that no ray of the arc
    /// can reach without first crossing a segment for which `blocks` is
    /// true: where a blocking segment lies across every ray of the arc
    /// (every ray from the box in its directions crosses its inside), the
    /// segments farther from the box than the farthest such crossing go.
    ///
    /// The lists then answer closest-hit queries exactly, also for a ray
    /// that goes on straight from a segment that does not block (with that
    /// segment skipped), but no longer all-crossings queries. Blocking
    /// segments that pass within a millionth of the coordinates of the
    /// box, or that rays meet at less than a thousandth of a radian, count
    /// as not blocking: rounding cannot move a crossing off them.
    pub fn drop_blocked(
        &mut self,
        set: &SegmentSet,
        lo: DVec2,
        hi: DVec2,
        blocks: impl Fn(u32) -> bool,
    ) {
        let scale = lo.abs().max(hi.abs()).max_element();
        let corners = box_corners(lo, hi);
        let mut kept = 0;
        let mut start = 0;
        for k in 0..self.arcs() {
            let end = self.starts[k + 1] as usize;
            let (d0, d1) = self.edges[k];
            // The nearest distance beyond which a blocker stops every ray.
            let mut reach = f64::INFINITY;
            for &index in &self.indices[start..end] {
                // Arcs block nothing here (their crossing is not linear).
                if blocks(index) && set.arc(index).is_none() {
                    let s = set.get(index);
                    if let Some(t) = blocked_beyond(s.a, s.b, &corners, d0, d1, scale) {
                        reach = reach.min(t);
                    }
                }
            }
            for j in start..end {
                let index = self.indices[j];
                let s = set.get(index);
                let extent = scale.max(s.a.abs().max(s.b.abs()).max_element());
                // An arc is kept: its chord is no bound on how near it
                // comes.
                let hidden =
                    set.arc(index).is_none() && gap(lo, hi, s.a, s.b) > reach + 1e-6 * extent;
                if !hidden {
                    self.indices[kept] = index;
                    kept += 1;
                }
            }
            start = end;
            self.starts[k + 1] = kept as u32;
        }
        self.indices.truncate(kept);
    }

    /// The number of arcs filled.
    pub fn arcs(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// Arc `k`'s segments, in ascending index order (empty beyond the
    /// arcs filled).
    #[inline]
    pub fn arc(&self, k: usize) -> &[u32] {
        match (self.starts.get(k), self.starts.get(k + 1)) {
            (Some(&a), Some(&b)) => &self.indices[a as usize..b as usize],
            _ => &[],
        }
    }
}

/// How far from the box (of corners `corners`) rays in the cone from `d0`
/// to `d1` (unit vectors, less than half a turn apart) can go before
/// segment `a b` stops them, if every such ray crosses its inside: the
/// largest distance of the eight rays from the corners along the cone's
/// edges. (A ray's distance to the segment's line is its origin's
/// distance, largest at a corner, over the cosine of its angle to the
/// normal, largest at an edge of the cone; where it crosses the line moves
/// monotonically between the same extremes.) `None` unless the box lies
/// wholly on one side of the line, clear of it by a millionth of `scale`,
/// and each of the eight rays meets the line at more than a thousandth of
/// a radian and crosses it clear of the segment's ends by a thousand
/// times the rounding any of them could carry.
fn blocked_beyond(
    a: DVec2,
    b: DVec2,
    corners: &[DVec2; 4],
    d0: DVec2,
    d1: DVec2,
    scale: f64,
) -> Option<f64> {
    let e = b - a;
    let length = e.length();
    let extent = scale.max(a.abs().max(b.abs()).max_element());
    let usable = length > 0.0 && extent.is_finite();
    if !usable {
        return None;
    }
    let tangent = e / length;
    // The normal pointing from the line towards the far side.
    let mut normal = tangent.perp();
    let sides = corners.map(|c| normal.dot(c - a));
    let clear = 1e-6 * extent;
    if sides.iter().all(|&h| h > clear) {
        normal = -normal;
    } else if !sides.iter().all(|&h| h < -clear) {
        return None;
    }
    let slack = 1e3 * DISTANCE_MARGIN * (1.0 + extent);
    let mut farthest: f64 = 0.0;
    for d in [d0, d1] {
        let cosine = d.dot(normal);
        let steep = cosine > 1e-3;
        if !steep {
            return None;
        }
        for &c in corners {
            let distance = -normal.dot(c - a);
            let t = distance / cosine;
            let along = tangent.dot(c + d * t - a);
            if !(along > slack / cosine && along < length - slack / cosine) {
                return None;
            }
            farthest = farthest.max(t);
        }
    }
    Some(farthest)
}

/// The arcs, `first..first + count` taken modulo `arcs`, that hold every
/// direction from a point of the box `[lo, hi]` to a point within about
/// `margin` of segment `a b`, with room to spare: every arc whose
/// [`Wedge`] can meet the segment. All arcs where the segment comes near
/// the box (within a millionth of the coordinates), where nothing is
/// finite, or where the directions span nearly the whole circle.
///
/// The directions from the box to the segment are those of the points of
/// the convex polygon `segment - box`, whose vertices are the segment's
/// ends less the box's corners. Away from the origin the polygon spans
/// less than half a turn, so the extreme directions are two of its eight
/// vertices, found by cross products; only those two take an `atan2`.
/// The range is then widened by the arcs' own margin and by the angle
/// the distance margin subtends at the polygon's least distance, both
/// several times over.
fn arc_range(lo: DVec2, hi: DVec2, a: DVec2, b: DVec2, arcs: usize, margin: f64) -> (usize, usize) {
    let all = (0, arcs);
    let least = gap(lo, hi, a, b);
    let scale = lo
        .abs()
        .max(hi.abs())
        .max(a.abs())
        .max(b.abs())
        .max_element();
    let apart = least > 1e-6 * scale && least > 1e3 * margin && scale.is_finite();
    if !apart {
        return all;
    }
    let corners = box_corners(lo, hi);
    // A direction inside the span: from the box's centre to the
    // segment's middle, a point of the polygon.
    let inside = (a + b) * 0.5 - (lo + hi) * 0.5;
    let (mut most_cw, mut most_ccw) = (inside, inside);
    for c in corners {
        for v in [a - c, b - c] {
            if cross(most_cw, v) < 0.0 {
                most_cw = v;
            }
            if cross(most_ccw, v) > 0.0 {
                most_ccw = v;
            }
        }
    }
    let width = std::f64::consts::TAU / arcs as f64;
    let pad = 4.0 * ARC_MARGIN + 4.0 * margin / least + 1e-9;
    let from = most_cw.y.atan2(most_cw.x) - pad;
    let mut to = most_ccw.y.atan2(most_ccw.x) + pad;
    if to < from {
        to += std::f64::consts::TAU;
    }
    let within_half_turn = to - from < std::f64::consts::PI;
    if !within_half_turn {
        return all;
    }
    let first = (from / width).floor();
    let last = (to / width).floor();
    let count = (last - first) as usize + 1;
    if count >= arcs {
        return all;
    }
    let first = (first as i64).rem_euclid(arcs as i64) as usize;
    (first, count)
}

/// The corners of the box `[lo, hi]`, counter-clockwise from `lo` (in a
/// y-up frame).
fn box_corners(lo: DVec2, hi: DVec2) -> [DVec2; 4] {
    [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
}

/// A lower bound on the distance between the box `[lo, hi]` and segment
/// `a b`: the widest gap between their extents along either axis
/// (negative where both extents overlap).
fn gap(lo: DVec2, hi: DVec2, a: DVec2, b: DVec2) -> f64 {
    (lo - a.max(b)).max(a.min(b) - hi).max_element()
}

/// The region swept by rays leaving a box with directions in a cone less
/// than half a turn wide.
struct Wedge {
    lo: DVec2,
    hi: DVec2,
    corners: [DVec2; 4],
    /// The cone's edge directions, `d1` counter-clockwise from `d0`.
    d0: DVec2,
    d1: DVec2,
}

impl Wedge {
    fn new(lo: DVec2, hi: DVec2, d0: DVec2, d1: DVec2) -> Wedge {
        Wedge {
            lo,
            hi,
            corners: box_corners(lo, hi),
            d0,
            d1,
        }
    }

    /// Whether segment `a b` comes within about `margin` of the region:
    /// `false` only when a separating line clears both by `margin`.
    fn meets(&self, a: DVec2, b: DVec2, margin: f64) -> bool {
        let Wedge {
            lo,
            hi,
            corners,
            d0,
            d1,
        } = *self;
        // The cone's edges, from the corners farthest out on each side
        // (|d| = 1, so the cross products are distances).
        let c0 = corners
            .map(|v| cross(d0, v))
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        if cross(d0, a) < c0 - margin && cross(d0, b) < c0 - margin {
            return false;
        }
        let c1 = corners
            .map(|v| cross(d1, v))
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max);
        if cross(d1, a) > c1 + margin && cross(d1, b) > c1 + margin {
            return false;
        }
        // The box's edges that face away from every direction of the cone.
        if d0.x >= 0.0 && d1.x >= 0.0 && a.x < lo.x - margin && b.x < lo.x - margin {
            return false;
        }
        if d0.x <= 0.0 && d1.x <= 0.0 && a.x > hi.x + margin && b.x > hi.x + margin {
            return false;
        }
        if d0.y >= 0.0 && d1.y >= 0.0 && a.y < lo.y - margin && b.y < lo.y - margin {
            return false;
        }
        if d0.y <= 0.0 && d1.y <= 0.0 && a.y > hi.y + margin && b.y > hi.y + margin {
            return false;
        }
        // The segment's own line: the whole region on one side of it, and
        // moving away along every direction of the cone.
        let e = b - a;
        let reach = margin * e.length();
        let side = corners.map(|v| cross(e, v - a));
        let (least, most) = side
            .into_iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, m), s| {
                (l.min(s), m.max(s))
            });
        let (e0, e1) = (cross(e, d0), cross(e, d1));
        if least > reach && e0 >= 0.0 && e1 >= 0.0 {
            return false;
        }
        if most < -reach && e0 <= 0.0 && e1 <= 0.0 {
            return false;
        }
        true
    }
}

/// The most points [`hull_candidates`] takes a hull of.
pub const MAX_HULL_POINTS: usize = 8;

/// Writes to `out` (ascending) the indices of the segments of `set` that
/// come within a relative `1e-9` of the convex hull of `points`: every
/// segment that a ray from one point of the hull to another can cross.
/// `points` may repeat or be collinear. With none, nothing is listed; with
/// more than [`MAX_HULL_POINTS`] or any not finite, every segment is
/// (nothing is culled). Allocates nothing once `out` has grown.
pub fn hull_candidates(set: &SegmentSet, points: &[DVec2], out: &mut Vec<u32>) {
    out.clear();
    if points.is_empty() {
        return;
    }
    let mut buffer = [DVec2::ZERO; 2 * MAX_HULL_POINTS + 1];
    let Some(hull) = convex_hull(points, &mut buffer) else {
        out.extend(0..set.len() as u32);
        return;
    };
    let scale = hull
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    for index in 0..set.len() as u32 {
        if set.arc(index).is_some() {
            // Every arc: a superset.
            out.push(index);
            continue;
        }
        let segment = set.get(index);
        let extent = scale.max(segment.a.abs().max(segment.b.abs()).max_element());
        if meets_polygon(hull, segment.a, segment.b, DISTANCE_MARGIN * (1.0 + extent)) {
            out.push(index);
        }
    }
}

/// The convex hull of `points`, counter-clockwise (in a y-up frame),
/// without collinear points (Andrew's monotone chain), written in `hull`:
/// one or two points for a point or a segment. `None` for more than
/// [`MAX_HULL_POINTS`] points or any that is not finite.
pub fn convex_hull<'h>(
    points: &[DVec2],
    hull: &'h mut [DVec2; 2 * MAX_HULL_POINTS + 1],
) -> Option<&'h [DVec2]> {
    if points.len() > MAX_HULL_POINTS || points.iter().any(|q| !q.is_finite()) {
        return None;
    }
    let mut sorted = [DVec2::ZERO; MAX_HULL_POINTS];
    let sorted = &mut sorted[..points.len()];
    sorted.copy_from_slice(points);
    sorted.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    // Without repeats.
    let mut n = 0;
    for k in 0..sorted.len() {
        if n == 0 || sorted[k] != sorted[n - 1] {
            sorted[n] = sorted[k];
            n += 1;
        }
    }
    let sorted = &sorted[..n];
    if n < 3 {
        hull[..n].copy_from_slice(sorted);
        return Some(&hull[..n]);
    }
    // The lower chain left to right, then the upper chain right to left;
    // each chain's last point is the next one's first.
    let mut len = 0;
    for pass in 0..2 {
        let start = len;
        for k in 0..n {
            let q = if pass == 0 {
                sorted[k]
            } else {
                sorted[n - 1 - k]
            };
            while len >= start + 2 && cross(hull[len - 1] - hull[len - 2], q - hull[len - 2]) <= 0.0
            {
                len -= 1;
            }
            hull[len] = q;
            len += 1;
        }
        len -= 1;
    }
    Some(&hull[..len])
}

/// Whether segment `a b` comes within about `margin` of the convex
/// polygon `hull` (counter-clockwise; one or two points stand for a point
/// or a segment): `false` only when a separating line clears both by
/// `margin`. The candidate lines are the polygon's edges (both sides, so
/// that degenerate and clockwise-by-rounding polygons stay conservative)
/// and the segment's own line.
fn meets_polygon(hull: &[DVec2], a: DVec2, b: DVec2, margin: f64) -> bool {
    if !(a.is_finite() && b.is_finite()) || hull.iter().any(|p| !p.is_finite()) {
        return true;
    }
    let n = hull.len();
    let separates = |o: DVec2, e: DVec2| -> bool {
        // The line through `o` along `e`: the segment on one side, every
        // vertex on the other, by `margin` in distance.
        let length = e.length();
        if length == 0.0 {
            return false;
        }
        let reach = margin * length;
        let (sa, sb) = (cross(e, a - o), cross(e, b - o));
        let (least, most) = hull
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, m), &p| {
                let s = cross(e, p - o);
                (l.min(s), m.max(s))
            });
        (sa > most + reach && sb > most + reach) || (sa < least - reach && sb < least - reach)
    };
    for k in 0..n {
        let (p, q) = (hull[k], hull[(k + 1) % n]);
        if separates(p, q - p) {
            return false;
        }
    }
    // A point or a segment: also the perpendicular directions.
    if n <= 2 {
        let e = if n == 2 { hull[1] - hull[0] } else { DVec2::X };
        if separates(hull[0], e.perp()) || separates(hull[0], e) {
            return false;
        }
        if n == 1 && separates(hull[0], DVec2::Y) {
            return false;
        }
    }
    // The segment's own line.
    let e = b - a;
    let length = e.length();
    if length > 0.0 {
        let reach = margin * length;
        let (least, most) = hull
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, m), &p| {
                let s = cross(e, p - a);
                (l.min(s), m.max(s))
            });
        if least > reach || most < -reach {
            return false;
        }
    }
    true
}

impl SegmentSet {
    /// [`SegmentSet::for_each_crossing`] among `candidates` only
    /// (ascending indices), visited in index order as brute force visits
    /// them: the same calls whenever every segment the ray crosses before
    /// `t_max` is a candidate.
    #[inline]
    pub fn for_each_crossing_among(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        candidates: &[u32],
        mut visit: impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        if self.has_arcs() {
            for &index in candidates {
                let go_on = if self.arc(index).is_some() {
                    self.arc_crossings_visit(ray, t_max, skip, Some(index), &mut visit)
                } else {
                    let s = self.get(index);
                    visit_crossings(
                        ray,
                        t_max,
                        skip,
                        std::iter::once((index, s.a, s.b)),
                        &mut visit,
                    )
                };
                if !go_on {
                    return false;
                }
            }
            return true;
        }
        let segments = candidates.iter().map(|&index| {
            let segment = self.get(index);
            (index, segment.a, segment.b)
        });
        visit_crossings(ray, t_max, skip, segments, &mut visit)
    }

    /// [`SegmentSet::closest_hit_among`] `candidates` where they are
    /// given, else [`SegmentSet::closest_hit`] over the whole set.
    #[inline(always)]
    pub fn closest_hit_within(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        candidates: Option<&[u32]>,
    ) -> Option<(u32, Hit)> {
        match candidates {
            Some(candidates) => self.closest_hit_among(ray, t_max, skip, candidates),
            None => self.closest_hit(ray, t_max, skip),
        }
    }

    /// [`SegmentSet::for_each_crossing_among`] `candidates` where they are
    /// given, else [`SegmentSet::for_each_crossing`] over the whole set.
    #[inline(always)]
    pub fn for_each_crossing_within(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        candidates: Option<&[u32]>,
        visit: impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        match candidates {
            Some(candidates) => self.for_each_crossing_among(ray, t_max, skip, candidates, visit),
            None => self.for_each_crossing(ray, t_max, skip, visit),
        }
    }

    /// [`SegmentSet::closest_hit`] among `candidates` only (ascending
    /// indices): the same answer whenever every segment the ray crosses
    /// before `t_max` is a candidate, as [`ArcCandidates`] guarantees for
    /// rays from its box in their arc. Scalar: the lists are short.
    #[inline]
    pub fn closest_hit_among(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        candidates: &[u32],
    ) -> Option<(u32, Hit)> {
        let mut best = Best::new(t_max);
        if self.has_arcs() {
            for &index in candidates {
                if self.arc(index).is_some() {
                    self.arc_crossings_visit(ray, t_max, skip, Some(index), &mut |i, hit| {
                        if hit.t < best.t {
                            best = Best {
                                t: hit.t,
                                index: i,
                                u: hit.u,
                            };
                        }
                        false
                    });
                    continue;
                }
                let segment = self.get(index);
                if let Some((t, sa, sb)) = crossing_parts(ray.origin, ray.dir, segment.a, segment.b)
                    && t > 0.0
                    && t < best.t
                    && !skip.contains(index)
                {
                    best = Best {
                        t,
                        index,
                        u: sa / (sa - sb),
                    };
                }
            }
            return best.found();
        }
        for &index in candidates {
            let segment = self.get(index);
            let Some((t, sa, sb)) = crossing_parts(ray.origin, ray.dir, segment.a, segment.b)
            else {
                continue;
            };
            // Ascending indices: an equal `t` found later never wins, as
            // in the full scan. (One test where `lanes::closest_scalar`,
            // which takes slots in any order, needs three: shared, this
            // query took 38 % longer in `closest_hit/culled-by-arc`.)
            if !(t > 0.0 && t < best.t) || skip.contains(index) {
                continue;
            }
            best = Best {
                t,
                index,
                u: sa / (sa - sb),
            };
        }
        best.found()
    }
}

/// Rays in lanes, structure-of-arrays: origins `(ox, oy)` and directions
/// `(dx, dy)`, for [`SegmentSet::closest_hits_among`].
#[derive(Clone, Copy, Debug)]
pub struct RayLanes<const N: usize> {
    pub ox: [f64; N],
    pub oy: [f64; N],
    pub dx: [f64; N],
    pub dy: [f64; N],
}

impl RayLanes<1> {
    /// One ray in one lane.
    #[inline]
    pub fn one(ray: &Ray) -> RayLanes<1> {
        RayLanes {
            ox: [ray.origin.x],
            oy: [ray.origin.y],
            dx: [ray.dir.x],
            dy: [ray.dir.y],
        }
    }
}

impl<const N: usize> RayLanes<N> {
    /// Lane `k`'s ray.
    #[inline]
    pub fn ray(&self, k: usize) -> Ray {
        Ray::new(
            DVec2::new(self.ox[k], self.oy[k]),
            DVec2::new(self.dx[k], self.dy[k]),
        )
    }
}

/// The answers of [`SegmentSet::closest_hits_among`], lane by lane:
/// structure-of-arrays, so that each is read back as it was written.
#[derive(Clone, Copy, Debug)]
pub struct HitLanes<const N: usize> {
    /// The segment hit, `u32::MAX` for none.
    pub index: [u32; N],
    pub t: [f64; N],
    pub u: [f64; N],
}

impl<const N: usize> HitLanes<N> {
    /// Lane `k`'s answer, as `closest_hit_among` gives it.
    #[inline(always)]
    pub fn hit(&self, k: usize) -> Option<(u32, Hit)> {
        (self.index[k] != u32::MAX).then_some((
            self.index[k],
            Hit {
                t: self.t[k],
                u: self.u[k],
            },
        ))
    }
}

impl SegmentSet {
    /// [`SegmentSet::closest_hit_among`] for `N` rays at once, with no
    /// limit and nothing skipped: each lane's answer is exactly that
    /// query's (the same operations in the same order, ties to the lower
    /// index). Rays that leave one box in one arc of directions share
    /// their candidates, and here their tests: one segment against every
    /// lane, with no branch. With the AVX kernel and a multiple of four
    /// lanes, four lanes at a time in AVX registers, written out
    /// (`lanes.rs`); otherwise as the compiler vectorises the loop (of the
    /// caller's target features: inlined always).
    #[inline(always)]
    pub fn closest_hits_among<const N: usize>(
        &self,
        rays: &RayLanes<N>,
        candidates: &[u32],
    ) -> HitLanes<N> {
        if self.has_arcs() {
            return self.closest_hits_one_by_one(rays, candidates);
        }
        if let Some(hits) =
            crate::lanes::closest_hits_avx(self.kernel(), self.segments(), rays, candidates)
        {
            return hits;
        }
        let mut best_t = [f64::INFINITY; N];
        let mut best_index = [u32::MAX; N];
        let mut best_sa = [0.0; N];
        let mut best_sb = [0.0; N];
        for &index in candidates {
            let Segment { a, b } = self.get(index);
            let e = b - a;
            for k in 0..N {
                // `crossing_parts`, lane by lane.
                let (pax, pay) = (a.x - rays.ox[k], a.y - rays.oy[k]);
                let (pbx, pby) = (b.x - rays.ox[k], b.y - rays.oy[k]);
                let sa = rays.dx[k] * pay - rays.dy[k] * pax;
                let sb = rays.dx[k] * pby - rays.dy[k] * pbx;
                let apart =
                    (sa > 0.0 && sb > 0.0) | (sa < 0.0 && sb < 0.0) | (sa == 0.0 && sb == 0.0);
                let t = (pax * e.y - pay * e.x) / (sb - sa);
                // Ascending indices: an equal `t` found later never wins.
                let wins = !apart & (t > 0.0) & (t < best_t[k]);
                best_t[k] = if wins { t } else { best_t[k] };
                best_index[k] = if wins { index } else { best_index[k] };
                best_sa[k] = if wins { sa } else { best_sa[k] };
                best_sb[k] = if wins { sb } else { best_sb[k] };
            }
        }
        let mut u = [0.0; N];
        for k in 0..N {
            u[k] = best_sa[k] / (best_sa[k] - best_sb[k]);
        }
        HitLanes {
            index: best_index,
            t: best_t,
            u,
        }
    }
}

impl SegmentSet {
    /// [`SegmentSet::closest_hits_among`] where arcs are among the walls,
    /// which have no lane kernel: each ray alone. Kept out of line, so
    /// that the lane kernels' callers stay as small as without arcs.
    #[cold]
    #[inline(never)]
    fn closest_hits_one_by_one<const N: usize>(
        &self,
        rays: &RayLanes<N>,
        candidates: &[u32],
    ) -> HitLanes<N> {
        let mut out = HitLanes {
            index: [u32::MAX; N],
            t: [f64::INFINITY; N],
            u: [0.0; N],
        };
        for k in 0..N {
            if let Some((index, hit)) =
                self.closest_hit_among(&rays.ray(k), f64::INFINITY, Skip::NONE, candidates)
            {
                (out.index[k], out.t[k], out.u[k]) = (index, hit.t, hit.u);
            }
        }
        out
    }
}

impl SegmentSet {
    /// [`SegmentSet::closest_hits_among`] for a single ray: its
    /// candidates four at a time, each candidate's test in a lane (as the
    /// compiler vectorises it), then the lanes compared in order. The same
    /// operations as that query's one lane, so the same answer, bit for
    /// bit; a short last group repeats its first candidate, whose equal
    /// `t` never wins twice.
    #[inline(always)]
    pub fn closest_hit_among_wide(&self, ray: &Ray, candidates: &[u32]) -> HitLanes<1> {
        const W: usize = 4;
        if self.has_arcs() {
            return self.closest_hits_one_by_one(&RayLanes::one(ray), candidates);
        }
        let segments = self.segments();
        let none = Segment {
            a: DVec2::NAN,
            b: DVec2::NAN,
        };
        let (o, d) = (ray.origin, ray.dir);
        let (mut best_t, mut best_index, mut best_sa, mut best_sb) =
            (f64::INFINITY, u32::MAX, 0.0, 0.0);
        for group in candidates.chunks(W) {
            let mut index = [group[0]; W];
            index[..group.len()].copy_from_slice(group);
            let segment = index.map(|i| segments.get(i as usize).copied().unwrap_or(none));
            let (mut sa, mut sb, mut t, mut crosses) = ([0.0; W], [0.0; W], [0.0; W], [false; W]);
            for k in 0..W {
                // `crossing_parts`, lane by lane.
                let Segment { a, b } = segment[k];
                let (pax, pay) = (a.x - o.x, a.y - o.y);
                let (pbx, pby) = (b.x - o.x, b.y - o.y);
                sa[k] = d.x * pay - d.y * pax;
                sb[k] = d.x * pby - d.y * pbx;
                let apart = (sa[k] > 0.0 && sb[k] > 0.0)
                    | (sa[k] < 0.0 && sb[k] < 0.0)
                    | (sa[k] == 0.0 && sb[k] == 0.0);
                let e = b - a;
                t[k] = (pax * e.y - pay * e.x) / (sb[k] - sa[k]);
                crosses[k] = !apart & (t[k] > 0.0);
            }
            for k in 0..W {
                if crosses[k] && t[k] < best_t {
                    (best_t, best_index, best_sa, best_sb) = (t[k], index[k], sa[k], sb[k]);
                }
            }
        }
        HitLanes {
            index: [best_index],
            t: [best_t],
            u: [best_sa / (best_sa - best_sb)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Every arc's wedge tested against every segment: what
    /// [`ArcCandidates::fill`] would list without [`arc_range`].
    fn every_arc(set: &SegmentSet, lo: DVec2, hi: DVec2, arcs: usize) -> Vec<Vec<u32>> {
        let scale = lo.abs().max(hi.abs()).max_element();
        let mut c = ArcCandidates::default();
        c.fill(set, lo, hi, arcs, None);
        c.edges
            .iter()
            .map(|&(d0, d1)| {
                let wedge = Wedge::new(lo, hi, d0, d1);
                (0..set.len() as u32)
                    .filter(|&i| {
                        let s = set.get(i);
                        let extent = scale.max(s.a.abs().max(s.b.abs()).max_element());
                        wedge.meets(s.a, s.b, DISTANCE_MARGIN * (1.0 + extent))
                    })
                    .collect()
            })
            .collect()
    }

    fn coordinate() -> impl Strategy<Value = f64> {
        prop_oneof![
            -50.0..50.0f64,
            (-20i32..20).prop_map(f64::from),
            (-1e6..1e6f64),
            (-1e-5..1e-5f64),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, rng_seed: proptest::test_runner::RngSeed::Fixed(5), ..ProptestConfig::default() })]

        /// The arcs a segment is tested against hold every arc whose
        /// wedge meets it: the lists are exactly those of testing every
        /// arc, for boxes near and far, large and tiny, and segments along
        /// the box's edges and through its corners.
        #[test]
        fn arc_ranges_lose_no_arc(
            (x, y) in (coordinate(), coordinate()),
            (w, h) in (prop_oneof![1e-6..1e-3f64, 0.1..4.0f64, Just(1.0)], prop_oneof![1e-6..1e-3f64, 0.1..4.0f64, Just(1.0)]),
            ends in prop::collection::vec((coordinate(), coordinate(), coordinate(), coordinate()), 1..40),
            arcs in prop_oneof![Just(8usize), Just(16), Just(64), Just(7)],
        ) {
            let lo = DVec2::new(x, y);
            let hi = lo + DVec2::new(w, h);
            let corners = box_corners(lo, hi);
            let segments: Vec<Segment> = ends
                .iter()
                .enumerate()
                .map(|(i, &(ax, ay, bx, by))| match i % 4 {
                    // From a corner of the box, or along one of its edges.
                    0 => Segment::new(corners[i % 3], DVec2::new(bx, by)),
                    1 => Segment::new(corners[0] + DVec2::new(0.0, ay.abs() + h), corners[3] + DVec2::new(0.0, by.abs() + h)),
                    _ => Segment::new(DVec2::new(ax, ay), DVec2::new(bx, by)),
                })
                .filter(|s| s.a != s.b)
                .collect();
            let set = SegmentSet::new(segments);
            let mut c = ArcCandidates::default();
            c.fill(&set, lo, hi, arcs, None);
            let expected = every_arc(&set, lo, hi, arcs);
            for (k, list) in expected.iter().enumerate() {
                prop_assert_eq!(c.arc(k), &list[..], "arc {} of {}", k, arcs);
            }
            // Filled within a larger box's lists: the same again.
            let outer = ArcCandidates { ..c.clone() };
            let mut inner = ArcCandidates::default();
            let mid = (lo + hi) * 0.5;
            inner.fill(&set, lo, mid, arcs, Some(&outer));
            let expected = every_arc(&set, lo, mid, arcs);
            for (k, list) in expected.iter().enumerate() {
                prop_assert_eq!(inner.arc(k), &list[..], "inner arc {} of {}", k, arcs);
            }
        }
    }
}
