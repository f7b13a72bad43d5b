//! A set of segments with closest-hit and all-crossings queries: brute
//! force over a structure-of-arrays copy for small sets, a bounding volume
//! hierarchy for large ones. Both give exactly the same answers.

use crate::{DVec2, Hit, Ray, Segment, crossing_parts};

/// Up to two segment indices that a query ignores: the wall a ray leaves
/// from, and the wall a light sample lies on. A ray that starts on a
/// segment can never meet that same segment again (a straight line meets
/// another line at most once), so skipping it is exact, not an epsilon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Skip(pub u32, pub u32);

impl Skip {
    /// Skip nothing.
    pub const NONE: Skip = Skip(u32::MAX, u32::MAX);

    /// Skip one segment.
    #[inline]
    pub fn one(index: u32) -> Skip {
        Skip(index, u32::MAX)
    }

    #[inline]
    pub fn contains(self, index: u32) -> bool {
        self.0 == index || self.1 == index
    }
}

/// How a [`SegmentSet`] answers queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Test every segment: fastest for a few dozen segments.
    BruteForce,
    /// Walk a bounding volume hierarchy: cost grows like log(segments).
    Bvh,
}

/// Sets with more segments than this use a BVH by default (measured: see
/// `docs/performance.md`).
pub const BVH_THRESHOLD: usize = 8;

/// The segments of a scene, stored once, queried by brute force or through
/// a BVH.
///
/// Segment indices are positions in the vector given to [`SegmentSet::new`].
/// Ties in the closest hit go to the lower index, so both strategies return
/// identical answers.
#[derive(Clone, Debug, Default)]
pub struct SegmentSet {
    segments: Vec<Segment>,
    /// Structure-of-arrays copies of the endpoints, in `order`.
    ax: Vec<f64>,
    ay: Vec<f64>,
    bx: Vec<f64>,
    by: Vec<f64>,
    /// The original index of each stored segment.
    order: Vec<u32>,
    /// Empty for brute force.
    nodes: Vec<Node>,
}

/// A BVH node: its box, and either two children (`count == 0`, children
/// at `first` and `first + 1`) or a leaf of `count` segments from `first`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec2,
    max: DVec2,
    first: u32,
    count: u32,
}

const LEAF_SIZE: usize = 4;
/// Below this depth the build splits by the surface-area heuristic; from
/// it on, at the median, so no tree is deeper than `MAX_SAH_DEPTH + 32`
/// for up to 2^32 segments, and the traversal stack never overflows.
const MAX_SAH_DEPTH: usize = 64;
const STACK: usize = MAX_SAH_DEPTH + 40;

impl SegmentSet {
    /// A set that picks its strategy by size.
    pub fn new(segments: Vec<Segment>) -> SegmentSet {
        let strategy = if segments.len() > BVH_THRESHOLD {
            Strategy::Bvh
        } else {
            Strategy::BruteForce
        };
        SegmentSet::with_strategy(segments, strategy)
    }

    /// A set with the given strategy.
    pub fn with_strategy(segments: Vec<Segment>, strategy: Strategy) -> SegmentSet {
        let mut order: Vec<u32> = (0..segments.len() as u32).collect();
        let mut nodes = Vec::new();
        if strategy == Strategy::Bvh && !segments.is_empty() {
            build(&segments, &mut order, &mut nodes);
        }
        let pick =
            |f: fn(&Segment) -> f64| order.iter().map(|&i| f(&segments[i as usize])).collect();
        SegmentSet {
            ax: pick(|s| s.a.x),
            ay: pick(|s| s.a.y),
            bx: pick(|s| s.b.x),
            by: pick(|s| s.b.y),
            order,
            nodes,
            segments,
        }
    }

    pub fn strategy(&self) -> Strategy {
        if self.nodes.is_empty() {
            Strategy::BruteForce
        } else {
            Strategy::Bvh
        }
    }

    #[inline]
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    #[inline]
    pub fn get(&self, index: u32) -> Segment {
        self.segments[index as usize]
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The stored segments in `slots` with their original indices, as an
    /// iterator over zipped slices (no bounds check per segment).
    #[inline(always)]
    fn stored(
        &self,
        slots: std::ops::Range<usize>,
    ) -> impl Iterator<Item = (DVec2, DVec2, u32)> + '_ {
        let s = slots;
        self.ax[s.clone()]
            .iter()
            .zip(&self.ay[s.clone()])
            .zip(self.bx[s.clone()].iter().zip(&self.by[s.clone()]))
            .zip(&self.order[s])
            .map(|(((&ax, &ay), (&bx, &by)), &index)| {
                (DVec2::new(ax, ay), DVec2::new(bx, by), index)
            })
    }

    /// Tests the stored segments in `slots` against `ray` and keeps the
    /// nearest crossing in `best`. (Two
    /// branch-free variants, computing every `t` and selecting the least,
    /// measured slower on this scalar-f64 target: the divisions cost more
    /// than the mispredicted branches they avoid.)
    #[inline(always)]
    fn closest_in(
        &self,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        best: &mut Best,
    ) {
        for (a, b, index) in self.stored(slots) {
            let Some((t, sa, sb)) = crossing_parts(ray.origin, ray.dir, a, b) else {
                continue;
            };
            if !(t > 0.0 && t < t_max) || t > best.t {
                continue;
            }
            if skip.contains(index) || (t == best.t && index >= best.index) {
                continue;
            }
            *best = Best {
                t,
                index,
                u: sa / (sa - sb),
            };
        }
    }

    /// Calls `visit` for the crossings with `0 < t < t_max` among `slots`,
    /// in slot order; `false` when `visit` stopped it.
    #[inline(always)]
    fn crossings_in<F: FnMut(u32, Hit) -> bool>(
        &self,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        visit: &mut F,
    ) -> bool {
        for (a, b, index) in self.stored(slots) {
            let Some((t, sa, sb)) = crossing_parts(ray.origin, ray.dir, a, b) else {
                continue;
            };
            if !(t > 0.0 && t < t_max) || skip.contains(index) {
                continue;
            }
            if !visit(
                index,
                Hit {
                    t,
                    u: sa / (sa - sb),
                },
            ) {
                return false;
            }
        }
        true
    }

    /// The nearest crossing with `0 < t < t_max`, with its segment index.
    /// Ties are won by the lower index, so the answer is deterministic and
    /// the same for every strategy.
    pub fn closest_hit(&self, ray: &Ray, t_max: f64, skip: Skip) -> Option<(u32, Hit)> {
        let mut best = Best {
            t: t_max,
            index: u32::MAX,
            u: 0.0,
        };
        if self.nodes.is_empty() {
            self.closest_in(ray, 0..self.order.len(), t_max, skip, &mut best);
            return best.found();
        }
        let inv = DVec2::new(1.0 / ray.dir.x, 1.0 / ray.dir.y);
        let mut stack = [0u32; STACK];
        let mut top = 0;
        let mut node_index = 0u32;
        loop {
            let node = self.nodes[node_index as usize];
            if node.count > 0 {
                let first = node.first as usize;
                self.closest_in(
                    ray,
                    first..first + node.count as usize,
                    t_max,
                    skip,
                    &mut best,
                );
            } else {
                let (l, r) = (node.first, node.first + 1);
                let tl = enter(&self.nodes[l as usize], ray, inv, best.t);
                let tr = enter(&self.nodes[r as usize], ray, inv, best.t);
                match (tl, tr) {
                    (Some(a), Some(b)) => {
                        let (near, far) = if a <= b { (l, r) } else { (r, l) };
                        // The depth bound of the build keeps `top` below
                        // STACK.
                        stack[top] = far;
                        top += 1;
                        node_index = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node_index = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node_index = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node that may still hold a nearer hit.
            loop {
                if top == 0 {
                    return best.found();
                }
                top -= 1;
                let candidate = stack[top];
                if enter(&self.nodes[candidate as usize], ray, inv, best.t).is_some() {
                    node_index = candidate;
                    break;
                }
            }
        }
    }

    /// Calls `visit(index, hit)` for every crossing with `0 < t < t_max`
    /// until `visit` returns `false`. Returns `false` when it was stopped
    /// early. The order of the calls is fixed for a given set, but depends
    /// on its strategy.
    pub fn for_each_crossing(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        mut visit: impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return self.crossings_in(ray, 0..self.order.len(), t_max, skip, &mut visit);
        }
        let inv = DVec2::new(1.0 / ray.dir.x, 1.0 / ray.dir.y);
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if enter(&node, ray, inv, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                if !self.crossings_in(
                    ray,
                    first..first + node.count as usize,
                    t_max,
                    skip,
                    &mut visit,
                ) {
                    return false;
                }
            } else {
                stack[top] = node.first + 1;
                stack[top + 1] = node.first;
                top += 2;
            }
        }
        true
    }
}

/// The nearest crossing so far.
#[derive(Clone, Copy, Debug)]
struct Best {
    t: f64,
    index: u32,
    u: f64,
}

impl Best {
    fn found(self) -> Option<(u32, Hit)> {
        (self.index != u32::MAX).then_some((
            self.index,
            Hit {
                t: self.t,
                u: self.u,
            },
        ))
    }
}

/// Where `ray` enters `node`'s box within `[0, t_max]`, if it does. The
/// boxes are padded when built, and a NaN from `0 * inf` is ignored by
/// `min`/`max`, so the test is conservative: it never rejects a box that
/// holds a crossing the exact test would report.
#[inline(always)]
fn enter(node: &Node, ray: &Ray, inv: DVec2, t_max: f64) -> Option<f64> {
    let t1 = (node.min - ray.origin) * inv;
    let t2 = (node.max - ray.origin) * inv;
    let lo = t1.x.min(t2.x).max(t1.y.min(t2.y)).max(0.0);
    let hi = t1.x.max(t2.x).min(t1.y.max(t2.y)).min(t_max);
    if lo <= hi { Some(lo) } else { None }
}

/// Builds the BVH over `segments`, reordering `order`, by a binned
/// surface-area heuristic (in 2D, the box's half perimeter).
fn build(segments: &[Segment], order: &mut [u32], nodes: &mut Vec<Node>) {
    nodes.clear();
    nodes.push(Node {
        min: DVec2::ZERO,
        max: DVec2::ZERO,
        first: 0,
        count: 0,
    });
    // (node index, first slot, count, depth)
    let mut work = vec![(0usize, 0usize, order.len(), 0usize)];
    while let Some((node, first, count, depth)) = work.pop() {
        let slots = &mut order[first..first + count];
        let (min, max) = bounds(segments, slots);
        nodes[node].min = min;
        nodes[node].max = max;
        let split = if count <= LEAF_SIZE {
            None
        } else if depth < MAX_SAH_DEPTH {
            sah_split(segments, slots)
        } else {
            Some(median_split(segments, slots))
        };
        match split {
            None => {
                nodes[node].first = first as u32;
                nodes[node].count = count as u32;
            }
            Some(mid) => {
                let left = nodes.len();
                nodes.push(Node {
                    min,
                    max,
                    first: 0,
                    count: 0,
                });
                nodes.push(Node {
                    min,
                    max,
                    first: 0,
                    count: 0,
                });
                nodes[node].first = left as u32;
                nodes[node].count = 0;
                work.push((left + 1, first + mid, count - mid, depth + 1));
                work.push((left, first, mid, depth + 1));
            }
        }
    }
}

/// Sorts `slots` by centre along the longer axis of their centres and
/// returns half their number.
fn median_split(segments: &[Segment], slots: &mut [u32]) -> usize {
    let centre = |i: u32| {
        let s = segments[i as usize];
        (s.a + s.b) * 0.5
    };
    let (mut cmin, mut cmax) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for &i in slots.iter() {
        cmin = cmin.min(centre(i));
        cmax = cmax.max(centre(i));
    }
    let axis = if cmax.x - cmin.x >= cmax.y - cmin.y {
        0
    } else {
        1
    };
    slots.sort_by(|&a, &b| centre(a)[axis].total_cmp(&centre(b)[axis]).then(a.cmp(&b)));
    slots.len() / 2
}

/// The padded bounding box of the given segments.
fn bounds(segments: &[Segment], slots: &[u32]) -> (DVec2, DVec2) {
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for &i in slots {
        let s = segments[i as usize];
        min = min.min(s.a).min(s.b);
        max = max.max(s.a).max(s.b);
    }
    // Pad by a few units in the last place of the largest coordinate, so
    // that the box test's rounding can never cut off an endpoint.
    let scale = min
        .abs()
        .max(max.abs())
        .max_element()
        .max(f64::MIN_POSITIVE);
    let pad = DVec2::splat(scale * 8.0 * f64::EPSILON + (max - min).max_element() * 1e-12);
    (min - pad, max + pad)
}

/// Reorders `slots` and returns the size of the left part, or `None` when
/// a leaf is cheaper than any split.
fn sah_split(segments: &[Segment], slots: &mut [u32]) -> Option<usize> {
    const BINS: usize = 12;
    let centre = |i: u32| {
        let s = segments[i as usize];
        (s.a + s.b) * 0.5
    };
    let mut cmin = DVec2::splat(f64::INFINITY);
    let mut cmax = DVec2::splat(f64::NEG_INFINITY);
    for &i in slots.iter() {
        cmin = cmin.min(centre(i));
        cmax = cmax.max(centre(i));
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y { 0 } else { 1 };
    let (lo, width) = (cmin[axis], extent[axis]);
    if width.is_nan() || width <= 0.0 || !width.is_finite() {
        // All centres coincide: split in the middle of the list.
        return Some(slots.len() / 2);
    }
    let bin_of = |i: u32| (((centre(i)[axis] - lo) / width * BINS as f64) as usize).min(BINS - 1);
    let mut counts = [0usize; BINS];
    let mut boxes = [(DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)); BINS];
    for &i in slots.iter() {
        let b = bin_of(i);
        counts[b] += 1;
        let s = segments[i as usize];
        boxes[b].0 = boxes[b].0.min(s.a).min(s.b);
        boxes[b].1 = boxes[b].1.max(s.a).max(s.b);
    }
    let half_perimeter = |(mn, mx): (DVec2, DVec2)| {
        let e = (mx - mn).max(DVec2::ZERO);
        e.x + e.y
    };
    let merge = |a: (DVec2, DVec2), b: (DVec2, DVec2)| (a.0.min(b.0), a.1.max(b.1));
    let empty = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut best: Option<(f64, usize)> = None;
    for split in 1..BINS {
        let (mut lb, mut rb) = (empty, empty);
        let (mut ln, mut rn) = (0, 0);
        for b in 0..split {
            lb = merge(lb, boxes[b]);
            ln += counts[b];
        }
        for b in split..BINS {
            rb = merge(rb, boxes[b]);
            rn += counts[b];
        }
        if ln == 0 || rn == 0 {
            continue;
        }
        let cost = half_perimeter(lb) * ln as f64 + half_perimeter(rb) * rn as f64;
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, split));
        }
    }
    let (_, split) = best?;
    // Partition in place, stably enough to be deterministic.
    let mut left: Vec<u32> = Vec::with_capacity(slots.len());
    let mut right: Vec<u32> = Vec::with_capacity(slots.len());
    for &i in slots.iter() {
        if bin_of(i) < split {
            left.push(i);
        } else {
            right.push(i);
        }
    }
    let mid = left.len();
    for (slot, i) in slots.iter_mut().zip(left.into_iter().chain(right)) {
        *slot = i;
    }
    Some(mid)
}
