//! The onward memo: what the rest of a path brings from a diffuse wall,
//! binned along the walls as the wall memo bins direct light.
//!
//! A path that reaches a diffuse wall with `m` reflections left adds the
//! wall's direct light (next-event estimation, `(rho / 2) E`) and would go
//! on in a cosine-weighted direction with its throughput times `rho`.
//! What it goes on to bring, on average over that direction, is
//!
//! ```text
//! C_m(y) = E_omega[ value of the path from y in direction omega,
//!                   with m reflections left ],
//! ```
//!
//! a function of the wall, the side and the position `y` alone. The memo
//! holds `C_m` for `m = 1 .. D - 1`, per (wall, side, bin), filled order
//! by order: a gather path for `C_m` is the path loop itself from the
//! bin's centre (mirrors, panes, line lights after a mirror, the caustic
//! pass's bins, the direct-light memo), ending at its first diffuse wall
//! with a reflection left by reading `C` one order lower there. A path
//! from the floor then ends at its first diffuse wall, adding
//! `rho C_m` there: one ray per sample where the path loop would cast
//! up to `D`.
//!
//! Each render pass (`passes.rs`) fills the memo anew, from its own seed:
//! each bin's gathers take `K` cosine-weighted directions stratified over
//! the half circle, `K` the pass's samples per pixel. The passes' memos
//! are independent, so the image's memo error falls as the samples grow
//! (to the memo's value at each bin's centre: the wall memo's kind of
//! bias). The first pass keeps the memo twice, from independent gathers:
//! the first half of its samples reads one copy and the second half the
//! other, so the noise estimate from its two halves includes the memo's
//! own error. A later pass is one half of the estimate by itself, and
//! keeps the memo once, with twice the gathers: the same work and error,
//! half the memory.

use flatray_cache::WallMemo;
use flatray_geometry::{Ray, Side, Skip};

use crate::memo::{Onward, OnwardMemo, to_value};
use crate::path::{Leg, Trace, follow};
use crate::sampling::{Stream, cosine_half_circle};
use crate::{Rgb, Stats};

/// Bytes the onward memo may take (both copies, every order): over it,
/// the plan leaves paths to the path loop.
pub const ONWARD_BUDGET: u64 = 256 << 20;

/// The fewest gather directions per bin, order and copy.
pub const MIN_GATHERS: u32 = 8;

/// The stream sample numbers of gathers start here, apart from every
/// pixel sample's.
const ONWARD_STREAM: u64 = 1 << 43;

/// Gather directions per bin, order and copy for a render pass of
/// `samples` per pixel over `pixels` pixels, with `values` (wall, side,
/// bin) values per table, `orders` orders and `copies` copies (1 or 2): as
/// many as the samples times 2 / `copies` (at least [`MIN_GATHERS`]), but
/// all gathers together at most half as many paths as the pass's pixel
/// samples (and at least one per bin).
pub(crate) fn gathers(samples: u32, pixels: u64, (values, orders): (u64, u32), copies: u32) -> u32 {
    let copies = copies.clamp(1, 2);
    let wanted = (samples as u64 * 2 / copies as u64).max(MIN_GATHERS as u64);
    let tables = (copies as u64 * orders as u64)
        .saturating_mul(values)
        .max(1);
    let cap = (pixels.saturating_mul(samples as u64) / 2) / tables;
    wanted.min(cap).max(1) as u32
}

/// The bytes of the onward memo for `bounces` reflections, given the
/// wall memo's: both copies of `bounces - 1` tables.
pub(crate) fn onward_bytes(wall_memo_bytes: u64, bounces: u32) -> u64 {
    wall_memo_bytes.saturating_mul(2 * bounces.saturating_sub(1) as u64)
}

/// Fills the onward memo for the paths `trace` describes (its `onward`
/// unset), on the bins of `wall_memo` (the memo its paths read), `copies`
/// times (1 or 2) with `gathers` directions per bin.
pub(crate) fn build_onward(
    trace: &Trace,
    wall_memo: &WallMemo,
    (gathers, copies): (u32, u32),
    seed: u64,
    stats: &mut Stats,
) -> OnwardMemo {
    let scene = trace.scene;
    let bounces = trace.bounces;
    let gathers = gathers.max(1);
    let (mut rays, mut listed, mut bytes) = (0u64, 0u64, 0u64);
    let kept = copies.clamp(1, 2) as usize;
    let mut copies: [Vec<WallMemo>; 2] = [Vec::new(), Vec::new()];
    for (copy, tables) in copies.iter_mut().enumerate().take(kept) {
        for m in 1..bounces {
            let lower: &[WallMemo] = tables;
            let gather_trace = Trace {
                onward: Some(Onward {
                    copies: [lower, lower],
                    half: 0,
                }),
                floor_direct: false,
                memo_checks: false,
                ..*trace
            };
            let counted = std::sync::atomic::AtomicU64::new(0);
            let counted_listed = std::sync::atomic::AtomicU64::new(0);
            let table = wall_memo.build_like(gathers as usize, |wall, side, u, k| {
                let w = &scene.walls[wall as usize];
                if !w.material.is_diffuse() {
                    return [0.0; 3];
                }
                let side_of = Side::of_index(side);
                let key = gather_key(wall, side, u, m, copy);
                let mut stream = Stream::new(seed, key, ONWARD_STREAM + k as u64);
                // Stratum k of K over the half circle's cosine measure.
                let fraction = (k as f64 + stream.uniform()) / gathers as f64;
                let x = w.shape.point_at(u);
                let dir = cosine_half_circle(w.shape.normal_on(side_of, x), fraction);
                let leg = Leg {
                    throughput: Rgb::ONE,
                    bounce: bounces - m,
                    skip: Skip::one(wall),
                };
                // The walls the first ray can meet, where a fast path
                // lists them.
                let line_walls = trace.mirror_arcs.and_then(|arcs| arcs.walls(wall, u, dir));
                if line_walls.is_some() {
                    counted_listed.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
                let mut local = Stats::default();
                let value = follow(
                    &gather_trace,
                    Rgb::ZERO,
                    Ray::new(x, dir),
                    None,
                    line_walls,
                    leg,
                    Some(lower),
                    &mut stream,
                    &mut local,
                );
                counted.fetch_add(
                    local.work.bounce_rays + local.work.shadow_rays,
                    std::sync::atomic::Ordering::Relaxed,
                );
                if value.is_finite() {
                    to_value(value / gathers as f64)
                } else {
                    [0.0; 3]
                }
            });
            rays += counted.into_inner();
            listed += counted_listed.into_inner();
            bytes += table.memory_bytes() as u64;
            tables.push(table);
        }
    }
    stats.work.onward_rays += rays;
    stats.work.onward_listed_rays += listed;
    // A part of the wall cache's bytes, and apart.
    stats.work.onward_bytes += bytes;
    stats.work.memo_bytes += bytes;
    OnwardMemo { copies }
}

/// The stream index of a bin's gathers: its wall, side, centre, order and
/// copy, mixed (the stream mixes it again).
fn gather_key(wall: u32, side: usize, u: f64, order: u32, copy: usize) -> u64 {
    let tag =
        ((wall as u64) << 8) | ((order as u64 & 0x3f) << 2) | ((side as u64) << 1) | copy as u64;
    u.to_bits().rotate_left(23) ^ tag.wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gathers_follow_the_samples_within_half_the_pixel_samples() {
        // As many as the samples, at least MIN_GATHERS; twice as many for
        // one copy.
        assert_eq!(gathers(64, 1_000_000, (1000, 2), 2), 64);
        assert_eq!(gathers(64, 1_000_000, (1000, 2), 1), 128);
        assert_eq!(gathers(2, 1_000_000, (1000, 2), 2), MIN_GATHERS);
        // Capped at half the pixel samples over 2 copies x 2 orders x
        // 1000 values: 100 x 64 / 2 / 4000 is below 1, so 1 per bin;
        // 10,000 x 64 / 2 / 4000 = 80, above the 64 wanted; 2,000 pixels
        // give 16 (32 for one copy).
        assert_eq!(gathers(64, 100, (1000, 2), 2), 1);
        assert_eq!(gathers(64, 10_000, (1000, 2), 2), 64);
        assert_eq!(gathers(64, 2_000, (1000, 2), 2), 16);
        assert_eq!(gathers(64, 2_000, (1000, 2), 1), 32);
        // No orders or no values: no division by zero.
        assert_eq!(gathers(16, 100, (0, 0), 2), 16);
        assert_eq!(onward_bytes(1000, 1), 0);
        assert_eq!(onward_bytes(1000, 3), 4000);
    }
}
