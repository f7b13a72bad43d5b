//! The floor memo's coherence masks (`tracer/src/coherence.rs`) let the
//! strata of a pixel share one shadow ray per light where no wall or shadow
//! edge passes near it. They must change nothing but the ray count: every
//! image here is bit-identical with the reference model's
//! (`RenderOptions::reference`: no masks, and no other fast path).

use flatray_tests::{render, scene, workspace_root};
use flatray_tracer::{Image, RenderOptions, Scene, Stats};

fn image_and_stats(
    scene: &Scene,
    options: &RenderOptions,
    coherence: bool,
) -> (flatray_tracer::Image, Stats) {
    let options = options.with_reference(!coherence);
    let rendered = render(scene, &options);
    (rendered.image, rendered.stats)
}

/// The floor's looks at walls towards a light: its shadow rays, and the
/// squares whose points, spots and suns looked at the walls in front of
/// them (`estimators::square`), where a mask could have told a shared
/// transmittance with one ray.
fn looks(stats: &Stats) -> u64 {
    // The closed form's rays through mirrors, which no mask shares, left
    // out: the same in both renders.
    let mirrored = stats.work.mirrored_shadow_rays;
    stats.work.shadow_rays - mirrored + stats.work.floor_square_lights
}

/// Renders with and without the masks, which must give the same image:
/// that image, and the floor's looks at walls with the masks and without.
fn rays_both_ways(name: &str, scene: &Scene, options: &RenderOptions) -> (Image, u64, u64) {
    let (with, with_stats) = image_and_stats(scene, options, true);
    let (without, without_stats) = image_and_stats(scene, options, false);
    assert!(with == without, "{name}: the masks changed the image");
    (with, looks(&with_stats), looks(&without_stats))
}

/// Renders with and without the masks; returns how many (pixel, light)
/// pairs shared their visibility.
fn assert_same_image(name: &str, scene: &Scene, options: &RenderOptions) -> u64 {
    let (with, with_stats) = image_and_stats(scene, options, true);
    let (without, without_stats) = image_and_stats(scene, options, false);
    assert!(with == without, "{name}: the masks changed the image");
    assert_eq!(without_stats.work.floor_shared_visibility, 0);
    assert!(looks(&with_stats) <= looks(&without_stats), "{name}");
    with_stats.work.floor_shared_visibility
}

#[test]
fn the_example_scenes_render_the_same_with_fewer_shadow_rays() {
    for name in [
        "room",
        "colour-bleed",
        "soft-shadow",
        "lens",
        "prism",
        "first-flat",
    ] {
        let loaded =
            flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron"))).unwrap();
        let options = {
            let mut options = loaded.options;
            options.samples = 16;
            options.scale = 0.25;
            options
        };
        if options.integrator == flatray_tracer::Integrator::Light {
            continue;
        }
        let shared = assert_same_image(name, &loaded.scene, &options);
        // Most of the rooms' floor is far from every shadow edge (the soft
        // shadow's occluders cut the line light off nearly everywhere).
        if name == "room" || name == "colour-bleed" {
            assert!(shared > 0, "{name}: nothing shared");
        }
    }
}

/// Configurations where a mask could be wrong: lights on walls and on wall
/// ends, walls through a light's line and touching its ends, transparent
/// walls (tints multiply), a sun, a spot, a light just off a wall, thin
/// slits, and coordinates far outside the canvas.
const HARD: &[&str] = &[
    // A point light on a wall's end, one on a wall's middle, a line light
    // sharing an end with a wall.
    "Scene(canvas: (60, 40), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (10, 10), b: (50, 10)), Wall(a: (30, 10), b: (30, 35), material: Transparent(tint: (0.5, 0.9, 0.7))),
                Wall(a: (5, 30), b: (20, 20))],
        lights: [Point(at: (10, 10), intensity: 5.0), Point(at: (40, 10), intensity: 5.0),
                 Line(a: (20, 20), b: (25, 30), intensity: 1.0)])",
    // A solid line light (it is also a wall), a sun and a spot.
    "Scene(canvas: (60, 40), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (15, 5), b: (15, 25)), Wall(a: (35, 12), b: (45, 30), material: Mirror())],
        lights: [Line(a: (50, 5), b: (58, 5), intensity: 2.0, solid: true),
                 Directional(direction: (0.3, 1.0), intensity: 1.0),
                 Spot(at: (5, 35), direction: (1, -1), cone: 0.6, softness: 0.2, intensity: 5.0)])",
    // A light a hair off a wall, and a slit narrower than a pixel.
    "Scene(canvas: (60, 40), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (20, 0), b: (20, 19.8)), Wall(a: (20, 20.1), b: (20, 40)), Wall(a: (40, 5), b: (40, 30))],
        lights: [Point(at: (10, 20), intensity: 5.0), Point(at: (40.000000000001, 15), intensity: 5.0),
                 Line(a: (5, 2), b: (5, 38), intensity: 0.5)])",
    // Walls from far outside the canvas, crossing it (not diffuse: the
    // wall memo would bin them at every unit of their length).
    "Scene(canvas: (60, 40), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (-1e9, -1e9), b: (1e9, 1e9), material: Transparent(tint: (0.5, 0.5, 0.5))),
                Wall(a: (-3e7, 30), b: (25, 30), material: Mirror())],
        lights: [Point(at: (45, 10), intensity: 5.0), Line(a: (10, 5), b: (20, 8), intensity: 1.0)])",
];

#[test]
fn hard_configurations_render_the_same() {
    for (k, text) in HARD.iter().enumerate() {
        let loaded = scene(text);
        for scale in [1.0, 0.37] {
            let options = {
                let mut options = loaded.options;
                options.samples = 16;
                options.scale = scale;
                options
            };
            assert_same_image(
                &format!("hard scene {k} at {scale}"),
                &loaded.scene,
                &options,
            );
        }
    }
}

/// A line light behind a pane, with an opaque wall casting a full shadow
/// and a small obstacle casting a soft one: where every wall that cuts the
/// light off stands between the whole pixel and the whole light (the
/// umbra, and the floor seen only through the pane), one ray from the
/// pixel's centre serves every stratum. The image is the same, with most
/// shadow rays saved; the soft shadow still traces its own.
#[test]
fn a_line_light_shares_one_ray_where_walls_cut_it_off_whole() {
    let loaded = scene(
        "Scene(canvas: (60, 40), floor: Color((0.8, 0.8, 0.8)),
            walls: [Wall(a: (20, -5), b: (20, 45)),
                    Wall(a: (35, -5), b: (35, 45), material: Transparent(tint: (0.5, 0.8, 0.9))),
                    Wall(a: (28, 12), b: (30, 24))],
            lights: [Line(a: (50, 10), b: (55, 30), intensity: 1.0)])",
    );
    let options = {
        let mut options = loaded.options;
        options.samples = 16;
        options.scale = 2.0;
        options
    };
    let (with, rays, rays_without) = rays_both_ways("line light", &loaded.scene, &options);
    // Without the shared umbra and pane, the floor left of the pane
    // traces every stratum (two thirds of all rays, with the pixels near
    // the other walls and the light's line); with them, only the pixels
    // near an edge or in the soft shadow do (two fifths).
    assert!(
        rays * 2 < rays_without,
        "{rays} shadow rays with the masks, {rays_without} without"
    );
    // The pane lets light through, tinted; the umbra is dark.
    let behind_pane = with.get(54, 70)[0];
    assert!(behind_pane > 0.0 && with.get(20, 40) == [0.0; 3]);
}

/// Shadow edges stop where they enter an opaque wall's shadow: behind it
/// the floor is dark on both sides of every edge. A lamp in a small room
/// of furniture stubs (their edges fan out across the plan), a sun, a
/// pane, a T-junction, a wall that an edge crosses near its end and one
/// it crosses at a grazing angle, turned by 23 degrees; beyond the room's
/// solid walls lies a large dark room. The image is the reference's, bit
/// for bit, and the dark room shares one ray per pixel: most strata there
/// cast none of their own. Measured under a light table, where each
/// point casts its own rays: without one, a pixel's square looks at its
/// walls once per light, and a mask's shared ray only stands in for that
/// look.
#[test]
fn shadow_edges_stop_inside_an_opaque_walls_shadow() {
    let turn = |x: f64, y: f64| {
        let (s, c) = 23f64.to_radians().sin_cos();
        let (x, y) = (x - 60.0, y - 50.0);
        (60.0 + c * x - s * y, 50.0 + s * x + c * y)
    };
    let wall = |a: (f64, f64), b: (f64, f64), material: &str| {
        let (a, b) = (turn(a.0, a.1), turn(b.0, b.1));
        format!(
            "Wall(a: ({}, {}), b: ({}, {}){material}),",
            a.0, a.1, b.0, b.1
        )
    };
    let mut walls = String::new();
    // The lamp's room, closed but for a pane; a T-junction inside.
    walls += &wall((30.0, 30.0), (60.0, 30.0), "");
    walls += &wall((60.0, 30.0), (60.0, 70.0), "");
    walls += &wall((60.0, 70.0), (30.0, 70.0), "");
    walls += &wall((30.0, 70.0), (30.0, 55.0), "");
    walls += &wall(
        (30.0, 55.0),
        (30.0, 45.0),
        ", material: Transparent(tint: (0.6, 0.7, 0.8))",
    );
    walls += &wall((30.0, 45.0), (30.0, 30.0), "");
    walls += &wall((45.0, 30.0), (45.0, 38.0), "");
    // Furniture stubs, each casting two edges through the solid walls.
    for k in 0..6 {
        let x = 34.0 + 4.0 * k as f64;
        walls += &wall((x, 60.0), (x + 1.5, 62.0), "");
    }
    // Beyond the right wall: a wall the edges cross near its end, one
    // they cross at a grazing angle, and the dark room's far wall.
    walls += &wall((75.0, 20.0), (75.0, 52.0), "");
    walls += &wall((66.0, 80.0), (110.0, 84.0), "");
    walls += &wall((110.0, 5.0), (110.0, 95.0), "");
    let (lx, ly) = turn(40.0, 50.0);
    let text = format!(
        "Scene(canvas: (120, 100), floor: Color((0.8, 0.8, 0.8)),
            walls: [{walls}],
            lights: [Point(at: ({lx}, {ly}), intensity: 20.0),
                     Directional(direction: (0.2, 1.0), intensity: 0.3)],
            render: (samples: 16, bounces: 1))"
    );
    let loaded = scene(&text);
    let options = {
        let mut options = loaded.options;
        options.samples = 16;
        options.light_choice = flatray_tracer::LightChoice::Table;
        options
    };
    let (_, rays, rays_without) = rays_both_ways("umbra", &loaded.scene, &options);
    assert!(
        rays * 10 < rays_without * 3,
        "{rays} shadow rays with the masks, {rays_without} without"
    );
}

/// A wall end that the light cannot see casts no shadow edge, and a wall
/// that one opaque wall hides end to end needs no band of its own: the
/// floor on both sides lies in that wall's shadow. A lamp in a closed
/// room and, beyond its solid wall, a dark room of 30 furniture stubs,
/// all turned by 31 degrees. The dark room shares one ray per pixel but
/// along its own walls, so the render casts fewer than two shadow rays a
/// pixel (about 1.8): the stubs' bands and their edges, fanning out
/// across the dark room, would make it about 5.
#[test]
fn wall_ends_the_light_cannot_see_cast_no_edge() {
    let turn = |x: f64, y: f64| {
        let (s, c) = 31f64.to_radians().sin_cos();
        let (x, y) = (x - 60.0, y - 50.0);
        (60.0 + c * x - s * y, 50.0 + s * x + c * y)
    };
    let wall = |a: (f64, f64), b: (f64, f64)| {
        let (a, b) = (turn(a.0, a.1), turn(b.0, b.1));
        format!("Wall(a: ({}, {}), b: ({}, {})),", a.0, a.1, b.0, b.1)
    };
    let mut walls = String::new();
    // The outer walls, and the wall between the two rooms.
    for (a, b) in [
        ((10.0, 10.0), (110.0, 10.0)),
        ((110.0, 10.0), (110.0, 90.0)),
        ((110.0, 90.0), (10.0, 90.0)),
        ((10.0, 90.0), (10.0, 10.0)),
        ((40.0, 10.0), (40.0, 90.0)),
    ] {
        walls += &wall(a, b);
    }
    // Stubs in the dark room, in a grid of slanted pieces.
    for row in 0..6 {
        for column in 0..5 {
            let (x, y) = (48.0 + 12.0 * column as f64, 16.0 + 12.0 * row as f64);
            walls += &wall((x, y), (x + 3.0, y + 2.0));
        }
    }
    let (lx, ly) = turn(25.0, 50.0);
    let text = format!(
        "Scene(canvas: (120, 100), floor: Color((0.8, 0.8, 0.8)),
            walls: [{walls}],
            lights: [Point(at: ({lx}, {ly}), intensity: 20.0)],
            render: (samples: 16, bounces: 1))"
    );
    let loaded = scene(&text);
    let options = {
        let mut options = loaded.options;
        options.samples = 16;
        options
    };
    let (with, rays, rays_without) = rays_both_ways("dark room", &loaded.scene, &options);
    let pixels = (with.width * with.height) as u64;
    // Beside the floor's, a ray at most per checked read of the wall memo
    // (one light).
    let checks = image_and_stats(&loaded.scene, &options, true)
        .1
        .work
        .memo_checks;
    assert!(checks > 0);
    assert!(
        rays < pixels * 2 + checks,
        "{rays} shadow rays with the masks ({rays_without} without, {checks} memo checks) for {pixels} pixels"
    );
}

/// Generated floor plans at a pixel per unit, where the masks leave out
/// the most: rooms with doors, furniture stubs, mirrors, panes, lamps and
/// a sun. Bit-identical, with most (pixel, light) pairs sharing; the
/// rays measured under a light table, as above.
#[test]
fn generated_plans_render_the_same() {
    for seed in [2, 9] {
        let text = flatray_io::generate::Apartment {
            rooms: 5,
            seed,
            ..Default::default()
        }
        .to_ron();
        let loaded = scene(&text);
        let options = {
            let mut options = loaded.options;
            options.samples = 16;
            options.bounces = 1;
            options.light_choice = flatray_tracer::LightChoice::Table;
            options
        };
        let name = format!("seed {seed}");
        let (_, rays, rays_without) = rays_both_ways(&name, &loaded.scene, &options);
        assert!(
            rays * 3 < rays_without,
            "{name}: {rays} shadow rays with the masks, {rays_without} without"
        );
    }
}
