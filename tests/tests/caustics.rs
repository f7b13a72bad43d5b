//! The default render sees points, spots and suns in mirrors and glass
//! (the caustic pass, `tracer/src/caustics.rs`, or where every mirror is
//! flat and on one line, the closed form of `estimators/mirrored.rs`):
//! on every scene here it agrees with the light tracer, the independent
//! estimator, block by block within 5 standard errors (from 24 runs
//! each, fixed seeds: a t distribution with 23 degrees of freedom is
//! beyond 5 once in 25,000 blocks). And a scene without mirrors, glass
//! or such lights pays nothing: no photon is traced; nor does one whose
//! mirrors' light the closed form takes whole.

use flatray_tests::{Agreement, block_stats, render, scene, workspace_root};
use flatray_tracer::{Integrator, MemoOptions, RenderOptions, Scene};

const BLOCK: u32 = 6;
const RUNS: u64 = 24;
const K: f64 = 5.0;

/// Default and light tracing agree on every block; the default's total
/// differs from what it would be without the caustic pass by more than
/// `min_share` of the light (the check is not vacuous).
fn assert_agree(name: &str, scene: &Scene, options: RenderOptions, min_share: f64) {
    let at = |integrator| {
        let mut options = options;
        options.integrator = integrator;
        options
    };
    let agreement = Agreement {
        block: BLOCK,
        runs: RUNS,
        first_seed: 2000,
        k: K,
        min_blocks: 20,
    };
    let path = agreement.check(name, scene, options, |_| true);
    if min_share < 0.0 {
        // Agreement only.
        return;
    }
    // What the caustic pass adds: the difference from the same scene with
    // its specular walls black.
    let total = |blocks: &[(f64, f64)]| blocks.iter().map(|b| b.0).sum::<f64>();
    let rendered = render(scene, &at(Integrator::Path));
    // The estimator the plan chose for this light traced some of it.
    if flatray_tracer::Plan::new(scene, &at(Integrator::Path)).aimed_runs_closed {
        assert!(rendered.stats.work.mirrored_shadow_rays > 0, "{name}");
    } else {
        assert!(rendered.stats.physics.caustic_photons > 0, "{name}");
    }
    let mut dark = scene.parts();
    for wall in &mut dark.walls {
        if let flatray_tracer::Material::Mirror { tint } = &mut wall.material {
            *tint = flatray_tracer::Rgb::ZERO;
        }
    }
    let dark = dark.build().expect("a valid scene");
    let without = block_stats(&dark, at(Integrator::Path), BLOCK, 4, 2000);
    if scene.glass().is_empty() {
        assert!(
            total(&path) > (1.0 + min_share) * total(&without),
            "{name}: the mirrors add {} of {}",
            total(&path) - total(&without),
            total(&path)
        );
    }
}

fn options(samples: u32, bounces: u32, scale: f64, memo: bool) -> RenderOptions {
    {
        let mut options = RenderOptions::default();
        options.samples = samples;
        options.bounces = bounces;
        options.scale = scale;
        options.memo = MemoOptions::default();
        options.memo.enabled = memo;
        options
    }
}

#[test]
fn a_lamp_in_front_of_a_mirror() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/bathroom.ron")).unwrap();
    for memo in [true, false] {
        assert_agree(
            &format!("bathroom, memo {memo}"),
            &loaded.scene,
            options(8, 2, 0.2, memo),
            0.05,
        );
    }
}

/// A lamp hidden from a corridor by a wall: its light reaches the
/// corridor's far wall only off a tilted mirror, and the floor only from
/// that wall (lamp, mirror, diffuse wall, floor: three bounces).
#[test]
fn lamp_mirror_diffuse_wall_floor() {
    let loaded = scene(
        "Scene(canvas: (60, 48), floor: Color((0.8, 0.8, 0.8)),
            walls: [Wall(a: (2, 2), b: (58, 2)), Wall(a: (58, 2), b: (58, 46)),
                    Wall(a: (58, 46), b: (2, 46)), Wall(a: (2, 46), b: (2, 2)),
                    Wall(a: (30, 2), b: (30, 34), material: Diffuse(albedo: Some((0.7, 0.7, 0.7)))),
                    Wall(a: (6, 40), b: (20, 45.5), material: Mirror()),
                    Wall(a: (40, 10), b: (54, 10), material: Diffuse(albedo: Some((0.9, 0.5, 0.3))))],
            lights: [Point(at: (12, 12), intensity: 30.0)])",
    );
    for (bounces, memo) in [(3, true), (2, false)] {
        assert_agree(
            &format!("corridor, {bounces} bounces, memo {memo}"),
            &loaded.scene,
            options(8, bounces, 1.0, memo),
            0.05,
        );
    }
}

/// Sunlight through a window (a clear pane) onto a mirror that throws it
/// across a rotated room; and a spot aimed at the mirror. With the wall
/// memo and without: the memo's bins smooth the sharp edges that the sun
/// and the spot cast on walls, and its checked reads take that bias out.
#[test]
fn sunlight_and_a_spot_through_a_window_onto_a_mirror() {
    let loaded = scene(
        "Scene(canvas: (64, 64), floor: Color((0.8, 0.8, 0.8)),
            walls: [Wall(a: (32, 2), b: (62, 32)), Wall(a: (62, 32), b: (32, 62)),
                    Wall(a: (32, 62), b: (2, 32)), Wall(a: (2, 32), b: (12, 22)),
                    Wall(a: (12, 22), b: (22, 12), material: Transparent(tint: (0.9, 0.95, 1.0))),
                    Wall(a: (22, 12), b: (32, 2)),
                    Wall(a: (40, 46), b: (50, 36), material: Mirror(tint: (0.9, 0.9, 0.9))),
                    Wall(a: (30, 30), b: (36, 36), material: Diffuse(albedo: Some((0.3, 0.6, 0.3))))],
            lights: [Directional(direction: (1.0, 0.7), intensity: 0.8),
                     Spot(at: (20, 40), direction: (1, 0), cone: 40, softness: 10, intensity: 20.0)])",
    );
    for memo in [true, false] {
        assert_agree(
            &format!("sun and spot, memo {memo}"),
            &loaded.scene,
            options(8, 3, 1.0, memo),
            0.05,
        );
    }
}

/// A lamp behind a glass lens: its focus on the far side.
#[test]
fn a_lamp_behind_a_lens() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/lens.ron")).unwrap();
    assert_agree("lens", &loaded.scene, options(8, 4, 0.15, true), 0.0);
}

#[test]
fn scenes_without_mirrors_glass_or_lamps_trace_no_photon() {
    for (name, text) in [
        (
            "no mirror",
            "Scene(canvas: (20, 20), floor: Color((0.8, 0.8, 0.8)),
                walls: [Wall(a: (2, 2), b: (18, 2)), Wall(a: (18, 2), b: (18, 18), material: Transparent())],
                lights: [Point(at: (10, 10))])",
        ),
        (
            "only line lights",
            "Scene(canvas: (20, 20), floor: Color((0.8, 0.8, 0.8)),
                walls: [Wall(a: (2, 2), b: (18, 2), material: Mirror())],
                lights: [Line(a: (5, 10), b: (15, 12)), Circle(at: (10, 15), radius: 2)])",
        ),
    ] {
        let loaded = scene(text);
        let options = {
 let mut options = loaded.options;
 options.bounces = 3;
 options
};
        let rendered = render(&loaded.scene, &options);
        assert_eq!(rendered.stats.physics.caustic_photons, 0, "{name}");
        assert!(!flatray_tracer::Plan::new(&loaded.scene, &options).caustics);
    }
}

/// Where every mirror is flat and all lie on one line, the closed form of
/// points, spots, suns and beams in a mirror takes all their light off
/// mirrors, and no photon is traced; a second mirror off that line, a
/// rough mirror, glass or a laser each bring the pass back. Rooms turned
/// and far from the origin as well.
#[test]
fn mirrors_on_one_line_leave_photons_nothing_to_carry() {
    let room = |turn: f64, offset: f64, extra: &str, lights: &str| {
        let (sin, cos) = turn.sin_cos();
        let at = |x: f64, y: f64| {
            let (x, y) = (x - 30.0, y - 30.0);
            let o = offset + 40.0;
            format!("({}, {})", o + x * cos - y * sin, o + x * sin + y * cos)
        };
        let walls = [
            (2.0, 2.0, 58.0, 2.0, ""),
            (58.0, 2.0, 58.0, 58.0, ""),
            (58.0, 58.0, 2.0, 58.0, ""),
            (2.0, 58.0, 2.0, 2.0, ""),
            (10.0, 4.0, 25.0, 4.0, ", material: Mirror()"),
            (
                30.0,
                4.0,
                50.0,
                4.0,
                ", material: Mirror(tint: (0.9, 0.8, 0.7))",
            ),
        ];
        let walls: Vec<String> = walls
            .iter()
            .map(|&(ax, ay, bx, by, m)| format!("Wall(a: {}, b: {}{m})", at(ax, ay), at(bx, by)))
            .collect();
        let extra = extra
            .split(';')
            .filter(|w| !w.is_empty())
            .map(|w| {
                let v: Vec<&str> = w.split(',').collect();
                let n = |i: usize| v[i].trim().parse::<f64>().unwrap();
                format!(
                    "Wall(a: {}, b: {}, material: {})",
                    at(n(0), n(1)),
                    at(n(2), n(3)),
                    v[4..].join(",")
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        let lights = lights.replace("AT", &at(30.0, 40.0));
        format!(
            "Scene(canvas: (80, 80), origin: ({offset}, {offset}), floor: Color((0.8, 0.8, 0.8)),
                walls: [{}, {extra}], lights: [{lights}])",
            walls.join(", "),
        )
    };
    let point = "Point(at: AT, intensity: 20.0)";
    let laser = "Point(at: AT, intensity: 20.0), Laser(at: AT, direction: (1, 1), intensity: 1.0)";
    let cases = [
        // What the scene holds, whether photons are traced, and whether
        // the closed form takes every path off the flat mirrors.
        ("two mirrors on one line", "", point, false, true),
        (
            "a third mirror facing them",
            "20, 30, 40, 50, Mirror()",
            point,
            true,
            false,
        ),
        (
            "a rough mirror",
            "20, 30, 40, 50, Rough(roughness: 0.3)",
            point,
            true,
            true,
        ),
        ("a laser", "", laser, true, true),
    ];
    for turn in [0.0, 0.55] {
        for offset in [0.0, 1e7] {
            for (name, extra, lights, photons, closed) in cases {
                let text = room(turn, offset, extra, lights);
                let loaded = scene(&text);
                let mut options = loaded.options;
                options.bounces = 1;
                options.samples = 2;
                options.scale = 0.5;
                let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
                let rendered = render(&loaded.scene, &options);
                let traced = rendered.stats.physics.caustic_photons;
                let what = format!("{name}, turned {turn}, at {offset}: {traced} photons");
                assert_eq!(plan.caustics, photons, "{what}");
                assert_eq!(traced > 0, photons, "{what}");
                assert_eq!(plan.aimed_runs_closed, closed, "{what}");
                assert!(rendered.stats.work.mirrored_shadow_rays > 0, "{what}");
            }
        }
    }
}

/// The caustic pass takes its full rate of photons where the mirrors take
/// a quarter of the lights' power or more, and less in proportion to the
/// square of their share below that, down to a sixteenth: a point light
/// facing one mirror that subtends a known angle, nothing in between. (A
/// second mirror, which a wall hides from the light, keeps the pass on:
/// alone, the mirror's light is taken in closed form.)
#[test]
fn the_photon_rate_follows_the_mirrors_share_of_the_light() {
    use flatray_tracer::{FULL_RATE_SHARE, LEAST_RATE, PHOTONS_PER_SAMPLE};
    // Half the mirror's length, and its distance from the light.
    for (half, distance) in [(40.0_f64, 10.0), (20.0, 60.0), (8.0, 60.0), (1.0, 70.0)] {
        let text = format!(
            "Scene(canvas: (100, 100), floor: Color((0.8, 0.8, 0.8)),
                walls: [Wall(a: ({x}, {y0}), b: ({x}, {y1}), material: Mirror()),
                        Wall(a: (5, 95), b: (8, 98), material: Mirror()),
                        Wall(a: (0, 90), b: (15, 90))],
                lights: [Point(at: (20, 50), intensity: 5.0)])",
            x = 20.0 + distance,
            y0 = 50.0 - half,
            y1 = 50.0 + half,
        );
        let loaded = scene(&text);
        let options = {
            let mut options = RenderOptions::default();
            options.samples = 16;
            options.bounces = 1;
            options
        };
        let rendered = render(&loaded.scene, &options);
        let share = 2.0 * (half / distance).atan() / std::f64::consts::TAU;
        let factor = ((share / FULL_RATE_SHARE).powi(2)).clamp(LEAST_RATE, 1.0);
        let expected = 16.0 * 100.0 * 100.0 * PHOTONS_PER_SAMPLE * factor;
        let photons = rendered.stats.physics.caustic_photons as f64;
        assert!(
            (photons - expected).abs() <= 1.0,
            "mirror {half} x 2 at {distance}: {photons} photons, expected {expected}"
        );
    }
}

/// A generated apartment (`flatray generate`): rooms with doors, windows
/// letting the sun in, furniture, mirrors and lamps, three bounces.
#[test]
fn a_generated_apartment() {
    let plan = flatray_io::generate::Apartment {
        rooms: 4,
        mirrors: 1.0,
        seed: 3,
        ..Default::default()
    };
    let loaded = scene(&plan.to_ron());
    assert!(loaded.scene.walls().len() > 20 && loaded.scene.lights().len() == 5);
    assert_agree("apartment", &loaded.scene, options(4, 3, 0.2, false), 0.005);
}

/// Every example scene: the default render against the light tracer,
/// but the prism, which renders by light tracing (its file says so): path
/// tracing finds its beam, a line light seen through two slits 3 units
/// wide and then the glass, so rarely that its block means are heavy
/// tailed, and 24 runs do not estimate their spread.
#[test]
fn every_example_scene_agrees_with_the_light_tracer() {
    let mut paths: Vec<_> = std::fs::read_dir(workspace_root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 10);
    for path in paths {
        let loaded = flatray_io::load(&path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        if name == "prism" {
            continue;
        }
        // About 60 pixels across.
        let scale = 60.0 / loaded.scene.canvas().width as f64;
        let options = {
            let mut options = loaded.options;
            // The optical bench's lasers fan out of its prism, one
            // wavelength a photon: at 4 samples a block past the prism
            // gets its light from a handful of caustic photons in most
            // runs, too few for 24 runs to measure their spread.
            options.samples = if name == "optics" { 16 } else { 4 };
            options.scale = scale;
            options
        };
        assert_agree(&name, &loaded.scene, options, -1.0);
    }
}
