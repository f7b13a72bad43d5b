//! A fast path beside the light table (`estimators/choice.rs`): which lights
//! one opaque wall hides from the whole of a table cell. A point that
//! chooses such a light casts no shadow ray: its contribution is exactly
//! 0, as the ray would find. The choice and its probabilities stay as the
//! model has them, so the image is the same, bit for bit.
//!
//! Never reads the light table's choices, only its cells and their
//! always-lights; never marks a light that any point of a cell might see.

use flatray_geometry::{DVec2, Ray, Segment, Skip, cross};
use rayon::prelude::*;

use crate::estimators::choice::LightTable;
use crate::lights::Source;
use crate::scene::Scene;

/// For every cell of `table`, a bit per light (`table.dark_words()`
/// words a cell): set for a light, beside the cell's always-lights, that
/// one opaque wall hides from every point of the cell. From each corner,
/// the way to the light crosses that wall well inside it, and the corner
/// and the light lie well off its line. The shadow of a wall from a point
/// light (or a sun) is convex, so it then holds the whole cell, and a
/// shadow ray from any point of it meets that wall: its transmittance is
/// exactly 0. A wall that hides the whole cell hides its centre: the
/// centre's one ray to the light finds every candidate. Lines and circles
/// are never marked. Also the rays cast, one per cell and light looked at.
pub(crate) fn dark_cells(scene: &Scene, table: &LightTable) -> (Vec<u64>, u64) {
    let words = table.dark_words();
    let lights = table.lights().min(scene.lights.len());
    let dark: Vec<(Vec<u64>, u64)> = (0..table.cells())
        .into_par_iter()
        .map(|cell| {
            let mut bits = vec![0u64; words];
            let (lo, hi) = table.cell_box(cell);
            let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
            let always: Vec<usize> = table.always(cell).collect();
            let mut rays = 0;
            for light in 0..lights {
                if always.contains(&light) {
                    continue;
                }
                rays += 1;
                if hidden_from_box(scene, light, corners) {
                    bits[light / 64] |= 1 << (light % 64);
                }
            }
            (bits, rays)
        })
        .collect();
    let rays = dark.iter().map(|(_, rays)| rays).sum();
    (dark.into_iter().flat_map(|(bits, _)| bits).collect(), rays)
}

/// Whether one opaque wall (not the light's own) hides light `index`
/// from all four `corners` of a box, with room to spare
/// ([`dark_cells`]). Walls are looked for along the way from
/// the box's centre to the light.
fn hidden_from_box(scene: &Scene, index: usize, corners: [DVec2; 4]) -> bool {
    let light = &scene.lights[index];
    // The way from a point to the light: towards `at` up to it, or
    // against the sun's direction without end.
    let (target, sun) = match light.shape.source() {
        Some(Source::At(at)) => (at, false),
        Some(Source::Sun(direction)) => (-direction, true),
        None => return false,
    };
    let way = |q: DVec2| if sun { target } else { target - q };
    let centre = (corners[0] + corners[2]) * 0.5;
    let (t_max, ray) = (
        if sun { f64::INFINITY } else { 1.0 },
        Ray::new(centre, way(centre)),
    );
    if !(ray.origin.is_finite() && ray.dir.is_finite()) || ray.dir == DVec2::ZERO {
        return false;
    }
    let skip = Skip(scene.light_wall[index].unwrap_or(u32::MAX), u32::MAX);
    let mut hidden = false;
    scene
        .segments
        .for_each_crossing(&ray, t_max, skip, |wall, _| {
            // An arc is not taken to hide a cell: its shadow is no wedge.
            let Some(segment) = scene.walls[wall as usize].as_segment() else {
                return true;
            };
            hidden = scene.stops_rays(wall)
                && corners
                    .iter()
                    .all(|&q| crosses_inside(segment, q, way(q), sun));
            !hidden
        });
    hidden
}

/// Whether the way from `q` along `to` (up to `q + to`, or without end
/// for a sun) crosses `wall` with room to spare: `q`, and the light's end
/// of the way, at least a millionth of the coordinates' magnitude off
/// the wall's line, and the crossing that far from the wall's ends.
fn crosses_inside(wall: &Segment, q: DVec2, to: DVec2, sun: bool) -> bool {
    let e = wall.b - wall.a;
    let length = e.length();
    let scale = 1.0
        + q.abs()
            .max(wall.a.abs())
            .max(wall.b.abs())
            .max((q + if sun { DVec2::ZERO } else { to }).abs())
            .max_element();
    let room = 1e-6 * scale;
    if !(length > room && to.is_finite()) {
        return false;
    }
    // Signed distances from the wall's line: of `q`, and their change
    // along the way.
    let side = cross(e, q - wall.a) / length;
    let change = cross(e, to) / length;
    if side.abs() < room || side * change >= 0.0 {
        return false;
    }
    // For a point light, the crossing lies before the light, and the
    // light that far off the line.
    let t = -side / change;
    let before_light = t < 1.0 && (side + change).abs() >= room;
    if !(sun || before_light) {
        return false;
    }
    let along = (q + to * t - wall.a).dot(e) / length;
    along >= room && along <= length - room
}

/// Where next-event estimation takes the light table's lights and casts
/// shadow rays.
pub(crate) fn supports(facts: &crate::accel::Facts) -> crate::accel::Decision {
    use crate::accel::Decision;
    use crate::options::FastPath;
    if !facts.light_table {
        return Decision::skipped("no light table");
    }
    if !facts.shadows {
        return Decision::skipped("no shadow rays");
    }
    if let Some(no) = Decision::allowed(facts.options, FastPath::DarkCells, "dark-cells") {
        return no;
    }
    Decision::runs("no shadow ray to a chosen light that a wall hides from the whole cell")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rgb;
    use crate::Stats;
    use crate::estimators::{Receiver, Visibility, light_contribution};
    use crate::sampling::Stream;
    use crate::scene::LightShape;

    /// A turned plan of two rooms joined by a door, with a stub, a pane,
    /// lamps in each room, a spot, a light on a wall's end and a sun.
    fn two_rooms() -> Scene {
        use crate::scene::{Canvas, Falloff, Floor, Light, Material, Wall};
        let (sin, cos) = 17f64.to_radians().sin_cos();
        let turn = |x: f64, y: f64| {
            let (x, y) = (x - 30.0, y - 20.0);
            DVec2::new(30.0 + cos * x - sin * y, 20.0 + sin * x + cos * y)
        };
        let wall = |a: (f64, f64), b: (f64, f64), material| Wall {
            shape: Segment::new(turn(a.0, a.1), turn(b.0, b.1)).into(),
            material,
        };
        let solid = Material::Diffuse { albedo: None };
        let pane = Material::Transparent {
            tint: Rgb::new(0.5, 0.8, 0.9),
        };
        let walls = vec![
            wall((5.0, 5.0), (55.0, 5.0), solid),
            wall((55.0, 5.0), (55.0, 35.0), solid),
            wall((55.0, 35.0), (5.0, 35.0), solid),
            wall((5.0, 35.0), (5.0, 5.0), solid),
            wall((30.0, 5.0), (30.0, 16.0), solid),
            wall((30.0, 20.0), (30.0, 35.0), solid),
            wall((40.0, 25.0), (46.0, 28.0), solid),
            wall((12.0, 20.0), (20.0, 20.0), pane),
        ];
        let light = |shape| Light {
            profile: None,
            shape,
            color: Rgb::ONE,
            intensity: 5.0,
            falloff: Falloff::Flatland,
            spectrum: None,
        };
        let lights = vec![
            light(LightShape::Point {
                at: turn(15.0, 12.0),
            }),
            light(LightShape::Point {
                at: turn(45.0, 15.0),
            }),
            light(LightShape::Spot {
                at: turn(20.0, 30.0),
                direction: DVec2::new(1.0, -0.2).normalize(),
                cone: 0.9,
                softness: 0.2,
            }),
            // On the end of the door's lower wall.
            light(LightShape::Point {
                at: turn(30.0, 16.0),
            }),
            light(LightShape::Directional {
                direction: DVec2::new(0.4, 1.0).normalize(),
            }),
        ];
        let canvas = Canvas {
            width: 60,
            height: 40,
            origin: DVec2::ZERO,
        };
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, lights).expect("a valid scene")
    }

    /// Every light marked dark in a cell brings exactly nothing to every
    /// point of the cell, its corners and edges included, through a traced
    /// shadow ray; and the marks are not empty: each room is dark to the
    /// other's lamp, and the sun is dark indoors.
    #[test]
    fn a_light_marked_dark_in_a_cell_brings_none_of_its_points_anything() {
        let scene = two_rooms();
        let Some(mut table) = LightTable::build(&scene, 2.0, 3, true) else {
            panic!("no table");
        };
        table.set_dark(dark_cells(&scene, &table));
        let mut stream = Stream::new(11, 0, 0);
        let mut stats = Stats::default();
        let mut marked = vec![0; scene.lights.len()];
        for cell in 0..table.cells() {
            let (lo, hi) = table.cell_box(cell);
            let size = hi - lo;
            for (light, count) in marked.iter_mut().enumerate() {
                let x = (lo + hi) * 0.5;
                if !table.dark_at(cell, light, x) {
                    continue;
                }
                *count += 1;
                let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
                let edges = (0..8).map(|k| lo + DVec2::new(k as f64 / 7.0, 0.0) * size);
                let inside = (0..32).map(|_| {
                    let (u, v) = stream.uniform_pair();
                    lo + DVec2::new(u, v) * size
                });
                for x in corners.into_iter().chain(edges).chain(inside) {
                    let c = light_contribution(
                        &scene,
                        light,
                        x,
                        Receiver::FLOOR,
                        0.5,
                        Visibility::Trace,
                        &mut stats,
                    );
                    assert_eq!(c, Rgb::ZERO, "light {light} at {x} in cell {cell}");
                }
            }
        }
        // The lamps and the spot: dark in the other room; the sun: indoors.
        for (light, &count) in marked.iter().enumerate() {
            assert!(count > 20, "light {light}: dark in {count} cells");
        }
        // A point off the canvas takes the nearest cell but not its marks.
        let far = DVec2::new(-50.0, -50.0);
        let cell = table.cell_of(far);
        assert!((0..scene.lights.len()).all(|l| !table.dark_at(cell, l, far)));
    }
}
