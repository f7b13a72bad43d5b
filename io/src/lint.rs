//! Warnings about a scene that loads but would render otherwise than its
//! author meant, or waste the time spent on it: no lights, things wholly
//! outside the canvas, a lamp on a wall or inside glass, glass that light
//! cannot cross at the scene's settings. (Walls lying on top of each
//! other are warned of where they are resolved, in `load.rs`.)
//!
//! Each warning names the item by its place in its list, counting from 0,
//! and stands at the item's line and column.

use flatray_geometry::{DVec2, Shape};
use flatray_tracer::scene::{Canvas, lies_on_shape};

use crate::format::{LightSpec, SceneFile};
use crate::load::{Warning, inside_polygon};
use crate::locate;

/// A spot's cone below this many degrees is warned of: such a narrow beam
/// is more often a cone meant in radians.
const MIN_CONE_DEGREES: f64 = 2.0;

/// The warnings for `file` (whose text is `text`) on `canvas`.
pub(crate) fn lint(text: &str, file: &SceneFile, canvas: &Canvas) -> Vec<Warning> {
    let mut out = Vec::new();
    let mut at = |offset: usize, message: String| {
        let (line, column) = locate::position(text, offset);
        out.push(Warning {
            line,
            column,
            message,
        });
    };
    let wall_items = locate::list_items(text, "walls");
    let light_items = locate::list_items(text, "lights");
    let glass_items = locate::list_items(text, "glass");
    let item = |items: &[usize], k: usize| items.get(k).copied().unwrap_or(0);

    let lo = canvas.origin;
    let hi = canvas.origin + DVec2::new(canvas.width as f64, canvas.height as f64);
    let spans = format!("x {} to {} and y {} to {}", lo.x, hi.x, lo.y, hi.y);
    // Whether the box from `a` to `b` misses the canvas.
    let outside = |a: DVec2, b: DVec2| {
        let (min, max) = (a.min(b), a.max(b));
        max.x < lo.x || max.y < lo.y || min.x > hi.x || min.y > hi.y
    };

    let emitting = file.walls.iter().any(|w| w.emit.is_some());
    if file.lights.is_empty() && !emitting {
        let offset = locate::field_value(text, "lights").unwrap_or(0);
        at(
            offset,
            "the scene has no lights (and no wall emits): its render is black".to_string(),
        );
    }

    let walls: Vec<Shape> = file.walls.iter().map(|w| w.geometry()).collect();
    for (k, wall) in walls.iter().enumerate() {
        let (lo, hi) = wall.bounds();
        if outside(lo, hi) {
            at(
                item(&wall_items, k),
                format!(
                    "wall {k} lies wholly outside the canvas ({spans}): it is never seen, though it may shadow or reflect light onto the canvas"
                ),
            );
        }
    }
    let polygons: Vec<Vec<DVec2>> = file.glass.iter().map(crate::load::glass_outline).collect();
    for (k, polygon) in polygons.iter().enumerate() {
        let (min, max) = polygon
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(a, b), &p| {
                (a.min(p), b.max(p))
            });
        if outside(min, max) {
            at(
                item(&glass_items, k),
                format!(
                    "glass {k} lies wholly outside the canvas ({spans}): it is never seen, though it may bend light onto the canvas"
                ),
            );
        }
    }
    if !file.glass.is_empty() && file.render.specular.0 < 2 {
        let s = file.render.specular.0;
        at(
            item(&glass_items, 0),
            format!(
                "light crosses glass in at least 2 glass events (in, then out), and `specular: {s}` allows {s} in a row: no light crosses the glass, which casts a full shadow"
            ),
        );
    }

    for (k, light) in file.lights.iter().enumerate() {
        let (centre, reach, name) = match light {
            LightSpec::Point { at, .. } | LightSpec::Laser { at, .. } => {
                (DVec2::new(at.0, at.1), 0.0, "light")
            }
            LightSpec::Spot {
                at: place, cone, ..
            } => {
                if cone.0 < MIN_CONE_DEGREES {
                    at(
                        item(&light_items, k),
                        format!(
                            "light {k}'s cone is {}°, a beam only {}° across: `cone` is the half-angle in degrees (a cone of {} radians is written `cone: {:.1}`)",
                            cone.0,
                            2.0 * cone.0,
                            cone.0,
                            cone.0.to_degrees()
                        ),
                    );
                }
                (DVec2::new(place.0, place.1), 0.0, "light")
            }
            LightSpec::Circle { at, radius, .. } => {
                (DVec2::new(at.0, at.1), radius.0, "circle light")
            }
            LightSpec::Line { a, b, .. } | LightSpec::Beam { a, b, .. } => {
                let (a, b) = (DVec2::new(a.0, a.1), DVec2::new(b.0, b.1));
                if outside(a, b) {
                    at(
                        item(&light_items, k),
                        format!(
                            "light {k} lies wholly outside the canvas ({spans}): it lights the canvas only from there"
                        ),
                    );
                }
                continue;
            }
            LightSpec::Sun { date, time, .. } => {
                let place = crate::daylight::place_of(light).and_then(Result::ok);
                if let Some(place) = place.filter(|p| p.elevation <= 0.0) {
                    at(
                        item(&light_items, k),
                        format!(
                            "light {k}: the sun is {:.1}° below the horizon on {:04}-{:02}-{:02} at {:02}:{:02}: it gives no light",
                            -place.elevation,
                            date.year,
                            date.month,
                            date.day,
                            time.hour,
                            time.minute
                        ),
                    );
                }
                continue;
            }
            LightSpec::Sky {
                profile: Some(knots),
                ..
            } => {
                if !knots.is_empty() && knots.iter().all(|(_, factor)| factor.0 == 0.0) {
                    at(
                        item(&light_items, k),
                        format!(
                            "light {k}: the sky's profile is 0 at every azimuth: it gives no light"
                        ),
                    );
                }
                continue;
            }
            LightSpec::Directional { .. } | LightSpec::Sky { .. } => continue,
        };
        let offset = item(&light_items, k);
        if outside(centre - DVec2::splat(reach), centre + DVec2::splat(reach)) {
            at(
                offset,
                format!(
                    "light {k} at ({}, {}) lies outside the canvas ({spans}): it lights the canvas only from there",
                    centre.x, centre.y
                ),
            );
        }
        for (j, polygon) in polygons.iter().enumerate() {
            if inside_polygon(centre, polygon) {
                at(
                    offset,
                    format!(
                        "light {k} lies inside glass {j}: its light reaches the floor only through the glass's edges, refracted"
                    ),
                );
            }
        }
        for (j, wall) in walls.iter().enumerate() {
            if reach == 0.0 && lies_on_shape(centre, wall) {
                at(
                    offset,
                    format!(
                        "light {k} lies on wall {j}: it lights both sides of the wall (move it off the wall to light one side)"
                    ),
                );
            } else if reach > 0.0 && distance(centre, wall) < reach {
                at(
                    offset,
                    format!(
                        "wall {j} crosses {name} {k}: the light's rim shines on both sides of the wall, and the wall is lit from within the lamp"
                    ),
                );
            }
        }
    }
    out
}

/// The distance from `p` to a wall's shape: to a segment's nearest point;
/// to an arc's point at `p`'s angle, or the nearer end.
fn distance(p: DVec2, shape: &Shape) -> f64 {
    match shape {
        Shape::Segment(s) => {
            let e = s.edge();
            let t = ((p - s.a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
            (s.a + e * t - p).length()
        }
        Shape::Arc(arc) => {
            let on = arc.point_at(arc.position_of(p));
            p.distance(on).min(p.distance(arc.a)).min(p.distance(arc.b))
        }
    }
}

/// How many cells the longer side of the grid that [`sealed`] floods has.
const SEAL_GRID: usize = 128;

/// A sealed light is warned of when its loop holds less than this share
/// of the canvas.
const SEALED_SHARE: f64 = 0.1;

/// Warnings for the lights that no opening lets out: each one inside a
/// closed loop of walls that block light (a column or a box drawn around
/// a lamp, a room with no door, window or gap), which lights nothing
/// outside that loop.
///
/// The walls' bounding box, one cell wider on each side, is divided into
/// a grid of [`SEAL_GRID`] cells on its longer side; neighbouring cells'
/// centres are joined where the segment between them crosses no wall that
/// blocks light (the crossing rule of the geometry, so that walls which
/// share an end leave no gap), and the cells joined to the grid's rim are
/// outside. A light joined to none of its four nearest centres by a clear
/// segment, and not to the outside through one, is sealed; a light too
/// closely enclosed to see any centre is sealed when rays in every
/// direction meet a blocking wall within two cells. A sealed light is
/// warned of when its loop holds less than [`SEALED_SHARE`] of the canvas
/// (a larger loop is a room or a bay closed on purpose). An
/// opening narrower than about two cells can be missed: the warning says
/// "appears".
pub(crate) fn sealed(text: &str, file: &SceneFile, scene: &flatray_tracer::Scene) -> Vec<Warning> {
    use flatray_geometry::{Ray, Skip};
    let segments = scene.segments();
    let walls = scene.walls();
    // Panes (tinted or clear) and glass let light through.
    let stops = |w: &flatray_tracer::scene::Wall| !w.material.is_pane() && !w.material.is_glass();
    let blocks = |i: u32| walls.get(i as usize).is_some_and(stops);
    if !walls.iter().any(stops) {
        return Vec::new();
    }
    // A little past both ends, so that a centre lying on a wall (a grid
    // lined up with a wall's corners) is cut off from both sides rather
    // than joining them.
    let clear = |a: DVec2, b: DVec2| {
        let d = b - a;
        let ray = Ray::new(a - d * 1e-6, d * (1.0 + 2e-6));
        segments.for_each_crossing(&ray, 1.0, Skip::NONE, |i, _| !blocks(i))
    };
    // From a light: not behind it (a light on a wall is warned of as such,
    // and sees both sides).
    let clear_from = |p: DVec2, b: DVec2| {
        let ray = Ray::new(p, (b - p) * (1.0 + 1e-6));
        segments.for_each_crossing(&ray, 1.0, Skip::NONE, |i, _| !blocks(i))
    };
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for w in walls.iter().filter(|w| stops(w)) {
        let (a, b) = w.shape.bounds();
        (lo, hi) = (lo.min(a), hi.max(b));
    }
    let size = (hi - lo).max_element();
    if !(size.is_finite() && size > 0.0) {
        return Vec::new();
    }
    let h = size / (SEAL_GRID - 2) as f64;
    lo -= DVec2::splat(h);
    let nx = (((hi.x - lo.x) / h).ceil() as usize + 1).clamp(2, SEAL_GRID);
    let ny = (((hi.y - lo.y) / h).ceil() as usize + 1).clamp(2, SEAL_GRID);
    let centre = |i: usize, j: usize| lo + DVec2::new((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);

    // The cells joined to each other, region by region; region 0 holds
    // the rim, the outside of every loop.
    const NONE: u32 = u32::MAX;
    let mut region = vec![NONE; nx * ny];
    let mut on_canvas = Vec::new();
    let mut queue = Vec::new();
    let starts = (0..nx)
        .map(|i| (i, 0))
        .chain((0..nx * ny).map(|c| (c % nx, c / nx)));
    for (si, sj) in starts {
        if region[sj * nx + si] != NONE {
            continue;
        }
        let label = on_canvas.len() as u32;
        on_canvas.push(0usize);
        region[sj * nx + si] = label;
        queue.push((si, sj));
        while let Some((i, j)) = queue.pop() {
            let here = centre(i, j);
            if scene.canvas().contains(here) {
                on_canvas[label as usize] += 1;
            }
            // The rim is all one region, joined around the walls.
            let rim = |i: usize, j: usize| i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
            let mut visit = |ni: usize, nj: usize| {
                if region[nj * nx + ni] == NONE
                    && ((rim(i, j) && rim(ni, nj)) || clear(here, centre(ni, nj)))
                {
                    region[nj * nx + ni] = label;
                    queue.push((ni, nj));
                }
            };
            if i > 0 {
                visit(i - 1, j);
            }
            if i + 1 < nx {
                visit(i + 1, j);
            }
            if j > 0 {
                visit(i, j - 1);
            }
            if j + 1 < ny {
                visit(i, j + 1);
            }
        }
    }
    let canvas = scene.canvas();
    let canvas_area = (canvas.width as f64 * canvas.height as f64).max(1.0);

    let light_items = locate::list_items(text, "lights");
    let mut out = Vec::new();
    for (k, light) in file.lights.iter().enumerate() {
        let p = match light {
            LightSpec::Point { at, .. }
            | LightSpec::Laser { at, .. }
            | LightSpec::Spot { at, .. }
            | LightSpec::Circle { at, .. } => DVec2::new(at.0, at.1),
            LightSpec::Line { a, b, .. } | LightSpec::Beam { a, b, .. } => {
                DVec2::new(a.0 + b.0, a.1 + b.1) * 0.5
            }
            LightSpec::Directional { .. } | LightSpec::Sun { .. } | LightSpec::Sky { .. } => {
                continue;
            }
        };
        if !(p.cmpgt(lo).all() && p.cmplt(lo + DVec2::new(nx as f64, ny as f64) * h).all()) {
            continue;
        }
        let g = (p - lo) / h - DVec2::splat(0.5);
        let (i0, j0) = (g.x.floor().max(0.0) as usize, g.y.floor().max(0.0) as usize);
        let mut seen: Vec<u32> = [(i0, j0), (i0 + 1, j0), (i0, j0 + 1), (i0 + 1, j0 + 1)]
            .into_iter()
            .filter(|&(i, j)| i < nx && j < ny && clear_from(p, centre(i, j)))
            .map(|(i, j)| region[j * nx + i])
            .collect();
        seen.sort_unstable();
        seen.dedup();
        let seen_any = !seen.is_empty();
        let reaches_out = seen.contains(&0);
        // A loop that holds a good part of the canvas is a room or a bay
        // closed on purpose (the scene's own room, bays each with their
        // lamp); a small one is a column, a box, a closet with no door.
        let lit: usize = seen.iter().map(|&r| on_canvas[r as usize]).sum();
        let share = lit as f64 * h * h / canvas_area;
        let most = share >= SEALED_SHARE;
        let enclosed_closely = || {
            (0..32).all(|r| {
                let angle = std::f64::consts::TAU * (r as f64 + 0.5) / 32.0;
                let far = p + DVec2::new(angle.cos(), angle.sin()) * 2.0 * h;
                !clear_from(p, far)
            })
        };
        if reaches_out || most || (!seen_any && !enclosed_closely()) {
            continue;
        }
        let (line, column) = locate::position(text, light_items.get(k).copied().unwrap_or(0));
        out.push(Warning {
            line,
            column,
            message: format!(
                "light {k} appears sealed inside a closed loop of walls: no opening lets its light out, so it lights only the inside of that loop, {:.0} % of the canvas (give the loop a gap, a pane or a door, or move the light out of it)",
                100.0 * share
            ),
        });
    }
    out
}
