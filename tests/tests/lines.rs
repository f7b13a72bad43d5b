//! The floor's indirect light along lines across the image (`docs/model.md`,
//! "Lines across the floor"): the same image as each pixel's own path
//! samples, block by block (5 standard errors over fixed seeds, as a
//! line's error is shared by the pixels it crosses), in a turned,
//! non-convex room of every kind of wall, at one and at three bounces;
//! no light through shared corners; radiance that is not finite left out
//! and counted; the same bits on any number of threads; the same light a
//! million units from the origin; path samples where walls stand a few
//! pixels apart.

use flatray_geometry::DVec2;
use flatray_tests::{block_stats, options, render, render_on, scene};
use flatray_tracer::{Plan, RenderOptions, Scene};

/// The point `(x, y)` of the room's frame, turned by 0.3 radians about
/// the canvas's centre, as the scene format writes it.
fn at(x: f64, y: f64) -> String {
    let (s, c) = 0.3f64.sin_cos();
    let p = DVec2::new(32.0, 32.0) + DVec2::new(c * x - s * y, s * x + c * y);
    format!("({}, {})", p.x, p.y)
}

/// A turned L-shaped room: diffuse, coloured, mirror, rough mirror and
/// emitting walls, a tinted pane across its bend, a point, a spot and a
/// line light, and `extra` among its walls.
fn room(extra: &str) -> Scene {
    let corners = [
        (-24.0, -24.0),
        (24.0, -24.0),
        (24.0, 2.0),
        (2.0, 2.0),
        (2.0, 24.0),
        (-24.0, 24.0),
    ];
    let materials = [
        "",
        ", material: Mirror()",
        ", material: Diffuse(albedo: (0.9, 0.3, 0.2))",
        ", material: Rough(roughness: 0.3)",
        ", emit: (intensity: 0.2)",
        "",
    ];
    let walls: Vec<String> = (0..6)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 6]);
            format!(
                "Wall(a: {}, b: {}{})",
                at(a.0, a.1),
                at(b.0, b.1),
                materials[k]
            )
        })
        .collect();
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((0.8, 0.8, 0.8)),
               walls: [{},
                       Wall(a: {}, b: {}, material: Transparent(tint: (0.9, 0.6, 0.6))),
                       Wall(a: {}, b: {}){extra}],
               lights: [Point(at: {}, intensity: 2.0),
                        Spot(at: {}, direction: (1, 0.3), cone: 40, softness: 10, intensity: 2.0),
                        Line(a: {}, b: {}, intensity: 0.2)])",
        walls.join(", "),
        at(-8.0, 2.0),
        at(2.0, 2.0),
        at(10.0, -12.0),
        at(14.0, -6.0),
        at(-16.0, -16.0),
        at(8.0, -18.0),
        at(-20.0, 14.0),
        at(-12.0, 20.0),
    );
    scene(&text).scene
}

fn with_lines(base: RenderOptions, lines: bool) -> RenderOptions {
    let mut options = base;
    options.floor_lines = lines;
    options
}

#[test]
fn lines_agree_with_path_samples_block_by_block() {
    for (bounces, extra) in [
        (1, ""),
        (3, ""),
        (
            2,
            ", Wall(center: (40, 40), radius: 3.0, material: Mirror())",
        ),
    ] {
        let scene = room(extra);
        let base = options(16, bounces, 0);
        let plan = Plan::new(&scene, &with_lines(base, true));
        assert!(plan.floor_lines, "{bounces} bounces {extra}");
        assert_eq!(plan.onward, bounces >= 2);
        let lines = block_stats(&scene, with_lines(base, true), 8, 12, 300);
        let samples = block_stats(&scene, with_lines(base, false), 8, 12, 300);
        let mut checked = 0;
        for (b, ((ml, sl), (ms, ss))) in lines.iter().zip(&samples).enumerate() {
            let se = (sl * sl + ss * ss).sqrt();
            assert!(
                (ml - ms).abs() <= 5.0 * se + 1e-9 * ms.abs(),
                "{bounces} bounces {extra}, block {b}: lines {ml}, samples {ms}, 5 SE = {}",
                5.0 * se
            );
            checked += usize::from(ms.abs() > 0.0);
        }
        assert!(checked >= 40, "only {checked} lit blocks");
    }
}

/// A grid of closed square cells sharing their corners, turned, with a
/// lamp in one: lines through the corners (stepped over within a hair of
/// their crossing) leave every other cell exactly dark.
#[test]
fn lines_through_shared_corners_leak_nothing() {
    let (s, c) = 0.37f64.sin_cos();
    let point = |i: usize, j: usize| {
        let (x, y) = (i as f64 * 12.0 - 24.0, j as f64 * 12.0 - 24.0);
        DVec2::new(32.0 + c * x - s * y, 32.0 + s * x + c * y)
    };
    let mut walls = Vec::new();
    for i in 0..=4 {
        for j in 0..4 {
            for (a, b) in [
                (point(i, j), point(i, j + 1)),
                (point(j, i), point(j + 1, i)),
            ] {
                walls.push(format!(
                    "Wall(a: ({}, {}), b: ({}, {}))",
                    a.x, a.y, b.x, b.y
                ));
            }
        }
    }
    let lamp = (point(1, 1) + point(2, 2)) / 2.0;
    let scene = scene(&format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: ({}, {}), intensity: 3.0)])",
        walls.join(", "),
        lamp.x,
        lamp.y
    ))
    .scene;
    let options = options(32, 3, 4);
    assert!(Plan::new(&scene, &options).floor_lines);
    let image = render(&scene, &options).image;
    // The pixel's centre, in the grid's own frame (cells 12 wide).
    let cell = |x: u32, y: u32| {
        let d = DVec2::new(x as f64 + 0.5, y as f64 + 0.5) - DVec2::new(32.0, 32.0);
        let (u, v) = (c * d.x + s * d.y + 24.0, -s * d.x + c * d.y + 24.0);
        let inside = |w: f64| w > 1.0 && w < 47.0 && (w % 12.0) > 1.0 && (w % 12.0) < 11.0;
        (inside(u) && inside(v)).then(|| ((u / 12.0) as u32, (v / 12.0) as u32))
    };
    let (mut dark, mut lit) = (0, 0);
    for y in 0..64 {
        for x in 0..64 {
            match cell(x, y) {
                Some((1, 1)) => lit += usize::from(image.get(x, y)[0] > 0.0),
                Some(_) => {
                    assert_eq!(image.get(x, y), [0.0; 3], "({x}, {y})");
                    dark += 1;
                }
                None => {}
            }
        }
    }
    assert!(dark > 800 && lit > 50, "{dark} dark, {lit} lit");
}

/// A light so strong that the wall memo (f32) holds infinities: every
/// piece of line that reads a wall is not finite. Those pieces are left
/// out and counted, and the floor keeps its own (finite) direct light.
#[test]
fn lines_leave_light_that_is_not_finite_out() {
    let mut loaded = scene(
        "Scene(canvas: (40, 40), floor: Color((0.8, 0.8, 0.8)),
            walls: [Wall(a: (5, 5), b: (35, 5)), Wall(a: (35, 5), b: (35, 35))],
            lights: [Point(at: (20, 20))],
            render: (samples: 16))",
    );
    let mut parts = loaded.scene.parts();
    parts.lights[0].intensity = 1e200;
    loaded.scene = parts.build_unchecked();
    loaded.options.exposure = 1e-200;
    assert!(Plan::new(&loaded.scene, &loaded.options).floor_lines);
    let rendered = render(&loaded.scene, &loaded.options);
    assert!(rendered.stats.physics.nonfinite_samples > 0);
    assert!(rendered.stats.work.line_pieces > 0);
    let image = &rendered.image;
    assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
    assert!(image.get(20, 26)[0] > 0.0);
}

#[test]
fn lines_give_the_same_bits_on_any_thread_count() {
    let scene = room(", Wall(center: (40, 40), radius: 3.0, material: Mirror())");
    let options = options(32, 2, 9);
    let one = render_on(&scene, &options, 1);
    let three = render_on(&scene, &options, 3);
    assert!(one.image == three.image);
    assert_eq!(one.stats.work.line_pieces, three.stats.work.line_pieces);
    assert!(one.stats.work.lines > 0);
}

/// Where walls stand a few pixels apart, each piece of line would serve a
/// pixel or two: the plan takes each pixel's path samples there, and says
/// why; the room takes lines.
#[test]
fn walls_a_few_pixels_apart_take_path_samples() {
    let walls: Vec<String> = (0..30)
        .map(|k| {
            format!(
                "Wall(a: ({}, 1), b: ({}, 63))",
                2.0 + 2.0 * k as f64,
                2.5 + 2.0 * k as f64
            )
        })
        .collect();
    let dense = scene(&format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: (31, 32))])",
        walls.join(", ")
    ))
    .scene;
    let plan = Plan::new(&dense, &options(16, 1, 0));
    assert!(!plan.floor_lines);
    let said = plan
        .effects()
        .into_iter()
        .find(|e| e.name == "floor's indirect light along lines")
        .map(|e| e.why)
        .unwrap_or_default();
    assert!(said.starts_with("walls so dense"), "{said}");
    assert!(Plan::new(&room(""), &options(16, 1, 0)).floor_lines);
}

/// The room moved `offset` units along both axes, as the scene format
/// writes it (the canvas with it).
fn moved(offset: f64) -> String {
    let p = |x: f64, y: f64| format!("({:?}, {:?})", offset + x, offset + y);
    format!(
        "Scene(canvas: (60, 40), origin: {}, floor: Color((1, 1, 1)),
            walls: [Wall(a: {}, b: {}), Wall(a: {}, b: {}, material: Mirror()),
                    Wall(a: {}, b: {}, material: Diffuse(albedo: (0.8, 0.3, 0.3))),
                    Wall(a: {}, b: {})],
            lights: [Point(at: {}, intensity: 5.0), Line(a: {}, b: {}, intensity: 0.5)])",
        p(0.0, 0.0),
        p(10.0, 8.0),
        p(50.0, 8.0),
        p(50.0, 8.0),
        p(50.0, 35.0),
        p(5.0, 30.0),
        p(25.0, 38.0),
        p(30.0, 14.0),
        p(30.0, 26.0),
        p(30.3, 20.7),
        p(12.0, 15.0),
        p(20.0, 13.0),
    )
}

/// Coordinates a million units out: no light lost or gained. (Which of
/// the wall memo's reads are checked hangs on the bits of the hit's place
/// along its wall, which rounding near 1e6 moves, so the images differ by
/// their noise, and only the whole image's light is compared.)
#[test]
fn lines_a_million_units_away_give_the_same_light() {
    let options = options(64, 2, 5);
    let near = scene(&moved(0.0)).scene;
    let far = scene(&moved(1e6)).scene;
    assert!(Plan::new(&near, &options).floor_lines && Plan::new(&far, &options).floor_lines);
    let (a, b) = (render(&near, &options), render(&far, &options));
    assert!(b.image.pixels.iter().flatten().all(|v| v.is_finite()));
    assert!(b.stats.work.line_pieces > 0);
    let sum = |i: &flatray_tracer::Image| i.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let ratio = sum(&b.image) / sum(&a.image);
    assert!((ratio - 1.0).abs() < 0.01, "{ratio}");
}
