//! Segments that lie on top of each other: which ones do, and their
//! common line cut into pieces at every endpoint.
//!
//! Two segments *overlap* when each endpoint of the shorter lies within
//! [`ALONG_TOLERANCE`] (relative to the coordinates' magnitude) of the
//! longer's line and their extents along that line share more than that
//! length. Closer than that, rounding decides which of the two a ray
//! meets first and on which side of the other a point computed on one
//! lies, so no query could keep them apart; farther, they are two walls,
//! and the crossing rule keeps each closed. The finding is independent of
//! the order the segments are given in.

use crate::{DVec2, Segment, cross};

/// How far from another segment's line (relative to the coordinates'
/// magnitude) a segment may lie and still lie on it: far beyond the
/// rounding of a point computed on either (about 1e-16 of the
/// magnitude), and far below anything drawn on purpose.
pub const ALONG_TOLERANCE: f64 = 1e-9;

/// How near a segment must lie to another's line to lie on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// [`ALONG_TOLERANCE`] of the coordinates' magnitude: the rule for
    /// walls in a scene (`docs/robustness.md`, rule 8).
    Rounding,
    /// At most this distance, or the rounding's if that is larger: for
    /// plans drawn by hand or exported in single precision.
    Distance(f64),
}

impl Tolerance {
    fn between(self, a: &Segment, b: &Segment) -> f64 {
        let rounding = tolerance(a, b);
        match self {
            Tolerance::Rounding => rounding,
            Tolerance::Distance(d) => rounding.max(d),
        }
    }

    /// The most it can be among segments of coordinates up to `magnitude`.
    fn at_most(self, magnitude: f64) -> f64 {
        let rounding = ALONG_TOLERANCE * magnitude.max(f64::MIN_POSITIVE);
        match self {
            Tolerance::Rounding => rounding,
            Tolerance::Distance(d) => rounding.max(d),
        }
    }
}

/// The distance within which two points of segments `a` and `b` count as
/// one: [`ALONG_TOLERANCE`] of the largest coordinate or length.
fn tolerance(a: &Segment, b: &Segment) -> f64 {
    let magnitude =
        a.a.abs()
            .max(a.b.abs())
            .max(b.a.abs())
            .max(b.b.abs())
            .max_element()
            .max(a.length())
            .max(b.length());
    ALONG_TOLERANCE * magnitude.max(f64::MIN_POSITIVE)
}

/// Whether both ends of `other` lie within `tolerance` of the line through
/// `host` (a segment of positive length).
pub fn lies_along(host: &Segment, other: &Segment, tolerance: Tolerance) -> bool {
    let e = host.edge();
    let length = e.length();
    if length.is_nan() || length <= 0.0 {
        return false;
    }
    let tol = tolerance.between(host, other);
    [other.a, other.b]
        .iter()
        .all(|&p| (cross(e, p - host.a) / length).abs() <= tol)
}

/// Whether `a` and `b` lie on one line and share a stretch of it longer
/// than the tolerance. Symmetric in its arguments.
pub fn overlap(a: &Segment, b: &Segment, tolerance: Tolerance) -> bool {
    // The longer is the host (ties by coordinates, so the answer does not
    // depend on the order of the arguments).
    let (host, other) = if (a.length(), key(a)) >= (b.length(), key(b)) {
        (a, b)
    } else {
        (b, a)
    };
    if !lies_along(host, other, tolerance) {
        return false;
    }
    let e = host.edge();
    let length = e.length();
    let along = |p: DVec2| (p - host.a).dot(e) / length;
    let (s0, s1) = (along(other.a), along(other.b));
    let shared = s0.max(s1).min(length) - s0.min(s1).max(0.0);
    shared > tolerance.between(host, other)
}

/// A segment's endpoints as a tuple that orders segments by coordinates.
fn key(s: &Segment) -> (f64, f64, f64, f64) {
    (s.a.x, s.a.y, s.b.x, s.b.y)
}

/// The segment's direction made unique up to sign: `y > 0`, or `y == 0`
/// and `x > 0`.
fn canonical_direction(s: &Segment) -> DVec2 {
    let d = s.edge().normalize_or_zero();
    if d.y < 0.0 || (d.y == 0.0 && d.x < 0.0) {
        -d
    } else {
        d
    }
}

/// Width of the buckets of directions in which candidates are sought: two
/// segments that overlap within [`Tolerance::Rounding`] differ in
/// direction by far less.
const BUCKET: f64 = 1e-4;

/// The groups of segments that overlap within [`Tolerance::Rounding`],
/// each of at least two, connected
/// by overlaps (if `a` overlaps `b` and `b` overlaps `c`, all three are one
/// group). Only the segments that `eligible` keeps take part. Members are
/// in increasing index order and groups by their first member, whatever
/// the order of the input.
///
/// Candidates are found by direction (buckets of 1e-4 rad, each searched
/// with its neighbour), then by the line's offset from the origin, then
/// by the extent along the line, so a plan of many walls end to end costs
/// about `n log n`.
pub fn overlap_groups(segments: &[Segment], eligible: impl Fn(usize) -> bool) -> Vec<Vec<usize>> {
    let tolerance = Tolerance::Rounding;
    let magnitude = segments
        .iter()
        .map(|s| s.a.abs().max(s.b.abs()).max_element().max(s.length()))
        .fold(0.0f64, f64::max);
    if !magnitude.is_finite() {
        return Vec::new();
    }
    // Two points of one line differ in offset by at most their distance
    // off it, twice the tolerance, plus the direction's rounding.
    let window = 8.0 * tolerance.at_most(magnitude);
    // (bucket, offset, index, direction): every segment once, and those
    // within a bucket of the direction's wrap at pi once more, flipped.
    let mut entries: Vec<(i64, f64, usize, DVec2)> = Vec::new();
    for (i, s) in segments.iter().enumerate() {
        if !eligible(i)
            || s.length().is_nan()
            || s.length() <= 0.0
            || !s.a.is_finite()
            || !s.b.is_finite()
        {
            continue;
        }
        let d = canonical_direction(s);
        let angle = d.y.atan2(d.x).max(0.0);
        let offset = cross(d, s.a);
        entries.push(((angle / BUCKET).floor() as i64, offset, i, d));
        if angle > std::f64::consts::PI - 2.0 * BUCKET {
            let flipped = angle - std::f64::consts::PI;
            entries.push(((flipped / BUCKET).floor() as i64, -offset, i, -d));
        }
    }
    entries.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)).then(x.2.cmp(&y.2)));

    let mut parent: Vec<usize> = (0..segments.len()).collect();
    let mut pool: Vec<(f64, usize, DVec2)> = Vec::new();
    let mut start = 0;
    while start < entries.len() {
        let bucket = entries[start].0;
        let end = start + entries[start..].partition_point(|e| e.0 == bucket);
        let next_end = end + entries[end..].partition_point(|e| e.0 == bucket + 1);
        // This bucket with the next one, by offset.
        pool.clear();
        pool.extend(entries[start..next_end].iter().map(|e| (e.1, e.2, e.3)));
        pool.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut c0 = 0;
        while c0 < pool.len() {
            // A cluster: offsets chained within the window.
            let mut c1 = c0 + 1;
            while c1 < pool.len() && pool[c1].0 - pool[c1 - 1].0 <= window {
                c1 += 1;
            }
            if c1 - c0 > 1 {
                join_cluster(segments, &pool[c0..c1], (tolerance, window), &mut parent);
            }
            c0 = c1;
        }
        start = end;
    }

    // Every root is its group's least index.
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for i in 0..segments.len() {
        let root = find(&mut parent, i);
        groups.entry(root).or_default().push(i);
    }
    groups.into_values().filter(|g| g.len() > 1).collect()
}

/// Joins the overlapping pairs among `cluster` (segments of about one
/// direction and offset), sweeping their extents along that direction.
fn join_cluster(
    segments: &[Segment],
    cluster: &[(f64, usize, DVec2)],
    (tolerance, window): (Tolerance, f64),
    parent: &mut [usize],
) {
    let d = cluster[0].2;
    let mut spans: Vec<(f64, f64, usize)> = cluster
        .iter()
        .map(|&(_, i, _)| {
            let s = &segments[i];
            let (p, q) = (s.a.dot(d), s.b.dot(d));
            (p.min(q), p.max(q), i)
        })
        .collect();
    spans.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.2.cmp(&y.2)));
    // The extents still open, one per group among them (the one reaching
    // farthest): a segment that overlaps a group's member lies along the
    // group's line and starts within its farthest member's extent.
    let mut active: Vec<(f64, usize)> = Vec::new();
    for &(lo, hi, i) in &spans {
        active.retain(|&(end, _)| end > lo - window);
        for &(_, j) in &active {
            if j != i
                && find(parent, i) != find(parent, j)
                && overlap(&segments[i], &segments[j], tolerance)
            {
                let (ri, rj) = (find(parent, i), find(parent, j));
                parent[ri.max(rj)] = ri.min(rj);
            }
        }
        active.push((hi, i));
        if active.len() > 64 {
            // Keep the farthest-reaching extent of each group.
            active.sort_by(|x, y| y.0.total_cmp(&x.0));
            let mut seen = std::collections::HashSet::new();
            active.retain(|&(_, j)| seen.insert(find(parent, j)));
        }
    }
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// A group's common line cut at every endpoint of its members.
#[derive(Clone, Debug, PartialEq)]
pub struct Pieces {
    /// The members' distinct endpoints, in order along the line. Piece `k`
    /// runs from `points[k]` to `points[k + 1]`.
    pub points: Vec<DVec2>,
    /// For each member, in the group's order, the pieces it covers,
    /// `lo..hi` (positions of its ends in `points`).
    pub spans: Vec<std::ops::Range<usize>>,
    /// For each member, in the group's order, whether it runs the way the
    /// points do (its `a` at the lower position).
    pub forward: Vec<bool>,
}

impl Pieces {
    /// Whether member `g` (a position in the group) covers piece `k`.
    pub fn covers(&self, g: usize, k: usize) -> bool {
        self.spans.get(g).is_some_and(|span| span.contains(&k))
    }
}

/// Cuts the line of `group` (members of one of [`overlap_groups`]'s
/// groups) at every endpoint. The pieces share their endpoints exactly,
/// and each endpoint is a member's own, so that the pieces join each
/// other, and the walls that met the members' ends, with no gap. The
/// result does not depend on the order of `group` or of `segments`, only
/// on the members' coordinates. Time `m log m`, memory `m`, for `m`
/// members.
pub fn pieces(segments: &[Segment], group: &[usize]) -> Pieces {
    // The line's direction and origin from the longest member (ties by
    // coordinates), so that any order of the members gives them.
    let reference = group
        .iter()
        .map(|&i| &segments[i])
        .max_by(|x, y| {
            x.length()
                .total_cmp(&y.length())
                .then_with(|| key_cmp(&key(y), &key(x)))
        })
        .copied()
        .unwrap_or(Segment::new(DVec2::ZERO, DVec2::X));
    let d = canonical_direction(&reference);
    let origin = if (reference.a - reference.b).dot(d) <= 0.0 {
        reference.a
    } else {
        reference.b
    };
    let along = |p: DVec2| (p - origin).dot(d);
    let order = |x: &(f64, DVec2), y: &(f64, DVec2)| {
        x.0.total_cmp(&y.0)
            .then(x.1.x.total_cmp(&y.1.x))
            .then(x.1.y.total_cmp(&y.1.y))
    };
    let mut points: Vec<(f64, DVec2)> = group
        .iter()
        .flat_map(|&i| [segments[i].a, segments[i].b])
        .map(|p| (along(p), p))
        .collect();
    points.sort_by(order);
    points.dedup_by(|x, y| x.1 == y.1);
    // Each end's position in `points`, found by the same order.
    let position = |p: DVec2| {
        let key = (along(p), p);
        points
            .binary_search_by(|q| order(q, &key))
            .unwrap_or_else(|k| k.min(points.len().saturating_sub(1)))
    };
    let (spans, forward) = group
        .iter()
        .map(|&i| {
            let (pa, pb) = (position(segments[i].a), position(segments[i].b));
            (pa.min(pb)..pa.max(pb), pa <= pb)
        })
        .unzip();
    Pieces {
        points: points.into_iter().map(|(_, p)| p).collect(),
        spans,
        forward,
    }
}

fn key_cmp(x: &(f64, f64, f64, f64), y: &(f64, f64, f64, f64)) -> std::cmp::Ordering {
    x.0.total_cmp(&y.0)
        .then(x.1.total_cmp(&y.1))
        .then(x.2.total_cmp(&y.2))
        .then(x.3.total_cmp(&y.3))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(a: (f64, f64), b: (f64, f64)) -> Segment {
        Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1))
    }

    #[test]
    fn duplicates_parts_and_reversed_copies_overlap_and_chains_do_not() {
        let on = |a: &Segment, b: &Segment| overlap(a, b, Tolerance::Rounding);
        let wall = seg((0.0, 0.0), (10.0, 0.0));
        assert!(on(&wall, &wall));
        assert!(on(&wall, &seg((10.0, 0.0), (0.0, 0.0))));
        assert!(on(&wall, &seg((3.0, 0.0), (6.0, 0.0))));
        assert!(on(&seg((6.0, 0.0), (3.0, 0.0)), &wall));
        assert!(on(&wall, &seg((8.0, 0.0), (12.0, 0.0))));
        // End to end, apart, parallel and near, crossing: not on one line.
        assert!(!on(&wall, &seg((10.0, 0.0), (20.0, 0.0))));
        assert!(!on(&wall, &seg((11.0, 0.0), (20.0, 0.0))));
        assert!(!on(&wall, &seg((2.0, 1e-6), (8.0, 1e-6))));
        assert!(!on(&wall, &seg((2.0, -1.0), (8.0, 1.0))));
        // Within rounding of the line, turned: on it.
        let (s, c) = 0.3f64.sin_cos();
        let turn = |x: f64| DVec2::new(100.0 + c * x, 50.0 + s * x);
        let long = Segment::new(turn(0.0), turn(40.0));
        let part = Segment::new(turn(12.5), turn(27.25));
        assert!(on(&long, &part) && on(&part, &long));
        // Within a distance: a hand-drawn window a little off the wall.
        let near = seg((2.0, 0.3), (8.0, -0.2));
        assert!(!on(&wall, &near));
        assert!(overlap(&wall, &near, Tolerance::Distance(0.5)));
        assert!(!overlap(&wall, &near, Tolerance::Distance(0.25)));
    }

    #[test]
    fn groups_are_found_whatever_the_order_and_across_the_directions_wrap() {
        let mut segments = vec![
            seg((0.0, 0.0), (10.0, 0.0)),
            seg((10.0, 0.0), (20.0, 0.0)),
            seg((15.0, 0.0), (25.0, 0.0)),
            seg((5.0, 5.0), (5.0, 9.0)),
            // Nearly horizontal both ways: directions just below pi and
            // just above 0, one line.
            seg((0.0, 30.0), (40.0, 30.0 - 1e-12)),
            seg((35.0, 30.0 - 1e-12 * 35.0 / 40.0), (20.0, 30.0 - 0.5e-12)),
            seg((5.0, 5.0), (5.0, 7.0)),
        ];
        let groups = overlap_groups(&segments, |_| true);
        assert_eq!(groups, vec![vec![1, 2], vec![3, 6], vec![4, 5]]);
        segments.reverse();
        assert_eq!(
            overlap_groups(&segments, |_| true),
            vec![vec![0, 3], vec![1, 2], vec![4, 5]]
        );
        assert_eq!(
            overlap_groups(&segments, |i| i != 3),
            vec![vec![1, 2], vec![4, 5]]
        );
    }

    #[test]
    fn many_walls_end_to_end_form_no_group() {
        let segments: Vec<Segment> = (0..20_000)
            .map(|i| {
                let (row, k) = ((i / 200) as f64, (i % 200) as f64);
                seg((k, row), (k + 1.0, row))
            })
            .collect();
        assert!(overlap_groups(&segments, |_| true).is_empty());
    }

    #[test]
    fn pieces_cut_the_line_at_every_endpoint_and_share_them() {
        let segments = vec![
            seg((0.0, 0.0), (10.0, 0.0)),
            seg((6.0, 0.0), (3.0, 0.0)),
            seg((8.0, 0.0), (12.0, 0.0)),
        ];
        let p = pieces(&segments, &[0, 1, 2]);
        let xs: Vec<f64> = p.points.iter().map(|q| q.x).collect();
        assert_eq!(xs, vec![0.0, 3.0, 6.0, 8.0, 10.0, 12.0]);
        assert_eq!(p.spans, vec![0..4, 1..2, 3..5]);
        let cover: Vec<Vec<usize>> = (0..5)
            .map(|k| (0..3).filter(|&g| p.covers(g, k)).collect())
            .collect();
        assert_eq!(
            cover,
            vec![vec![0], vec![0, 1], vec![0], vec![0, 2], vec![2]]
        );
        assert_eq!(p.forward, vec![true, false, true]);
        // Another order of the members and of the segments: the same cut.
        let mut shuffled = segments.clone();
        shuffled.rotate_left(1);
        let q = pieces(&shuffled, &[2, 1, 0]);
        assert_eq!(q.points, p.points);
    }
}
