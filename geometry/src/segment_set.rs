//! A set of segments and arcs with closest-hit and all-crossings queries:
//! brute force over a structure-of-arrays copy for small sets (four
//! segments at a time where the processor has AVX), a bounding volume
//! hierarchy for large ones. All give exactly the same answers.

use crate::arc::arc_crossings;
use crate::lanes::{Best, Kernel, Lanes};
use crate::{Arc, DVec2, Hit, Ray, Segment, Shape};

/// Up to two indices that a query ignores: the wall a ray leaves from
/// (the first), and the wall its end lies on (the second: a light
/// sample's). A ray that starts on a segment can never meet that same
/// segment again (a straight line meets another line at most once), so
/// skipping it is exact, not an epsilon. An arc is not skipped whole: a
/// ray can meet the arc it leaves again, and only its root at the origin
/// (or at `t_max`) is dropped (`arc.rs`, "Leaving an arc").
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

/// Sets with more segments than this use a BVH by default, on every
/// processor, so that a render's plan (and with it which rays are culled)
/// does not depend on the processor. Brute force with the AVX kernel,
/// which tests four segments for little more than the price of one, beats
/// the BVH on a room's 13 walls by a quarter, and on 32 walls spread over
/// a room by a third (`cargo bench -p flatray-benches --bench render --
/// bvh_threshold`); the scalar kernel is slower there, but culled queries
/// test only a few walls each.
pub const BVH_THRESHOLD: usize = 32;

/// The walls' shapes of a scene, stored once, queried by brute force or
/// through a BVH: segments, and circular arcs beside them.
///
/// Indices are positions in the vector given to [`SegmentSet::new`] or
/// [`SegmentSet::of_shapes`]. Ties in the closest hit go to the lower
/// index, so both strategies (and both kernels) return identical answers.
/// A BVH holds segments and arcs together (an arc by its box, tested in
/// its leaf); brute force tests the segments, then each arc behind a test
/// of its box. A set without arcs pays one check of a flag per query or
/// leaf.
#[derive(Clone, Debug, Default)]
pub struct SegmentSet {
    /// Per index, the segment, or an arc's chord (`arcs` holds the arc).
    segments: Vec<Segment>,
    /// The arcs, in index order, with their indices and padded boxes.
    arcs: Vec<(u32, Arc, DVec2, DVec2)>,
    /// Per index, its place in `arcs`, or `u32::MAX` for a segment;
    /// empty when there are no arcs.
    arc_slot: Vec<u32>,
    /// Whether the BVH holds the arcs (in its leaves) as well.
    arcs_in_tree: bool,
    /// The segments as the kernels read them: in index order and padded
    /// to whole blocks for brute force; in leaf order for the BVH, whose
    /// leaves are tested one segment at a time (measured: four-wide
    /// leaves, padded, were slower on mazes of 100,000 walls).
    lanes: Lanes,
    /// Empty for brute force.
    nodes: Vec<Node>,
    kernel: Option<Kernel>,
}

/// A BVH node: its box, and either two children (`count == 0`, children
/// at `first` and `first + 1`) or a leaf of `count` segments from slot
/// `first`.
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
    /// A set that picks its strategy by size alone ([`BVH_THRESHOLD`]),
    /// and the fastest kernel the processor runs.
    pub fn new(segments: Vec<Segment>) -> SegmentSet {
        SegmentSet::of_shapes(segments.into_iter().map(Shape::Segment).collect())
    }

    /// A set of segments and arcs that picks its strategy by its size
    /// ([`BVH_THRESHOLD`]).
    pub fn of_shapes(shapes: Vec<Shape>) -> SegmentSet {
        let strategy = if shapes.len() > BVH_THRESHOLD {
            Strategy::Bvh
        } else {
            Strategy::BruteForce
        };
        SegmentSet::shapes_with_strategy(shapes, strategy)
    }

    /// A set with the given strategy, and the fastest kernel the processor
    /// runs.
    pub fn with_strategy(segments: Vec<Segment>, strategy: Strategy) -> SegmentSet {
        SegmentSet::shapes_with_strategy(
            segments.into_iter().map(Shape::Segment).collect(),
            strategy,
        )
    }

    /// A set of segments and arcs with the given strategy. A BVH holds
    /// both, an arc by its box; brute force tests the segments four at a
    /// time and then each arc behind its box.
    pub fn shapes_with_strategy(shapes: Vec<Shape>, strategy: Strategy) -> SegmentSet {
        let mut arcs = Vec::new();
        let mut arc_slot = Vec::new();
        if shapes.iter().any(|s| s.as_arc().is_some()) {
            arc_slot = vec![u32::MAX; shapes.len()];
            for (i, shape) in shapes.iter().enumerate() {
                if let Shape::Arc(arc) = shape {
                    arc_slot[i] = arcs.len() as u32;
                    let (lo, hi) = arc.bounds();
                    let (lo, hi) = pad_box(lo, hi);
                    arcs.push((i as u32, *arc, lo, hi));
                }
            }
        }
        let segments: Vec<Segment> = shapes.iter().map(Shape::chord).collect();
        let is_arc = |i: u32| arc_slot.get(i as usize).is_some_and(|&k| k != u32::MAX);
        let mut nodes = Vec::new();
        let mut lanes = Lanes::default();
        let arcs_in_tree = strategy == Strategy::Bvh && !shapes.is_empty() && !arcs.is_empty();
        if strategy == Strategy::Bvh && !shapes.is_empty() {
            // The tree is built over every shape, an arc standing in as
            // its box's diagonal (the same box and centre); in the lanes an
            // arc's slot holds a segment of NaNs, which no ray crosses, and
            // a leaf tests its arcs itself.
            let proxies: Vec<Segment> = (0..shapes.len())
                .map(
                    |i| match arc_slot.get(i).and_then(|&k| arcs.get(k as usize)) {
                        Some(&(_, _, lo, hi)) => Segment::new(lo, hi),
                        None => segments[i],
                    },
                )
                .collect();
            let mut order: Vec<u32> = (0..shapes.len() as u32).collect();
            build(&proxies, &mut order, &mut nodes);
            let nothing = Segment::new(DVec2::NAN, DVec2::NAN);
            for &i in &order {
                lanes.push(
                    if is_arc(i) {
                        &nothing
                    } else {
                        &segments[i as usize]
                    },
                    i,
                );
            }
        } else {
            let order: Vec<u32> = (0..segments.len() as u32).filter(|&i| !is_arc(i)).collect();
            for &i in &order {
                lanes.push(&segments[i as usize], i);
            }
            lanes.pad();
        }
        SegmentSet {
            segments,
            arcs,
            arc_slot,
            arcs_in_tree,
            lanes,
            nodes,
            kernel: None,
        }
    }

    /// Keeps in `best` the nearest crossing of the arcs among a leaf's
    /// `slots`, as [`SegmentSet::closest_arc`] does for all of them.
    #[inline]
    fn closest_arc_in(
        &self,
        slots: std::ops::Range<usize>,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        best: &mut Best,
    ) {
        for slot in slots {
            let index = self.lanes.order[slot];
            if let Some(arc) = self.arc(index) {
                keep_nearer_arc(index, arc, ray, t_max, skip, best);
            }
        }
    }

    /// Calls `visit` for the crossings of the arcs among a leaf's `slots`;
    /// `false` when `visit` stopped it.
    #[inline]
    fn arc_crossings_in(
        &self,
        slots: std::ops::Range<usize>,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        visit: &mut impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        slots.into_iter().all(|slot| {
            let index = self.lanes.order[slot];
            self.arc(index)
                .is_none_or(|arc| visit_arc(index, arc, ray, t_max, skip, visit))
        })
    }

    /// Whether any shape is an arc.
    #[inline]
    pub fn has_arcs(&self) -> bool {
        !self.arcs.is_empty()
    }

    /// The arc of index `index`, if that shape is one.
    #[inline]
    pub fn arc(&self, index: u32) -> Option<&Arc> {
        let k = *self.arc_slot.get(index as usize)?;
        self.arcs.get(k as usize).map(|(_, arc, _, _)| arc)
    }

    /// The shape of index `index`.
    #[inline]
    pub fn shape(&self, index: u32) -> Shape {
        match self.arc(index) {
            Some(arc) => Shape::Arc(*arc),
            None => Shape::Segment(self.segments[index as usize]),
        }
    }

    /// Keeps in `best` the nearest arc crossing below `best.t`, the lower
    /// index on a tie; `t_max` is the query's, where an arriving ray ends.
    #[inline]
    fn closest_arc(&self, ray: &Ray, t_max: f64, skip: Skip, best: &mut Best) {
        let inv = DVec2::new(1.0 / ray.dir.x, 1.0 / ray.dir.y);
        for &(index, ref arc, lo, hi) in &self.arcs {
            if enter_box(lo, hi, ray, inv, best.t).is_some() {
                keep_nearer_arc(index, arc, ray, t_max, skip, best);
            }
        }
    }

    /// Calls `visit` for every arc crossing below `t_max`, arcs in index
    /// order, each arc's nearer first; `false` when `visit` stopped it.
    #[inline]
    pub(crate) fn arc_crossings_visit(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        only: Option<u32>,
        visit: &mut impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        let inv = DVec2::new(1.0 / ray.dir.x, 1.0 / ray.dir.y);
        let arcs = match only.and_then(|i| self.arc_slot.get(i as usize)) {
            Some(&k) => self.arcs.get(k as usize..k as usize + 1).unwrap_or(&[]),
            None if only.is_some() => &[],
            None => &self.arcs[..],
        };
        arcs.iter().all(|&(index, ref arc, lo, hi)| {
            enter_box(lo, hi, ray, inv, t_max).is_none()
                || visit_arc(index, arc, ray, t_max, skip, visit)
        })
    }

    /// The same set, answering with `kernel` if this processor runs it
    /// (and with the scalar kernel otherwise). For tests and benchmarks:
    /// every kernel returns the same answers.
    pub fn with_kernel(mut self, kernel: Kernel) -> SegmentSet {
        self.kernel = (kernel == Kernel::Scalar || Kernel::detect() == kernel).then_some(kernel);
        self
    }

    pub fn strategy(&self) -> Strategy {
        if self.nodes.is_empty() {
            Strategy::BruteForce
        } else {
            Strategy::Bvh
        }
    }

    /// How queries run, in words: "BVH", or "brute force" with its kernel.
    /// It depends on the processor (AVX or not) as well as on the set.
    pub fn describe(&self) -> String {
        match (self.strategy(), self.kernel()) {
            (Strategy::Bvh, _) => "BVH".into(),
            (Strategy::BruteForce, Kernel::Avx) => {
                "brute force with AVX, four segments at a time".into()
            }
            (Strategy::BruteForce, Kernel::Scalar) => "brute force, one segment at a time".into(),
        }
    }

    /// The kernel that tests blocks of segments in a brute-force set (a
    /// BVH tests its small leaves with the scalar kernel).
    #[inline]
    pub fn kernel(&self) -> Kernel {
        self.kernel.unwrap_or_else(detected)
    }

    #[inline]
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// The segment of index `index`; for an arc, its chord.
    #[inline]
    pub fn get(&self, index: u32) -> Segment {
        self.segments[index as usize]
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The slots of a leaf.
    #[inline(always)]
    fn leaf(node: &Node) -> std::ops::Range<usize> {
        let first = node.first as usize;
        first..first + node.count as usize
    }

    /// The children of inner node `node` whose boxes the ray enters within
    /// `t_max`: the nearer, then the farther.
    #[inline(always)]
    fn children(
        &self,
        node: &Node,
        ray: &Ray,
        inv: DVec2,
        t_max: f64,
    ) -> (Option<u32>, Option<u32>) {
        let (l, r) = (node.first, node.first + 1);
        let tl = enter(&self.nodes[l as usize], ray, inv, t_max);
        let tr = enter(&self.nodes[r as usize], ray, inv, t_max);
        match (tl, tr) {
            (Some(a), Some(b)) if a <= b => (Some(l), Some(r)),
            (Some(_), Some(_)) => (Some(r), Some(l)),
            (Some(_), None) => (Some(l), None),
            (None, Some(_)) => (Some(r), None),
            (None, None) => (None, None),
        }
    }

    /// The nearest crossing with `0 < t < t_max`, with its segment index.
    /// Ties are won by the lower index, so the answer is deterministic and
    /// the same for every strategy.
    pub fn closest_hit(&self, ray: &Ray, t_max: f64, skip: Skip) -> Option<(u32, Hit)> {
        let mut best = Best::new(t_max);
        if self.nodes.is_empty() {
            let all = 0..self.lanes.order.len();
            self.lanes
                .closest(self.kernel(), ray, all, t_max, skip, &mut best);
            if !self.arcs.is_empty() {
                self.closest_arc(ray, t_max, skip, &mut best);
            }
            return best.found();
        }
        let inv = DVec2::new(1.0 / ray.dir.x, 1.0 / ray.dir.y);
        let mut stack = [0u32; STACK];
        let mut top = 0;
        let mut node_index = 0u32;
        loop {
            let node = self.nodes[node_index as usize];
            if node.count > 0 {
                self.lanes.closest(
                    Kernel::Scalar,
                    ray,
                    Self::leaf(&node),
                    t_max,
                    skip,
                    &mut best,
                );
                if self.arcs_in_tree {
                    self.closest_arc_in(Self::leaf(&node), ray, t_max, skip, &mut best);
                }
            } else {
                let (near, far) = self.children(&node, ray, inv, best.t);
                if let Some(far) = far {
                    // The depth bound of the build keeps `top` below STACK.
                    stack[top] = far;
                    top += 1;
                }
                if let Some(near) = near {
                    node_index = near;
                    continue;
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

    /// Calls `visit(index)` for every segment whose bounding box meets the
    /// box from `min` to `max` (closed), each once, in ascending index
    /// order; for brute force, every segment. What a region query needs
    /// before its own exact test (the walls in front of a line or circle
    /// light, for instance). `scratch` holds the indices while they are
    /// sorted; it allocates nothing once it has grown.
    pub fn for_each_in_box(
        &self,
        min: DVec2,
        max: DVec2,
        scratch: &mut Vec<u32>,
        visit: impl FnMut(u32),
    ) {
        if self.nodes.is_empty() {
            (0..self.segments.len() as u32).for_each(visit);
            return;
        }
        scratch.clear();
        for &(index, _, lo, hi) in &self.arcs {
            if lo.x <= max.x && lo.y <= max.y && hi.x >= min.x && hi.y >= min.y {
                scratch.push(index);
            }
        }
        let overlaps = |node: &Node| {
            node.min.x <= max.x && node.min.y <= max.y && node.max.x >= min.x && node.max.y >= min.y
        };
        if !overlaps(&self.nodes[0]) {
            scratch.sort_unstable();
            scratch.iter().copied().for_each(visit);
            return;
        }
        let mut stack = [0u32; STACK];
        let mut top = 0;
        let mut node_index = 0u32;
        loop {
            let node = self.nodes[node_index as usize];
            if node.count > 0 {
                for slot in Self::leaf(&node) {
                    let index = self.lanes.order[slot];
                    if self.arcs_in_tree && self.arc(index).is_some() {
                        // Listed with the arcs, by its own box.
                        continue;
                    }
                    let s = &self.segments[index as usize];
                    let (lo, hi) = (s.a.min(s.b), s.a.max(s.b));
                    if lo.x <= max.x && lo.y <= max.y && hi.x >= min.x && hi.y >= min.y {
                        scratch.push(index);
                    }
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let (a, b) = (
                    overlaps(&self.nodes[l as usize]),
                    overlaps(&self.nodes[r as usize]),
                );
                if a && b {
                    stack[top] = r;
                    top += 1;
                    node_index = l;
                    continue;
                } else if a || b {
                    node_index = if a { l } else { r };
                    continue;
                }
            }
            if top == 0 {
                break;
            }
            top -= 1;
            node_index = stack[top];
        }
        scratch.sort_unstable();
        scratch.iter().copied().for_each(visit);
    }

    /// Calls `visit(index, hit)` for every crossing with `0 < t < t_max`
    /// until `visit` returns `false`. Returns `false` when it was stopped
    /// early. The order of the calls is fixed for a given set and ray, but
    /// depends on its strategy: brute force calls in index order, the BVH
    /// roughly from near to far (by the boxes it enters), so that a query
    /// that stops at its first blocker stops early; the arcs' crossings
    /// come after the segments', arc by arc (an arc can be crossed twice).
    pub fn for_each_crossing(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        mut visit: impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        if !self.segment_crossings(ray, t_max, skip, &mut visit) {
            return false;
        }
        self.arcs.is_empty()
            || self.arcs_in_tree
            || self.arc_crossings_visit(ray, t_max, skip, None, &mut visit)
    }

    /// [`SegmentSet::for_each_crossing`] over the segments alone.
    fn segment_crossings(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        mut visit: impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            let all = 0..self.lanes.order.len();
            return self
                .lanes
                .crossings(self.kernel(), ray, all, t_max, skip, &mut visit);
        }
        let inv = DVec2::new(1.0 / ray.dir.x, 1.0 / ray.dir.y);
        if enter(&self.nodes[0], ray, inv, t_max).is_none() {
            return true;
        }
        // Nearer boxes first, as for the closest hit: a query that stops
        // at its first blocker (a shadow ray) then tends to stop early.
        let mut stack = [0u32; STACK];
        let mut top = 0;
        let mut node_index = 0u32;
        loop {
            let node = self.nodes[node_index as usize];
            if node.count > 0 {
                if !self.lanes.crossings(
                    Kernel::Scalar,
                    ray,
                    Self::leaf(&node),
                    t_max,
                    skip,
                    &mut visit,
                ) {
                    return false;
                }
                if self.arcs_in_tree
                    && !self.arc_crossings_in(Self::leaf(&node), ray, t_max, skip, &mut visit)
                {
                    return false;
                }
            } else {
                let (near, far) = self.children(&node, ray, inv, t_max);
                if let Some(far) = far {
                    // The depth bound of the build keeps `top` below STACK.
                    stack[top] = far;
                    top += 1;
                }
                if let Some(near) = near {
                    node_index = near;
                    continue;
                }
            }
            if top == 0 {
                return true;
            }
            top -= 1;
            node_index = stack[top];
        }
    }
}

/// The kernel detected once per process.
fn detected() -> Kernel {
    static DETECTED: std::sync::OnceLock<Kernel> = std::sync::OnceLock::new();
    *DETECTED.get_or_init(Kernel::detect)
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

/// Calls `visit` for each crossing of arc `index` below `t_max`, nearer
/// first; `false` when `visit` stopped it.
#[inline]
fn visit_arc(
    index: u32,
    arc: &Arc,
    ray: &Ray,
    t_max: f64,
    skip: Skip,
    visit: &mut impl FnMut(u32, Hit) -> bool,
) -> bool {
    let (leaving, arriving) = (skip.0 == index, skip.1 == index && t_max.is_finite());
    let (hits, n) = arc_crossings(ray, arc, t_max, leaving, arriving);
    hits[..n].iter().all(|hit| visit(index, *hit))
}

/// Keeps in `best` the nearest crossing of arc `index` below `best.t`,
/// the lower index on a tie; `t_max` is the query's, where an arriving ray
/// ends. The roots alone: the position along the arc (an `atan2`) only
/// for a root that wins.
#[inline]
fn keep_nearer_arc(index: u32, arc: &Arc, ray: &Ray, t_max: f64, skip: Skip, best: &mut Best) {
    let (leaving, arriving) = (skip.0 == index, skip.1 == index && t_max.is_finite());
    let (roots, n) = arc.line_crossings(ray, leaving, arriving.then_some(t_max));
    if let Some(&t) = roots[..n].iter().find(|&&t| t > 0.0 && t < t_max)
        && (t < best.t || (t == best.t && index < best.index))
    {
        *best = Best {
            t,
            index,
            u: arc.position_of(ray.at(t)),
        };
    }
}

/// Where `ray` enters the box `[lo, hi]` within `[0, t_max]`, if it does
/// (as [`enter`]).
#[inline(always)]
fn enter_box(lo: DVec2, hi: DVec2, ray: &Ray, inv: DVec2, t_max: f64) -> Option<f64> {
    enter(
        &Node {
            min: lo,
            max: hi,
            first: 0,
            count: 0,
        },
        ray,
        inv,
        t_max,
    )
}

/// A box padded as the BVH's are, so that the box test's rounding never
/// cuts off what it holds.
fn pad_box(min: DVec2, max: DVec2) -> (DVec2, DVec2) {
    let scale = min
        .abs()
        .max(max.abs())
        .max_element()
        .max(f64::MIN_POSITIVE);
    let pad = DVec2::splat(scale * 8.0 * f64::EPSILON + (max - min).max_element() * 1e-12);
    (min - pad, max + pad)
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
    pad_box(min, max)
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
