//! Direct light: shadow rays from a receiver point to every light.

use flatray_geometry::DVec2;

use crate::estimators::choice::{LightTable, NUMBERS};
use crate::estimators::{
    Receiver, Visibility, light_contribution, weighed_contribution, with_closed_forms,
};
use crate::ledger::Ledger;
use crate::material::{Bsdf, Sampling};
use crate::sampling::Stream;
use crate::scene::{Light, Scene};
use crate::{Rgb, Stats};

/// The light that reaches `x` directly from every light: fluence for the
/// floor, irradiance for a wall side, with the closed forms the `ledger`
/// gives it (`estimators::with_closed_forms`). Shadow rays are cast
/// where `shadows` says. Without a `table`, one shadow ray
/// per light, each light drawing its numbers from `stream`
/// (`LightShape::numbers`); with one, the lights the table chooses, from
/// [`NUMBERS`] numbers.
pub(crate) fn direct_light(
    scene: &Scene,
    x: DVec2,
    receiver: Receiver,
    (shadows, ledger): (bool, &Ledger),
    table: Option<&LightTable>,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let vis = Visibility::of(shadows);
    let direct = match table {
        Some(table) => {
            let numbers = std::array::from_fn(|_| stream.uniform());
            table.direct_light(scene, x, receiver, &numbers, |_| vis, stats)
        }
        None => direct_light_with(scene, x, receiver, |_| vis, stream, stats),
    };
    with_closed_forms(direct, ledger, scene, (x, receiver), None, stats)
}

/// [`direct_light`] from every light, whatever the `table`, but those it
/// proves dark at `x` (exactly zero there): for an estimate that no
/// light's random choice can leave below the light that arrives, as the
/// wall memo's checks need (`path::wall_irradiance`).
pub(crate) fn direct_light_every(
    scene: &Scene,
    x: DVec2,
    receiver: Receiver,
    (shadows, ledger): (bool, &Ledger),
    table: Option<&LightTable>,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let vis = Visibility::of(shadows);
    let direct = match table {
        Some(table) => {
            let cell = table.cell_of(x);
            let mut sum = Rgb::ZERO;
            for index in 0..scene.lights.len() {
                let u = light_number(&scene.lights[index], stream);
                if !table.dark_at(cell, index, x) {
                    sum += light_contribution(scene, index, x, receiver, u, vis, stats);
                }
            }
            sum
        }
        None => direct_light_with(scene, x, receiver, |_| vis, stream, stats),
    };
    with_closed_forms(direct, ledger, scene, (x, receiver), None, stats)
}

/// Next-event estimation at a glossy wall point `x` (the receiver: the
/// wall side the path arrived on, of unit normal `n`) for a path leaving
/// towards `wo`: the outgoing light `∫ f(wo, wi) L(wi) cos dtheta`, one
/// sample of every light (the lights' own numbers from `stream`, as
/// [`direct_light_with`] draws them; no light table). A light with an area
/// is weighed against the BSDF's own samples by the power heuristic; the
/// path loop gives a BSDF sample that meets it the other share
/// ([`glossy_emission_weight`]). A sample where `f` is zero casts no shadow
/// ray. With `aimed_by_photons`, the lights whose photons the caustic pass
/// aims ([`crate::scene::LightShape::aims_photons`]) are left to it.
pub(crate) fn direct_light_glossy(
    scene: &Scene,
    x: DVec2,
    (receiver, n): (Receiver, DVec2),
    (bsdf, wo): (&Bsdf, DVec2),
    (shadows, aimed_by_photons): (bool, bool),
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let vis = Visibility::of(shadows);
    let mut sum = Rgb::ZERO;
    for index in 0..scene.lights.len() {
        let light = &scene.lights[index];
        let u = light_number(light, stream);
        if aimed_by_photons && light.shape.aims_photons() {
            continue;
        }
        let area = light.shape.has_area();
        sum += weighed_contribution(scene, index, x, receiver, u, vis, stats, |s, v| {
            let wi = s.dir();
            let f = bsdf.eval(n, wo, wi);
            if f == Rgb::ZERO {
                return None;
            }
            let weight = if area {
                power_heuristic(s.pdf, bsdf.pdf(n, wo, wi, Sampling::Cosine))
            } else {
                1.0
            };
            Some(f * (v * weight))
        });
    }
    sum
}

/// The share of a glossy BSDF's sample from `x` (of density `pdf`, on
/// wall `wall`) that meets light `light` at `at`: the power heuristic
/// against the light's own sampling there, 1 where next-event estimation
/// takes none.
#[inline]
pub(crate) fn glossy_emission_weight(
    scene: &Scene,
    light: &Light,
    (x, wall): (DVec2, u32),
    pdf: f64,
    at: DVec2,
) -> f64 {
    if light.shape.grazes(wall, &scene.walls[wall as usize].shape) {
        return 1.0;
    }
    power_heuristic(pdf, light.shape.pdf_towards(x, at))
}

/// The power heuristic's weight for a sample of density `a` against one
/// other strategy of density `b` (Veach's `beta = 2`).
#[inline]
fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
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

/// What `accel::strata::direct_light_strata` computes, the plain way: each point alone,
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
