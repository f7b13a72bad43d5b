//! A fast path beside the model: the one-bounce shortcut. Where a render
//! has one bounce and the wall memo, most paths go from the floor to one
//! diffuse wall and stop there (no line or circle light can come back to
//! that side of it by a mirror: `run::last_leg_sides`); this reads that
//! case straight from the memo, through the path loop's own functions
//! (`path::add_caustics`, `path::lambertian_light`), and leaves every other
//! case to it (`path::path_finish`).

use std::f64::consts::TAU;

use flatray_cache::{Check, WallMemo};
use flatray_geometry::{DVec2, Shape};

use crate::material::diffuse_albedo;
use crate::path::{Trace, add_caustics, lambertian_light, memo_read};
use crate::{Rgb, Stats};

/// The common case of `path::path_finish`, straight: one bounce, the first
/// ray from the floor (direction `dir`) meeting diffuse wall `index` at
/// `u`, its light read from the memo. The same operations, in the same
/// order, as the path loop would make (a first flight crosses no glass it
/// knows of, so its transmittance is exactly 1). The caller takes it only
/// for one bounce with the memo, not in the reference. `None` where the
/// path takes the loop: another material, a wall's end, and an `index` of
/// no wall, and a read the path loop checks (`flatray_cache::Check`, by
/// `path`, the key of the stream the loop would take: `Stream::key`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn memo_bounce(
    trace: &Trace,
    memo: &WallMemo,
    fluence: Rgb,
    index: u32,
    u: f64,
    dir: DVec2,
    path: u64,
    stats: &mut Stats,
) -> Option<Rgb> {
    let scene = trace.scene;
    let wall = scene.walls.get(index as usize)?;
    let albedo = wall.material.diffuse_albedo()?;
    if u == 0.0 || u == 1.0 {
        return None;
    }
    let side = match &wall.shape {
        Shape::Segment(s) => s.arrival_side(dir)?,
        Shape::Arc(arc) => arc.arrival_side(arc.point_at(u), dir)?,
    };
    let (read, check) = memo_read(memo, (index, side, u), path, trace.memo_checks);
    if trace.memo_checks && check != Check::No {
        return None;
    }
    if trace
        .last_leg_sides
        .is_some_and(|sides| sides.get(2 * index as usize + side.index()) != Some(&false))
    {
        // The path goes on past this wall: the loop follows it.
        return None;
    }
    stats.work.bounce_rays += 1;
    stats.work.memo_lookups += 1;
    stats.physics.paths_bounce_limit += 1;
    let x = wall.shape.point_at(u);
    let rho = diffuse_albedo(scene, albedo, (index, u, x), trace.tables, stats);
    // The path loop's own steps: the memo's read, the caustic bins, f E.
    let irradiance = add_caustics(trace, read, (index, side, u), 1);
    Some(fluence + lambertian_light(Rgb::splat(TAU), rho, irradiance))
}

/// One bounce with the wall memo: most paths then end at their first wall.
pub(crate) fn supports(facts: &crate::accel::Facts) -> crate::accel::Decision {
    use crate::accel::Decision;
    use crate::options::FastPath;
    if !facts.indirect {
        return Decision::skipped("no indirect light is traced");
    }
    if facts.options.bounces != 1 {
        return Decision::skipped("only for one bounce");
    }
    if !facts.wall_memo {
        return Decision::skipped("no wall cache");
    }
    if let Some(no) = Decision::allowed(facts.options, FastPath::Shortcut, "shortcut") {
        return no;
    }
    Decision::runs("a path that ends at its first diffuse wall reads it from the wall cache")
}
