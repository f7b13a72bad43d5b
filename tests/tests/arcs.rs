//! Curved walls: rooms of arcs and segments that leak nothing, a concave
//! mirror and a lens against their closed forms, and arcs through every
//! integrator. Fixed seeds; statistical checks state their tolerance.

use std::f64::consts::{PI, TAU};

use flatray_geometry::DVec2;
use flatray_tests::{render, scene};
use flatray_tracer::{Image, Integrator, MemoOptions, RenderOptions};

fn options(samples: u32, bounces: u32) -> RenderOptions {
    let mut options = RenderOptions::default();
    options.samples = samples;
    options.bounces = bounces;
    options
}

/// A closed room of `sides` corners on a circle of `radius` about
/// `centre`, turned by `angle`, each edge an arc bulging out (a positive
/// `bulge`, as a share of the chord) or in (negative), or a segment (0),
/// as RON walls sharing their ends exactly.
fn room(centre: DVec2, radius: f64, sides: usize, angle: f64, bulges: &[f64]) -> String {
    let corner = |k: usize| {
        let a = angle + TAU * k as f64 / sides as f64;
        centre + radius * DVec2::new(a.cos(), a.sin())
    };
    (0..sides)
        .map(|k| {
            let (p, q) = (corner(k), corner((k + 1) % sides));
            let bulge = bulges[k % bulges.len()];
            if bulge == 0.0 {
                format!("Wall(a: ({:?}, {:?}), b: ({:?}, {:?}))", p.x, p.y, q.x, q.y)
            } else {
                let mid = (p + q) * 0.5;
                let m = mid + (mid - centre).normalize() * bulge * p.distance(q);
                format!(
                    "Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}))",
                    p.x, p.y, m.x, m.y, q.x, q.y
                )
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn pixels_where(image: &Image, test: impl Fn(DVec2) -> bool) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for y in 0..image.height {
        for x in 0..image.width {
            if test(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                out.push((x, y));
            }
        }
    }
    out
}

/// Every pixel that `dark` holds is exactly zero, for direct light, three
/// bounces with and without the memo, and light tracing; and some pixel
/// is lit.
fn assert_dark(name: &str, text: &str, dark: impl Fn(DVec2) -> bool) {
    let loaded = scene(text);
    let runs: [(u32, bool, Integrator); 5] = [
        (0, false, Integrator::Path),
        (1, true, Integrator::Path),
        (3, false, Integrator::Path),
        (3, true, Integrator::Path),
        (2, false, Integrator::Light),
    ];
    for (bounces, memo, integrator) in runs {
        let mut options = options(4, bounces);
        options.memo = MemoOptions::default();
        options.memo.enabled = memo;
        options.integrator = integrator;
        let image = render(&loaded.scene, &options).image;
        assert!(
            image.pixels.iter().flatten().all(|v| v.is_finite()),
            "{name}"
        );
        let pixels = pixels_where(&image, &dark);
        assert!(pixels.len() > 100, "{name}: {} dark pixels", pixels.len());
        for (x, y) in pixels {
            assert_eq!(
                image.get(x, y),
                [0.0; 3],
                "{name}, D = {bounces}, memo {memo}, {integrator:?}: light leaked into ({x}, {y})"
            );
        }
        assert!(
            image.pixels.iter().any(|p| p[0] > 0.0),
            "{name}: nothing lit"
        );
    }
}

/// Rooms of arcs and segments sharing their ends, at odd rotations and
/// centres no float holds, with every kind of wall-finding light outside
/// (a point, a line, the sun) and then a lamp inside: not a photon gets
/// through, at any depth, by either integrator. Pixels within 2 of a
/// wall are left out (a pixel the wall crosses is partly lit).
#[test]
fn rooms_of_arcs_and_segments_let_no_light_through() {
    let centre = DVec2::new(50.0 + 1.0 / 3.0, 50.0 + 0.1);
    let cases: [(&str, usize, f64, &[f64]); 5] = [
        ("bulging triangle", 3, 0.3, &[0.25, 0.0, 0.4]),
        (
            "pentagon of arcs in and out",
            5,
            1.1,
            &[0.2, -0.1, 0.3, -0.08, 0.15],
        ),
        ("heptagon of arcs", 7, 2.9, &[0.12]),
        (
            "square, two arcs",
            4,
            std::f64::consts::FRAC_PI_4 + 1e-3,
            &[0.0, 0.5],
        ),
        ("octagon, every other arc", 8, 0.0123, &[0.0, -0.1]),
    ];
    for (name, sides, angle, bulges) in cases {
        let walls = room(centre, 34.0, sides, angle, bulges);
        // Inside: well within the inscribed circle less the inward bulges.
        let inward =
            bulges.iter().fold(0.0f64, |m, b| m.max(-b)) * 2.0 * 34.0 * (PI / sides as f64).sin();
        let inner = 34.0 * (PI / sides as f64).cos() - inward - 2.0;
        let outer = 34.0 * (1.0 + 0.5 * bulges.iter().fold(0.0f64, |m, b| m.max(*b)) * 2.0) + 2.0;
        let outside = format!(
            "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{walls}],
               lights: [Point(at: (1.5, 98.5), intensity: 50.0), Line(a: (99, 2), b: (99, 97), intensity: 2.0),
                        Directional(direction: (-0.37, 1.0), intensity: 3.0)])"
        );
        assert_dark(&format!("{name}, lights outside"), &outside, |p| {
            p.distance(centre) < inner
        });
        let inside = format!(
            "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{walls}],
               lights: [Point(at: ({:?}, {:?}), intensity: 50.0), Circle(at: ({:?}, {:?}), radius: 3, intensity: 1.0)])",
            centre.x + 3.0, centre.y - 2.0, centre.x - 6.0, centre.y + 4.0
        );
        assert_dark(&format!("{name}, lights inside"), &inside, |p| {
            p.distance(centre) > outer && p.x > 1.0 && p.y > 1.0
        });
    }
}

/// A round room (a full circle, two half circles, and a circle of a
/// mirror) keeps its light in, and a round column casts a shadow that
/// nothing enters but light off the walls.
#[test]
fn round_rooms_and_columns_keep_their_light() {
    let c = (50.333333333333336, 49.9);
    for (name, walls) in [
        (
            "circle",
            format!("Wall(center: ({:?}, {:?}), radius: 33)", c.0, c.1),
        ),
        (
            "two half circles",
            format!(
                "Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?})), Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}))",
                c.0 - 33.0,
                c.1,
                c.0,
                c.1 - 33.0,
                c.0 + 33.0,
                c.1,
                c.0 + 33.0,
                c.1,
                c.0,
                c.1 + 33.0,
                c.0 - 33.0,
                c.1
            ),
        ),
        (
            "mirror circle",
            format!(
                "Wall(center: ({:?}, {:?}), radius: 33, material: Mirror())",
                c.0, c.1
            ),
        ),
    ] {
        let text = format!(
            "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{walls}],
               lights: [Point(at: (40, 55), intensity: 30.0), Line(a: (45, 40), b: (60, 47), intensity: 1.0)])"
        );
        let centre = DVec2::new(c.0, c.1);
        assert_dark(name, &text, |p| p.distance(centre) > 35.0);
    }
    // A black column: behind it, no direct light; with no walls around,
    // nothing at all.
    let text = "Scene(canvas: (100, 100), floor: Color((1, 1, 1)),
        walls: [Wall(center: (50.3, 50.1), radius: 10, material: Diffuse(albedo: (0, 0, 0)))],
        lights: [Point(at: (10.2, 50.1), intensity: 30.0)])";
    assert_dark("column's shadow", text, |p| {
        // The shadow: beyond the column, within the tangents from the lamp.
        let (lamp, c) = (DVec2::new(10.2, 50.1), DVec2::new(50.3, 50.1));
        let d = p - lamp;
        let half = (10.0 / (c - lamp).length()).asin();
        let angle = d.y.atan2(d.x).abs();
        p.x > 62.0 && angle < half - 0.03
    });
}

/// The mean of the image over the pixels `within` holds.
fn mean_where(image: &Image, within: impl Fn(DVec2) -> bool) -> (f64, usize) {
    let pixels = pixels_where(image, within);
    let sum: f64 = pixels.iter().map(|&(x, y)| image.get(x, y)[1] as f64).sum();
    (sum / pixels.len().max(1) as f64, pixels.len())
}

/// A half circle of mirror about a point light at its centre sends every
/// ray straight back through the centre: each line through the centre
/// meets the mirror once, so on that line the reflected light is the
/// direct light again, times the tint. Everywhere inside the circle the
/// fluence is `1 + tint` times the light's alone. Checked in rings about
/// the centre, by the path tracer (its caustic pass) and by light
/// tracing, to 4 standard errors over 8 seeds.
#[test]
fn a_point_at_a_concave_mirrors_centre_is_lit_again_by_it() {
    let c = (100.33333333333333, 100.1);
    let tint = 0.7;
    let text = |mirror: bool| {
        let wall = if mirror {
            format!(
                "Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}), material: Mirror(tint: ({tint}, {tint}, {tint})))",
                c.0 - 80.0,
                c.1,
                c.0,
                c.1 - 80.0,
                c.0 + 80.0,
                c.1
            )
        } else {
            String::new()
        };
        format!(
            "Scene(canvas: (200, 200), floor: Color((1, 1, 1)), walls: [{wall}],
               lights: [Point(at: ({:?}, {:?}), intensity: 1.0)])",
            c.0, c.1
        )
    };
    let alone = scene(&text(false));
    let mirrored = scene(&text(true));
    let centre = DVec2::new(c.0, c.1);
    for integrator in [Integrator::Path, Integrator::Light] {
        for (r0, r1) in [(6.0, 20.0), (20.0, 45.0), (45.0, 70.0)] {
            let ring = |p: DVec2| {
                let d = p.distance(centre);
                d > r0 && d < r1
            };
            let mut ratios = Vec::new();
            for seed in 0..8u64 {
                let mut options = options(16, 0);
                options.integrator = integrator;
                options.specular = 1;
                options.seed = 100 + seed;
                let with = mean_where(&render(&mirrored.scene, &options).image, ring).0;
                let without = mean_where(&render(&alone.scene, &options).image, ring).0;
                ratios.push(with / without);
            }
            let n = ratios.len() as f64;
            let mean = ratios.iter().sum::<f64>() / n;
            let var = ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n).sqrt().max(1e-4);
            assert!(
                (mean - (1.0 + tint)).abs() < 4.0 * se,
                "{integrator:?}, ring {r0} to {r1}: {mean} against {} (SE {se})",
                1.0 + tint
            );
        }
    }
}

/// A lamp at the focus of a thin concave mirror (half its radius from
/// it) sends back a parallel beam: the reflected light's fluence along the
/// beam stays the same with distance (to 1 %, 0.2 % measured: the rays
/// near the axis leave all but parallel), where a flat
/// mirror of the same ends gives a beam that spreads as from the lamp's
/// image, its fluence falling to 0.6 between the same two windows.
#[test]
fn a_lamp_at_a_thin_mirrors_focus_makes_a_parallel_beam() {
    // The mirror: radius 200 about (180, 100), from -15 to 15 degrees,
    // its middle at (380, 100), facing -x; the focus at 100 from it, at
    // (280, 100). A spot aimed at the mirror lights nothing behind itself
    // but by the mirror: the two windows on the axis, behind the lamp.
    let (cx, cy, r) = (180.0f64, 100.0f64, 200.0f64);
    let at = |deg: f64| {
        (
            cx + r * deg.to_radians().cos(),
            cy + r * deg.to_radians().sin(),
        )
    };
    let ((ax, ay), (mx, my), (bx, by)) = (at(-15.0), at(0.0), at(15.0));
    let measure = |wall: String| {
        let text = format!(
            "Scene(canvas: (400, 200), floor: Color((1, 1, 1)), walls: [{wall}],
               lights: [Spot(at: (280, 100), direction: (1, 0), cone: 40, softness: 0, intensity: 1.0)])"
        );
        let loaded = scene(&text);
        let mut options = options(32, 0);
        options.integrator = Integrator::Light;
        options.specular = 1;
        let image = render(&loaded.scene, &options).image;
        let window = |x0: f64| {
            mean_where(&image, |p| {
                p.x > x0 && p.x < x0 + 20.0 && (p.y - 100.0).abs() < 10.0
            })
            .0
        };
        (window(200.0), window(20.0))
    };
    let arc = format!(
        "Wall(a: ({ax:?}, {ay:?}), through: ({mx:?}, {my:?}), b: ({bx:?}, {by:?}), material: Mirror())"
    );
    let flat = format!("Wall(a: ({ax:?}, {ay:?}), b: ({bx:?}, {by:?}), material: Mirror())");
    let (near, far) = measure(arc);
    assert!(near > 0.0, "the beam reaches the window");
    assert!(
        (far / near - 1.0).abs() < 0.01,
        "the curved mirror's beam: {near} then {far}"
    );
    let (near, far) = measure(flat);
    assert!(
        far / near < 0.8,
        "the flat mirror's beam spreads: {near} then {far}"
    );
}

/// A biconvex lens of two arcs (radius 100, index 1.5, 57.2 thick)
/// focuses a narrow parallel beam where the thick lensmaker's equation
/// puts it: the effective focal length `1 / f = (n - 1) (1/R1 - 1/R2 +
/// (n - 1) d / (n R1 R2))` and the back focal distance `f (1 - (n - 1) d
/// / (n R1))` from the lens's back, 89.5 there. The beam, 6 wide about the
/// axis, narrows linearly to the focus and widens after it, so the focus
/// lies where the widths at two columns either side say (each from the
/// second moment of its column); its rays 3 off the axis meet it 0.1
/// nearer the lens (spherical aberration, traced by hand). Within 0.05,
/// a tenth of a pixel (measured: 0.007 off); the same lens of 96 flat
/// facets (`scenes/lens-polygon.ron`) is 0.18 off.
#[test]
fn a_lens_focuses_where_the_lensmakers_equation_puts_it() {
    let (n, r, half) = (1.5f64, 100.0f64, 70.0f64);
    let sag = r - (r * r - half * half).sqrt();
    let d = 2.0 * sag;
    let f = 1.0 / ((n - 1.0) * (2.0 / r - (n - 1.0) * d / (n * r * r)));
    let bfd = f * (1.0 - (n - 1.0) * d / (n * r));
    let focus = 170.0 + sag + bfd;
    let text = format!(
        "Scene(canvas: (400, 240), floor: Color((1, 1, 1)),
           glass: [Glass(points: [(170, 50), (170, 190)],
                         through: [Some(({:?}, 120)), Some(({:?}, 120))], ior: 1.5)],
           lights: [Beam(a: (20, 117), b: (20, 123), direction: (1, 0), intensity: 1.0)])",
        170.0 + sag,
        170.0 - sag
    );
    let found = beam_focus(&text, 1);
    assert!(
        (found - focus).abs() < 0.05,
        "the focus at x = {found}; the lensmaker's equation puts it at {focus}"
    );
}

/// Where a beam along `y = 120` focuses, from its widths at `x = 240`
/// and `x = 336` (world units), rendered at 2 pixels per unit by light
/// tracing through two refractions (no light reflected inside the glass
/// to widen it): `w(x)` is proportional to `|x - focus|`.
fn beam_focus(text: &str, seed: u64) -> f64 {
    const SCALE: f64 = 2.0;
    let loaded = scene(text);
    let mut options = options(16, 0);
    options.seed = seed;
    options.integrator = Integrator::Light;
    options.scale = SCALE;
    options.specular = 2;
    let image = render(&loaded.scene, &options).image;
    let width = |x: f64| {
        // The beam's rows in the column at world x, by its second moment
        // within 4 of the axis: a uniform beam of width w has variance
        // w^2 / 12, and each pixel's own height adds 1 / 12 (in pixels).
        let column = (x * SCALE) as u32;
        let (mut sum, mut first, mut second) = (0.0, 0.0, 0.0);
        for y in (116.0 * SCALE) as u32..(124.0 * SCALE) as u32 {
            let v = image.get(column, y)[1] as f64;
            let at = y as f64 + 0.5;
            sum += v;
            first += v * at;
            second += v * at * at;
        }
        let mean = first / sum;
        let variance = second / sum - mean * mean - 1.0 / 12.0;
        (12.0 * variance.max(0.0)).sqrt() / SCALE
    };
    let (x1, x2) = (240.0, 336.0);
    let (w1, w2) = (width(x1), width(x2));
    // The columns' centres.
    let (x1, x2) = (x1 + 0.5 / SCALE, x2 + 0.5 / SCALE);
    (x1 * w2 + x2 * w1) / (w1 + w2)
}

/// The flatland furnace in rooms of arcs: walls that emit radiance `L_e`
/// and reflect with albedo `rho` give the same fluence everywhere
/// inside, `2 pi L_e (1 + rho + ... + rho^D)`: a round room (one circle
/// that emits), a room of two half circles, and a turned pentagon of
/// arcs bulging in and out and segments, sharing their ends. A point on
/// an arc's concave side receives the arc's own light (rule 4b's
/// exclusion is for straight walls only). The mean over the pixels 2
/// clear of the walls within 4 standard errors (over 6 seeds) of the
/// closed form, at D = 0 to 3, memo on and off, for both path
/// integrators, as the turned rooms' furnace (`path_tracing.rs`).
#[test]
fn furnaces_of_arcs_give_the_same_fluence_everywhere_inside() {
    let (l_e, rho) = (0.3f64, 0.6f64);
    let c = DVec2::new(40.0 + 1.0 / 3.0, 40.1);
    let extra =
        format!(", material: Diffuse(albedo: ({rho}, {rho}, {rho})), emit: (intensity: {l_e})");
    let rooms: [(&str, String, f64); 3] = [
        (
            "round room",
            format!("Wall(center: ({:?}, {:?}), radius: 33{extra})", c.x, c.y),
            33.0,
        ),
        (
            "two half circles",
            format!(
                "Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}){extra}), Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}){extra})",
                c.x - 33.0,
                c.y,
                c.x,
                c.y - 33.0,
                c.x + 33.0,
                c.y,
                c.x + 33.0,
                c.y,
                c.x,
                c.y + 33.0,
                c.x - 33.0,
                c.y
            ),
            33.0,
        ),
        (
            "pentagon of arcs and segments",
            room(c, 34.0, 5, 0.7, &[0.15, 0.0, -0.08, 0.25, 0.0])
                .replace("))", &format!("){extra})")),
            // The inscribed circle less the inward bulge.
            34.0 * (PI / 5.0).cos() - 0.08 * 2.0 * 34.0 * (PI / 5.0).sin(),
        ),
    ];
    for (name, walls, inner) in rooms {
        let loaded = scene(&format!(
            "Scene(canvas: (80, 80), floor: Color((1, 1, 1)), walls: [{walls}])"
        ));
        assert!(
            (0..loaded.scene.walls().len() as u32).all(|w| loaded.scene.light_of_wall(w).is_some()),
            "{name}: every wall emits"
        );
        for (integrator, bounces, memo) in [
            (Integrator::Path, 0, false),
            (Integrator::Path, 1, false),
            (Integrator::Path, 3, false),
            (Integrator::Path, 3, true),
            (Integrator::Original, 1, false),
            (Integrator::Original, 2, true),
        ] {
            // The memo's pixels share its bins: the standard error is over
            // seeds, of the image's mean.
            let means: Vec<f64> = (0..6u64)
                .map(|seed| {
                    let mut options = options(8, bounces);
                    options.seed = 12 + seed;
                    options.integrator = integrator;
                    options.memo = MemoOptions::default();
                    options.memo.enabled = memo;
                    let image = render(&loaded.scene, &options).image;
                    let pixels = pixels_where(&image, |p| p.distance(c) < inner - 2.0);
                    let n = pixels.len() as f64;
                    assert!(n > 400.0, "{name}: {n} pixels inside");
                    pixels
                        .iter()
                        .map(|&(x, y)| image.get(x, y)[1] as f64)
                        .sum::<f64>()
                        / n
                })
                .collect();
            let n = means.len() as f64;
            let mean = means.iter().sum::<f64>() / n;
            let var = means.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n).sqrt();
            let expected = TAU * l_e * (0..=bounces).map(|k| rho.powi(k as i32)).sum::<f64>();
            assert!(
                (mean - expected).abs() <= 4.0 * se + 1e-5 * expected,
                "{name}, {integrator:?}, D = {bounces}, memo {memo}: mean {mean}, expected {expected}, 4 SE = {}",
                4.0 * se
            );
        }
    }
}
