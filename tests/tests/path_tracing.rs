//! Closed forms 3 to 6 of `model.md` with indirect light on, and the
//! estimator's unbiasedness. Each statistical check states its tolerance
//! in standard errors, estimated from the spread of independent pixels or
//! runs, with fixed seeds so every run is the same.

use std::f64::consts::{PI, TAU};

use flatray_geometry::DVec2;
use flatray_tests::{render, scene};
use flatray_tracer::{Image, Integrator, MemoOptions, RenderOptions};

/// Mean and standard error of the mean of channel 0 over selected pixels.
fn mean_se(image: &Image, keep: impl Fn(DVec2) -> bool) -> (f64, f64, usize) {
    let mut values = Vec::new();
    for y in 0..image.height {
        for x in 0..image.width {
            if keep(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                values.push(image.get(x, y)[0] as f64);
            }
        }
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt(), values.len())
}

fn polygon_walls(points: &[DVec2], extra: &str) -> String {
    (0..points.len())
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % points.len()]);
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){extra})",
                a.x, a.y, b.x, b.y
            )
        })
        .collect::<Vec<_>>()
        .join(",\n")
}

/// Whether `p` is inside the polygon (even-odd rule) and at least `margin`
/// from every edge.
fn well_inside(points: &[DVec2], p: DVec2, margin: f64) -> bool {
    let mut inside = false;
    for i in 0..points.len() {
        let (a, b) = (points[i], points[(i + 1) % points.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        let e = b - a;
        let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        if p.distance(a + t * e) < margin {
            return false;
        }
    }
    inside
}

/// The memo switched on or off. The closed forms hold for both: the
/// memo's binning bias is below these tests' noise (`docs/performance.md`
/// measures it on the room).
fn memo_options(enabled: bool) -> MemoOptions {
    {
        let mut memo = MemoOptions::default();
        memo.enabled = enabled;
        memo
    }
}

fn geometric_sum(rho: f64, terms: u32) -> f64 {
    (0..terms).map(|k| rho.powi(k as i32)).sum()
}

/// Closed form 4: the flatland furnace. Walls that emit radiance `L_e` and
/// reflect with albedo `rho` give the same fluence everywhere inside,
/// `2pi L_e (1 + rho + ... + rho^D)`, for a convex and a non-convex room.
#[test]
fn closed_form_4_flatland_furnace() {
    let square = [
        DVec2::new(10.3, 10.1),
        DVec2::new(70.7, 10.1),
        DVec2::new(70.7, 69.9),
        DVec2::new(10.3, 69.9),
    ];
    let l_shape = [
        DVec2::new(5.0, 5.0),
        DVec2::new(75.0, 5.0),
        DVec2::new(75.0, 35.3),
        DVec2::new(35.7, 35.3),
        DVec2::new(35.7, 75.0),
        DVec2::new(5.0, 75.0),
    ];
    let (l_e, rho) = (0.3, 0.6);
    for (name, room) in [("square", &square[..]), ("L-shaped", &l_shape[..])] {
        for (bounces, memo) in [(0, false), (1, false), (3, false), (1, true), (3, true)] {
            let extra = format!(
                ", material: Diffuse(albedo: ({rho}, {rho}, {rho})), emit: (intensity: {l_e})"
            );
            let text = format!(
                "Scene(canvas: (80, 80), floor: Color((1, 1, 1)), walls: [{}])",
                polygon_walls(room, &extra)
            );
            let loaded = scene(&text);
            let options = {
                let mut options = RenderOptions::default();
                options.samples = 8;
                options.bounces = bounces;
                options.seed = 11;
                options.memo = memo_options(memo);
                options
            };
            let image = render(&loaded.scene, &options).image;
            let expected = TAU * l_e * geometric_sum(rho, bounces + 1);
            // The whole interior, and each quadrant of the canvas apart:
            // the fluence must be uniform, not just right on average.
            for quadrant in 0..5 {
                let (mean, se, n) = mean_se(&image, |p| {
                    let in_quadrant = match quadrant {
                        0 => true,
                        1 => p.x < 40.0 && p.y < 40.0,
                        2 => p.x >= 40.0 && p.y < 40.0,
                        3 => p.x < 40.0 && p.y >= 40.0,
                        _ => p.x >= 40.0 && p.y >= 40.0,
                    };
                    in_quadrant && well_inside(room, p, 1.0)
                });
                if n < 100 {
                    continue;
                }
                // Direct light alone has no noise in a convex room: allow
                // f32 rounding on top of 4 standard errors.
                let tolerance = 4.0 * se + 1e-5 * expected;
                assert!(
                    (mean - expected).abs() <= tolerance,
                    "{name}, D = {bounces}, memo {memo}, quadrant {quadrant}: mean {mean}, expected {expected}, 4 SE = {}",
                    4.0 * se
                );
            }
        }
    }
}

/// Closed form 4 in rooms whose walls are not axis-aligned: a square and
/// an L turned by 17 degrees and a five-pointed star (non-convex). A
/// receiver on a wall lies off the wall's line by rounding there, and
/// must still never collect that wall's own light; for both path
/// integrators, memo on and off.
#[test]
fn closed_form_4_furnace_in_rotated_and_star_rooms() {
    let turn = |points: &[(f64, f64)], degrees: f64| -> Vec<DVec2> {
        let (s, c) = degrees.to_radians().sin_cos();
        points
            .iter()
            .map(|&(x, y)| {
                let (x, y) = (x - 40.0, y - 40.0);
                DVec2::new(40.0 + c * x - s * y, 40.0 + s * x + c * y)
            })
            .collect()
    };
    let square = turn(
        &[(12.0, 12.0), (68.0, 12.0), (68.0, 68.0), (12.0, 68.0)],
        17.0,
    );
    let l_shape = turn(
        &[
            (10.0, 10.0),
            (70.0, 10.0),
            (70.0, 36.3),
            (36.7, 36.3),
            (36.7, 70.0),
            (10.0, 70.0),
        ],
        17.0,
    );
    let star: Vec<DVec2> = (0..10)
        .map(|k| {
            let r = if k % 2 == 0 { 38.0 } else { 17.0 };
            let a = TAU * k as f64 / 10.0 + 0.1;
            DVec2::new(40.0 + r * a.cos(), 40.0 + r * a.sin())
        })
        .collect();
    let (l_e, rho) = (0.3, 0.6);
    for (name, room) in [("square", &square), ("L-shaped", &l_shape), ("star", &star)] {
        let extra =
            format!(", material: Diffuse(albedo: ({rho}, {rho}, {rho})), emit: (intensity: {l_e})");
        let text = format!(
            "Scene(canvas: (80, 80), floor: Color((1, 1, 1)), walls: [{}])",
            polygon_walls(room, &extra)
        );
        let loaded = scene(&text);
        for (integrator, bounces, memo) in [
            (Integrator::Path, 1, false),
            (Integrator::Path, 3, false),
            (Integrator::Path, 1, true),
            (Integrator::Path, 3, true),
            (Integrator::Original, 1, false),
            (Integrator::Original, 2, true),
        ] {
            let options = |seed: u64| {
                let mut options = RenderOptions::default();
                options.samples = 8;
                options.bounces = bounces;
                options.seed = seed;
                options.integrator = integrator;
                options.memo = memo_options(memo);
                options
            };
            let expected = TAU * l_e * geometric_sum(rho, bounces + 1);
            // With the memo the floor's indirect light comes along lines
            // across the image: its error is shared by the pixels a line
            // crosses, so the standard error comes from 8 renders'
            // means (5 of them: the t distribution's tail at 7 degrees
            // of freedom), not from the pixels of one.
            let (mean, se, sigmas) = if memo && integrator == Integrator::Path {
                let means: Vec<f64> = (12..20)
                    .map(|seed| {
                        let image = render(&loaded.scene, &options(seed)).image;
                        mean_se(&image, |p| well_inside(room, p, 1.0)).0
                    })
                    .collect();
                let k = means.len() as f64;
                let mean = means.iter().sum::<f64>() / k;
                let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (k - 1.0);
                (mean, (var / k).sqrt(), 5.0)
            } else {
                let image = render(&loaded.scene, &options(12)).image;
                let (mean, se, n) = mean_se(&image, |p| well_inside(room, p, 1.0));
                assert!(n > 400, "{name}: {n} pixels inside");
                (mean, se, 4.0)
            };
            let tolerance = sigmas * se + 1e-5 * expected;
            assert!(
                (mean - expected).abs() <= tolerance,
                "{name}, {integrator:?}, D = {bounces}, memo {memo}: mean {mean}, expected {expected}, tolerance {tolerance}"
            );
        }
    }
}

/// Closed form 3 with indirect light: a light outside a closed polygon
/// leaves every pixel inside exactly zero, for every number of bounces.
#[test]
fn closed_form_3_no_leak_with_bounces() {
    // A pentagon with one mirror wall and one transparent-free diffuse
    // set, corners at shared endpoints.
    let points: Vec<DVec2> = (0..5)
        .map(|k| {
            let a = TAU * k as f64 / 5.0 + 0.1;
            DVec2::new(50.0, 50.0) + 35.3 * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    let mut walls = Vec::new();
    for i in 0..5 {
        let (a, b) = (points[i], points[(i + 1) % 5]);
        let material = if i == 2 { ", material: Mirror()" } else { "" };
        walls.push(format!(
            "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){material})",
            a.x, a.y, b.x, b.y
        ));
    }
    let text = format!(
        "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: (3, 3), intensity: 50.0), Line(a: (97, 1), b: (99, 99), intensity: 5.0)])",
        walls.join(", ")
    );
    let loaded = scene(&text);
    for (bounces, memo) in [(1, false), (2, false), (5, false), (1, true), (5, true)] {
        let image = render(&loaded.scene, &{
            let mut options = RenderOptions::default();
            options.samples = 4;
            options.bounces = bounces;
            options.memo = memo_options(memo);
            options
        })
        .image;
        let mut inside = 0;
        for y in 0..100 {
            for x in 0..100 {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                if well_inside(&points, p, 0.8) {
                    inside += 1;
                    assert_eq!(
                        image.get(x, y),
                        [0.0; 3],
                        "D = {bounces}: leak at ({x}, {y})"
                    );
                }
            }
        }
        assert!(inside > 2000);
        let (outside, _, _) = mean_se(&image, |p| !well_inside(&points, p, 0.0));
        assert!(outside > 0.0);
    }
}

/// Closed form 5: a regular N-gon of radius R and albedo rho with a point
/// light at its centre: the indirect fluence is about uniform,
/// `2pi (rho I / 2R) (1 + ... + rho^(D-1))`.
#[test]
fn closed_form_5_circle_room() {
    let (n, radius, rho, intensity) = (96, 40.0, 0.5, 3.0);
    let centre = DVec2::new(50.0, 50.0);
    let points: Vec<DVec2> = (0..n)
        .map(|k| {
            let a = TAU * k as f64 / n as f64;
            centre + radius * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    let text = format!(
        "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: (50, 50), intensity: {intensity})])",
        polygon_walls(
            &points,
            &format!(", material: Diffuse(albedo: ({rho}, {rho}, {rho}))")
        )
    );
    let loaded = scene(&text);
    for (bounces, memo) in [(1, false), (2, false), (1, true), (2, true)] {
        let base = {
            let mut options = RenderOptions::default();
            options.samples = 16;
            options.seed = 5;
            options.memo = memo_options(memo);
            options
        };
        // The direct part draws no random numbers after the jitter, so the
        // difference of two renders with one seed is the indirect part.
        let direct = render(&loaded.scene, &{
            let mut options = base;
            options.bounces = 0;
            options
        })
        .image;
        let total = render(&loaded.scene, &{
            let mut options = base;
            options.bounces = bounces;
            options
        })
        .image;
        let indirect = Image {
            pixels: total
                .pixels
                .iter()
                .zip(&direct.pixels)
                .map(|(t, d)| [t[0] - d[0], t[1] - d[1], t[2] - d[2]])
                .collect(),
            ..total.clone()
        };
        let expected = TAU * rho * intensity / (2.0 * radius) * geometric_sum(rho, bounces);
        for ring in [(0.0, 0.4), (0.4, 0.8)] {
            let (mean, se, count) = mean_se(&indirect, |p| {
                let r = p.distance(centre) / radius;
                r >= ring.0 && r < ring.1
            });
            assert!(count > 300);
            // The polygon's irradiance differs from I / R by about
            // (pi / N)^2 / 3 < 0.04 %: allow 0.5 % on top of 4 SE.
            let tolerance = 4.0 * se + 0.005 * expected;
            assert!(
                (mean - expected).abs() <= tolerance,
                "D = {bounces}, memo {memo}, ring {ring:?}: mean {mean}, expected {expected}, 4 SE = {}",
                4.0 * se
            );
        }
    }
}

/// Closed form 6: a scene symmetric about the line x = 50 gives an image
/// symmetric within noise.
#[test]
fn closed_form_6_symmetric_scene_gives_symmetric_image() {
    let text = "Scene(canvas: (100, 80), floor: Color((0.8, 0.8, 0.8)),
        walls: [
            Wall(a: (10, 10), b: (90, 10), material: Diffuse(albedo: (0.9, 0.3, 0.3))),
            Wall(a: (20, 30), b: (35, 50), material: Diffuse(albedo: (0.2, 0.9, 0.2))),
            Wall(a: (80, 30), b: (65, 50), material: Diffuse(albedo: (0.2, 0.9, 0.2))),
            Wall(a: (45, 70), b: (30, 75), material: Mirror()),
            Wall(a: (55, 70), b: (70, 75), material: Mirror()),
            Wall(a: (40, 20), b: (60, 20), material: Transparent(tint: (0.5, 0.5, 1.0))),
        ],
        lights: [
            Point(at: (50, 40), intensity: 20.0),
            Line(a: (5, 60), b: (15, 70), intensity: 1.0),
            Line(a: (95, 60), b: (85, 70), intensity: 1.0),
        ])";
    let loaded = scene(text);
    let image = render(&loaded.scene, &{
        let mut options = RenderOptions::default();
        options.samples = 16;
        options.bounces = 2;
        options.seed = 3;
        options.memo = memo_options(false);
        options
    })
    .image;
    // Compare regions of the left half with their mirror images.
    for channel in 0..3 {
        for (y0, y1) in [(0, 20), (20, 40), (40, 60), (60, 80)] {
            let mut diffs = Vec::new();
            for y in y0..y1 {
                for x in 0..50 {
                    let left = image.get(x, y)[channel] as f64;
                    let right = image.get(99 - x, y)[channel] as f64;
                    diffs.push(left - right);
                }
            }
            let n = diffs.len() as f64;
            let mean = diffs.iter().sum::<f64>() / n;
            let sd = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            assert!(
                mean.abs() <= 4.0 * sd / n.sqrt() + 1e-7,
                "channel {channel}, rows {y0}..{y1}: mean difference {mean}, 4 SE = {}",
                4.0 * sd / n.sqrt()
            );
        }
    }
}

/// The scene of the unbiasedness tests: diffuse, coloured, mirror and
/// transparent walls, all three light shapes that path tracing samples.
const MIXED: &str = "Scene(canvas: (40, 32), floor: Color((0.9, 0.9, 0.9)),
    walls: [
        Wall(a: (5, 5), b: (35, 5), material: Diffuse(albedo: (0.9, 0.2, 0.2))),
        Wall(a: (35, 5), b: (35, 28)),
        Wall(a: (12, 14), b: (22, 22), material: Mirror(tint: (0.9, 0.9, 0.9))),
        Wall(a: (28, 12), b: (28, 22), material: Transparent(tint: (0.4, 0.6, 1.0))),
        Wall(a: (4, 27), b: (20, 29)),
    ],
    lights: [
        Point(at: (8.5, 11.2), intensity: 5.0),
        Line(a: (15, 8), b: (25, 8), intensity: 0.5),
        Spot(at: (33, 25), direction: (-1, -0.5), cone: 40, softness: 10, intensity: 4.0),
    ])";

/// Per-run totals of each 8 x 8 block of the image.
fn block_totals(image: &Image) -> Vec<f64> {
    let mut totals = vec![0.0; 20];
    for y in 0..32 {
        for x in 0..40 {
            let p = image.get(x, y);
            totals[(y / 8 * 5 + x / 8) as usize] += (p[0] + p[1] + p[2]) as f64;
        }
    }
    totals
}

#[test]
fn the_mean_of_many_low_sample_renders_matches_a_high_sample_render() {
    let loaded = scene(MIXED);
    for integrator in [Integrator::Path, Integrator::Original] {
        let options = {
            let mut options = RenderOptions::default();
            options.samples = 1;
            options.bounces = 3;
            options.integrator = integrator;
            options.memo = memo_options(false);
            options
        };
        let runs = 128;
        let per_run: Vec<Vec<f64>> = (0..runs)
            .map(|seed| {
                block_totals(
                    &render(&loaded.scene, &{
                        let mut options = options;
                        options.seed = seed;
                        options
                    })
                    .image,
                )
            })
            .collect();
        let high_samples = 256;
        let high = block_totals(
            &render(&loaded.scene, &{
                let mut options = options;
                options.samples = high_samples;
                options.seed = 10_000;
                options
            })
            .image,
        );
        for block in 0..20 {
            let values: Vec<f64> = per_run.iter().map(|t| t[block]).collect();
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            // The mean of `runs` one-sample runs and one render of
            // `high_samples` samples: both errors, added in quadrature.
            let se = (sd * sd / n + sd * sd / high_samples as f64).sqrt();
            assert!(
                (mean - high[block]).abs() <= 4.0 * se + 1e-6 * mean.abs(),
                "{integrator:?}, block {block}: low-sample mean {mean}, high-sample {}, 4 SE = {}",
                high[block],
                4.0 * se
            );
        }
    }
}

#[test]
fn the_original_estimator_converges_to_the_same_image() {
    let loaded = scene(MIXED);
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 128;
        options.bounces = 2;
        options.seed = 99;
        options.memo = memo_options(false);
        options
    };
    let path = render(&loaded.scene, &options).image;
    let original = render(&loaded.scene, &{
        let mut options = options;
        options.integrator = Integrator::Original;
        options.seed = 100;
        options
    })
    .image;
    // Pixel differences are independent between pixels: their spread
    // gives the standard error of their mean over a block.
    for block in 0..20u32 {
        let (bx, by) = (block % 5 * 8, block / 5 * 8);
        let mut diffs = Vec::new();
        for y in by..by + 8 {
            for x in bx..bx + 8 {
                let (a, b) = (path.get(x, y), original.get(x, y));
                diffs.push((a[0] + a[1] + a[2] - b[0] - b[1] - b[2]) as f64);
            }
        }
        let n = diffs.len() as f64;
        let mean = diffs.iter().sum::<f64>() / n;
        let sd = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!(
            mean.abs() <= 4.0 * sd / n.sqrt() + 1e-6,
            "block {block}: mean difference {mean}, 4 SE = {}",
            4.0 * sd / n.sqrt()
        );
    }
    let _ = PI;
}
