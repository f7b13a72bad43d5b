//! Direct light: shadow rays from a receiver point to every light.

use flatray_geometry::{DVec2, Ray, Skip};

use crate::lights::choice::{LightTable, NUMBERS};
use crate::lights::{arriving, point_incident};
use crate::sampling::{Stream, angle_sample_lanes};
use crate::scene::{EMITTING_SIDE, Light, LightShape, Material, Scene};
use crate::{Rgb, Stats};

/// Who receives the light: the floor (no cosine, every direction) or one
/// side of a wall (cosine to its normal, only that side).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Receiver<'a> {
    /// The unit normal of the receiving side; `None` for the floor.
    pub normal: Option<DVec2>,
    /// The wall the receiver lies on, skipped by its shadow rays.
    pub wall: Option<u32>,
    /// Per light, the only walls its shadow rays can cross, in index
    /// order, where that is known (floor points, culled per block of
    /// pixels: `hull_candidates`; `None` for a light without a list, a
    /// sun); `None`: every wall for every light.
    pub shadow_walls: Option<&'a [Option<Vec<u32>>]>,
}

impl<'a> Receiver<'a> {
    pub const FLOOR: Receiver<'static> = Receiver {
        normal: None,
        wall: None,
        shadow_walls: None,
    };

    /// The walls that shadow rays towards light `index` can cross, if
    /// known.
    #[inline]
    fn walls_towards(&self, index: usize) -> Option<&'a [u32]> {
        self.shadow_walls
            .and_then(|lists| lists.get(index))
            .and_then(|list| list.as_deref())
    }

    #[inline]
    fn skip(&self, light_wall: Option<u32>) -> Skip {
        Skip(
            self.wall.unwrap_or(u32::MAX),
            light_wall.unwrap_or(u32::MAX),
        )
    }
}

/// How a light's transmittance to a receiver point is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Visibility {
    /// By a shadow ray.
    Trace,
    /// Already known: 1 when the plan casts no shadow rays, or what the
    /// floor's coherence masks proved for a whole pixel.
    Known(Rgb),
}

impl Visibility {
    /// Traced when the plan casts shadow rays, else 1.
    #[inline]
    pub fn of(shadows: bool) -> Visibility {
        if shadows {
            Visibility::Trace
        } else {
            Visibility::Known(Rgb::ONE)
        }
    }
}

/// The light that reaches `x` directly from every light: fluence for the
/// floor, irradiance for a wall side. Without a `table`, one shadow ray
/// per light, each light drawing its numbers from `stream`
/// (`LightShape::numbers`); with one, the lights the table chooses, from
/// [`NUMBERS`] numbers.
pub(crate) fn direct_light(
    scene: &Scene,
    x: DVec2,
    receiver: Receiver,
    shadows: bool,
    table: Option<&LightTable>,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let vis = Visibility::of(shadows);
    match table {
        Some(table) => {
            let numbers = std::array::from_fn(|_| stream.uniform());
            table.direct_light(scene, x, receiver, &numbers, |_| vis, stats)
        }
        None => direct_light_with(scene, x, receiver, |_| vis, stream, stats),
    }
}

/// How many numbers each floor stratum draws for its direct light.
pub(crate) fn numbers_per_point(scene: &Scene, table: Option<&LightTable>) -> usize {
    match table {
        Some(_) => NUMBERS,
        None => scene.lights.iter().map(|l| l.shape.numbers()).sum(),
    }
}

/// The direct light at every point of `strata`, each from the lights that
/// `table` chooses with the point's [`NUMBERS`] numbers: the same for the
/// reference model and the fast paths.
fn direct_light_chosen(
    scene: &Scene,
    table: &LightTable,
    strata: &mut Strata,
    visibility: &[Visibility],
    stats: &mut Stats,
) {
    let Strata {
        points,
        numbers,
        values,
    } = strata;
    values.clear();
    for (&x, numbers) in points.iter().zip(numbers.chunks_exact(NUMBERS)) {
        let numbers: &[f64; NUMBERS] = numbers.try_into().unwrap_or(&[0.0; NUMBERS]);
        values.push(table.direct_light(
            scene,
            x,
            Receiver::FLOOR,
            numbers,
            |light| visibility[light],
            stats,
        ));
    }
}

/// [`direct_light`] with each light's visibility given by `vis(light)`:
/// draws the same numbers from `stream`.
#[inline]
pub(crate) fn direct_light_with(
    scene: &Scene,
    x: DVec2,
    receiver: Receiver,
    vis: impl Fn(usize) -> Visibility,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    for index in 0..scene.lights.len() {
        let u = light_number(&scene.lights[index], stream);
        sum += light_contribution(scene, index, x, receiver, u, vis(index), stats);
    }
    sum
}

/// The number a light's sample takes from `stream`, or 0 for a light that
/// takes none.
#[inline]
pub(crate) fn light_number(light: &Light, stream: &mut Stream) -> f64 {
    if light.shape.numbers() > 0 {
        stream.uniform()
    } else {
        0.0
    }
}

/// The floor memo's points in one pixel, with the numbers their lights
/// draw.
#[derive(Default)]
pub(crate) struct Strata {
    pub points: Vec<DVec2>,
    /// For point `k`, the number each light that takes one draws (in the
    /// lights' order): that many numbers per point.
    pub numbers: Vec<f64>,
    /// The direct light at each point.
    pub values: Vec<Rgb>,
}

/// The floor strata a line light's angle samples take at once.
const ANGLE_LANES: usize = 4;

/// [`direct_light_with`] at every point of `strata`, on the floor, each
/// value computed exactly as it would be there (the same operations in
/// the same order), but light by light over all points, so that work on
/// one light runs without the branches of the others.
///
/// Two kinds have loops of their own, named here: a point light whose
/// visibility is known (the floor's most common case), and line lights,
/// whose angle samples are drawn in lanes of points. Every other light
/// goes through [`light_contribution`], point by point.
/// With `shadow_walls` (per light: the walls its shadow rays from these
/// points can cross, or `None` for every wall), shadow rays test only
/// those. Inlined always, with the line lights' angle samples, into the
/// pixel loop compiled with AVX2.
#[inline(always)]
pub(crate) fn direct_light_strata(
    scene: &Scene,
    strata: &mut Strata,
    visibility: &[Visibility],
    shadow_walls: Option<&[Option<Vec<u32>>]>,
    table: Option<&LightTable>,
    stats: &mut Stats,
) {
    if let Some(table) = table {
        return direct_light_chosen(scene, table, strata, visibility, stats);
    }
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
        match (light.shape, vis) {
            (LightShape::Point { at }, Visibility::Known(known)) => {
                for (value, &x) in values.iter_mut().zip(points.iter()) {
                    // As `light_contribution` computes it for the floor.
                    // `LightShape::incident` of a point, inlined into this
                    // loop.
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
            (
                LightShape::Line {
                    segment, one_sided, ..
                },
                _,
            ) => {
                // As `light_contribution` computes it for the floor, with
                // the angle samples drawn in lanes of points; a test holds
                // the two to the same bits.
                let skip = receiver.skip(scene.light_wall[index]);
                let count = points.len();
                for first in (0..count).step_by(ANGLE_LANES) {
                    // A last part lane is filled with the last point again.
                    let at = |k: usize| (first + k).min(count - 1);
                    let px = std::array::from_fn(|k| points[at(k)].x);
                    let py = std::array::from_fn(|k| points[at(k)].y);
                    let us = std::array::from_fn(|k| numbers[at(k) * per_point + taken]);
                    let lanes = angle_sample_lanes::<ANGLE_LANES>(&px, &py, &us, &segment);
                    for k in 0..ANGLE_LANES.min(count - first) {
                        let (x, value) = (points[first + k], &mut values[first + k]);
                        let lit = !one_sided || segment.side_of(x) == Some(EMITTING_SIDE);
                        if !(lit && lanes.valid[k]) {
                            continue;
                        }
                        let distance = lanes.distance[k];
                        let v = arriving(
                            light.intensity,
                            light.falloff.per_radian(distance, r0),
                            1.0,
                            1.0 / lanes.subtended[k],
                        );
                        if v == 0.0 {
                            continue;
                        }
                        let vis = match vis {
                            Visibility::Known(known) => known,
                            Visibility::Trace => transmittance(
                                scene,
                                &Ray::new(x, DVec2::new(lanes.x[k], lanes.y[k]) - x),
                                1.0,
                                skip,
                                receiver.walls_towards(index),
                                stats,
                            ),
                        };
                        *value += Rgb::splat(v) * vis * light.color;
                    }
                }
            }
            _ => {
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

/// What [`direct_light_strata`] computes, the plain way: each point alone,
/// every light through [`light_contribution`] in the lights' order, with
/// the numbers the strata drew. The reference model's floor memo.
pub(crate) fn direct_light_points(
    scene: &Scene,
    strata: &mut Strata,
    visibility: &[Visibility],
    table: Option<&LightTable>,
    stats: &mut Stats,
) {
    if let Some(table) = table {
        return direct_light_chosen(scene, table, strata, visibility, stats);
    }
    let Strata {
        points,
        numbers,
        values,
    } = strata;
    let per_point: usize = scene.lights.iter().map(|l| l.shape.numbers()).sum();
    values.clear();
    for (k, &x) in points.iter().enumerate() {
        let mut next = numbers[k * per_point..(k + 1) * per_point].iter();
        let mut sum = Rgb::ZERO;
        for (index, light) in scene.lights.iter().enumerate() {
            let u = if light.shape.numbers() > 0 {
                next.next().copied().unwrap_or(0.0)
            } else {
                0.0
            };
            let vis = visibility[index];
            sum += light_contribution(scene, index, x, Receiver::FLOOR, u, vis, stats);
        }
        values.push(sum);
    }
}

/// The light that reaches `x` from one light, coloured: the light's
/// [`Incident`] sample, times the receiver's cosine over its pdf, times
/// the transmittance of one shadow ray (none when `vis` is known: the plan
/// found nothing that occludes, or the floor's coherence masks know the
/// answer). `u` in `[0, 1)` is the light's number, if it takes one.
pub(crate) fn light_contribution(
    scene: &Scene,
    index: usize,
    x: DVec2,
    receiver: Receiver,
    u: f64,
    vis: Visibility,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    if let Some(w) = receiver.wall
        && light.shape.grazes(w, &scene.walls[w as usize].segment)
    {
        return Rgb::ZERO;
    }
    let Some(s) = light.shape.incident(light, x, u, scene.small_radius) else {
        return Rgb::ZERO;
    };
    if s.at_the_light() {
        // The receiver sits on the light: no direction to test, nothing
        // in between. A wall gets no cosine from it.
        if receiver.normal.is_some() {
            return Rgb::ZERO;
        }
        return Rgb::splat(arriving(light.intensity, s.value, 1.0, s.pdf)) * light.color;
    }
    let cosine = match receiver.normal {
        None => 1.0,
        Some(n) => n.dot(s.dir()).max(0.0),
    };
    let v = arriving(light.intensity, s.value, cosine, s.pdf);
    if v == 0.0 {
        return Rgb::ZERO;
    }
    // A light that sits on a wall shines past it: its shadow rays ignore
    // that wall (for a solid line light, its own wall).
    let vis = match vis {
        Visibility::Trace => transmittance(
            scene,
            &Ray::new(x, s.to),
            s.t_max,
            receiver.skip(scene.light_wall[index]),
            receiver.walls_towards(index),
            stats,
        ),
        Visibility::Known(known) => known,
    };
    Rgb::splat(v) * vis * light.color
}

/// What fraction of light gets along `ray` for `0 < t < t_max`: zero when
/// an opaque wall is in the way, else the product of the transparent
/// walls' tints. Counts one shadow ray.
/// With `walls`, only those walls are tested (in index order, as brute
/// force visits them): the same answer when they hold every wall the ray
/// can cross.
pub(crate) fn transmittance(
    scene: &Scene,
    ray: &Ray,
    t_max: f64,
    skip: Skip,
    walls: Option<&[u32]>,
    stats: &mut Stats,
) -> Rgb {
    stats.work.shadow_rays += 1;
    let mut through = Rgb::ONE;
    let visit = |index: u32, _| match scene.walls[index as usize].material {
        Material::Transparent { tint } => {
            through *= tint;
            through != Rgb::ZERO
        }
        // Glass refracts: no straight shadow ray gets through it.
        Material::Diffuse { .. } | Material::Mirror { .. } | Material::Glass { .. } => {
            through = Rgb::ZERO;
            false
        }
    };
    match walls {
        Some(walls) => scene
            .segments
            .for_each_crossing_among(ray, t_max, skip, walls, visit),
        None => scene.segments.for_each_crossing(ray, t_max, skip, visit),
    };
    through
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Canvas, Falloff, Floor, Light, Wall};
    use flatray_geometry::Segment;

    /// The floor memo's light-by-light passes give every point exactly what
    /// `direct_light_with` gives it, for every kind of light, with shadow
    /// rays traced or known, and with culled shadow walls.
    #[test]
    fn strata_light_by_light_equal_each_point_alone() {
        let light = |shape, falloff| Light {
            shape,
            color: Rgb::new(1.0, 0.8, 0.6),
            intensity: 2.0,
            falloff,
        };
        let walls = [
            ((10.0, 10.0), (30.0, 12.0)),
            ((25.0, 5.0), (25.0, 30.0)),
            ((5.0, 25.0), (15.0, 35.0)),
        ]
        .map(|((ax, ay), (bx, by))| Wall {
            segment: Segment::new(DVec2::new(ax, ay), DVec2::new(bx, by)),
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
        let scene = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, lights);
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
                direct_light_strata(&scene, &mut strata, &visibility, shadow_walls, None, &mut a);
                let fast = strata.values.clone();
                direct_light_points(&scene, &mut strata, &visibility, None, &mut b);
                assert_eq!(fast, strata.values);
                assert_eq!(a.work.shadow_rays, b.work.shadow_rays);
            }
        }
    }
}
