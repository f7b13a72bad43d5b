//! The onward memo (`tracer/src/onward.rs`): paths that end at their
//! first diffuse wall and read the rest of their light there give the same
//! expected image as paths followed from wall to wall, in a rotated,
//! non-convex plan with mirrors, a pane, coloured walls, walls that take
//! the floor's colour, and lights of every kind; it runs where the plan
//! says, and it saves the rays it should. Statistical checks state their
//! tolerance in standard errors, with fixed seeds.

use flatray_tests::{block_stats, render, scene};
use flatray_tracer::{Integrator, Plan, RenderOptions};

/// A rotated, non-convex plan of three rooms: doors, a pane, two mirrors
/// (one facing a lamp, for the caustic pass, and one facing a line
/// light, seen only by path rays), a furniture stub, walls of their own
/// colour and walls of the floor's.
const ROOMS: &str = "Scene(
    canvas: (96, 72),
    floor: Tiles(size: 9, grout_width: 2, tile: (0.9, 0.85, 0.7), grout: (0.3, 0.4, 0.6), variation: 0.1),
    walls: [
        Wall(a: (8, 10), b: (70, 4), material: Diffuse(albedo: (0.8, 0.6, 0.5))),
        Wall(a: (70, 4), b: (90, 30)),
        Wall(a: (90, 30), b: (60, 40), material: Mirror()),
        Wall(a: (60, 40), b: (64, 66)),
        Wall(a: (64, 66), b: (12, 62), material: Diffuse(albedo: (0.5, 0.7, 0.8))),
        Wall(a: (12, 62), b: (8, 10)),
        Wall(a: (38, 7), b: (40, 30)),
        Wall(a: (40, 38), b: (41, 63), material: Diffuse(albedo: (0.9, 0.9, 0.9))),
        Wall(a: (10, 36), b: (24, 35), material: Transparent(tint: (0.9, 0.8, 0.7))),
        Wall(a: (30, 35), b: (40, 34)),
        Wall(a: (50, 20), b: (56, 26), material: Diffuse(albedo: (0.3, 0.3, 0.3))),
        Wall(a: (14, 58), b: (30, 59), material: Mirror(tint: (0.9, 0.95, 1.0))),
    ],
    lights: [
        Point(at: (20, 20), intensity: 20),
        Point(at: (78, 24), intensity: 12, color: (1.0, 0.8, 0.6)),
        Spot(at: (52, 52), direction: (1, -1), cone: 40, softness: 10, intensity: 25),
        Line(a: (20, 44), b: (30, 43), intensity: 0.8),
        Directional(direction: (1, 0.3), intensity: 0.2),
    ],
    render: (samples: 16, bounces: 3),
)";

fn options(onward: bool, bounces: u32) -> RenderOptions {
    let loaded = scene(ROOMS);
    {
        let mut options = loaded.options;
        options.bounces = bounces;
        options.memo.onward = onward;
        options
    }
}

/// Block by block, over 24 seeds, the onward memo against the same render
/// with paths followed from wall to wall (the wall memo on in both, so
/// that only the onward memo differs), for 2 and 3 bounces: within 5
/// standard errors. Each seed draws its own gathers, so runs are
/// independent and the spread over runs includes the memo's own error.
#[test]
fn ending_paths_at_the_first_diffuse_wall_keeps_the_expected_image() {
    let loaded = scene(ROOMS);
    for bounces in [2, 3] {
        let on = block_stats(&loaded.scene, options(true, bounces), 12, 24, 100);
        let off = block_stats(&loaded.scene, options(false, bounces), 12, 24, 100);
        let mut checked = 0;
        let (mut sum_on, mut sum_off) = (0.0, 0.0);
        for (b, ((m1, s1), (m2, s2))) in on.iter().zip(&off).enumerate() {
            sum_on += m1;
            sum_off += m2;
            if *m2 <= 0.0 {
                continue;
            }
            let se = (s1 * s1 + s2 * s2).sqrt();
            assert!(
                (m1 - m2).abs() <= 5.0 * se + 1e-9 * m2.abs(),
                "D = {bounces}, block {b}: onward {m1}, followed {m2}, 5 SE = {}",
                5.0 * se
            );
            checked += 1;
        }
        assert!(checked >= 40, "D = {bounces}: {checked} blocks checked");
        // And overall, where the blocks' errors add up: within 2 %.
        assert!(
            (sum_on / sum_off - 1.0).abs() < 0.02,
            "D = {bounces}: total {sum_on} against {sum_off}"
        );
    }
}

/// Paths end at their first diffuse wall: about one closest-hit ray per
/// sample (more only through panes and off mirrors) instead of up to one
/// per bounce, and the rays that fill the memo are counted apart.
#[test]
fn paths_cast_one_ray_to_the_first_diffuse_wall() {
    let loaded = scene(ROOMS);
    // Each pixel's own path samples, which lines would replace.
    let samples = |onward: bool| {
        let mut options = options(onward, 3);
        options.floor_lines = false;
        options
    };
    let on = render(&loaded.scene, &samples(true)).stats;
    let off = render(&loaded.scene, &samples(false)).stats;
    let per_sample =
        |s: &flatray_tracer::Stats| s.work.bounce_rays as f64 / s.physics.camera_samples as f64;
    assert!(on.physics.paths_onward > 0);
    assert_eq!(off.physics.paths_onward, 0);
    assert!(on.work.onward_rays > 0 && off.work.onward_rays == 0);
    assert!(
        per_sample(&on) < 1.3 && per_sample(&off) > 2.0,
        "bounce rays per sample: onward {}, followed {}",
        per_sample(&on),
        per_sample(&off)
    );
}

/// The plan runs the memo where paths take more than one reflection, and
/// says why not elsewhere.
#[test]
fn the_plan_runs_the_onward_memo_only_where_it_applies() {
    let loaded = scene(ROOMS);
    let runs = |options: RenderOptions| {
        let plan = Plan::new(&loaded.scene, &options);
        let effect = plan
            .effects()
            .into_iter()
            .find(|e| e.name == "cache: light between walls")
            .expect("the plan lists the onward memo");
        assert_eq!(effect.runs, plan.onward);
        (plan.onward, effect.why)
    };
    assert!(runs(options(true, 2)).0);
    assert!(runs(options(true, 3)).0);
    let (one, why) = runs(options(true, 1));
    assert!(!one && why.contains("one bounce"), "{why}");
    let (off, why) = runs(options(false, 3));
    assert!(!off && why.contains("--cache direct"), "{why}");
    let (no_cache, why) = runs({
        let mut options = options(true, 3);
        options.memo.enabled = false;
        options
    });
    assert!(!no_cache && why.contains("--cache off"), "{why}");
    let (original, why) = runs({
        let mut options = options(true, 3);
        options.integrator = Integrator::Original;
        options
    });
    assert!(!original && why.contains("original"), "{why}");
    let (light, _) = runs({
        let mut options = options(true, 3);
        options.integrator = Integrator::Light;
        options
    });
    assert!(!light);
    // Glass: a wall's bins cannot tell whether a path is inside a body.
    let glassy = scene(
        "Scene(canvas: (40, 40), floor: Color((0.8, 0.8, 0.8)),
            walls: [Wall(a: (2, 2), b: (38, 2)), Wall(a: (38, 2), b: (38, 38))],
            glass: [Glass(points: [(10, 10), (20, 10), (15, 18)], ior: 1.5)],
            lights: [Point(at: (30, 30), intensity: 10)],
            render: (bounces: 3))",
    );
    let plan = Plan::new(&glassy.scene, &glassy.options);
    assert!(!plan.onward);
}
