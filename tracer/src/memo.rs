//! The wall memo (`flatray-cache`): filling it with each diffuse wall's
//! direct irradiance per (wall, side, bin), summed over the lights, and
//! the onward memo's tables as paths read them (`onward.rs` fills them).
//! The floor memo, the floor's direct light once per pixel over its
//! points, is the pixel loop's (`pixel.rs`, `accel/strata.rs`).

use std::sync::atomic::{AtomicU64, Ordering};

use flatray_cache::{Value, WallMemo};
use flatray_geometry::Side;

use crate::estimators::{Receiver, Visibility, light_contribution, with_closed_forms};
use crate::ledger::Ledger;
use crate::options::MemoOptions;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Bytes the wall memo may take: over it, the plan switches it off.
pub const WALL_MEMO_BUDGET: u64 = 256 << 20;

/// At most the bytes the wall memo of `scene` at `scale` would take,
/// counted without building it: each diffuse wall's bins (its length over
/// the bin length, plus one per span that a junction starts), per side,
/// summed over the lights. `None` as soon as the count passes `budget`,
/// so walls that cross very often cost no more than the budget to count.
pub(crate) fn wall_memo_bytes(
    scene: &Scene,
    options: &MemoOptions,
    scale: f64,
    budget: u64,
) -> Option<u64> {
    let bin_length = options.bin_length / scale;
    // Both sides' sums over the lights, and the flags of their reads.
    let per_bin = 2 * (std::mem::size_of::<Value>() as u64 + 1);
    let mut bytes = 0u64;
    for (index, w) in scene.walls.iter().enumerate() {
        if !w.material.is_diffuse() {
            bytes += per_bin;
            continue;
        }
        let bins = (w.shape.length() / bin_length).ceil();
        if !(bins.is_finite() && bins < budget as f64) {
            return None;
        }
        bytes = bytes.checked_add((bins as u64 + 1).checked_mul(per_bin)?)?;
        if bytes > budget {
            return None;
        }
        // A junction starts a span: at most one more bin.
        let junctions = scene.junctions_of(index as u32).len() as u64;
        bytes = bytes.saturating_add(junctions.saturating_mul(per_bin + SPAN_BYTES));
        let over = bytes > budget;
        if over {
            return None;
        }
    }
    Some(bytes)
}

/// Points along an arc light at which each bin takes its light: the
/// midpoint rule, whose error falls with the square of their number where
/// the arc is seen whole, and the checked reads take out the rest.
const ARC_LIGHT_SAMPLES: usize = 64;

/// What a span of the memo takes besides its bins (an upper bound).
const SPAN_BYTES: u64 = 64;

/// Fills the wall memo for `scene` rendered at `scale` pixels per unit.
/// Only diffuse walls get real bins; the others hold one unused zero bin.
pub(crate) fn build_wall_memo(
    scene: &Scene,
    options: &MemoOptions,
    scale: f64,
    (shadows, ledger): (bool, &Ledger),
    stats: &mut Stats,
) -> WallMemo {
    let lengths = scene.diffuse_lengths();
    let junctions = scene.junctions();
    let bin_length = options.bin_length / scale;
    let rays = AtomicU64::new(0);
    let memo = WallMemo::build(
        &lengths,
        &junctions,
        bin_length,
        scene.lights.len(),
        |wall, side, u, light_index| {
            let w = &scene.walls[wall as usize];
            if !w.material.is_diffuse() {
                return [0.0; 3];
            }
            let side = Side::of_index(side);
            let x = w.shape.point_at(u);
            let receiver = Receiver {
                normal: Some(w.shape.normal_on(side, x)),
                wall: Some(wall),
                shadow_walls: None,
            };
            let mut local = Stats::default();
            // Lines and circles in closed form, every light one call; an
            // arc light, sampled, by the midpoint rule along it.
            let samples = if scene.lights[light_index].shape.numbers() > 0
                && !crate::estimators::is_exact(&scene.lights[light_index].shape)
            {
                ARC_LIGHT_SAMPLES
            } else {
                1
            };
            let mut value = crate::Rgb::ZERO;
            for k in 0..samples {
                value += light_contribution(
                    scene,
                    light_index,
                    x,
                    receiver,
                    (k as f64 + 0.5) / samples as f64,
                    Visibility::of(shadows),
                    &mut local,
                );
            }
            let value = value / samples as f64;
            let value = with_closed_forms(
                value,
                ledger,
                scene,
                (x, receiver),
                Some(light_index),
                &mut local,
            );
            rays.fetch_add(local.work.shadow_rays, Ordering::Relaxed);
            to_value(value)
        },
    );
    let mut memo = memo;
    let edge_rays = mark_shadow_edges(scene, &mut memo);
    stats.work.memo_entries += memo.entries() as u64;
    stats.work.memo_bytes += memo.memory_bytes() as u64;
    stats.work.memo_fill_rays += rays.load(Ordering::Relaxed) + edge_rays;
    memo
}

/// The most rays [`mark_shadow_edges`] casts: past it (many lights times
/// many walls), the bins' own values alone say where reads are always
/// checked.
const EDGE_RAYS: usize = 1 << 21;

/// Where light from a point, or from a direction, casts its shadows'
/// edges: the ray from the light through each wall's ends (and past the
/// sides of each arc as the light sees them), to the first wall behind.
/// The memo checks the reads about each more often, as the light that
/// the edge may cut off there asks ([`WallMemo::mark_edge`]): a shadow
/// narrower than a bin falls between two centres that both see the light,
/// and only its edges tell that it is there. Line lights cast their edges
/// from both ends; a circle from its centre (its shadows' edges are
/// soft). Returns the rays cast.
fn mark_shadow_edges(scene: &Scene, memo: &mut WallMemo) -> u64 {
    use flatray_geometry::{DVec2, Ray, Shape};
    use rayon::prelude::*;

    use crate::scene::LightShape;

    /// Where a shadow's edge starts: from a point, or along a direction.
    #[derive(Clone, Copy)]
    enum From {
        Point(DVec2),
        Along(DVec2),
    }
    // Each edge's source, and the light that casts it.
    let mut sources = Vec::new();
    for (light, l) in scene.lights.iter().enumerate() {
        match &l.shape {
            LightShape::Point { at } | LightShape::Circle { at, .. } => {
                sources.push((From::Point(*at), light))
            }
            LightShape::Spot { at, .. } => sources.push((From::Point(*at), light)),
            LightShape::Line { segment, .. } => {
                sources.extend([
                    (From::Point(segment.a), light),
                    (From::Point(segment.b), light),
                ]);
            }
            LightShape::Directional { direction } | LightShape::Beam { direction, .. } => {
                sources.extend([
                    (From::Along(*direction), light),
                    (From::Along(-*direction), light),
                ]);
            }
            _ => {}
        }
    }
    let mut ends = Vec::new();
    let mut arcs = Vec::new();
    for wall in &scene.walls {
        match &wall.shape {
            Shape::Segment(s) => ends.extend([s.a, s.b]),
            Shape::Arc(arc) => {
                if !arc.is_full() {
                    ends.extend([arc.a, arc.b]);
                }
                arcs.push((arc.center, arc.radius));
            }
        }
    }
    let rays = sources.len().saturating_mul(ends.len() + 2 * arcs.len());
    if rays == 0 || rays > EDGE_RAYS {
        return 0;
    }
    let edges: Vec<(u32, f64, [Value; 2])> = sources
        .par_iter()
        .flat_map_iter(|&(source, light)| {
            // The points a shadow's edge passes: the walls' ends, and
            // where the light grazes each arc's circle.
            let grazes = arcs.iter().flat_map(move |&(c, r)| {
                let side = match source {
                    From::Point(p) => p - c,
                    From::Along(d) => d.perp(),
                };
                let d = side.length();
                let angle = match source {
                    From::Point(_) if d > r => (r / d).acos(),
                    From::Point(_) => f64::NAN,
                    From::Along(_) => std::f64::consts::FRAC_PI_2,
                };
                let towards = side.y.atan2(side.x);
                [towards - angle, towards + angle].map(|a| c + r * DVec2::new(a.cos(), a.sin()))
            });
            ends.iter().copied().chain(grazes).filter_map(move |v| {
                let (dir, reach) = match source {
                    From::Point(p) => ((v - p).normalize(), p.distance(v)),
                    From::Along(d) => (d.normalize(), f64::INFINITY),
                };
                if !(dir.is_finite() && v.is_finite()) {
                    return None;
                }
                // The light must reach the end: nothing opaque between.
                let margin = 1e-9 * (1.0 + v.abs().max_element());
                let back = Ray::new(v - dir * margin, -dir);
                if first_stop(scene, back, reach - 2.0 * margin).is_some() {
                    return None;
                }
                // Just past the end, so that the walls that meet there
                // are not the ones found.
                let (index, hit) =
                    first_stop(scene, Ray::new(v + dir * margin, dir), f64::INFINITY)?;
                Some((index, hit.u, unshadowed(scene, light, index, hit.u)))
            })
        })
        .collect();
    for (index, u, jump) in edges {
        memo.mark_edge(index, u, jump);
    }
    2 * rays as u64
}

/// What `light` sends, with no wall in between, to each side of `wall` at
/// `u`: at most what a shadow's edge there can cut off a bin's value.
fn unshadowed(scene: &Scene, light: usize, wall: u32, u: f64) -> [Value; 2] {
    let Some(w) = scene.walls.get(wall as usize) else {
        return [[0.0; 3]; 2];
    };
    if !w.material.is_diffuse() {
        return [[0.0; 3]; 2];
    }
    let x = w.shape.point_at(u);
    let mut local = Stats::default();
    [0, 1].map(|i| {
        let side = Side::of_index(i);
        let receiver = Receiver {
            normal: Some(w.shape.normal_on(side, x)),
            wall: Some(wall),
            shadow_walls: None,
        };
        let all = Visibility::Known(Rgb::ONE);
        let value = light_contribution(scene, light, x, receiver, 0.5, all, &mut local);
        to_value(value)
    })
}

/// The first wall along `ray` before `t_max` that light does not pass
/// (a pane lets it through, tinted), among the first few it meets.
fn first_stop(
    scene: &Scene,
    mut ray: flatray_geometry::Ray,
    mut t_max: f64,
) -> Option<(u32, flatray_geometry::Hit)> {
    use flatray_geometry::Skip;
    let mut skip = Skip::NONE;
    for _ in 0..8 {
        let (index, hit) = scene.segments.closest_hit(&ray, t_max, skip)?;
        if scene.stops_rays(index) {
            return Some((index, hit));
        }
        ray.origin += ray.dir * hit.t;
        t_max -= hit.t;
        skip = Skip::one(index);
    }
    None
}

pub(crate) fn to_value(v: Rgb) -> Value {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// The onward memo (`onward.rs` fills it) as paths read it. Its copies: `copies[h][m - 1]` holds `C_m`; the second
/// is empty where the memo is kept once.
#[derive(Debug, Default)]
pub(crate) struct OnwardMemo {
    pub(crate) copies: [Vec<WallMemo>; 2],
}

/// What a path reads: one copy per half of a pixel's samples.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Onward<'a> {
    pub(crate) copies: [&'a [WallMemo]; 2],
    /// Samples below this read the first copy (`Pass::middle`: the noise
    /// estimate's first half).
    pub(crate) half: u32,
}

impl<'a> Onward<'a> {
    /// The memo as a render pass reads it: samples below `middle` (the
    /// pass's first half) read the first copy, the others the second (the
    /// first too, where the memo is kept once).
    pub fn of(memo: &'a OnwardMemo, middle: u32) -> Onward<'a> {
        let second = match memo.copies[1].is_empty() {
            true => &memo.copies[0],
            false => &memo.copies[1],
        };
        Onward {
            copies: [&memo.copies[0], second],
            half: middle,
        }
    }

    /// The tables that sample `sample` reads: `[m - 1]` for `C_m`.
    #[inline(always)]
    pub fn for_sample(self, sample: u32) -> &'a [WallMemo] {
        self.copies[(sample >= self.half) as usize]
    }
}

#[cfg(test)]
mod tests {
    use flatray_cache::Key;
    use flatray_geometry::DVec2;

    use super::*;
    use crate::options::RenderOptions;
    use crate::plan::Plan;
    use crate::scene::{Canvas, Falloff, Floor, Light, LightShape, Material, Wall};

    /// A long wall lit by a bright lamp and a dim one, each behind a post
    /// thinner than a bin, so that each casts a shadow on the wall that
    /// falls between two bin centres which both see the lamp; all of it
    /// turned by `angle` about (50, 10).
    fn posts(dim: f64, angle: f64) -> Scene {
        let diffuse = Material::Diffuse { albedo: None };
        let turn = |(x, y): (f64, f64)| {
            let (sin, cos) = angle.sin_cos();
            let (dx, dy) = (x - 50.0, y - 10.0);
            DVec2::new(50.0 + dx * cos - dy * sin, 10.0 + dx * sin + dy * cos)
        };
        let segment = |a: (f64, f64), b: (f64, f64)| Wall::segment(turn(a), turn(b), diffuse);
        let walls = vec![
            segment((0.0, 0.0), (100.0, 0.0)),
            segment((49.9, 10.0), (50.1, 10.0)),
            segment((24.9, 10.0), (25.1, 10.0)),
        ];
        let lamp = |x: f64, intensity: f64| Light {
            profile: None,
            shape: LightShape::Point {
                at: turn((x, 20.0)),
            },
            color: Rgb::ONE,
            intensity,
            falloff: Falloff::Flatland,
            spectrum: None,
        };
        let lights = vec![lamp(50.0, 1.0), lamp(15.0, dim)];
        let canvas = Canvas {
            width: 120,
            height: 120,
            origin: DVec2::new(-10.0, -50.0),
        };
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, lights).expect("a valid scene")
    }

    #[test]
    fn a_read_checked_at_its_rate_is_not_below_zero_in_a_shadow_thinner_than_a_bin() {
        for angle in [0.0, 0.3, 2.0] {
            reads_checked_at_their_rates_are_not_below_zero(&posts(0.01, angle));
        }
    }

    fn reads_checked_at_their_rates_are_not_below_zero(scene: &Scene) {
        let options = RenderOptions::default();
        let plan = Plan::new(scene, &options);
        let ledger = plan.ledger();
        let mut stats = Stats::default();
        let memo = build_wall_memo(
            scene,
            &options.memo,
            options.scale,
            (true, &ledger),
            &mut stats,
        );
        let wall = &scene.walls[0];
        let mut dim_shadow_rates = Vec::new();
        for k in 0..20_000 {
            let u = (k as f64 + 0.5) / 20_000.0;
            let x = wall.shape.point_at(u);
            for side in [Side::Positive, Side::Negative] {
                let receiver = Receiver {
                    normal: Some(wall.shape.normal_on(side, x)),
                    wall: Some(0),
                    shadow_walls: None,
                };
                // Point lights: one shadow ray each gives the exact value.
                let exact: Rgb = (0..scene.lights.len())
                    .map(|l| {
                        let vis = Visibility::Trace;
                        light_contribution(scene, l, x, receiver, 0.5, vis, &mut stats)
                    })
                    .sum();
                let key = Key {
                    wall: 0,
                    side: side.index(),
                    u,
                };
                let m = memo.lookup(key)[1] as f64;
                let rate = memo.check_rate(key);
                let checked = m + rate as f64 * (exact.y - m);
                assert!(
                    checked >= -1e-6 * m,
                    "u {u}: the memo's {m}, exact {}, rate {rate} -> {checked}",
                    exact.y
                );
                // Where the dim lamp's post shades the lit side (the ray
                // from (15, 20) past (25, 10) meets the wall 35 from its
                // start, before the turn).
                if side == Side::Positive && (u - 0.35).abs() < 0.0005 {
                    dim_shadow_rates.push(rate);
                }
            }
        }
        // The dim lamp's shadow asks for no more than a check in 8 there.
        assert!(!dim_shadow_rates.is_empty());
        assert!(
            dim_shadow_rates.iter().all(|&r| r >= 8),
            "{dim_shadow_rates:?}"
        );
    }
}
