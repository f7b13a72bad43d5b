//! Points, spots, suns and beams seen in one flat mirror, in closed form
//! (`tracer/src/estimators/mirrored.rs`): the default render, which takes
//! that reflection at every receiver and leaves it out of the caustic
//! pass, agrees with the light tracer, the independent estimator, block
//! by block within 5 standard errors (24 runs each, fixed seeds), in a
//! rotated, non-convex room with a tinted mirror, a pane between the lamp
//! and the mirror, and a sun and a beam through an opening; with the memo
//! and without, with no bounce and with two. And it takes noise out: the
//! same render's noise estimate is lower than with the mirror's light
//! left to photons alone (the mirror turned by a hair into an arc is not
//! a flat mirror, so photons take it).

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, render, scene};
use flatray_tracer::{Plan, RenderOptions};

/// An L-shaped room turned by `angle` about the canvas's centre: a
/// tinted mirror on one wall, a pane across the short arm, an opening
/// that lets a sun and a beam in, and a point and a spot. With `bowed`,
/// the mirror is an arc through a point a hundredth of a unit off its
/// middle.
fn room(angle: f64, bowed: bool) -> String {
    let centre = DVec2::new(40.0, 40.0);
    let (s, c) = angle.sin_cos();
    let p = |x: f64, y: f64| {
        let d = DVec2::new(x, y) - centre;
        let r = centre + DVec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
        format!("({:.6}, {:.6})", r.x, r.y)
    };
    let dir = |x: f64, y: f64| format!("({:.6}, {:.6})", c * x - s * y, s * x + c * y);
    let wall = |a: (f64, f64), b: (f64, f64), material: &str| {
        format!("Wall(a: {}, b: {}{material}),", p(a.0, a.1), p(b.0, b.1))
    };
    let walls = [
        // The L: its outline, with an opening in the top wall.
        wall((12.0, 12.0), (30.0, 12.0), ""),
        wall((38.0, 12.0), (68.0, 12.0), ""),
        wall((68.0, 12.0), (68.0, 40.0), ""),
        wall((68.0, 40.0), (40.0, 40.0), ""),
        wall((40.0, 40.0), (40.0, 68.0), ""),
        wall((40.0, 68.0), (12.0, 68.0), ""),
        wall((12.0, 68.0), (12.0, 12.0), ""),
        // The mirror, inside the long arm, at a slant.
        wall(
            (50.0, 36.0),
            (64.0, 26.0),
            &match bowed {
                // Along the normal (10, 14) of its edge (14, -10).
                true => format!(
                    ", through: {}, material: Mirror(tint: (0.9, 0.8, 0.7))",
                    p(
                        57.0 + 0.01 * 10.0 / 296f64.sqrt(),
                        31.0 + 0.01 * 14.0 / 296f64.sqrt()
                    )
                ),
                false => ", material: Mirror(tint: (0.9, 0.8, 0.7))".to_string(),
            },
        ),
        // A pane across the short arm.
        wall(
            (12.0, 46.0),
            (40.0, 46.0),
            ", material: Transparent(tint: (0.8, 0.9, 1.0))",
        ),
        // A pillar that shades part of the mirror's light.
        wall((44.0, 22.0), (48.0, 26.0), ""),
    ]
    .join("\n");
    format!(
        "Scene(canvas: (80, 80), floor: Color((0.8, 0.8, 0.8)),
            walls: [{walls}],
            lights: [
                Point(at: {point}, intensity: 20.0),
                Spot(at: {spot}, direction: {spot_dir}, cone: 30, softness: 10, intensity: 30.0),
                Directional(direction: {sun}, intensity: 0.6),
                Beam(a: {beam_a}, b: {beam_b}, direction: {beam_dir}, intensity: 0.8),
            ])",
        point = p(24.0, 58.0),
        spot = p(20.0, 24.0),
        spot_dir = dir(1.0, 0.2),
        sun = dir(0.45, 1.0),
        beam_a = p(31.0, 4.0),
        beam_b = p(37.0, 4.0),
        beam_dir = dir(0.5, 1.0),
    )
}

/// Whether block `b` (5 pixels of 4/3 units, 12 to a row) lies wholly
/// inside the room turned by `angle`: the blocks the test holds the two
/// estimators to. (Outside it, the light tracer finds photons of next to
/// no power, 1e-13 of the room's light, that graze the shared corner at
/// (40, 40).)
fn inside(angle: f64, b: usize) -> bool {
    let centre = DVec2::new(40.0, 40.0);
    let (s, c) = (-angle).sin_cos();
    let (bx, by) = ((b % 12) as f64, (b / 12) as f64);
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
    corners.iter().all(|&(dx, dy)| {
        let d = DVec2::new(bx + dx, by + dy) * (5.0 * 4.0 / 3.0) - centre;
        let q = centre + DVec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
        let long = (12.0..=68.0).contains(&q.x) && (12.0..=40.0).contains(&q.y);
        let short = (12.0..=40.0).contains(&q.x) && (12.0..=68.0).contains(&q.y);
        long || short
    })
}

fn options(bounces: u32, memo: bool) -> RenderOptions {
    let mut options = flatray_tests::options(4, bounces, 0);
    options.scale = 0.75;
    options.memo.enabled = memo;
    options
}

#[test]
fn points_spots_suns_and_beams_in_a_mirror_agree_with_the_light_tracer() {
    let agreement = Agreement {
        block: 5,
        runs: 24,
        first_seed: 4100,
        k: 5.0,
        min_blocks: 30,
    };
    for angle in [0.0, 0.55] {
        let loaded = scene(&room(angle, false));
        for (bounces, memo) in [(0, true), (2, true), (2, false)] {
            let options = options(bounces, memo);
            let plan = Plan::new(&loaded.scene, &options);
            assert!(
                plan.closed_forms.aimed_mirrors.runs,
                "{}",
                plan.closed_forms.aimed_mirrors.why
            );
            agreement.check(
                &format!("turned {angle}, {bounces} bounces, memo {memo}"),
                &loaded.scene,
                options,
                |b| inside(angle, b),
            );
        }
    }
}

#[test]
fn the_closed_form_takes_the_noise_of_the_mirrors_light_out() {
    let flat = scene(&room(0.3, false));
    // The same mirror bowed: an arc, which the closed form does not
    // take, so photons bring its light.
    let bowed = scene(&room(0.3, true));
    let options = options(0, true);
    assert!(
        Plan::new(&flat.scene, &options)
            .closed_forms
            .aimed_mirrors
            .runs
    );
    assert!(
        !Plan::new(&bowed.scene, &options)
            .closed_forms
            .aimed_mirrors
            .runs
    );
    let noise = |loaded: &flatray_io::Loaded| {
        let noise = render(&loaded.scene, &options).stats.noise;
        noise.relmse().expect("a noise estimate")
    };
    let (closed, photons) = (noise(&flat), noise(&bowed));
    assert!(
        closed < 0.7 * photons,
        "relMSE noise {closed} with the closed form, {photons} by photons"
    );
}
