//! Direct light: shadow rays from a receiver point to every light.

use flatray_geometry::DVec2;

use crate::lights::choice::{LightTable, NUMBERS};
use crate::lights::{Receiver, Visibility, light_contribution};
use crate::sampling::Stream;
use crate::scene::{Light, Scene};
use crate::{Rgb, Stats};

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
/// `table` chooses with the point's [`NUMBERS`] numbers, each light's
/// visibility given by `vis(light)` when a point takes it: the same for
/// the reference model and the fast paths. `receiver` is the floor, with
/// the walls its shadow rays towards each light can cross where known.
pub(crate) fn direct_light_chosen(
    scene: &Scene,
    table: &LightTable,
    receiver: Receiver,
    strata: &mut Strata,
    mut vis: impl FnMut(usize) -> Visibility,
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
        values.push(table.direct_light(scene, x, receiver, numbers, &mut vis, stats));
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

/// What `strata::direct_light_strata` computes, the plain way: each point alone,
/// every light through [`light_contribution`] in the lights' order, with
/// the numbers the strata drew. The reference model's floor memo.
pub(crate) fn direct_light_points(
    scene: &Scene,
    strata: &mut Strata,
    visibility: &[Visibility],
    stats: &mut Stats,
) {
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
