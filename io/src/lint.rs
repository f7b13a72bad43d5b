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
            LightSpec::Spot { at, .. } => (DVec2::new(at.0, at.1), 0.0, "light"),
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
            LightSpec::Directional { .. } => continue,
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
