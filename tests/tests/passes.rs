//! A render taken pass by pass (`flatray_tracer::Progressive`) gives, after
//! any pass, the image, path counts and noise estimate of a single render
//! of the samples reached, to the bit; and it refuses a pass that a single
//! render would not take. On scenes that use every per-pass fill: the caustic pass
//! (mirrors), the onward memo (three bounces), the light table (many
//! lights), and the light tracer.

use flatray_tests::{render, render_on, workspace_root};
use flatray_tracer::{Integrator, Progressive, RenderOptions, next_pass_end};

fn load(name: &str) -> flatray_io::Loaded {
    flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron")))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Drives `options` pass by pass to `samples` (the last pass short of the
/// schedule where `samples` is not on it), checking the image after every
/// pass against a single render of that many samples.
fn check_passes(name: &str, options: RenderOptions, samples: u32) {
    let loaded = load(name);
    let mut progressive = Progressive::new(&loaded.scene, &options);
    while progressive.samples() < samples {
        let end = progressive
            .next_end()
            .unwrap_or_else(|| panic!("{name}: no pass may follow"))
            .min(samples);
        assert!(progressive.pass(end, &|_| {}), "{name}: pass to {end}");
        let passes = progressive.rendered();
        let single = render(&loaded.scene, &{
            let mut options = options;
            options.samples = end;
            options
        });
        assert!(
            passes.image == single.image,
            "{name}: the image after the pass to {end} spp is not the single render's"
        );
        // The work differs (a single render shares a pixel's culling and
        // shadow rays between its passes); what the paths did does not.
        assert_eq!(
            passes.stats.physics, single.stats.physics,
            "{name}: {end} spp"
        );
        assert_eq!(passes.stats.noise, single.stats.noise, "{name}: {end} spp");
    }
}

#[test]
fn passes_give_the_single_render_at_every_step() {
    // Mirrors and a pane: the caustic pass, two bounces.
    let first_flat = load("first-flat").options;
    check_passes(
        "first-flat",
        {
            let mut options = first_flat;
            options.scale = 0.2;
            options
        },
        100,
    );
    // Three bounces, 17 lights: the onward memo and the light table.
    let apartment = load("apartment").options;
    check_passes(
        "apartment",
        {
            let mut options = apartment;
            options.scale = 0.12;
            options.bounces = 3;
            options
        },
        40,
    );
    // The light tracer's photons, pass by pass.
    let room = load("room").options;
    check_passes(
        "room",
        {
            let mut options = room;
            options.scale = 0.1;
            options.integrator = Integrator::Light;
            options
        },
        35,
    );
}

/// A pass that ends short of the schedule is the last one; a pass must
/// add samples and may not go past the schedule.
#[test]
fn a_short_pass_is_the_last() {
    let loaded = load("room");
    let options = {
        let mut options = loaded.options;
        options.scale = 0.05;
        options
    };
    let mut progressive = Progressive::new(&loaded.scene, &options);
    assert_eq!(progressive.next_end(), Some(16));
    assert!(!progressive.pass(17, &|_| {}), "past the first pass's end");
    assert!(!progressive.pass(0, &|_| {}), "no samples");
    assert!(progressive.pass(16, &|_| {}));
    assert_eq!(progressive.next_end(), Some(next_pass_end(16)));
    assert!(progressive.pass(20, &|_| {}));
    assert_eq!(progressive.samples(), 20);
    assert_eq!(progressive.next_end(), None);
    assert!(!progressive.pass(32, &|_| {}));
    assert_eq!(progressive.samples(), 20);
}

/// The passes' sums do not depend on the threads: one thread and two give
/// the same image at a sample count of several passes.
#[test]
fn passes_do_not_depend_on_the_threads() {
    let loaded = load("bathroom");
    let options = {
        let mut options = loaded.options;
        options.samples = 70;
        options.scale = 0.2;
        options
    };
    let one = render_on(&loaded.scene, &options, 1);
    let two = render_on(&loaded.scene, &options, 2);
    assert!(one.image == two.image);
    assert_eq!(one.stats, two.stats);
}

/// A window of a render takes the whole render's floor points: the first
/// pass measures their rate at the same probe pixels, in every tile, also
/// those outside the window, so the window's pixels have the whole
/// render's bits. With the probes of the window's tiles only, the rate
/// would differ and so would the bits.
#[test]
fn a_window_takes_the_whole_renders_points() {
    for name in ["room", "first-flat"] {
        let loaded = load(name);
        let options = {
            let mut options = loaded.options;
            options.samples = 96;
            options.scale = 0.25;
            options
        };
        let whole = render(&loaded.scene, &options);
        let window = flatray_tracer::Window {
            x0: 37,
            y0: 21,
            x1: 70,
            y1: 50,
        };
        let part = render(&loaded.scene, &{
            let mut options = options;
            options.window = Some(window);
            options
        });
        for y in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                assert_eq!(
                    part.image.get(x, y),
                    whole.image.get(x, y),
                    "{name} ({x}, {y})"
                );
            }
        }
        // The probes a window measures outside itself are not its work:
        // two windows that split the image on a tile border count the
        // whole's samples.
        let (width, height) = (whole.image.width, whole.image.height);
        let halves: u64 = [(0, 32), (32, height)]
            .into_iter()
            .map(|(y0, y1)| {
                let mut options = options;
                options.window = Some(flatray_tracer::Window {
                    x0: 0,
                    y0,
                    x1: width,
                    y1,
                });
                render(&loaded.scene, &options).stats.physics.camera_samples
            })
            .sum();
        assert_eq!(halves, whole.stats.physics.camera_samples, "{name}");
    }
}

/// The later passes' floor points follow the first pass's measure: the
/// room, whose noise is its bounce when path samples take it, takes under
/// an eighth of a point per sample (a quarter would be 64 a pixel), and
/// more where lines take the bounce with less noise; nine lamps under a light table,
/// where each point draws one light beside the brightest, with little
/// other noise (one dark wall), take over a quarter (one a sample, 256 a
/// pixel).
#[test]
fn floor_points_go_where_the_noise_is() {
    let points = |text: &str, samples: u32, scale: f64, lines: bool| {
        let loaded = flatray_io::parse(
            text,
            std::path::Path::new("test.ron"),
            std::path::Path::new("."),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let options = {
            let mut options = loaded.options;
            options.samples = samples;
            options.scale = scale;
            options.floor_lines = lines;
            options
        };
        let rendered = render(&loaded.scene, &options);
        let pixels = rendered.image.width as f64 * rendered.image.height as f64;
        rendered.stats.work.floor_points as f64 / pixels
    };
    let room = std::fs::read_to_string(workspace_root().join("scenes/room.ron")).unwrap();
    // With its bounce taken by path samples, 8 in the first pass, then a
    // few a pass; along lines, whose noise is far lower, more.
    let room_points = points(&room, 256, 0.5, false);
    assert!(
        room_points < 256.0 / 8.0,
        "room: {room_points} points a pixel"
    );
    let room_lines = points(&room, 256, 0.5, true);
    assert!(
        room_lines > 1.5 * room_points,
        "room along lines: {room_lines} points a pixel, against {room_points}"
    );
    let lamps = "Scene(canvas: (64, 64), floor: Color((1, 1, 1)),
        walls: [Wall(a: (30, -1000), b: (30, 40.9), material: Diffuse(albedo: Some((0.05, 0.05, 0.05)))),
                Wall(a: (20, 20), b: (25, 28))],
        lights: [Point(at: (10.3, 30.2)), Point(at: (12.3, 10.2)), Point(at: (14.3, 50.2)),
                 Point(at: (40.3, 30.2)), Point(at: (50.3, 10.2)), Point(at: (55.3, 55.2)),
                 Point(at: (8.3, 5.2)), Point(at: (45.3, 44.2)), Point(at: (20.3, 60.2))],
        render: (bounces: 1))";
    let lamp_points = points(lamps, 256, 1.0, true);
    assert!(lamp_points > 256.0 / 4.0, "nine lamps: {lamp_points}");
}
