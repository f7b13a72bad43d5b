//! Hard cases: one named test per case, each asserting finite output and
//! the right answer (a closed form, a no-leak zero, or agreement with a
//! slightly perturbed twin). `docs/robustness.md` gives the rule behind
//! each.

use std::f64::consts::TAU;

use flatray_geometry::{DVec2, Ray, Segment, SegmentSet, Skip, intersect};
use flatray_tests::{render, scene};
use flatray_tracer::sampling::{Stream, cosine_half_circle};
use flatray_tracer::scene::Item;
use flatray_tracer::{
    Canvas, Falloff, Floor, Image, Integrator, Light, LightShape, Material, MemoOptions,
    RenderOptions, Rgb, Scene, Wall,
};

fn options(samples: u32, bounces: u32) -> RenderOptions {
    {
        let mut options = RenderOptions::default();
        options.samples = samples;
        options.bounces = bounces;
        options.memo = MemoOptions::default();
        options.memo.enabled = false;
        options
    }
}

fn all_finite(image: &Image) -> bool {
    image.pixels.iter().flatten().all(|v| v.is_finite())
}

/// Relative difference of the channel sums of two images.
fn relative_difference(a: &Image, b: &Image) -> f64 {
    let sum = |i: &Image| i.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let diff: f64 = a
        .pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .map(|(x, y)| (x - y).abs() as f64)
        .sum();
    diff / sum(b).max(f64::MIN_POSITIVE)
}

fn walls_text(points: &[(f64, f64)], closed: bool, extra: &str) -> String {
    let n = points.len();
    let count = if closed { n } else { n - 1 };
    (0..count)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){extra})",
                a.0, a.1, b.0, b.1
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Renders `walls` with lights outside and asserts every pixel whose centre
/// satisfies `inside` is exactly zero, for direct light and three bounces.
fn assert_no_leak(name: &str, walls: &str, inside: impl Fn(DVec2) -> bool) {
    let text = format!(
        "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{walls}],
               lights: [Point(at: (1.5, 98.5), intensity: 50.0), Line(a: (99, 2), b: (99, 97), intensity: 2.0),
                        Directional(direction: (-0.37, 1.0), intensity: 3.0)])"
    );
    let loaded = scene(&text);
    for (bounces, memo) in [(0, false), (3, false), (3, true)] {
        let image = render(&loaded.scene, &{
            let mut options = options(4, bounces);
            options.memo = MemoOptions::default();
            options.memo.enabled = memo;
            options
        })
        .image;
        assert!(all_finite(&image), "{name}");
        let mut inside_count = 0;
        for y in 0..100 {
            for x in 0..100 {
                if inside(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                    inside_count += 1;
                    assert_eq!(
                        image.get(x, y),
                        [0.0; 3],
                        "{name}, D = {bounces}: light leaked into ({x}, {y})"
                    );
                }
            }
        }
        assert!(inside_count > 100, "{name}: {inside_count} pixels inside");
        assert!(
            image.pixels.iter().any(|p| p[0] > 0.0),
            "{name}: the outside is lit"
        );
    }
}

/// A wall's own light never reaches it: one emitting wall, tilted so
/// that its points are off its line by rounding, alone in the scene, gives
/// the same image with one bounce as with none (the floor's direct light),
/// for both path integrators, memo on and off; and so does a wall that
/// only lies along a line light's line.
#[test]
fn an_emitting_wall_does_not_light_itself() {
    let emitting = "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [
        Wall(a: (20, 50), b: (80, 50.001), material: Diffuse(albedo: (0.8, 0.8, 0.8)), emit: (intensity: 0.5))])";
    let along = "Scene(canvas: (100, 100), floor: Color((1, 1, 1)),
        walls: [Wall(a: (20, 50), b: (50, 50.0005), material: Diffuse(albedo: (0.8, 0.8, 0.8)))],
        lights: [Line(a: (50, 50.0005), b: (80, 50.001), intensity: 0.5)])";
    for (name, text) in [
        ("emitting wall", emitting),
        ("wall along a line light", along),
    ] {
        let loaded = scene(text);
        for integrator in [Integrator::Path, Integrator::Original] {
            for memo in [false, true] {
                let render_with = |bounces| {
                    let mut o = options(16, bounces);
                    o.integrator = integrator;
                    o.memo.enabled = memo;
                    o.seed = 3;
                    render(&loaded.scene, &o).image
                };
                let (none, one) = (render_with(0), render_with(1));
                assert!(all_finite(&one));
                // Memo off, both draw the same direct light: equal to
                // rounding. Memo on, one bounce takes the floor's direct
                // light from the memo's strata instead, another jitter of
                // the receiver (0.2 % apart here); the defect added 25 %.
                let difference = relative_difference(&one, &none);
                let tolerance = if memo { 1e-2 } else { 1e-6 };
                assert!(
                    difference < tolerance,
                    "{name}, {integrator:?}, memo {memo}: D = 1 differs from D = 0 by {difference}"
                );
            }
        }
    }
}

/// A light outside a closed room, on the extension of one of its walls'
/// lines (a point light, or sunlight parallel to the wall), in a square
/// turned by 17 degrees: every pixel inside stays exactly zero with
/// bounces. A shadow ray from a point of that wall runs along its line
/// through the corner, where rounding decided whether it crossed the next
/// wall; such light reaches a wall only at grazing incidence, cosine
/// zero, so the wall receives none of it.
#[test]
fn no_leak_from_a_light_on_a_walls_line() {
    let (s, c) = 17f64.to_radians().sin_cos();
    let corners: Vec<DVec2> = [(-30.0, -30.0), (30.0, -30.0), (30.0, 30.0), (-30.0, 30.0)]
        .iter()
        .map(|&(x, y)| DVec2::new(50.0 + c * x - s * y, 50.0 + s * x + c * y))
        .collect();
    let points: Vec<(f64, f64)> = corners.iter().map(|p| (p.x, p.y)).collect();
    let walls = walls_text(&points, true, "");
    let inside = |p: DVec2| {
        let q = p - DVec2::new(50.0, 50.0);
        let (x, y) = (c * q.x + s * q.y, -s * q.x + c * q.y);
        x.abs() < 29.0 && y.abs() < 29.0
    };
    let along = corners[1] - corners[0];
    let lights = [
        // Beyond each end of the first wall, on its line.
        format!(
            "Point(at: ({:?}, {:?}), intensity: 50.0)",
            (corners[1] + 0.3 * along).x,
            (corners[1] + 0.3 * along).y
        ),
        format!(
            "Point(at: ({:?}, {:?}), intensity: 50.0)",
            (corners[0] - 0.2 * along).x,
            (corners[0] - 0.2 * along).y
        ),
        format!(
            "Directional(direction: ({:?}, {:?}), intensity: 3.0)",
            along.x, along.y
        ),
    ];
    for light in &lights {
        let text = format!(
            "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{walls}], lights: [{light}])"
        );
        let loaded = scene(&text);
        for integrator in [Integrator::Path, Integrator::Original] {
            for (bounces, memo) in [(1, false), (3, false), (1, true), (3, true)] {
                let mut o = options(16, bounces);
                o.integrator = integrator;
                o.memo.enabled = memo;
                let image = render(&loaded.scene, &o).image;
                let mut leaks = 0;
                for y in 0..100 {
                    for x in 0..100 {
                        if inside(DVec2::new(x as f64 + 0.5, y as f64 + 0.5))
                            && image.get(x, y) != [0.0; 3]
                        {
                            leaks += 1;
                        }
                    }
                }
                assert_eq!(
                    leaks, 0,
                    "{light}, {integrator:?}, D = {bounces}, memo {memo}: {leaks} pixels inside lit"
                );
                assert!(
                    image.pixels.iter().any(|p| p[0] > 0.0),
                    "{light}: outside lit"
                );
            }
        }
    }
}

#[test]
fn ray_parallel_to_a_wall_misses_it() {
    let wall = Segment::new(DVec2::new(0.0, 5.0), DVec2::new(10.0, 5.0));
    for offset in [1e-300, 1e-12, 1.0, -1e-12] {
        assert!(
            intersect(
                &Ray::new(DVec2::new(-3.0, 5.0 + offset), DVec2::new(1.0, 0.0)),
                &wall
            )
            .is_none()
        );
    }
}

#[test]
fn ray_collinear_with_a_wall_slides_along_it() {
    // Overlapping and not: no hit, so a light on a wall's line lights the
    // floor along it as if the wall were edge-on (zero thickness).
    let text = |y: f64| {
        format!(
            "Scene(canvas: (60, 20), floor: Color((1, 1, 1)), walls: [Wall(a: (20, 10), b: (40, 10))],
                   lights: [Point(at: (5, {y:?}), intensity: 5.0)])"
        )
    };
    let on_line = render(&scene(&text(10.0)).scene, &options(16, 1)).image;
    let perturbed = render(&scene(&text(10.0 + 1e-9)).scene, &options(16, 1)).image;
    assert!(all_finite(&on_line));
    assert!(relative_difference(&on_line, &perturbed) < 1e-3);
}

#[test]
fn no_leak_through_a_convex_corner() {
    let square = [(20.3, 20.1), (80.7, 20.1), (80.7, 79.9), (20.3, 79.9)];
    assert_no_leak("convex", &walls_text(&square, true, ""), |p| {
        p.x > 21.0 && p.x < 80.0 && p.y > 21.0 && p.y < 79.0
    });
}

#[test]
fn no_leak_through_a_reflex_corner() {
    let l_shape = [
        (10.0, 10.0),
        (90.0, 10.0),
        (90.0, 45.3),
        (45.7, 45.3),
        (45.7, 90.0),
        (10.0, 90.0),
    ];
    assert_no_leak("reflex", &walls_text(&l_shape, true, ""), |p| {
        (p.x > 11.0 && p.x < 89.0 && p.y > 11.0 && p.y < 44.5)
            || (p.x > 11.0 && p.x < 45.0 && p.y > 11.0 && p.y < 89.0)
    });
}

#[test]
fn no_leak_through_a_t_junction() {
    // A room closed by a wall that ends on the middle of another: the end
    // point (50, 20) lies exactly on the long wall.
    let walls = "Wall(a: (10, 20), b: (90, 20)), Wall(a: (50, 20), b: (50, 80)), Wall(a: (50, 80), b: (85.5, 80)),
                 Wall(a: (85.5, 80), b: (85.5, 20.0))";
    assert_no_leak("T-junction", walls, |p| {
        p.x > 51.0 && p.x < 85.0 && p.y > 21.0 && p.y < 79.0
    });
}

#[test]
fn no_leak_through_crossing_walls() {
    // Four walls that overshoot each other at every corner, like a '#'.
    let walls = "Wall(a: (10, 25.3), b: (90, 25.3)), Wall(a: (10, 75.1), b: (90, 75.1)),
                 Wall(a: (25.7, 10), b: (25.7, 90)), Wall(a: (74.9, 10), b: (74.9, 90))";
    assert_no_leak("crossing", walls, |p| {
        p.x > 26.5 && p.x < 74.0 && p.y > 26.0 && p.y < 74.5
    });
}

/// The caustic pass's wall bins stop where walls cross, as the wall
/// memo's do: a mirror that overshoots a corner throws the outside lights
/// onto the outside of the walls it crosses, next to the room's inside.
#[test]
fn no_leak_through_crossing_walls_into_the_caustic_bins() {
    let walls = "Wall(a: (10, 25.3), b: (90, 25.3), material: Mirror()), Wall(a: (10, 75.1), b: (90, 75.1), material: Mirror()),
                 Wall(a: (25.7, 10), b: (25.7, 90)), Wall(a: (74.9, 10), b: (74.9, 90), material: Mirror())";
    assert_no_leak("crossing mirrors", walls, |p| {
        p.x > 26.5 && p.x < 74.0 && p.y > 26.0 && p.y < 74.5
    });
}

#[test]
fn no_leak_through_a_rotated_room_with_inexact_corners() {
    let points: Vec<(f64, f64)> = (0..7)
        .map(|k| {
            let a = TAU * k as f64 / 7.0 + 0.3;
            (50.0 + 37.0 * a.cos(), 50.0 + 37.0 * a.sin())
        })
        .collect();
    assert_no_leak("heptagon", &walls_text(&points, true, ""), |p| {
        p.distance(DVec2::new(50.0, 50.0)) < 32.0
    });
}

#[test]
fn a_path_leaving_a_wall_never_hits_it_again_at_any_angle() {
    // From points on each wall of a closed room, directions from the
    // normal to the most grazing the sampler can give: every ray meets
    // another wall, never its own, never nothing.
    let points: Vec<DVec2> = (0..5)
        .map(|k| {
            let a = TAU * k as f64 / 5.0 + 0.2;
            DVec2::new(1e3 * a.cos() + 0.3, 1e3 * a.sin() + 0.7)
        })
        .collect();
    let segments: Vec<Segment> = (0..5)
        .map(|i| Segment::new(points[i], points[(i + 1) % 5]))
        .collect();
    let set = SegmentSet::new(segments.clone());
    let mut stream = Stream::new(9, 9, 9);
    for (i, seg) in segments.iter().enumerate() {
        // The inward normal: towards the centre.
        let centre = points.iter().copied().sum::<DVec2>() / 5.0;
        let n = if seg.normal().dot(centre - seg.a) > 0.0 {
            seg.normal()
        } else {
            -seg.normal()
        };
        let extremes = [
            0.0,
            f64::EPSILON,
            1e-12,
            0.5,
            1.0 - 1e-12,
            1.0 - f64::EPSILON,
        ];
        let us: Vec<f64> = extremes
            .iter()
            .copied()
            .chain((0..300).map(|_| stream.uniform()))
            .collect();
        // A path that meets a wall exactly at an end stops there (the
        // corner rule); from 1e-7 of the length on, the leaving angle keeps
        // every ray inside.
        let positions: Vec<f64> = [1e-7, 0.5, 1.0 - 1e-7]
            .into_iter()
            .chain((0..20).map(|_| stream.uniform()))
            .collect();
        for &position in &positions {
            let x = seg.point_at(position);
            for &u in &us {
                let d = cosine_half_circle(n, u);
                let hit = set.closest_hit(&Ray::new(x, d), f64::INFINITY, Skip::one(i as u32));
                let (j, _) = hit.unwrap_or_else(|| {
                    panic!("wall {i}, position {position}, u {u}: escaped the room")
                });
                assert_ne!(j, i as u32);
            }
        }
    }
}

#[test]
fn facing_mirrors_end_at_the_bounce_limit() {
    // An endless corridor: two parallel mirrors, a line light between them,
    // a thousand reflections in a row allowed. The loop is iterative: it
    // ends, with finite values and many reflections counted. The mirrors reach far enough
    // that most paths stay between them for all their bounces (those
    // within 79 degrees of the corridor's normal), whatever the numbers.
    let text = "Scene(canvas: (60, 30), floor: Color((1, 1, 1)),
        walls: [Wall(a: (-1e5, 5), b: (1e5, 5), material: Mirror(tint: (0.999, 0.999, 0.999))),
                Wall(a: (-1e5, 25), b: (1e5, 25), material: Mirror(tint: (0.999, 0.999, 0.999)))],
        lights: [Line(a: (25, 12), b: (35, 12), intensity: 1.0)])";
    let loaded = scene(text);
    let rendered = render(&loaded.scene, &{
        let mut options = options(2, 1);
        options.specular = 1000;
        options
    });
    assert!(all_finite(&rendered.image));
    assert!(
        rendered.stats.physics.mirror_reflections > 100_000,
        "{}",
        rendered.stats
    );
    // Samples between the mirrors (two thirds of the floor) whose first
    // ray leaves within 79 degrees of the normal: 58 % of the 3,600 (2,121
    // with these numbers; the binomial's deviation is 30) end by the limit
    // or, as the tint takes their light, by Russian roulette.
    let physics = rendered.stats.physics;
    assert!(physics.paths_roulette > 0, "{}", rendered.stats);
    assert!(
        physics.paths_bounce_limit + physics.paths_roulette > 1_800,
        "{}",
        rendered.stats
    );
}

#[test]
fn grazing_reflection_off_a_mirror_is_finite_and_matches_its_twin() {
    let text = |y: f64| {
        format!(
            "Scene(canvas: (80, 40), floor: Color((1, 1, 1)),
                   walls: [Wall(a: (10, 20), b: (70, 20), material: Mirror())],
                   lights: [Point(at: (2, {y:?}), intensity: 5.0), Line(a: (74, 20.001), b: (78, 20.002))])"
        )
    };
    let a = render(&scene(&text(20.0)).scene, &{
        let mut options = options(16, 2);
        options.integrator = Integrator::Light;
        options
    })
    .image;
    let b = render(&scene(&text(20.0 + 1e-7)).scene, &{
        let mut options = options(16, 2);
        options.integrator = Integrator::Light;
        options
    })
    .image;
    assert!(all_finite(&a) && all_finite(&b));
    assert!(relative_difference(&a, &b) < 0.02);
}

#[test]
fn point_light_exactly_on_a_wall_lights_both_sides() {
    // A diagonal wall and a light at a point computed on it: the light is
    // off the wall's line only by rounding, so each shadow ray's crossing
    // with the wall lands at t = 1 give or take rounding. The rule (the
    // light belongs to the wall) lights both sides everywhere, no speckle.
    let (a, b) = (DVec2::new(3.1, 5.3), DVec2::new(36.7, 33.9));
    let at = a + 0.437 * (b - a);
    let text = format!(
        "Scene(canvas: (40, 40), floor: Color((1, 1, 1)),
               walls: [Wall(a: ({:?}, {:?}), b: ({:?}, {:?}))],
               lights: [Point(at: ({:?}, {:?}), intensity: 5.0)])",
        a.x, a.y, b.x, b.y, at.x, at.y
    );
    let image = render(&scene(&text).scene, &options(8, 0)).image;
    assert!(all_finite(&image));
    let wall = Segment::new(a, b);
    let mut dark = Vec::new();
    for y in 0..40u32 {
        for x in 0..40u32 {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            // Away from the wall's line, every pixel sees the light.
            let distance = wall.side_value(p).abs() / wall.length();
            if distance > 1.0 && image.get(x, y)[0] == 0.0 {
                dark.push((x, y));
            }
        }
    }
    assert!(dark.is_empty(), "dark pixels: {dark:?}");
}

#[test]
fn point_light_on_a_wall_endpoint_and_at_a_pixel_centre_stays_finite() {
    for at in ["(35, 20)", "(5, 20)", "(20.5, 10.5)"] {
        let text = format!(
            "Scene(canvas: (40, 40), floor: Color((1, 1, 1)),
                   walls: [Wall(a: (5, 20), b: (35, 20)), Wall(a: (35, 20), b: (35, 35))],
                   lights: [Point(at: {at}, intensity: 5.0)])"
        );
        let loaded = scene(&text);
        for integrator in [Integrator::Path, Integrator::Light] {
            let rendered = render(&loaded.scene, &{
                let mut options = options(8, 2);
                options.integrator = integrator;
                options
            });
            assert!(all_finite(&rendered.image), "{at}");
            assert_eq!(rendered.stats.physics.nonfinite_samples, 0, "{at}");
        }
    }
    // At a pixel centre the small-radius clamp bounds the pixel: its value
    // is at most I / r0 with the default r0 = 0.5.
    let loaded = scene(
        "Scene(canvas: (40, 40), floor: Color((1, 1, 1)), lights: [Point(at: (20.5, 10.5), intensity: 5.0)])",
    );
    let image = render(&loaded.scene, &options(64, 0)).image;
    let centre = image.get(20, 10)[0] as f64;
    assert!(
        centre <= 5.0 / 0.5 + 1e-6 && centre > 5.0 / 0.75,
        "{centre}"
    );
}

#[test]
fn a_receiver_pixel_cut_by_a_wall_averages_its_two_sides() {
    // A wall along y = 10.5 cuts the row of pixels 10 in half: the pixel's
    // value is the mean over its square of I / r above the wall and zero
    // below it (closed form 1 with a shadow), within 5 standard errors.
    let text = "Scene(canvas: (30, 21), floor: Color((1, 1, 1)),
        walls: [Wall(a: (-1, 10.5), b: (31, 10.5))],
        lights: [Point(at: (15, 3), intensity: 5.0)])";
    let samples = 256;
    let image = render(&scene(text).scene, &options(samples, 0)).image;
    assert!(all_finite(&image));
    let light = DVec2::new(15.0, 3.0);
    for x in 5..25u32 {
        let (mut s1, mut s2, n) = (0.0, 0.0, 32);
        for j in 0..n {
            for i in 0..n {
                let p = DVec2::new(
                    x as f64 + (i as f64 + 0.5) / n as f64,
                    10.0 + (j as f64 + 0.5) / n as f64,
                );
                let v = if p.y < 10.5 {
                    5.0 / p.distance(light)
                } else {
                    0.0
                };
                s1 += v;
                s2 += v * v;
            }
        }
        let count = (n * n) as f64;
        let mean = s1 / count;
        let se = ((s2 / count - mean * mean) / samples as f64).sqrt();
        let cut = image.get(x, 10)[0] as f64;
        assert!(
            (cut - mean).abs() <= 5.0 * se,
            "x = {x}: {cut} vs {mean} (5 SE = {})",
            5.0 * se
        );
        assert_eq!(image.get(x, 11), [0.0; 3]);
    }
}

#[test]
fn degenerate_input_is_handled_as_documented() {
    // Duplicate walls block like one; a zero-intensity light adds nothing.
    let one =
        "Scene(canvas: (30, 30), floor: Color((1, 1, 1)), walls: [Wall(a: (10, 5), b: (10, 25))],
        lights: [Point(at: (3, 15), intensity: 4.0)])";
    let twice = "Scene(canvas: (30, 30), floor: Color((1, 1, 1)), walls: [Wall(a: (10, 5), b: (10, 25)), Wall(a: (10, 5), b: (10, 25))],
        lights: [Point(at: (3, 15), intensity: 4.0), Point(at: (20, 20), intensity: 0.0)])";
    let a = render(&scene(one).scene, &options(8, 2)).image;
    let b = render(&scene(twice).scene, &options(8, 2)).image;
    assert!(all_finite(&b));
    assert!(
        relative_difference(&a, &b) < 0.05,
        "{}",
        relative_difference(&a, &b)
    );
    // Zero-length walls and line lights are refused by the loader (see
    // bad_scenes.rs) and by a scene built in code, with the same words.
    let canvas = Canvas {
        width: 20,
        height: 20,
        origin: DVec2::ZERO,
    };
    let p = DVec2::new(10.0, 10.0);
    let dot = Wall {
        shape: Segment::new(p, p).into(),
        material: Material::Diffuse { albedo: None },
    };
    let error = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, vec![dot], vec![]).unwrap_err();
    assert_eq!(
        error.to_string(),
        "wall 0: a wall needs two different endpoints, found (10, 10) twice"
    );
    let line = Light {
        profile: None,
        shape: LightShape::Line {
            segment: Segment::new(p, p),
            one_sided: false,
            wall: None,
        },
        color: Rgb::ONE,
        intensity: 1.0,
        falloff: Falloff::Flatland,
        spectrum: None,
    };
    let error = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, vec![], vec![line]).unwrap_err();
    assert_eq!(error.item, Item::Light(0));
    assert!(error.message.contains("two different endpoints"), "{error}");
}

fn shifted_scene(offset: f64) -> String {
    format!(
        "Scene(canvas: (60, 40), origin: ({o:?}, {o:?}), floor: Color((1, 1, 1)),
            walls: [Wall(a: ({a:?}, {b:?}), b: ({c:?}, {b:?})), Wall(a: ({c:?}, {b:?}), b: ({c:?}, {d:?}), material: Mirror()),
                    Wall(a: ({e:?}, {f:?}), b: ({g:?}, {h:?}), material: Diffuse(albedo: (0.8, 0.3, 0.3)))],
            lights: [Point(at: ({lx:?}, {ly:?}), intensity: 5.0), Line(a: ({mx:?}, {my:?}), b: ({nx:?}, {ny:?}), intensity: 0.5)])",
        o = offset,
        a = offset + 10.0,
        b = offset + 8.0,
        c = offset + 50.0,
        d = offset + 35.0,
        e = offset + 5.0,
        f = offset + 30.0,
        g = offset + 25.0,
        h = offset + 38.0,
        lx = offset + 30.3,
        ly = offset + 20.7,
        mx = offset + 12.0,
        my = offset + 15.0,
        nx = offset + 20.0,
        ny = offset + 13.0,
    )
}

#[test]
fn a_scene_translated_a_million_units_gives_the_same_image() {
    let near = render(&scene(&shifted_scene(0.0)).scene, &options(16, 2)).image;
    let far = render(&scene(&shifted_scene(1e6)).scene, &options(16, 2)).image;
    assert!(all_finite(&far));
    // The same random streams: only rounding of coordinates near 1e6
    // (about 1e-10) differs, which moves a few samples across shadow edges.
    assert!(
        relative_difference(&near, &far) < 1e-3,
        "{}",
        relative_difference(&near, &far)
    );
}

/// With the memo on, a scene a billion units from the origin checks the
/// same memo reads as at the origin (the checks are keyed by the read's
/// cell along its wall, not by the last bits of its position there), so
/// the images agree pixel by pixel but for rounding at shadow edges.
#[test]
fn a_scene_translated_a_billion_units_checks_the_same_memo_reads() {
    for onward in [true, false] {
        let options = {
            let mut options = options(16, 2);
            options.memo = MemoOptions::default();
            options.memo.onward = onward;
            options.floor_lines = false;
            options
        };
        let near = render(&scene(&shifted_scene(0.0)).scene, &options).image;
        let far = render(&scene(&shifted_scene(1e9)).scene, &options).image;
        assert!(all_finite(&far));
        let most = near
            .pixels
            .iter()
            .flatten()
            .zip(far.pixels.iter().flatten())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        // A read checked in one and not the other moves a pixel by a
        // tenth or more (its mean is 0.92).
        assert!(
            most < 0.01,
            "onward memo {onward}: a pixel differs by {most}"
        );
    }
}

#[test]
fn a_scene_scaled_down_gives_the_scaled_image() {
    // The same scene 100 times smaller, rendered at 100 pixels per unit:
    // with Flatland a point light's fluence grows as 1 / length, so a light
    // 100 times weaker gives the same image (r0 shrinks with the scene).
    let big = "Scene(canvas: (40, 30), floor: Color((1, 1, 1)), small_radius: 0.5,
        walls: [Wall(a: (10, 5), b: (30, 5)), Wall(a: (30, 5), b: (30, 25), material: Mirror())],
        lights: [Point(at: (15.3, 15.7), intensity: 1.0)])";
    let small = "Scene(canvas: (1, 1), floor: Color((1, 1, 1)), small_radius: 0.005,
        walls: [Wall(a: (0.1, 0.05), b: (0.3, 0.05)), Wall(a: (0.3, 0.05), b: (0.3, 0.25), material: Mirror())],
        lights: [Point(at: (0.153, 0.157), intensity: 0.01)])";
    let crop = |image: &Image| Image {
        width: 40,
        height: 30,
        pixels: (0..30)
            .flat_map(|y| (0..40).map(move |x| (x, y)))
            .map(|(x, y)| image.get(x, y))
            .collect(),
    };
    let total = |image: &Image| {
        image
            .pixels
            .iter()
            .flatten()
            .map(|&v| v as f64)
            .sum::<f64>()
    };
    // Direct light: pixel by pixel (only the jitter differs: the streams
    // are keyed by pixel index, and the images' widths differ). At 256
    // samples that noise is 0.40-0.57 % (seeds 0 to 9), half the bound.
    // Without the caustic pass: the mirror's light, which it adds at
    // `bounces: 0`, is compared with the bounces below.
    let direct = {
        let mut options = options(256, 0);
        options.caustics = false;
        options
    };
    let a = render(&scene(big).scene, &direct).image;
    let b = crop(
        &render(&scene(small).scene, &{
            let mut options = direct;
            options.scale = 100.0;
            options
        })
        .image,
    );
    assert!(all_finite(&b));
    assert!(
        relative_difference(&b, &a) < 0.01,
        "{}",
        relative_difference(&b, &a)
    );
    // With bounces: the totals, where per-pixel noise averages out.
    let a = render(&scene(big).scene, &options(64, 2)).image;
    let b = crop(
        &render(&scene(small).scene, &{
            let mut options = options(64, 2);
            options.scale = 100.0;
            options
        })
        .image,
    );
    assert!(
        (total(&b) / total(&a) - 1.0).abs() < 0.01,
        "{} vs {}",
        total(&b),
        total(&a)
    );
}

#[test]
fn walls_that_touch_the_canvas_edge_are_fine() {
    let text = "Scene(canvas: (30, 30), floor: Color((1, 1, 1)),
        walls: [Wall(a: (0, 0), b: (30, 0)), Wall(a: (30, 0), b: (30, 30)), Wall(a: (0, 15), b: (30, 15))],
        lights: [Point(at: (10, 8), intensity: 4.0)])";
    for integrator in [Integrator::Path, Integrator::Light] {
        let image = render(&scene(text).scene, &{
            let mut options = options(8, 3);
            options.integrator = integrator;
            options
        })
        .image;
        assert!(all_finite(&image));
        assert!(
            image.get(10, 20)[0] == 0.0,
            "{integrator:?}: below the dividing wall is dark"
        );
    }
}

#[test]
fn a_non_finite_value_is_reported_not_written() {
    let canvas = Canvas {
        width: 8,
        height: 8,
        origin: DVec2::ZERO,
    };
    let lamp = |intensity| Light {
        profile: None,
        shape: LightShape::Point {
            at: DVec2::new(4.0, 4.0),
        },
        color: Rgb::ONE,
        intensity,
        falloff: Falloff::Constant,
        spectrum: None,
    };
    // An intensity past the bound is refused where the scene is built...
    let error = Scene::new(
        canvas,
        Floor::Color(Rgb::ONE),
        0.5,
        vec![],
        vec![lamp(f64::MAX)],
    )
    .unwrap_err();
    assert_eq!(error.item, Item::Light(0));
    // ... and a value that overflows anyway (here through an exposure
    // no file may give) is counted and written as 0, never as NaN or
    // infinity.
    let scene = Scene::new(
        canvas,
        Floor::Color(Rgb::ONE),
        0.5,
        vec![],
        vec![lamp(1e9), lamp(1e9)],
    )
    .expect("a valid scene");
    let mut overflowing = options(2, 0);
    overflowing.exposure = f64::MAX;
    let rendered = render(&scene, &overflowing);
    assert!(
        rendered
            .image
            .pixels
            .iter()
            .flatten()
            .all(|v| v.is_finite())
    );
    assert!(rendered.stats.physics.nonfinite_samples > 0);
    let first = rendered.stats.physics.first_nonfinite;
    assert_eq!(first, Some((0, 0, u32::MAX)), "{first:?}");
}

/// Renders `text` with both integrators and many bounces: finite, no
/// sample dropped, glass touched; returns the images.
fn glass_case(text: &str) -> Vec<Image> {
    let loaded = scene(text);
    [Integrator::Path, Integrator::Light]
        .into_iter()
        .map(|integrator| {
            let rendered = render(&loaded.scene, &{
                let mut options = options(16, 6);
                options.integrator = integrator;
                options
            });
            assert!(all_finite(&rendered.image), "{integrator:?}");
            assert_eq!(
                rendered.stats.physics.nonfinite_samples, 0,
                "{integrator:?}"
            );
            assert!(rendered.stats.physics.glass_events > 0, "{integrator:?}");
            rendered.image
        })
        .collect()
}

#[test]
fn grazing_incidence_on_glass() {
    // The point light lies on the line of the glass's top edge: its rays
    // meet that edge at grazing incidence (Fresnel reflectance 1).
    let images = glass_case(
        "Scene(canvas: (60, 40), floor: Color((1, 1, 1)),
            lights: [Point(at: (2, 10), intensity: 3.0), Line(a: (2, 30), b: (6, 34))],
            glass: [Glass(points: [(10, 10), (40, 10), (38, 20), (12, 22)], ior: 1.7, dispersion: 0.02)])",
    );
    let twin = glass_case(
        "Scene(canvas: (60, 40), floor: Color((1, 1, 1)),
            lights: [Point(at: (2, 9.999999), intensity: 3.0), Line(a: (2, 30), b: (6, 34))],
            glass: [Glass(points: [(10, 10), (40, 10), (38, 20), (12, 22)], ior: 1.7, dispersion: 0.02)])",
    );
    for (a, b) in images.iter().zip(&twin) {
        assert!(
            relative_difference(a, b) < 0.05,
            "{}",
            relative_difference(a, b)
        );
    }
}

#[test]
fn rays_through_a_glass_vertex() {
    // The light is aimed along the diagonal through two opposite vertices
    // of a glass square: rays through the vertices end there (the corner
    // rule) and everything stays finite.
    glass_case(
        "Scene(canvas: (60, 60), floor: Color((1, 1, 1)),
            lights: [Point(at: (5, 5), intensity: 3.0)],
            glass: [Glass(points: [(20, 20), (40, 20), (40, 40), (20, 40)], ior: 1.5)])",
    );
}

#[test]
fn glass_touching_a_wall() {
    // A glass vertex on a wall: the wall still shadows the far side.
    let images = glass_case(
        "Scene(canvas: (60, 40), floor: Color((1, 1, 1)),
            walls: [Wall(a: (40, 5), b: (40, 35))],
            lights: [Point(at: (5, 10), intensity: 3.0), Line(a: (2, 30), b: (6, 34))],
            glass: [Glass(points: [(10, 10), (40, 12), (38, 20), (25, 25)], ior: 1.7, dispersion: 0.02)])",
    );
    for image in &images {
        assert_eq!(image.get(50, 20), [0.0; 3]);
    }
}

/// Lasers and beams at a closed room's walls: a laser that starts at a
/// point computed on a tilted wall and points out of the room (it shines
/// past the wall it sits on), one that runs from outside along a wall's
/// line into the room's corner, and a beam outside the room whose
/// rays run parallel to a wall, one of them along its line into the
/// room's corner, for both integrators and D = 0 and 2. Every value is
/// finite, and no light gets into the room: every pixel inside is
/// exactly 0.
#[test]
fn lasers_and_beams_on_and_along_walls_do_not_leak() {
    let corners = [(20.3, 14.1), (78.9, 22.7), (70.2, 81.6), (12.8, 73.0)];
    let walls = walls_text(&corners, true, "");
    let (a, b) = (DVec2::from(corners[0]), DVec2::from(corners[1]));
    let on = a + 0.37 * (b - a);
    let out = (b - a).perp().normalize();
    // Outward is the side away from the room's centre.
    let out = if out.dot(on - DVec2::new(45.0, 48.0)) > 0.0 {
        out
    } else {
        -out
    };
    let along = (b - a).normalize();
    let text = format!(
        "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{walls}],
               lights: [Laser(at: ({:?}, {:?}), direction: ({:?}, {:?}), intensity: 20),
                        Laser(at: ({:?}, {:?}), direction: ({:?}, {:?}), intensity: 20),
                        Beam(a: (5, 20), b: (10, 2), direction: ({:?}, {:?}), intensity: 2)])",
        on.x,
        on.y,
        out.x,
        out.y,
        (a - 10.0 * along).x,
        (a - 10.0 * along).y,
        along.x,
        along.y,
        along.x,
        along.y
    );
    let loaded = scene(&text);
    let room = Segment::new(a, b);
    let inside = |p: DVec2| {
        (0..4).all(|k| {
            let s = Segment::new(DVec2::from(corners[k]), DVec2::from(corners[(k + 1) % 4]));
            s.side_value(p) / s.length() > 1.5
        })
    };
    assert!(inside(DVec2::new(45.0, 48.0)) && room.length() > 0.0);
    for integrator in [Integrator::Path, Integrator::Light] {
        for bounces in [0, 2] {
            let image = render(&loaded.scene, &{
                let mut options = options(4, bounces);
                options.integrator = integrator;
                options
            })
            .image;
            assert!(all_finite(&image), "{integrator:?}, D = {bounces}");
            assert!(image.pixels.iter().any(|p| p[0] > 0.0));
            for y in 0..100 {
                for x in 0..100 {
                    if inside(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                        assert_eq!(
                            image.get(x, y),
                            [0.0; 3],
                            "{integrator:?}, D = {bounces}: light leaked into ({x}, {y})"
                        );
                    }
                }
            }
        }
    }
}
