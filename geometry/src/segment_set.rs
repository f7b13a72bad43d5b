//! A set of segments with closest-hit and all-crossings queries.

use crate::{Hit, Ray, Segment, line_crossing};

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

/// The segments of a scene, stored once, queried by brute force.
///
/// Segment indices are positions in the vector given to [`SegmentSet::new`].
#[derive(Clone, Debug, Default)]
pub struct SegmentSet {
    segments: Vec<Segment>,
}

impl SegmentSet {
    pub fn new(segments: Vec<Segment>) -> SegmentSet {
        SegmentSet { segments }
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

    /// The nearest crossing with `0 < t < t_max`, with its segment index.
    /// Ties are won by the lower index, so the answer is deterministic.
    pub fn closest_hit(&self, ray: &Ray, t_max: f64, skip: Skip) -> Option<(u32, Hit)> {
        let mut best: Option<(u32, Hit)> = None;
        let mut best_t = t_max;
        for (index, seg) in self.segments.iter().enumerate() {
            let index = index as u32;
            if skip.contains(index) {
                continue;
            }
            if let Some(hit) = line_crossing(ray, seg)
                && hit.t > 0.0
                && hit.t < best_t
            {
                best_t = hit.t;
                best = Some((index, hit));
            }
        }
        best
    }

    /// Calls `visit(index, hit)` for every crossing with `0 < t < t_max`, in
    /// index order, until `visit` returns `false`. Returns `false` when it
    /// was stopped early.
    pub fn for_each_crossing(
        &self,
        ray: &Ray,
        t_max: f64,
        skip: Skip,
        mut visit: impl FnMut(u32, Hit) -> bool,
    ) -> bool {
        for (index, seg) in self.segments.iter().enumerate() {
            let index = index as u32;
            if skip.contains(index) {
                continue;
            }
            if let Some(hit) = line_crossing(ray, seg)
                && hit.t > 0.0
                && hit.t < t_max
                && !visit(index, hit)
            {
                return false;
            }
        }
        true
    }
}
