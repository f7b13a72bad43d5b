//! The circle light: closed form 7 of `model.md` (an unoccluded disk gives
//! the floor its radiance times the angle it subtends), and agreement of
//! path and light tracing with walls, a mirror and every falloff. Each
//! statistical check states its tolerance in standard errors, with fixed
//! seeds.

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, pixel_moments, render, scene};
use flatray_tracer::{Integrator, MemoOptions, RenderOptions, Scene};

/// `I * 2 asin(R / d)` outside the disk, nothing inside.
fn disk(p: DVec2, centre: DVec2, radius: f64, intensity: f64) -> f64 {
    let d = p.distance(centre);
    if d > radius {
        intensity * 2.0 * (radius / d).asin()
    } else {
        0.0
    }
}

#[test]
fn closed_form_7_an_unoccluded_disk_gives_radiance_times_subtended_angle() {
    let (centre, radius, intensity) = (DVec2::new(37.3, 29.6), 6.25, 0.8);
    let loaded = scene(
        "Scene(canvas: (80, 64), floor: Color((1, 1, 1)),
               lights: [Circle(at: (37.3, 29.6), radius: 6.25, intensity: 0.8)])",
    );
    for bounces in [0, 2] {
        let samples = 16;
        let image = render(&loaded.scene, &{
            let mut options = RenderOptions::default();
            options.samples = samples;
            options.bounces = bounces;
            options.seed = 7;
            options
        })
        .image;
        let (mut outside, mut inside) = (0, 0);
        for y in 0..image.height {
            for x in 0..image.width {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let got = image.get(x, y)[0] as f64;
                let d = p.distance(centre);
                if d < radius - 1.0 {
                    // Wholly inside: the rim emits outward only.
                    assert_eq!(got, 0.0, "pixel ({x}, {y}) inside the disk");
                    inside += 1;
                    continue;
                }
                if d < radius + 1.0 {
                    continue;
                }
                // The estimate has no variance at a point (sampled by the
                // angle it subtends, `Flatland`): only the jitter's.
                let (mean, sd) = pixel_moments(x, y, 24, |q| disk(q, centre, radius, intensity));
                let se = sd / (samples as f64).sqrt();
                let tolerance = 5.0 * se + 1e-5 * mean;
                assert!(
                    (got - mean).abs() <= tolerance,
                    "D = {bounces}, pixel ({x}, {y}): got {got}, exact {mean}, 5 SE = {}",
                    5.0 * se
                );
                outside += 1;
            }
        }
        assert!(
            outside > 4000 && inside > 80,
            "{outside} outside, {inside} inside"
        );
    }
}

const BLOCK: u32 = 8;
/// Independent runs per integrator; with standard errors from 24 runs the
/// statistic follows a t distribution with 23 degrees of freedom: beyond
/// 5, once in 25,000 blocks.
const RUNS: u64 = 24;
const K: f64 = 5.0;

/// Path and light tracing agree on every block within `K` combined
/// standard errors.
fn assert_agree(name: &str, scene: &Scene, bounces: u32) {
    let at = |integrator| {
        let mut options = RenderOptions::default();
        options.samples = 8;
        options.bounces = bounces;
        options.integrator = integrator;
        options.memo = MemoOptions::default();
        options.memo.enabled = false;
        options
    };
    let agreement = Agreement {
        block: BLOCK,
        runs: RUNS,
        first_seed: 1000,
        k: K,
        min_blocks: 30,
    };
    agreement.check(name, scene, at(Integrator::Path), |_| true);
}

/// A rotated, non-convex room (an L) with a circle light in one arm,
/// a wall stub casting a shadow, and `mirror` on one wall.
fn l_room(falloff: &str, mirror: bool) -> Scene {
    let material = if mirror {
        ", material: Mirror(tint: (0.9, 0.9, 0.9))"
    } else {
        ""
    };
    let (s, c) = 0.3f64.sin_cos();
    let centre = DVec2::new(32.0, 32.0);
    let at = |x: f64, y: f64| {
        let p = DVec2::new(x, y);
        centre + DVec2::new(c * p.x - s * p.y, s * p.x + c * p.y)
    };
    let corners = [
        at(-24.0, -24.0),
        at(24.0, -24.0),
        at(24.0, 0.0),
        at(0.0, 0.0),
        at(0.0, 24.0),
        at(-24.0, 24.0),
    ];
    let mut walls: Vec<String> = (0..6)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 6]);
            let m = if k == 1 { material } else { "" };
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){m})",
                a.x, a.y, b.x, b.y
            )
        })
        .collect();
    let (a, b) = (at(-10.0, -4.0), at(-4.0, -10.0));
    walls.push(format!(
        "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}), material: Diffuse(albedo: Some((0.6, 0.3, 0.2))))",
        a.x, a.y, b.x, b.y
    ));
    let light = at(-16.0, -14.0);
    scene(&format!(
        "Scene(canvas: (64, 64), floor: Color((0.8, 0.8, 0.8)),
               walls: [{}],
               lights: [Circle(at: ({:?}, {:?}), radius: 2.5, intensity: 3.0{falloff})])",
        walls.join(", "),
        light.x,
        light.y
    ))
    .scene
}

#[test]
fn path_and_light_tracing_agree_on_a_circle_light_in_a_rotated_l_room() {
    for falloff in [
        "",
        ", falloff: InverseSquare",
        ", falloff: Window(range: 30)",
    ] {
        assert_agree(&format!("falloff '{falloff}'"), &l_room(falloff, false), 2);
    }
}

#[test]
fn path_tracing_sees_a_circle_light_in_a_mirror() {
    let scene = l_room("", true);
    assert_agree("mirror", &scene, 2);
    // And the mirror adds light that the same room without it lacks, on
    // the mirror's side of the room: the test above is not vacuous.
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 32;
        options.bounces = 2;
        options
    };
    let with = render(&scene, &options).image;
    let without = render(&l_room("", false), &options).image;
    let total =
        |image: &flatray_tracer::Image| image.pixels.iter().map(|p| p[0] as f64).sum::<f64>();
    assert!(total(&with) > 1.02 * total(&without));
}

#[test]
fn a_circle_lights_radius_must_be_positive() {
    for radius in ["0", "-1", "2e15"] {
        let text = format!(
            "Scene(canvas: (8, 8), floor: Color((1, 1, 1)),\n  lights: [\n    Circle(at: (4, 4), radius: {radius}),\n  ])"
        );
        let path = std::path::Path::new("c.ron");
        let error = flatray_io::parse(&text, path, std::path::Path::new("."))
            .err()
            .unwrap_or_else(|| panic!("radius {radius} was accepted"));
        let message = error.to_string();
        assert!(message.contains("c.ron:3:"), "{message}");
        assert!(
            message.contains("radius") || message.contains("> 0"),
            "{message}"
        );
    }
}
