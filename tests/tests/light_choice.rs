//! Choosing lights by a table (`estimators::choice`): the same expected image
//! as a shadow ray to every light, in a non-convex room of many lights of
//! every kind, with the wall cache on and off; and a cost per point that
//! does not grow with the lights. Statistical checks state their
//! tolerance in standard errors, with fixed seeds.

use flatray_tests::{block_stats, render, scene};
use flatray_tracer::{FastPath, FastPaths, LightChoice};

/// A rotated, non-convex plan of three rooms (doors, a pane, a mirror, a
/// furniture stub) lit by 13 lights of every kind and falloff.
const ROOMS: &str = "Scene(
    canvas: (96, 72), floor: Color((0.8, 0.8, 0.8)),
    walls: [
        Wall(a: (8, 10), b: (70, 4), material: Diffuse(albedo: (0.8, 0.6, 0.5))),
        Wall(a: (70, 4), b: (90, 30)),
        Wall(a: (90, 30), b: (60, 40), material: Mirror()),
        Wall(a: (60, 40), b: (64, 66)),
        Wall(a: (64, 66), b: (12, 62), material: Diffuse(albedo: (0.5, 0.7, 0.8))),
        Wall(a: (12, 62), b: (8, 10)),
        Wall(a: (38, 7), b: (40, 30)),
        Wall(a: (40, 38), b: (41, 63)),
        Wall(a: (10, 36), b: (24, 35), material: Transparent(tint: (0.9, 0.8, 0.7))),
        Wall(a: (30, 35), b: (40, 34)),
        Wall(a: (50, 20), b: (56, 26), material: Diffuse(albedo: (0.3, 0.3, 0.3))),
    ],
    lights: [
        Point(at: (20, 20), intensity: 20),
        Point(at: (28, 50), intensity: 15, color: (1.0, 0.8, 0.6)),
        Point(at: (52, 50), intensity: 12, falloff: InverseSquare),
        Point(at: (60, 14), intensity: 10),
        Point(at: (80, 25), intensity: 8, falloff: Window(range: 60)),
        Point(at: (39, 34), intensity: 6),
        Spot(at: (15, 55), direction: (1, -1), cone: 40, softness: 10, intensity: 25),
        Spot(at: (75, 12), direction: (-1, 1), cone: 25, intensity: 20),
        Line(a: (45, 60), b: (58, 58), intensity: 0.8),
        Line(a: (12, 14), b: (12, 30), one_sided: true, solid: true, intensity: 0.6),
        Circle(at: (50, 33), radius: 2, intensity: 1.5),
        Directional(direction: (1, 0.3), intensity: 0.2),
        Point(at: (200, 200), intensity: 50),
    ],
    render: (samples: 16, bounces: 2),
)";

/// One open, rotated room of 14 lights of about the same brightness: most
/// of the light comes from the lights chosen at random, not from the
/// always-lights.
const OPEN: &str = "Scene(
    canvas: (72, 72), floor: Color((0.8, 0.8, 0.8)),
    walls: [
        Wall(a: (36, 2), b: (70, 36), material: Diffuse(albedo: (0.8, 0.5, 0.4))),
        Wall(a: (70, 36), b: (36, 70)),
        Wall(a: (36, 70), b: (2, 36), material: Mirror()),
        Wall(a: (2, 36), b: (36, 2)),
        Wall(a: (30, 30), b: (42, 38)),
    ],
    lights: [
        Point(at: (36, 12), intensity: 6), Point(at: (46, 22), intensity: 6),
        Point(at: (56, 34), intensity: 6), Point(at: (48, 48), intensity: 6),
        Point(at: (36, 60), intensity: 6), Point(at: (24, 48), intensity: 6),
        Point(at: (14, 36), intensity: 6), Point(at: (24, 22), intensity: 6),
        Point(at: (36, 24), intensity: 5, falloff: InverseSquare),
        Spot(at: (40, 44), direction: (0, 1), cone: 60, intensity: 6),
        Line(a: (30, 16), b: (34, 14), intensity: 0.5),
        Circle(at: (50, 36), radius: 1.5, intensity: 1),
        Point(at: (20, 40), intensity: 6), Point(at: (52, 28), intensity: 6),
    ],
    render: (samples: 16, bounces: 2),
)";

const BLOCK: u32 = 8;
/// Runs per choice; with standard errors from 40 runs a statistic beyond
/// 5 comes about once in 50,000 blocks. Enough runs that a light whose
/// rare choice carries a large weight (a spot's cone that every probe of
/// its cell missed, chosen with the even share alone) shows as a bias of
/// its block: fewer runs would hide it in a heavy tail.
const RUNS: u64 = 40;
const K: f64 = 5.0;

#[test]
fn a_table_of_chosen_lights_has_the_expected_image_of_every_light() {
    for (name, text, cache) in [
        ("rooms", ROOMS, true),
        ("rooms", ROOMS, false),
        ("open", OPEN, true),
    ] {
        let loaded = scene(text);
        let options = |light_choice| {
            let mut options = loaded.options;
            options.light_choice = light_choice;
            options.samples = 8;
            options.memo.enabled = cache;
            options
        };
        let table = block_stats(&loaded.scene, options(LightChoice::Table), BLOCK, RUNS, 1);
        let every = block_stats(&loaded.scene, options(LightChoice::Every), BLOCK, RUNS, 101);
        let mut checked = 0;
        for (b, ((mt, st), (me, se))) in table.iter().zip(&every).enumerate() {
            let sigma = (st * st + se * se).sqrt();
            assert!(
                (mt - me).abs() <= K * sigma + 1e-9 * me.abs(),
                "{name}, cache {cache}, block {b}: table {mt}, every light {me}, {K} SE = {}",
                K * sigma
            );
            // The table is noisier, not silent: its error is measured.
            if *mt > 0.0 {
                checked += 1;
            }
        }
        assert!(
            checked > 40,
            "{name}, cache {cache}: only {checked} lit blocks"
        );
    }
}

/// A row of `rooms` rooms, each with `per_room` point lights.
fn row_of_rooms(rooms: usize, per_room: usize) -> String {
    let width = 40 * rooms;
    let mut walls = format!(
        "Wall(a: (0, 0), b: ({width}, 0)), Wall(a: (0, 40), b: ({width}, 40)), \
         Wall(a: (0, 0), b: (0, 40)), Wall(a: ({width}, 0), b: ({width}, 40)),"
    );
    let mut lights = String::new();
    for r in 0..rooms {
        let x = 40 * r;
        if r > 0 {
            walls += &format!("Wall(a: ({x}, 0), b: ({x}, 16)), Wall(a: ({x}, 24), b: ({x}, 40)),");
        }
        for k in 0..per_room {
            let (lx, ly) = (x + 8 + 24 * (k % 2), 8 + 24 * (k / 2 % 2));
            lights += &format!("Point(at: ({lx}.5, {ly}.5), intensity: 10),");
        }
    }
    format!(
        "Scene(canvas: ({width}, 40), floor: Color((0.7, 0.7, 0.7)), walls: [{walls}], \
         lights: [{lights}], render: (samples: 4, bounces: 1))"
    )
}

#[test]
fn shadow_rays_per_point_do_not_grow_with_the_lights() {
    let per_point = |rooms: usize| {
        let loaded = scene(&row_of_rooms(rooms, 4));
        let rendered = render(&loaded.scene, &{
            let mut options = loaded.options;
            options.light_choice = LightChoice::Table;
            options
        });
        let stats = rendered.stats;
        let points = (rendered.image.width * rendered.image.height) as f64 * 4.0;
        stats.work.shadow_rays as f64 / points
    };
    // 16 and 64 lights: at most the always-lights and one chosen light per
    // floor point, whatever the lights (every light would be 16 and 64).
    let (few, many) = (per_point(4), per_point(16));
    assert!(few <= 5.5 && many <= 5.5, "{few} and {many} per point");
    assert!(many < few * 1.5, "{few} then {many} per point");
}

/// A chosen light that one opaque wall hides from the point's whole cell
/// brings exactly nothing, and costs no shadow ray: the image is the same
/// bit for bit without that fast path. On a generated plan of 12 rooms,
/// turned, with two lamps a room and a sun, most lights chosen at random
/// lie in other rooms, and at least a third of the chosen lights need
/// no ray.
#[test]
fn lights_a_wall_hides_from_the_whole_cell_cost_no_shadow_ray() {
    let text = flatray_io::generate::Apartment {
        rooms: 12,
        lamps_per_room: 2,
        seed: 4,
        ..Default::default()
    }
    .to_ron();
    let loaded = scene(&text);
    let options = {
        let mut options = loaded.options;
        options.samples = 16;
        options.scale = 0.5;
        options.bounces = 1;
        options.light_choice = LightChoice::Table;
        options
    };
    let with = render(&loaded.scene, &options);
    let without = render(
        &loaded.scene,
        &options.with_fast_paths(FastPaths::ALL.without(FastPath::DarkCells)),
    );
    assert!(with.image == without.image, "dark cells changed the image");
    let (w, wo) = (with.stats.work, without.stats.work);
    assert_eq!(w.chosen_lights, wo.chosen_lights);
    assert_eq!(wo.chosen_dark, 0);
    assert!(
        w.chosen_dark * 3 > w.chosen_lights,
        "{} of {} chosen lights dark",
        w.chosen_dark,
        w.chosen_lights
    );
    assert!(
        w.shadow_rays < wo.shadow_rays,
        "{} shadow rays, {} without",
        w.shadow_rays,
        wo.shadow_rays
    );
}
