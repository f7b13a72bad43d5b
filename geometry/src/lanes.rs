//! The segments of a [`SegmentSet`](crate::SegmentSet) as the hot loop
//! reads them: structure of arrays, in blocks of four, and the two kernels
//! that test a run of blocks against a ray, one scalar and one with AVX
//! (four `f64` lanes), chosen once per set at run time.
//!
//! Both kernels do the same IEEE operations in the same order (Rust never
//! fuses a multiply and an add on its own), so they return the same bits.
//! Slots past the last segment of a block hold NaN endpoints, which no
//! crossing test accepts.

use crate::{DVec2, Hit, Ray, Skip, crossing_parts};

/// Segments per block: the lanes of one AVX register of `f64`.
pub(crate) const BLOCK: usize = 4;

/// How a set tests a block of segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// One segment at a time, on any processor.
    Scalar,
    /// Four segments at a time with AVX, where the processor has it
    /// (detected at run time).
    Avx,
}

impl Kernel {
    /// The fastest kernel this processor runs: the scalar one when the
    /// portable code is forced ([`portable_forced`]).
    pub fn detect() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        if !portable_forced() && std::is_x86_feature_detected!("avx") {
            return Kernel::Avx;
        }
        Kernel::Scalar
    }
}

/// Whether the environment variable `FLATRAY_PORTABLE` is set (to
/// anything but empty or `0`): then only the code that runs on every
/// processor is used, as on a processor without AVX. The answers are the
/// same either way; tests run both (`.ci/run`). Read once per process.
pub fn portable_forced() -> bool {
    static FORCED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FORCED.get_or_init(|| {
        std::env::var_os("FLATRAY_PORTABLE").is_some_and(|v| !v.is_empty() && v != "0")
    })
}

/// Endpoints, edges and original indices, padded to whole blocks.
#[derive(Clone, Debug, Default)]
pub(crate) struct Lanes {
    pub ax: Vec<f64>,
    pub ay: Vec<f64>,
    pub bx: Vec<f64>,
    pub by: Vec<f64>,
    /// `b - a`, as the crossing rule computes it.
    pub ex: Vec<f64>,
    pub ey: Vec<f64>,
    /// The original index of each slot, as `f64` for the lane compares
    /// (exact: every `u32` is an `f64`); `u32::MAX` in padding.
    pub id: Vec<f64>,
    /// The original index of each slot; `u32::MAX` in padding.
    pub order: Vec<u32>,
    /// The number of slots before the padding.
    pub len: usize,
}

impl Lanes {
    /// Appends `segment` with original index `index`.
    pub fn push(&mut self, segment: &crate::Segment, index: u32) {
        let e = segment.b - segment.a;
        self.ax.push(segment.a.x);
        self.ay.push(segment.a.y);
        self.bx.push(segment.b.x);
        self.by.push(segment.b.y);
        self.ex.push(e.x);
        self.ey.push(e.y);
        self.id.push(index as f64);
        self.order.push(index);
        self.len = self.order.len();
    }

    /// Pads to a whole number of blocks with slots nothing crosses.
    pub fn pad(&mut self) {
        while !self.order.len().is_multiple_of(BLOCK) {
            for v in [
                &mut self.ax,
                &mut self.ay,
                &mut self.bx,
                &mut self.by,
                &mut self.ex,
                &mut self.ey,
            ] {
                v.push(f64::NAN);
            }
            self.id.push(u32::MAX as f64);
            self.order.push(u32::MAX);
        }
    }

    #[inline(always)]
    fn a(&self, slot: usize) -> DVec2 {
        DVec2::new(self.ax[slot], self.ay[slot])
    }

    #[inline(always)]
    fn b(&self, slot: usize) -> DVec2 {
        DVec2::new(self.bx[slot], self.by[slot])
    }

    /// Keeps in `best` the nearest crossing among `slots`: the least
    /// `(t, index)` with `0 < t < t_max` not skipped. The AVX kernel
    /// settles ties within a lane by slot order, so `slots` must be in
    /// index order and `best` must hold nothing from a higher index: true
    /// of brute force (one call, all slots, a fresh `best`), the only user.
    #[inline(always)]
    pub fn closest(
        &self,
        kernel: Kernel,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        best: &mut Best,
    ) {
        match kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: a set holds `Kernel::Avx` only when `Kernel::detect`
            // found AVX on this processor.
            Kernel::Avx => unsafe { avx::closest(self, ray, slots, t_max, skip, best) },
            _ => self.closest_scalar(ray, slots, t_max, skip, best),
        }
    }

    #[inline(always)]
    fn closest_scalar(
        &self,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        best: &mut Best,
    ) {
        for slot in slots {
            let (a, b, index) = (self.a(slot), self.b(slot), self.order[slot]);
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
    pub fn crossings<F: FnMut(u32, Hit) -> bool>(
        &self,
        kernel: Kernel,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        visit: &mut F,
    ) -> bool {
        match kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `closest`.
            Kernel::Avx => unsafe { avx::crossings(self, ray, slots, t_max, skip, visit) },
            _ => self.crossings_scalar(ray, slots, t_max, skip, visit),
        }
    }

    #[inline(always)]
    fn crossings_scalar<F: FnMut(u32, Hit) -> bool>(
        &self,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        visit: &mut F,
    ) -> bool {
        let segments = slots.map(|slot| (self.order[slot], self.a(slot), self.b(slot)));
        visit_crossings(ray, t_max, skip, segments, visit)
    }
}

/// Calls `visit(index, hit)` for each of `segments` (index and ends, in
/// the order given) that `ray` crosses with `0 < t < t_max` and `skip`
/// does not hold, until `visit` returns `false`; `false` when it did.
#[inline(always)]
pub(crate) fn visit_crossings<F: FnMut(u32, Hit) -> bool>(
    ray: &Ray,
    t_max: f64,
    skip: Skip,
    segments: impl Iterator<Item = (u32, DVec2, DVec2)>,
    visit: &mut F,
) -> bool {
    for (index, a, b) in segments {
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

/// The nearest crossing so far.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Best {
    pub t: f64,
    pub index: u32,
    pub u: f64,
}

impl Best {
    /// Nothing found yet below `t_max`.
    #[inline]
    pub fn new(t_max: f64) -> Best {
        Best {
            t: t_max,
            index: u32::MAX,
            u: 0.0,
        }
    }

    pub fn found(self) -> Option<(u32, Hit)> {
        (self.index != u32::MAX).then_some((
            self.index,
            Hit {
                t: self.t,
                u: self.u,
            },
        ))
    }
}

/// `SegmentSet::closest_hits_among` with the AVX kernel, where `kernel`
/// is AVX and the lanes come in fours; `None` otherwise. Inlined always,
/// like the kernel, into the caller's loop.
#[inline(always)]
pub(crate) fn closest_hits_avx<const N: usize>(
    kernel: Kernel,
    segments: &[crate::Segment],
    rays: &crate::RayLanes<N>,
    candidates: &[u32],
) -> Option<crate::HitLanes<N>> {
    #[cfg(target_arch = "x86_64")]
    if kernel == Kernel::Avx && N.is_multiple_of(BLOCK) {
        // SAFETY: a set's kernel is AVX only where the processor has it
        // (`Kernel::detect`, `SegmentSet::with_kernel`).
        return Some(unsafe { avx::closest_hits(segments, rays, candidates) });
    }
    let _ = (kernel, segments, rays, candidates);
    None
}

#[cfg(target_arch = "x86_64")]
mod avx {
    //! The crossing rule on four segments at once. Every lane computes
    //! exactly what `crossing_parts` computes for its segment.

    use std::arch::x86_64::*;

    use super::{BLOCK, Best, Lanes};
    use crate::cull::{HitLanes, RayLanes};
    use crate::{Hit, Ray, Segment, Skip, crossing_parts};

    /// The lanes of one block, and the mask of its crossings with
    /// `0 < t < t_max` that are not skipped.
    struct Block {
        t: __m256d,
        sa: __m256d,
        sb: __m256d,
        id: __m256d,
        ok: __m256d,
    }

    /// The ray and bounds, broadcast to every lane.
    struct Wide {
        ox: __m256d,
        oy: __m256d,
        dx: __m256d,
        dy: __m256d,
        t_max: __m256d,
        skip0: __m256d,
        skip1: __m256d,
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn wide(ray: &Ray, t_max: f64, skip: Skip) -> Wide {
        Wide {
            ox: _mm256_set1_pd(ray.origin.x),
            oy: _mm256_set1_pd(ray.origin.y),
            dx: _mm256_set1_pd(ray.dir.x),
            dy: _mm256_set1_pd(ray.dir.y),
            t_max: _mm256_set1_pd(t_max),
            skip0: _mm256_set1_pd(skip.0 as f64),
            skip1: _mm256_set1_pd(skip.1 as f64),
        }
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn load(v: &[f64], slot: usize) -> __m256d {
        let lanes = &v[slot..slot + BLOCK];
        // SAFETY: the slice (bounds-checked above) is four readable f64;
        // the load is unaligned.
        unsafe { _mm256_loadu_pd(lanes.as_ptr()) }
    }

    /// Four lanes of the crossing rule.
    struct Crossing {
        /// The sides of `a` and `b`, as in `crossing_parts`.
        sa: __m256d,
        sb: __m256d,
        /// All ones where the ray's line crosses the segment.
        crosses: __m256d,
        /// The ray parameter of the crossing (meaningful where it crosses).
        t: __m256d,
    }

    /// What `crossing_parts` computes, lane by lane, for rays `o + t d`
    /// and segments `a b` with edges `e = b - a`, in the same operations
    /// and order (so the same bits). The rule "not both sides > 0, not
    /// both < 0, not both 0" is `lo <= 0 <= hi` and `lo != hi` for
    /// `lo = min` and `hi = max` of the two sides (equal only when both are
    /// 0; -0 counts as 0). A NaN side makes a NaN `t`, which every caller's
    /// `t > 0` test rejects, as in the scalar kernel.
    #[inline]
    #[target_feature(enable = "avx")]
    fn crossing(
        (ox, oy): (__m256d, __m256d),
        (dx, dy): (__m256d, __m256d),
        (ax, ay): (__m256d, __m256d),
        (bx, by): (__m256d, __m256d),
        (ex, ey): (__m256d, __m256d),
    ) -> Crossing {
        let zero = _mm256_setzero_pd();
        let (pax, pay) = (_mm256_sub_pd(ax, ox), _mm256_sub_pd(ay, oy));
        let (pbx, pby) = (_mm256_sub_pd(bx, ox), _mm256_sub_pd(by, oy));
        let sa = _mm256_sub_pd(_mm256_mul_pd(dx, pay), _mm256_mul_pd(dy, pax));
        let sb = _mm256_sub_pd(_mm256_mul_pd(dx, pby), _mm256_mul_pd(dy, pbx));
        let lo = _mm256_min_pd(sa, sb);
        let hi = _mm256_max_pd(sa, sb);
        let crosses = _mm256_and_pd(
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_LE_OQ>(lo, zero),
                _mm256_cmp_pd::<_CMP_GE_OQ>(hi, zero),
            ),
            _mm256_cmp_pd::<_CMP_NEQ_OQ>(lo, hi),
        );
        let num = _mm256_sub_pd(_mm256_mul_pd(pax, ey), _mm256_mul_pd(pay, ex));
        let t = _mm256_div_pd(num, _mm256_sub_pd(sb, sa));
        Crossing { sa, sb, crosses, t }
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn block(l: &Lanes, w: &Wide, slot: usize) -> Block {
        let zero = _mm256_setzero_pd();
        let Crossing { sa, sb, crosses, t } = crossing(
            (w.ox, w.oy),
            (w.dx, w.dy),
            (load(&l.ax, slot), load(&l.ay, slot)),
            (load(&l.bx, slot), load(&l.by, slot)),
            (load(&l.ex, slot), load(&l.ey, slot)),
        );
        let both = |p: __m256d, q: __m256d| _mm256_and_pd(p, q);
        let id = load(&l.id, slot);
        let in_range = both(
            _mm256_cmp_pd::<_CMP_GT_OQ>(t, zero),
            _mm256_cmp_pd::<_CMP_LT_OQ>(t, w.t_max),
        );
        let not_skipped = both(
            _mm256_cmp_pd::<_CMP_NEQ_OQ>(id, w.skip0),
            _mm256_cmp_pd::<_CMP_NEQ_OQ>(id, w.skip1),
        );
        Block {
            t,
            sa,
            sb,
            id,
            ok: both(crosses, both(in_range, not_skipped)),
        }
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn lanes(v: __m256d) -> [f64; BLOCK] {
        let mut out = [0.0; BLOCK];
        // SAFETY: `out` is four writable f64; the store is unaligned.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
        out
    }

    /// # Safety
    /// The processor must have AVX.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn closest(
        l: &Lanes,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        best: &mut Best,
    ) {
        let w = wide(ray, t_max, skip);
        // Per lane, the least (t, index) so far and its slot (-1: the
        // `best` passed in).
        let mut bt = _mm256_set1_pd(best.t);
        let mut bi = _mm256_set1_pd(best.index as f64);
        let mut bs = _mm256_set1_pd(-1.0);
        let lane_offsets = _mm256_set_pd(3.0, 2.0, 1.0, 0.0);
        let mut slot = slots.start;
        while slot < slots.end {
            let b = block(l, &w, slot);
            // Each lane meets its slots in index order, so a tie never
            // goes to the later one: `t < bt` keeps the lower index. (The
            // reduction below compares indices across lanes.) No branch:
            // which lanes improve is as unpredictable as the scalar
            // kernel's branches were.
            let take = _mm256_and_pd(b.ok, _mm256_cmp_pd::<_CMP_LT_OQ>(b.t, bt));
            bt = _mm256_blendv_pd(bt, b.t, take);
            bi = _mm256_blendv_pd(bi, b.id, take);
            let here = _mm256_add_pd(_mm256_set1_pd(slot as f64), lane_offsets);
            bs = _mm256_blendv_pd(bs, here, take);
            slot += BLOCK;
        }
        let (ts, is, ss) = (lanes(bt), lanes(bi), lanes(bs));
        let mut winner: Option<usize> = None;
        let (mut t, mut index) = (best.t, best.index as f64);
        for lane in 0..BLOCK {
            if ss[lane] >= 0.0 && (ts[lane] < t || (ts[lane] == t && is[lane] < index)) {
                (t, index) = (ts[lane], is[lane]);
                winner = Some(ss[lane] as usize);
            }
        }
        if let Some(slot) = winner {
            let a = crate::DVec2::new(l.ax[slot], l.ay[slot]);
            let b = crate::DVec2::new(l.bx[slot], l.by[slot]);
            if let Some((t, sa, sb)) = crossing_parts(ray.origin, ray.dir, a, b) {
                *best = Best {
                    t,
                    index: l.order[slot],
                    u: sa / (sa - sb),
                };
            }
        }
    }

    /// # Safety
    /// The processor must have AVX.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn crossings<F: FnMut(u32, Hit) -> bool>(
        l: &Lanes,
        ray: &Ray,
        slots: std::ops::Range<usize>,
        t_max: f64,
        skip: Skip,
        visit: &mut F,
    ) -> bool {
        let w = wide(ray, t_max, skip);
        let mut slot = slots.start;
        while slot < slots.end {
            let b = block(l, &w, slot);
            let mask = _mm256_movemask_pd(b.ok);
            if mask != 0 {
                let (t, sa, sb) = (lanes(b.t), lanes(b.sa), lanes(b.sb));
                for lane in 0..BLOCK {
                    if mask & (1 << lane) != 0
                        && !visit(
                            l.order[slot + lane],
                            Hit {
                                t: t[lane],
                                u: sa[lane] / (sa[lane] - sb[lane]),
                            },
                        )
                    {
                        return false;
                    }
                }
            }
            slot += BLOCK;
        }
        true
    }

    /// `SegmentSet::closest_hits_among` for `N` rays (a multiple of four),
    /// four lanes at a time, each lane a ray against one candidate at a
    /// time: the crossing rule as above, so each lane's answer is exactly
    /// the scalar query's. Written out, a group's rays and best hits stay
    /// in registers (the compiler's own vectors of eight lanes kept them
    /// on the stack, written back with masked stores).
    ///
    /// Inlined always, without AVX as its own target feature: only so
    /// can it be inlined (with the helpers it calls) into the caller's
    /// loop compiled with AVX2; called elsewhere, its helpers run out of
    /// line.
    ///
    /// # Safety
    /// The processor must have AVX.
    #[inline(always)]
    pub(crate) unsafe fn closest_hits<const N: usize>(
        segments: &[Segment],
        rays: &RayLanes<N>,
        candidates: &[u32],
    ) -> HitLanes<N> {
        // SAFETY: the caller guarantees AVX, all these functions need.
        unsafe {
            let mut hits = HitLanes {
                index: [u32::MAX; N],
                t: [f64::INFINITY; N],
                u: [0.0; N],
            };
            let zero = _mm256_setzero_pd();
            let both = |p: __m256d, q: __m256d| _mm256_and_pd(p, q);
            for first in (0..N).step_by(BLOCK) {
                let o = (load(&rays.ox, first), load(&rays.oy, first));
                let d = (load(&rays.dx, first), load(&rays.dy, first));
                let mut best_t = _mm256_set1_pd(f64::INFINITY);
                let mut best_id = _mm256_set1_pd(u32::MAX as f64);
                let (mut best_sa, mut best_sb) = (zero, zero);
                for &index in candidates {
                    let Segment { a, b } = segments[index as usize];
                    let e = b - a;
                    let c = crossing(
                        o,
                        d,
                        (_mm256_set1_pd(a.x), _mm256_set1_pd(a.y)),
                        (_mm256_set1_pd(b.x), _mm256_set1_pd(b.y)),
                        (_mm256_set1_pd(e.x), _mm256_set1_pd(e.y)),
                    );
                    // Ascending indices: an equal `t` found later never wins.
                    let wins = both(
                        c.crosses,
                        both(
                            _mm256_cmp_pd::<_CMP_GT_OQ>(c.t, zero),
                            _mm256_cmp_pd::<_CMP_LT_OQ>(c.t, best_t),
                        ),
                    );
                    best_t = _mm256_blendv_pd(best_t, c.t, wins);
                    best_sa = _mm256_blendv_pd(best_sa, c.sa, wins);
                    best_sb = _mm256_blendv_pd(best_sb, c.sb, wins);
                    best_id = _mm256_blendv_pd(best_id, _mm256_set1_pd(index as f64), wins);
                }
                let u = _mm256_div_pd(best_sa, _mm256_sub_pd(best_sa, best_sb));
                let (t, u, id) = (lanes(best_t), lanes(u), lanes(best_id));
                for k in 0..BLOCK {
                    hits.t[first + k] = t[k];
                    hits.u[first + k] = u[k];
                    // Exact: a u32, or u32::MAX, held as an f64.
                    hits.index[first + k] = id[k] as u32;
                }
            }
            hits
        }
    }
}
