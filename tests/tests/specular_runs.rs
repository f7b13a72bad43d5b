//! Mirrors and glass at the default settings: `bounces` counts diffuse
//! reflections only, and runs of mirror and glass events have their own
//! limit (`RenderOptions::specular`, 32 in a row, Russian roulette past
//! 8). So a lamp behind glass lights the floor behind it, and facing
//! mirrors show many images, at `bounces: 1`, by the closed forms; and a
//! line light seen in a mirror lights the walls at one bounce. Each block
//! is held within 5 standard errors of its closed form, from 16 runs of
//! fixed seeds (a t distribution with 15 degrees of freedom is beyond 5
//! once in 6,000 blocks).

use flatray_tests::{block_stats, pixel_moments, scene};
use flatray_tracer::RenderOptions;
use flatray_tracer::optics::fresnel;
use glam::DVec2;

const RUNS: u64 = 16;
const K: f64 = 5.0;

/// Checks the blocks of `block` x `block` pixels that `wanted` picks
/// against `expected` (the mean over a pixel, per channel, summed over
/// the block's pixels and the three channels); returns how many.
fn assert_blocks(
    name: &str,
    text: &str,
    options: RenderOptions,
    block: u32,
    wanted: impl Fn(u32, u32) -> bool,
    expected: impl Fn(u32, u32) -> f64,
) -> usize {
    let loaded = scene(text);
    let (width, _) = flatray_tracer::image_size(&loaded.scene, options.scale);
    let per_row = width / block;
    let stats = block_stats(&loaded.scene, options, block, RUNS, 100);
    let mut checked = 0;
    for (b, &(mean, se)) in stats.iter().enumerate() {
        let (bx, by) = (b as u32 % per_row, b as u32 / per_row);
        if !wanted(bx, by) {
            continue;
        }
        let mut truth = 0.0;
        for y in by * block..(by + 1) * block {
            for x in bx * block..(bx + 1) * block {
                truth += 3.0 * expected(x, y);
            }
        }
        // The floor of one part in 10^4 covers the f32 image's rounding
        // where the noise is nil.
        let tolerance = K * se + 1e-4 * truth;
        assert!(
            (mean - truth).abs() <= tolerance,
            "{name}: block ({bx}, {by}) is {mean}, its closed form {truth} (se {se})"
        );
        checked += 1;
    }
    checked
}

/// Sunlight falls straight, or at 35 degrees, through a clear glass slab
/// of index 1.5 wider than the canvas. Below it, the floor takes the
/// light that crosses both faces, summed over its reflections inside:
/// `E (1 - R)^2 (1 + R^2 + R^4 + ...) = E (1 - R) / (1 + R)`, `R` the
/// Fresnel reflectance at the angle of incidence (the same at both faces).
/// Above it, the light the slab reflects back adds to the sun's. At the
/// default `bounces: 1` (and even at `bounces: 0`): with `specular: 1`
/// the floor below is black, and the test fails.
#[test]
fn sunlight_through_a_glass_slab_at_the_default_settings() {
    for (degrees, bounces) in [(0.0f64, 1), (35.0, 1), (0.0, 0)] {
        let a = degrees.to_radians();
        let text = format!(
            "Scene(canvas: (48, 48), floor: Color((1, 1, 1)),
                lights: [Directional(direction: ({}, {}), intensity: 0.5)],
                glass: [Glass(points: [(-400, 14), (400, 14), (400, 22), (-400, 22)], ior: 1.5)],
                render: (bounces: {bounces}))",
            a.sin(),
            a.cos()
        );
        let r = fresnel(1.0, 1.5, a.cos());
        let below = 0.5 * (1.0 - r) / (1.0 + r);
        // Above the slab: the sun and what the slab sends back, all of it
        // but what it lets through.
        let above = 0.5 + 0.5 * (1.0 - (1.0 - r) / (1.0 + r));
        let options = {
            let mut options = scene(&text).options;
            options.samples = 16;
            options
        };
        let checked = assert_blocks(
            &format!("slab at {degrees} degrees, {bounces} bounces"),
            &text,
            options,
            8,
            // Whole blocks above or below the glass, off the corners that
            // the oblique sun leaves in the reflected beam's shadow.
            |_, by| by == 0 || by >= 3,
            |_, y| if y < 14 { above } else { below },
        );
        assert!(checked >= 24, "{checked}");
    }
}

/// A lamp between two long facing mirrors of tint 0.9: the floor sees the
/// lamp and its images, `0.9^k I / r_k` for the `k`-th reflection,
/// through 32 reflections in a row (the default limit): at `bounces: 1`
/// the images past the first add about a fifth of the light here, and a
/// render of one reflection in a row fails the test.
#[test]
fn facing_mirrors_show_many_images_at_the_default_settings() {
    let (a, b) = (4.0, 28.0);
    let lamp = DVec2::new(30.5, 11.25);
    let tint: f64 = 0.9;
    let text = format!(
        "Scene(canvas: (60, 32), floor: Color((1, 1, 1)), small_radius: 0.5,
            walls: [Wall(a: (-4000, {a}), b: (4000, {a}), material: Mirror(tint: ({tint}, {tint}, {tint}))),
                    Wall(a: (-4000, {b}), b: (4000, {b}), material: Mirror(tint: ({tint}, {tint}, {tint})))],
            lights: [Point(at: ({}, {}), intensity: 1.0, falloff: Flatland)])",
        lamp.x, lamp.y
    );
    let limit = flatray_tracer::DEFAULT_SPECULAR;
    // The images: the lamp mirrored first in one mirror, then the other,
    // alternately, k times.
    let mut images = vec![(lamp, 0)];
    for first in [a, b] {
        let (mut y, mut line) = (lamp.y, first);
        for k in 1..=limit {
            y = 2.0 * line - y;
            images.push((DVec2::new(lamp.x, y), k as i32));
            line = if line == a { b } else { a };
        }
    }
    let fluence = |p: DVec2| -> f64 {
        images
            .iter()
            .map(|&(image, k)| tint.powi(k) / (p - image).length().max(0.5))
            .sum()
    };
    let options = {
        let mut options = scene(&text).options;
        options.samples = 64;
        options
    };
    assert_eq!(options.bounces, 1);
    let checked = assert_blocks(
        "facing mirrors",
        &text,
        options,
        4,
        // Between the mirrors, off the lamp's own blocks.
        |bx, by| (2..7).contains(&by) && !(6..9).contains(&bx),
        |x, y| pixel_moments(x, y, 8, fluence).0,
    );
    assert!(checked >= 60, "{checked}");
    // What the images past the first bring, at a point of the floor.
    let p = DVec2::new(10.5, 16.5);
    let first: f64 = images
        .iter()
        .filter(|&&(_, k)| k <= 1)
        .map(|&(image, k)| tint.powi(k) / (p - image).length())
        .sum();
    assert!(fluence(p) > 1.15 * first, "{} vs {first}", fluence(p));
}

/// A line light that the room's walls see only in a tilted mirror: at
/// `bounces: 1` its light reaches the floor by light, mirror, wall, floor
/// (one diffuse bounce), which a path finds by going on past its wall
/// (`run::last_leg_sides`). The default render agrees with the light
/// tracer block by block, within 5 standard errors over 24 runs, and
/// holds more light than it would without that path (the check is not
/// vacuous: the mirror's light is over 3 % of the total).
#[test]
fn a_line_light_seen_in_a_mirror_lights_the_walls_at_one_bounce() {
    let text = "Scene(canvas: (64, 48), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (4, 4), b: (60, 6)), Wall(a: (60, 6), b: (58, 44)),
                Wall(a: (58, 44), b: (3, 42)), Wall(a: (3, 42), b: (4, 4)),
                Wall(a: (24, 4.7), b: (26, 30), material: Diffuse(albedo: Some((0.7, 0.7, 0.7)))),
                Wall(a: (8, 30), b: (18, 38), material: Mirror(tint: (0.9, 0.9, 0.9))),
                Wall(a: (36, 12), b: (52, 12.5), material: Diffuse(albedo: Some((0.9, 0.6, 0.4))))],
        lights: [Line(a: (8, 8), b: (14, 14), intensity: 0.5)])";
    let loaded = scene(text);
    let options = {
        let mut options = loaded.options;
        options.samples = 16;
        options
    };
    assert_eq!(options.bounces, 1);
    let path = flatray_tests::Agreement {
        block: 8,
        runs: 24,
        first_seed: 3000,
        k: K,
        min_blocks: 30,
    }
    .check("line light in a mirror", &loaded.scene, options, |_| true);
    let mut dark = loaded.scene.parts();
    for wall in &mut dark.walls {
        if let flatray_tracer::Material::Mirror { tint } = &mut wall.material {
            *tint = flatray_tracer::Rgb::ZERO;
        }
    }
    let dark = dark.build().expect("a valid scene");
    let without = block_stats(&dark, options, 8, 4, 3000);
    let total = |blocks: &[(f64, f64)]| blocks.iter().map(|b| b.0).sum::<f64>();
    assert!(
        total(&path) > 1.03 * total(&without),
        "{} against {}",
        total(&path),
        total(&without)
    );
}
