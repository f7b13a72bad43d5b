//! The floor's rays are culled by direction (`geometry/src/cull.rs`): per
//! block of 4x4 pixels (of 16x16 below 64 samples) and 1/64 turn, a ray
//! tests only the walls such rays can meet before an opaque wall; the floor memo's shadow rays test only the walls between the
//! block and the light (the floor memo's, or every sample's without the
//! memo); a ray off a mirror, only the walls that rays from its piece of
//! the mirror (4 pixels long) in its 1/64 turn can meet. That must change
//! nothing but the work: every image here is bit-identical with the
//! reference model's (`RenderOptions::reference`: no fast path at all),
//! the physics statistics are the same, and the counts show culling ran.

use flatray_tests::{render, scene, workspace_root};
use flatray_tracer::{Image, RenderOptions, Scene, Stats};

fn image_and_stats(scene: &Scene, options: &RenderOptions, cull: bool) -> (Image, Stats) {
    // The floor's rays are pixels' path samples here, which lines would
    // replace (`tests/tests/lines.rs` holds lines to the reference).
    let mut options = options.with_reference(!cull);
    options.floor_lines = false;
    let rendered = render(scene, &options);
    (rendered.image, rendered.stats)
}

/// Renders with culling and with the reference model; returns the culled
/// render's stats.
fn assert_same_image(name: &str, scene: &Scene, options: &RenderOptions) -> Stats {
    let (with, with_stats) = image_and_stats(scene, options, true);
    let (without, without_stats) = image_and_stats(scene, options, false);
    assert!(with == without, "{name}: culling changed the image");
    assert_eq!(without_stats.work.culled_rays, 0, "{name}");
    // The same paths: only the walls tested differ, and the rays of arcs
    // that meet no wall, which culling does not trace (their paths escape).
    // Rays off mirrors are culled too (a reflection at the bounce limit
    // casts none).
    assert!(
        with_stats.work.culled_mirror_rays <= with_stats.physics.mirror_reflections,
        "{name}"
    );
    assert_eq!(with_stats.physics, without_stats.physics, "{name}");
    assert_eq!(
        with_stats.work.bounce_rays + with_stats.work.culled_empty,
        without_stats.work.bounce_rays,
        "{name}"
    );
    with_stats
}

#[test]
fn the_example_rooms_render_the_same_testing_an_eighth_of_the_walls() {
    for name in ["room", "colour-bleed"] {
        let loaded =
            flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron"))).unwrap();
        // 128 samples: after the first pass (16 samples, alone: it
        // measures the later passes' floor points), the lists of each
        // block of 4x4 pixels, not of its tile (below 64 samples a group).
        let options = {
            let mut options = loaded.options;
            options.samples = 128;
            options.scale = 0.3;
            options
        };
        let stats = assert_same_image(name, &loaded.scene, &options);
        assert_eq!(
            stats.work.culled_rays, stats.physics.camera_samples,
            "{name}"
        );
        // One flat mirror, one bounce: every reflection casts a ray.
        assert_eq!(
            stats.work.culled_mirror_rays,
            stats.physics.mirror_reflections
        );
        // Half the room's floor rays meet no wall (at full size, 61 M of
        // 125 M): they are not traced.
        assert!(
            stats.work.culled_empty * 3 > stats.work.culled_rays,
            "{name}: {stats:?}"
        );
        // 13 walls: a block's lists give 1.18 tested per ray here (1.0 at
        // full size, where the blocks are smaller in world units), the
        // first pass's tile lists about 1.9.
        let walls = loaded.scene.walls().len() as u64;
        assert!(
            stats.work.culled_walls_tested * 8 < stats.work.culled_rays * walls,
            "{name}: {} walls tested for {} rays",
            stats.work.culled_walls_tested,
            stats.work.culled_rays
        );
    }
}

/// Where a list could miss a wall: walls along pixel and block borders, a
/// ray's-width slit, walls through one point, walls ending exactly on
/// block corners, rays grazing a wall, mirrors and transparent walls
/// (their rays continue unculled), lights on walls, odd image sizes (part
/// blocks and tiles), and coordinates far outside the canvas.
const HARD: &[&str] = &[
    // Walls on pixel, block (4) and tile (16) borders, a fan of walls
    // through one point, a slit of a hundredth of a pixel.
    "Scene(canvas: (37, 23), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (4, 0), b: (4, 16)), Wall(a: (0, 8), b: (16, 8)), Wall(a: (16, 4), b: (32, 4)),
                Wall(a: (20, 12), b: (30, 22)), Wall(a: (20, 12), b: (36, 12)), Wall(a: (20, 12), b: (20, 22)),
                Wall(a: (8, 12), b: (8, 17.995)), Wall(a: (8, 18.005), b: (8, 23)),
                Wall(a: (12, 16), b: (16, 20), material: Mirror())],
        lights: [Point(at: (2, 20), intensity: 5.0), Point(at: (30, 2), intensity: 5.0)])",
    // A closed room whose corners sit on block corners, a light on a
    // wall, a transparent pane, a line light, a spot and a sun.
    "Scene(canvas: (41, 41), floor: Tiles(size: 5.0, grout_width: 1.0, tile: (0.8, 0.7, 0.6), grout: (0.2, 0.2, 0.2)),
        walls: [Wall(a: (4, 4), b: (36, 4)), Wall(a: (36, 4), b: (36, 36)), Wall(a: (36, 36), b: (4, 36)),
                Wall(a: (4, 36), b: (4, 4)), Wall(a: (20, 4), b: (20, 24), material: Transparent(tint: (0.9, 0.5, 0.5))),
                Wall(a: (8, 28), b: (28, 28.000001))],
        lights: [Point(at: (12, 4), intensity: 5.0), Line(a: (24, 32), b: (32, 32), intensity: 1.0),
                 Spot(at: (30, 10), direction: (-1, 1), cone: 0.6, softness: 0.2, intensity: 5.0),
                 Directional(direction: (0.3, 1.0), intensity: 1.0)])",
    // Walls from a billion units away crossing the canvas.
    "Scene(canvas: (30, 30), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (-1e9, -1e9), b: (1e9, 1e9), material: Mirror()),
                Wall(a: (-3e7, 20), b: (25, 20), material: Transparent(tint: (0.5, 0.5, 0.5))),
                Wall(a: (15, -1e9), b: (15.5, 1e9), material: Mirror())],
        lights: [Point(at: (25, 5), intensity: 5.0), Point(at: (5, 25), intensity: 5.0)])",
];

#[test]
fn hard_configurations_render_the_same() {
    for (k, text) in HARD.iter().enumerate() {
        let loaded = scene(text);
        // Without the memo, every sample casts the floor's shadow rays.
        for (scale, bounces, memo) in [
            (1.0, 1, true),
            (0.37, 2, true),
            (2.5, 1, true),
            (1.0, 2, false),
        ] {
            let options = {
                let mut options = loaded.options;
                options.samples = 24;
                options.scale = scale;
                options.bounces = bounces;
                options.memo.enabled = memo;
                options
            };
            let stats = assert_same_image(
                &format!("hard scene {k} at {scale}, {bounces} bounces, memo {memo}"),
                &loaded.scene,
                &options,
            );
            assert!(stats.work.culled_rays > 0);
            // Without the memo a path holds the floor's direct light: an
            // escaping ray does not make it zero, so every ray is traced.
            if !memo {
                assert_eq!(stats.work.culled_empty, 0);
            }
        }
    }
}

/// A turned, non-convex floor plan of more walls than brute force takes
/// (a BVH answers the rays that are not culled): a star-shaped outer wall,
/// inner walls with doors, a window pane, a mirror and furniture stubs.
fn turned_plan() -> String {
    let (turn, centre) = (0.37f64, (60.0, 60.0));
    let at = |r: f64, a: f64| {
        let (s, c) = (a + turn).sin_cos();
        (centre.0 + r * c, centre.1 + r * s)
    };
    let mut walls = String::new();
    let mut wall = |p: (f64, f64), q: (f64, f64), material: &str| {
        walls += &format!(
            "Wall(a: ({}, {}), b: ({}, {}){material}),",
            p.0, p.1, q.0, q.1
        );
    };
    let tau = std::f64::consts::TAU;
    // The outer wall: ten corners, in and out; one side a window.
    for k in 0..10 {
        let r = |k: usize| if k.is_multiple_of(2) { 50.0 } else { 38.0 };
        let (p, q) = (
            at(r(k), tau * k as f64 / 10.0),
            at(r(k + 1), tau * (k + 1) as f64 / 10.0),
        );
        let material = if k == 3 {
            ", material: Transparent(tint: (0.8, 0.9, 1.0))"
        } else {
            ""
        };
        wall(p, q, material);
    }
    // Inner walls from the middle, each with a door.
    for k in 0..5 {
        let a = tau * (2 * k + 1) as f64 / 10.0;
        wall(at(3.0, a), at(15.0, a), "");
        wall(
            at(19.0, a),
            at(38.0, a),
            if k == 2 { ", material: Mirror()" } else { "" },
        );
    }
    // A glass partition across one room, wall to wall: rays go on
    // through it to what lies behind.
    wall(
        at(37.0, tau * 0.62),
        at(37.0, tau * 0.78),
        ", material: Transparent(tint: (0.9, 0.9, 0.9))",
    );
    // Furniture: short stubs in every room.
    for k in 0..20 {
        let a = tau * (k as f64 + 0.5) / 20.0;
        wall(at(25.0, a), at(29.0, a + 0.05), "");
    }
    format!(
        "Scene(canvas: (120, 120), floor: Color((0.7, 0.7, 0.7)), walls: [{walls}],
            lights: [Point(at: {:?}, intensity: 20.0), Point(at: {:?}, intensity: 20.0),
                     Directional(direction: (0.4, 1.0), intensity: 0.5)])",
        at(20.0, 0.2),
        at(25.0, 3.0)
    )
}

#[test]
fn floor_plans_of_many_walls_render_the_same_testing_few_of_them() {
    let plan = flatray_io::generate::Apartment {
        rooms: 9,
        mirrors: 1.0,
        seed: 5,
        ..Default::default()
    };
    // So many lights that a tile lists the shadow rays only of those its
    // table's cells take most.
    let lamps = flatray_io::generate::Apartment {
        lamps_per_room: 12,
        ..plan
    };
    for (name, text) in [
        ("apartment", plan.to_ron()),
        ("many lights", lamps.to_ron()),
        ("turned", turned_plan()),
    ] {
        let loaded = scene(&text);
        let walls = loaded.scene.walls().len() as u64;
        assert!(walls > 32, "{name}: {walls} walls: a BVH");
        let tests = walls as usize * loaded.scene.lights().len();
        assert_eq!(
            name == "many lights",
            tests > flatray_tracer::TILE_SHADOW_TESTS,
            "{name}: {tests} wall tests for every light's shadow list"
        );
        // Below 64 samples the tiles' lists, from 64 the blocks'; two
        // bounces, and three without the memo (every sample casts the
        // floor's shadow rays and follows its path wall to wall).
        for (samples, bounces, memo) in [(16, 2, true), (64, 2, true), (16, 3, false)] {
            let options = {
                let mut options = loaded.options;
                options.samples = samples;
                options.scale = if name == "turned" { 1.0 } else { 0.25 };
                options.bounces = bounces;
                options.memo.enabled = memo;
                options
            };
            let name = format!("{name}, {samples} spp, {bounces} bounces, memo {memo}");
            let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
            assert!(plan.floor_ray_culling, "{name}");
            let stats = assert_same_image(&name, &loaded.scene, &options);
            assert!(stats.work.culled_rays > 0, "{name}");
            // Walls hidden behind opaque ones are not listed: a ray tests
            // a small share of the walls.
            assert!(
                stats.work.culled_walls_tested * 4 < stats.work.culled_rays * walls,
                "{name}: {} walls tested for {} rays",
                stats.work.culled_walls_tested,
                stats.work.culled_rays
            );
            assert!(stats.work.culled_mirror_rays > 0, "{name}");
            // With the memo, the onward memo's gathers take the lists of
            // their wall's piece: at least one for every four of its rays.
            if memo {
                let (listed, rays) = (stats.work.onward_listed_rays, stats.work.onward_rays);
                assert!(
                    listed * 4 > rays,
                    "{name}: {listed} gathers listed, {rays} fill rays"
                );
            }
            assert!(stats.work.listed_shadow_rays > 0, "{name}");
        }
    }
}

#[test]
fn plans_of_very_many_walls_are_not_culled() {
    // More walls than culling takes: the BVH answers every ray, and the
    // plan says so.
    let count = flatray_tracer::MAX_CULLED_WALLS + 1;
    let walls: String = (0..count)
        .map(|k| {
            let x = 2.0 + (k % 40) as f64;
            let y = 2.0 + (k / 40) as f64;
            format!("Wall(a: ({x}, {y}), b: ({}, {})),", x + 0.5, y + 0.3)
        })
        .collect();
    let loaded = scene(&format!(
        "Scene(canvas: (50, 20), floor: Color((0.8, 0.8, 0.8)), walls: [{walls}],
            lights: [Point(at: (45, 5), intensity: 1.0)])"
    ));
    let options = {
        let mut options = loaded.options;
        options.samples = 4;
        options
    };
    let stats = assert_same_image("many walls", &loaded.scene, &options);
    assert_eq!(stats.work.culled_rays, 0);
    let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
    assert!(!plan.floor_ray_culling);
    assert!(plan.to_string().contains("the BVH answers every ray"));
}

#[test]
fn samples_that_are_not_finite_are_left_out_as_without_culling() {
    // The memo keeps wall light in f32: a light this strong fills it with
    // infinities, so every path that reads a wall is not finite, while the
    // floor's own light (f64) is. Culled, the samples are summed unchecked
    // and a pixel whose sum is not finite takes them again, checked.
    // The loader and `Scene::new` refuse such values; the renderer still
    // guards against them.
    let mut loaded = scene(
        "Scene(canvas: (12, 12), floor: Color((0.8, 0.8, 0.8)),
            walls: [Wall(a: (2, 2), b: (10, 2)), Wall(a: (10, 2), b: (10, 10))],
            lights: [Point(at: (6, 6))],
            render: (samples: 16))",
    );
    let mut parts = loaded.scene.parts();
    parts.lights[0].intensity = 1e200;
    loaded.scene = parts.build_unchecked();
    loaded.options.exposure = 1e-200;
    let stats = assert_same_image("overflow", &loaded.scene, &loaded.options);
    assert!(stats.work.culled_rays > 0);
    // Many samples meet a wall: all dropped and counted, the first of them
    // the same (compared above).
    assert!(
        stats.physics.nonfinite_samples > stats.physics.camera_samples / 10,
        "{stats:?}"
    );
    let (image, _) = image_and_stats(&loaded.scene, &loaded.options, true);
    assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
    assert!(image.get(6, 8)[0] > 0.0);
}
