//! A fast path beside the model: the floor memo's direct light computed
//! light by light over all of a pixel's strata (point lights whose
//! visibility is known in one loop), each value exactly as
//! `direct::direct_light_points` computes it, point by point.

use flatray_geometry::DVec2;

use crate::direct::{Strata, direct_light_chosen};
use crate::estimators::choice::{LightTable, NUMBERS};
use crate::estimators::{Receiver, Visibility, light_contribution};
use crate::lights::Emitter;
use crate::lights::{arriving, point_incident};
use crate::scene::{Light, Scene};
use crate::{Rgb, Stats};

/// [`direct_light_with`] at every point of `strata`, on the floor, each
/// value computed exactly as it would be there (the same operations in
/// the same order), but light by light over all points, so that work on
/// one light runs without the branches of the others.
///
/// A point light whose visibility is known (the floor's most common
/// case) has a loop of its own. Every other light goes through
/// [`light_contribution`], point by point (lines and circles in closed
/// form).
/// With `shadow_walls` (per light: the walls its shadow rays from these
/// points can cross, or `None` for every wall), shadow rays test only
/// those. Inlined always into the pixel loop compiled with AVX2.
#[inline(always)]
pub(crate) fn direct_light_strata(
    scene: &Scene,
    strata: &mut Strata,
    visibility: &[Visibility],
    shadow_walls: Option<&[Option<Vec<u32>>]>,
    stats: &mut Stats,
) {
    let Strata {
        points,
        numbers,
        values,
    } = strata;
    values.clear();
    values.resize(points.len(), Rgb::ZERO);
    let per_point: usize = scene.lights.iter().map(|l| l.shape.numbers()).sum();
    let mut number = 0;
    let receiver = Receiver {
        shadow_walls,
        ..Receiver::FLOOR
    };
    let r0 = scene.small_radius;
    for (index, light) in scene.lights.iter().enumerate() {
        let vis = visibility[index];
        let taken = number;
        number += light.shape.numbers();
        if vis == Visibility::Known(Rgb::ZERO) {
            // A pixel in the light's full shadow (the coherence masks
            // keep out the pixel of a point light itself, the one point
            // that ignores its transmittance): every stratum would add
            // exactly +0, a zero transmittance times a finite value.
            continue;
        }
        match (light.shape.emitter(), vis) {
            (
                Emitter::Point {
                    at,
                    windowed: false,
                },
                Visibility::Known(known),
            ) => {
                add_point_known(light, at, known, points, values, r0);
            }
            (
                Emitter::Point { .. }
                | Emitter::Direction(_)
                | Emitter::Segment { .. }
                | Emitter::Disk { .. }
                | Emitter::Arc(_)
                | Emitter::Parallel { .. },
                _,
            ) => {
                let takes = light.shape.numbers() > 0;
                for (k, (value, &x)) in values.iter_mut().zip(points.iter()).enumerate() {
                    let u = if takes {
                        numbers[k * per_point + taken]
                    } else {
                        0.0
                    };
                    *value += light_contribution(scene, index, x, receiver, u, vis, stats);
                }
            }
        }
    }
}

/// Adds point light `light` at `at`, whose transmittance to every one of
/// `points` is `known`, to each point's value, as `light_contribution`
/// computes it for the floor (`LightShape::incident` of a point, inlined
/// into this loop).
#[inline(always)]
fn add_point_known(
    light: &Light,
    at: DVec2,
    known: Rgb,
    points: &[DVec2],
    values: &mut [Rgb],
    r0: f64,
) {
    for (value, &x) in values.iter_mut().zip(points) {
        let s = point_incident(at, light, x, r0);
        let v = arriving(light.intensity, s.value, 1.0, s.pdf);
        let v = if s.at_the_light() {
            Rgb::splat(v)
        } else {
            Rgb::splat(v) * known
        };
        *value += v * light.color;
    }
}

/// [`direct_light_chosen`] at every point of `strata`, each value computed
/// exactly as it would be there, but where all the points lie in one cell
/// of `table`, its always-lights light by light over all points (a point
/// light whose visibility is known in one loop), then each point's chosen
/// light. Each point still adds its lights in the same order. Points
/// spread over several cells, and receivers other than the floor, take
/// the model's loop.
#[inline(always)]
pub(crate) fn direct_light_chosen_strata(
    scene: &Scene,
    table: &LightTable,
    receiver: Receiver,
    (strata, weights): (&mut Strata, &mut Vec<f64>),
    mut vis: impl FnMut(usize) -> Visibility,
    stats: &mut Stats,
) {
    let cell = match strata.points.first() {
        Some(&x) => table.cell_of(x),
        None => {
            strata.values.clear();
            return;
        }
    };
    let on_floor = receiver.normal.is_none() && receiver.wall.is_none();
    if !on_floor || strata.points.iter().any(|&x| table.cell_of(x) != cell) {
        direct_light_chosen(scene, table, receiver, strata, vis, stats);
        return;
    }
    let Strata {
        points,
        numbers,
        values,
    } = strata;
    // As many points as have their numbers, as the model takes.
    let points = &points[..points.len().min(numbers.len() / NUMBERS)];
    values.clear();
    if points.is_empty() {
        return;
    }
    values.resize(points.len(), Rgb::ZERO);
    let r0 = scene.small_radius;
    for (k, index) in table.always(cell).enumerate() {
        let light = &scene.lights[index];
        let v = vis(index);
        match (light.shape.emitter(), v) {
            (
                Emitter::Point {
                    at,
                    windowed: false,
                },
                Visibility::Known(known),
            ) => {
                add_point_known(light, at, known, points, values, r0);
            }
            (
                Emitter::Point { .. }
                | Emitter::Direction(_)
                | Emitter::Segment { .. }
                | Emitter::Disk { .. }
                | Emitter::Arc(_)
                | Emitter::Parallel { .. },
                _,
            ) => {
                for (value, (&x, numbers)) in values
                    .iter_mut()
                    .zip(points.iter().zip(numbers.chunks_exact(NUMBERS)))
                {
                    *value += light_contribution(scene, index, x, receiver, numbers[k], v, stats);
                }
            }
        }
    }
    // The seen lights' weights at every point, light by light; then each
    // point's choice.
    table.seen_weights(scene, cell, points, weights);
    for (k, (value, (&x, numbers))) in values
        .iter_mut()
        .zip(points.iter().zip(numbers.chunks_exact(NUMBERS)))
        .enumerate()
    {
        let numbers: &[f64; NUMBERS] = numbers.try_into().unwrap_or(&[0.0; NUMBERS]);
        let column = (weights.get(k..).unwrap_or(&[]), points.len());
        *value += table.chosen_light_weighed(
            scene,
            (cell, x),
            column,
            receiver,
            numbers,
            &mut vis,
            stats,
        );
    }
}

/// The floor memo's points taken light by light wherever there is a floor
/// memo: the same values as point by point.
pub(crate) fn supports(facts: &crate::accel::Facts) -> crate::accel::Decision {
    use crate::accel::Decision;
    use crate::options::FastPath;
    if !facts.floor_memo {
        return Decision::skipped("no floor cache");
    }
    if let Some(no) = Decision::allowed(facts.options, FastPath::StrataLoops, "strata-loops") {
        return no;
    }
    Decision::runs(
        "the floor cache's points light by light, a point light of known transmittance in one loop",
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::direct::direct_light_points;
    use crate::sampling::Stream;
    use crate::scene::Material;
    use crate::scene::{Canvas, Falloff, Floor, Light, LightShape, Wall};
    use flatray_geometry::Segment;

    /// Walls, and a light of every kind: points, lines, a spot, a sun, a
    /// circle.
    fn every_kind_of_light() -> Scene {
        let light = |shape, falloff| Light {
            profile: None,
            shape,
            color: Rgb::new(1.0, 0.8, 0.6),
            intensity: 2.0,
            falloff,
            spectrum: None,
        };
        let walls = [
            ((10.0, 10.0), (30.0, 12.0)),
            ((25.0, 5.0), (25.0, 30.0)),
            ((5.0, 25.0), (15.0, 35.0)),
        ]
        .map(|((ax, ay), (bx, by))| Wall {
            shape: Segment::new(DVec2::new(ax, ay), DVec2::new(bx, by)).into(),
            material: Material::Diffuse { albedo: None },
        })
        .to_vec();
        let lights = vec![
            light(
                LightShape::Point {
                    at: DVec2::new(20.0, 20.0),
                },
                Falloff::Flatland,
            ),
            light(
                LightShape::Line {
                    segment: Segment::new(DVec2::new(2.0, 2.0), DVec2::new(8.0, 3.0)),
                    one_sided: false,
                    wall: None,
                },
                Falloff::Window { range: 50.0 },
            ),
            light(
                LightShape::Line {
                    segment: Segment::new(DVec2::new(35.0, 35.0), DVec2::new(38.0, 20.0)),
                    one_sided: true,
                    wall: None,
                },
                Falloff::InverseSquare,
            ),
            light(
                LightShape::Spot {
                    at: DVec2::new(5.0, 15.0),
                    direction: DVec2::new(1.0, 0.0),
                    cone: 0.8,
                    softness: 0.3,
                },
                Falloff::Flatland,
            ),
            light(
                LightShape::Directional {
                    direction: DVec2::new(0.6, 0.8),
                },
                Falloff::Flatland,
            ),
            // On a wall: its shadow rays skip that wall.
            light(
                LightShape::Point {
                    at: DVec2::new(25.0, 20.0),
                },
                Falloff::Flatland,
            ),
            light(
                LightShape::Circle {
                    at: DVec2::new(30.0, 30.0),
                    radius: 3.0,
                },
                Falloff::InverseSquare,
            ),
        ];
        let canvas = Canvas {
            width: 40,
            height: 40,
            origin: DVec2::ZERO,
        };
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, lights).expect("a valid scene")
    }

    /// The floor memo's light-by-light passes give every point exactly what
    /// `direct_light_with` gives it, for every kind of light, with shadow
    /// rays traced or known, and with culled shadow walls.
    #[test]
    fn strata_light_by_light_equal_each_point_alone() {
        let scene = every_kind_of_light();
        let lines = 3;
        let mut stream = Stream::new(1, 2, 3);
        let mut strata = Strata::default();
        // Not a whole number of lanes: the last part lane too.
        for _ in 0..301 {
            strata
                .points
                .push(DVec2::new(stream.uniform() * 40.0, stream.uniform() * 40.0));
            for _ in 0..lines {
                strata.numbers.push(stream.uniform());
            }
        }
        // Every wall as the culled list of every light but the sun.
        let all: Vec<Option<Vec<u32>>> = scene
            .lights
            .iter()
            .map(|l| l.shape.hull().map(|_| vec![0, 1, 2]))
            .collect();
        for visibility in [
            vec![Visibility::Trace; 7],
            vec![Visibility::Known(Rgb::new(0.5, 1.0, 0.25)); 7],
        ] {
            for shadow_walls in [None, Some(&all[..])] {
                let (mut a, mut b) = (Stats::default(), Stats::default());
                direct_light_strata(&scene, &mut strata, &visibility, shadow_walls, &mut a);
                let fast = strata.values.clone();
                direct_light_points(&scene, &mut strata, &visibility, &mut b);
                assert_eq!(fast, strata.values);
                assert_eq!(a.work.shadow_rays, b.work.shadow_rays);
            }
        }
    }

    /// With a light table, the always-lights taken light by light over
    /// the points of one cell and then each point's chosen light give every
    /// point exactly what the model's point-by-point loop gives it, and the
    /// same counts; for every kind of light, visibility traced, known or
    /// mixed, and points in one cell or spread over several.
    #[test]
    fn chosen_lights_light_by_light_equal_each_point_alone() {
        let scene = every_kind_of_light();
        let Some(table) = LightTable::build(&scene, 1.0, 7, true) else {
            panic!("a scene with lights has a table");
        };
        let mut stream = Stream::new(4, 5, 6);
        let tint = Visibility::Known(Rgb::new(0.5, 1.0, 0.25));
        let visibilities = [
            vec![Visibility::Trace; 7],
            vec![tint; 7],
            (0..7)
                .map(|l| match l % 3 {
                    0 => Visibility::Trace,
                    1 => tint,
                    _ => Visibility::Known(Rgb::ZERO),
                })
                .collect(),
        ];
        let mut in_one_cell = 0;
        for spread in [0.5, 3.0, 40.0] {
            for _ in 0..20 {
                let corner = DVec2::new(stream.uniform() * 39.0, stream.uniform() * 39.0);
                let mut strata = Strata::default();
                for _ in 0..37 {
                    let offset = DVec2::new(stream.uniform(), stream.uniform()) * spread;
                    strata.points.push(corner + offset);
                    for _ in 0..NUMBERS {
                        strata.numbers.push(stream.uniform());
                    }
                }
                let cell = table.cell_of(strata.points[0]);
                in_one_cell += strata.points.iter().all(|&x| table.cell_of(x) == cell) as u32;
                for visibility in &visibilities {
                    let (mut a, mut b) = (Stats::default(), Stats::default());
                    let vis = |light: usize| visibility[light];
                    direct_light_chosen_strata(
                        &scene,
                        &table,
                        Receiver::FLOOR,
                        (&mut strata, &mut Vec::new()),
                        vis,
                        &mut a,
                    );
                    let fast = strata.values.clone();
                    direct_light_chosen(&scene, &table, Receiver::FLOOR, &mut strata, vis, &mut b);
                    assert_eq!(fast, strata.values, "spread {spread}");
                    assert_eq!(a.work, b.work, "spread {spread}");
                }
            }
        }
        assert!(in_one_cell >= 20, "{in_one_cell} sets in one cell");
    }
}
