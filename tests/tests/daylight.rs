//! The sky and the sun of a date: the sky's direct light against the
//! angle of sky a point sees, a pane's tint on it, a closed room under it
//! dark, light tracing against path tracing, and the sun against the
//! directional light it stands for. Statistical checks state their
//! tolerance in standard errors of the pixel's jittered mean.

use std::f64::consts::TAU;

use flatray_geometry::{DVec2, Segment};
use flatray_io::daylight::{sun_direction, sun_place};
use flatray_io::format::{Date, TimeOfDay};
use flatray_tests::{Agreement, pixel_moments, render, scene};
use flatray_tracer::RenderOptions;
use flatray_tracer::sampling::subtended_angle;

const SIZE: u32 = 64;
const CENTRE: DVec2 = DVec2::new(32.1, 31.9);
const HALF: f64 = 22.3;
/// The opening's half-width, in the room's top wall.
const GAP: f64 = 5.2;

fn options(samples: u32, bounces: u32) -> RenderOptions {
    let mut options = RenderOptions::default();
    options.samples = samples;
    options.bounces = bounces;
    options
}

/// A square room turned by `degrees` about `CENTRE`, with an opening of
/// width `2 GAP` in the middle of its top wall, across which `pane` (a
/// wall's material) stands where given; and the opening's segment.
fn room(degrees: f64, pane: Option<&str>, sky: &str) -> (String, Segment) {
    let (s, c) = degrees.to_radians().sin_cos();
    let at = |x: f64, y: f64| CENTRE + DVec2::new(c * x - s * y, s * x + c * y);
    let corners = [
        at(-HALF, -HALF),
        at(HALF, -HALF),
        at(HALF, HALF),
        at(-HALF, HALF),
    ];
    let (gap_a, gap_b) = (at(-GAP, -HALF), at(GAP, -HALF));
    let wall = |a: DVec2, b: DVec2, material: &str| {
        format!(
            "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){material})",
            a.x, a.y, b.x, b.y
        )
    };
    let mut walls = vec![
        wall(corners[0], gap_a, ""),
        wall(gap_b, corners[1], ""),
        wall(corners[1], corners[2], ""),
        wall(corners[2], corners[3], ""),
        wall(corners[3], corners[0], ""),
    ];
    if let Some(material) = pane {
        walls.push(wall(gap_a, gap_b, &format!(", material: {material}")));
    }
    let text = format!(
        "Scene(canvas: ({SIZE}, {SIZE}), floor: Color((1, 1, 1)), walls: [{}], lights: [{sky}])",
        walls.join(", ")
    );
    (text, Segment::new(gap_a, gap_b))
}

/// Whether `p` lies inside the room turned by `degrees`, `margin` clear of
/// its walls.
fn inside(p: DVec2, degrees: f64, margin: f64) -> bool {
    let (s, c) = (-degrees).to_radians().sin_cos();
    let d = p - CENTRE;
    let local = DVec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
    local.abs().max_element() < HALF - margin
}

/// Every pixel well inside the room matches `exact` per channel within 5
/// standard errors of its jittered mean; returns how many were checked.
fn assert_inside_matches(
    image: &flatray_tracer::Image,
    samples: u32,
    degrees: f64,
    exact: impl Fn(DVec2) -> [f64; 3],
) -> usize {
    let mut checked = 0;
    for y in 0..image.height {
        for x in 0..image.width {
            let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            if !inside(centre, degrees, 1.5) {
                continue;
            }
            for c in 0..3 {
                let (mean, sd) = pixel_moments(x, y, 16, |p| exact(p)[c]);
                let se = sd / (samples as f64).sqrt();
                let got = image.get(x, y)[c] as f64;
                let tolerance = 5.0 * se + 1e-4 * mean.abs() + 1e-6;
                assert!(
                    (got - mean).abs() <= tolerance,
                    "{degrees} degrees, pixel ({x}, {y}) channel {c}: got {got}, exact {mean}, 5 SE = {}",
                    5.0 * se
                );
            }
            checked += 1;
        }
    }
    checked
}

/// Through an opening, a point receives the sky's radiance times the
/// angle the opening subtends (every other direction is a wall), in
/// rooms turned three ways, by the default render at 4 spp.
#[test]
fn the_sky_through_an_opening_gives_radiance_times_the_angle_it_subtends() {
    let samples = 4;
    for degrees in [0.0, 17.0, 45.0] {
        let (text, gap) = room(degrees, None, "Sky(intensity: 0.8)");
        let image = render(&scene(&text).scene, &options(samples, 0)).image;
        let checked = assert_inside_matches(&image, samples, degrees, |p| {
            [0.8 * subtended_angle(p, &gap); 3]
        });
        assert!(checked > 1000, "only {checked} pixels");
    }
}

/// A pane in the opening tints the sky by its colour; a black pane and a
/// wall shut it out.
#[test]
fn a_pane_in_the_opening_tints_the_sky_and_a_shut_room_is_dark() {
    let samples = 4;
    let tint = [0.2, 0.5, 0.9];
    let (text, gap) = room(
        17.0,
        Some("Transparent(tint: (0.2, 0.5, 0.9))"),
        "Sky(color: (1, 1, 1), intensity: 0.5)",
    );
    let image = render(&scene(&text).scene, &options(samples, 0)).image;
    let checked = assert_inside_matches(&image, samples, 17.0, |p| {
        let angle = subtended_angle(p, &gap);
        tint.map(|t| 0.5 * t * angle)
    });
    assert!(checked > 1000, "only {checked} pixels");
    // Shut by a wall: nothing inside, at every bounce count.
    for bounces in [0, 2] {
        let (text, _) = room(
            17.0,
            Some("Diffuse()"),
            "Sky(color: (0.6, 0.8, 1), intensity: 3)",
        );
        let image = render(&scene(&text).scene, &options(8, bounces)).image;
        let mut dark = 0;
        for y in 0..SIZE {
            for x in 0..SIZE {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                if inside(p, 17.0, 1.0) {
                    assert_eq!(
                        image.get(x, y),
                        [0.0; 3],
                        "pixel ({x}, {y}), {bounces} bounces"
                    );
                    dark += 1;
                }
            }
        }
        assert!(dark > 1000, "only {dark} pixels");
    }
}

/// With nothing in the way, every point sees the whole sky: `2 pi` times
/// its radiance, exactly, at every sample count.
#[test]
fn an_open_floor_under_the_sky_takes_two_pi_times_its_radiance() {
    let loaded = scene(
        "Scene(canvas: (40, 30), origin: (-1e6, 3e5), floor: Color((1, 1, 1)),
               lights: [Sky(color: (1, 0.5, 0.25), intensity: 0.3)])",
    );
    let image = render(&loaded.scene, &options(1, 2)).image;
    for p in &image.pixels {
        for (c, share) in [1.0, 0.5, 0.25].into_iter().enumerate() {
            let exact = TAU * 0.3 * share;
            assert!(
                (p[c] as f64 - exact).abs() <= 1e-5 * exact,
                "{p:?} against {exact}"
            );
        }
    }
}

/// Light tracing (photons from the sky's frame, inward) and path tracing
/// agree per block within 5 standard errors over 24 seeds, with a bounce
/// off the walls.
#[test]
fn light_tracing_agrees_with_path_tracing_under_the_sky() {
    let (text, _) = room(17.0, None, "Sky(intensity: 0.5)");
    agree_per_block("sky in a room", &text, 300);
}

/// Light tracing and path tracing of `text` (4 spp, 2 bounces, no memo)
/// agree per 8-px block within 5 standard errors over 24 seeds from
/// `first_seed`.
fn agree_per_block(name: &str, text: &str, first_seed: u64) {
    let loaded = scene(text);
    let mut options = options(4, 2);
    options.memo.enabled = false;
    let agreement = Agreement {
        block: 8,
        runs: 24,
        first_seed,
        k: 5.0,
        min_blocks: 40,
    };
    agreement.check(name, &loaded.scene, options, |_| true);
}

fn date(year: i32, month: u32, day: u32) -> Date {
    Date { year, month, day }
}

fn time(hour: u32, minute: u32) -> TimeOfDay {
    TimeOfDay {
        hour,
        minute,
        second: 0,
    }
}

/// A sun of a date renders as the directional light along its azimuth
/// (turned by the plan's north) whose irradiance is its own times the
/// sine of its elevation, bit for bit; at night, black, and `check`'s
/// warning says why.
#[test]
fn the_sun_of_a_date_is_the_directional_light_it_stands_for() {
    let place = sun_place(date(2026, 12, 21), time(10, 0), 1.0, 48.85, 2.35).unwrap();
    assert!(place.elevation > 5.0, "{place:?}");
    for north in [0.0, 20.0, -135.0] {
        let d = sun_direction(place.azimuth, north);
        let irradiance = 2.0 * place.elevation.to_radians().sin();
        let room = |light: String| {
            format!(
                "Scene(canvas: (48, 40), floor: Color((0.7, 0.7, 0.7)),
                   walls: [Wall(a: (10, 10), b: (30, 14)), Wall(a: (30, 14), b: (26, 32))],
                   lights: [{light}])"
            )
        };
        let sun = scene(&room(format!(
            "Sun(date: \"2026-12-21\", time: \"10:00\", zone: 1, latitude: 48.85, longitude: 2.35, north: {north:?}, intensity: 2)"
        )));
        let directional = scene(&room(format!(
            "Directional(direction: ({:?}, {:?}), intensity: {irradiance:?})",
            d.x, d.y
        )));
        let options = options(4, 1);
        assert_eq!(
            render(&sun.scene, &options).image,
            render(&directional.scene, &options).image,
            "north {north}"
        );
        assert!(sun.warnings.is_empty(), "{:?}", sun.warnings);
    }
    let night = scene(
        "Scene(canvas: (16, 16), floor: Color((1, 1, 1)),
               lights: [Sun(date: \"2026-12-21\", time: \"02:00\", zone: 1, latitude: 48.85, longitude: 2.35)])",
    );
    let image = render(&night.scene, &options(2, 1)).image;
    assert!(image.pixels.iter().all(|p| *p == [0.0; 3]));
    assert!(
        night
            .warnings
            .iter()
            .any(|w| w.message.contains("below the horizon") && w.line == 2),
        "{:?}",
        night.warnings
    );
}

/// That `text`, read as file `name`, is refused on its line 2 with a
/// message holding `expected` (`about` names the case).
fn assert_refused_on_line_2(text: &str, name: &str, expected: &str, about: &str) {
    let error = flatray_io::parse(text, name.as_ref(), ".".as_ref()).unwrap_err();
    let message = error.to_string();
    assert!(message.contains(expected), "{about}: {message}");
    assert!(
        message.contains(&format!("{name}:2:")),
        "{about}: {message}"
    );
}

/// Dates that do not exist, times out of range and places off the globe
/// are refused where they stand.
#[test]
fn a_bad_date_time_or_place_is_refused_at_its_line_and_column() {
    let cases = [
        ("date: \"2026-02-30\"", "expected a day from 1 to 28"),
        ("date: \"21/12/2026\"", "expected a date as \"YYYY-MM-DD\""),
        ("time: \"25:00\"", "expected a time of day"),
        ("latitude: 95", "expected a latitude from -90 to 90"),
        ("longitude: -200", "expected a longitude from -180 to 180"),
        ("zone: 15", "expected a time zone from -14 to 14"),
    ];
    for (field, expected) in cases {
        let mut fields = vec![
            "date: \"2026-06-21\"",
            "time: \"12:00\"",
            "latitude: 40",
            "longitude: 3",
        ];
        let name = field.split(':').next().unwrap();
        fields.retain(|f| !f.starts_with(name));
        fields.push(field);
        let text = format!(
            "Scene(canvas: (8, 8), floor: Color((1, 1, 1)),\n  lights: [Sun({})])",
            fields.join(", ")
        );
        assert_refused_on_line_2(&text, "sun.ron", expected, field);
    }
}

/// The sky is drawn around whatever the scene holds: a wall far off the
/// canvas still stands between the sky and the floor.
#[test]
fn a_wall_far_off_the_canvas_still_shades_the_floor_from_the_sky() {
    // A long wall 500 units to the left, from far above to far below the
    // canvas: the floor sees the sky over less than the full turn.
    let with = scene(
        "Scene(canvas: (20, 20), floor: Color((1, 1, 1)),
               walls: [Wall(a: (-500, -5000), b: (-500, 5000))],
               lights: [Sky(intensity: 1)])",
    );
    let image = render(&with.scene, &options(1, 0)).image;
    let exact = |p: DVec2| {
        TAU - subtended_angle(
            p,
            &Segment::new(DVec2::new(-500.0, -5000.0), DVec2::new(-500.0, 5000.0)),
        )
    };
    let p = image.get(10, 10)[0] as f64;
    let (mean, _) = pixel_moments(10, 10, 16, exact);
    assert!((p - mean).abs() < 1e-3 * mean, "{p} against {mean}");
    assert!(p < TAU - 2.5, "{p}");
}

/// Walls as far out as a scene may hold them (1e15): the sky's frame
/// stays within that bound, and the render is finite and not negative,
/// with a profile too.
#[test]
fn a_sky_around_walls_at_the_coordinate_limit_loads_and_renders() {
    let at_the_limit = |sky: &str| {
        scene(&format!(
            "Scene(canvas: (16, 16), floor: Color((1, 1, 1)),
               walls: [Wall(a: (-1e15, 5), b: (1e15, 5.5)), Wall(a: (3, -1e15), b: (3, 1e15))],
               lights: [{sky}])"
        ))
    };
    let profiled = at_the_limit(&format!(
        "Sky(north: 33, profile: {})",
        profile_text(&SOUTH)
    ));
    let loaded = at_the_limit("Sky(intensity: 1)");
    for scene in [&loaded.scene, &profiled.scene] {
        let image = render(scene, &options(2, 2)).image;
        assert!(
            image
                .pixels
                .iter()
                .flatten()
                .all(|v| v.is_finite() && *v >= 0.0),
            "{:?}",
            image.pixels
        );
    }
    // The quarter right of the vertical wall and below the other sees a
    // quarter turn of sky directly: pi / 2.
    let direct = render(&loaded.scene, &options(2, 0)).image;
    let v = direct.get(10, 12)[0] as f64;
    assert!((v - TAU / 4.0).abs() < 0.05, "{v}");
}

/// A sky brighter to the south: azimuths (degrees clockwise from north)
/// and factors, as the scene file gives them.
const SOUTH: [(f64, f64); 4] = [(0.0, 0.4), (90.0, 1.0), (180.0, 1.8), (270.0, 0.9)];

fn profile_text(knots: &[(f64, f64)]) -> String {
    let pairs: Vec<String> = knots
        .iter()
        .map(|(a, f)| format!("({a:?}, {f:?})"))
        .collect();
    format!("[{}]", pairs.join(", "))
}

/// The profile's factor for light arriving from canvas direction `d` (y
/// down), with north `north` degrees clockwise from up: the file's
/// reading, written here apart from the renderer's.
fn factor(knots: &[(f64, f64)], north: f64, d: DVec2) -> f64 {
    let bearing = d.x.atan2(-d.y).to_degrees();
    let azimuth = (bearing - north).rem_euclid(360.0);
    let n = knots.len();
    for k in 0..n {
        let (a0, f0) = knots[k];
        let (mut a1, f1) = knots[(k + 1) % n];
        if a1 <= a0 {
            a1 += 360.0;
        }
        let mut t = azimuth;
        if t < a0 {
            t += 360.0;
        }
        if t >= a0 && t <= a1 {
            return f0 + (f1 - f0) * (t - a0) / (a1 - a0);
        }
    }
    unreachable!("{azimuth}")
}

/// `∫ factor` over the directions from `p` across `gap`, by the
/// trapezoid rule between the profile's knots (exact for a factor linear
/// between them).
fn profile_over(knots: &[(f64, f64)], north: f64, p: DVec2, gap: &Segment) -> f64 {
    let (a, b) = (gap.a - p, gap.b - p);
    let (a, b) = if a.perp_dot(b) < 0.0 { (b, a) } else { (a, b) };
    let sweep = a.perp_dot(b).atan2(a.dot(b));
    let start = a.y.atan2(a.x);
    let mut cuts = vec![0.0, sweep];
    for &(azimuth, _) in knots {
        // The knot's world angle: bearing north + azimuth, less 90 degrees.
        let world = (north + azimuth - 90.0).to_radians();
        let t = (world - start).rem_euclid(TAU);
        if t < sweep {
            cuts.push(t);
        }
    }
    cuts.sort_by(f64::total_cmp);
    let at = |t: f64| {
        let angle = start + t;
        factor(knots, north, DVec2::new(angle.cos(), angle.sin()))
    };
    cuts.windows(2)
        .map(|w| 0.5 * (at(w[0]) + at(w[1])) * (w[1] - w[0]))
        .sum()
}

/// Through an opening, a point receives the sky's radiance times its
/// profile integrated over the directions the opening shows it, exactly
/// at 4 spp, in rooms turned three ways with north turned with them or
/// not.
#[test]
fn a_sky_brighter_to_the_south_gives_its_profile_over_the_opening() {
    let samples = 4;
    for (degrees, north) in [(0.0, 0.0), (17.0, 47.0), (45.0, -160.0)] {
        let sky = format!(
            "Sky(intensity: 0.8, north: {north:?}, profile: {})",
            profile_text(&SOUTH)
        );
        let (text, gap) = room(degrees, None, &sky);
        let image = render(&scene(&text).scene, &options(samples, 0)).image;
        let checked = assert_inside_matches(&image, samples, degrees, |p| {
            [0.8 * profile_over(&SOUTH, north, p, &gap); 3]
        });
        assert!(checked > 1000, "only {checked} pixels");
    }
}

/// One knot of factor 1, at any azimuth and north, is the uniform sky:
/// the same image to a relative 1e-5 (the profile's integrals round
/// differently from the plain angle), by path tracing and by light
/// tracing, with bounces.
#[test]
fn a_profile_of_one_knot_is_the_uniform_sky() {
    let (uniform, _) = room(17.0, None, "Sky(intensity: 0.5)");
    let (flat, _) = room(
        17.0,
        None,
        "Sky(intensity: 0.5, north: 33, profile: [(120, 1)])",
    );
    for integrator in [
        flatray_tracer::Integrator::Path,
        flatray_tracer::Integrator::Light,
    ] {
        let mut options = options(2, 2);
        options.integrator = integrator;
        let a = render(&scene(&uniform).scene, &options).image;
        let b = render(&scene(&flat).scene, &options).image;
        for (p, q) in a.pixels.iter().zip(&b.pixels) {
            for c in 0..3 {
                assert!(
                    (p[c] - q[c]).abs() <= 1e-5 * p[c].abs().max(1e-3),
                    "{integrator:?}: {p:?} against {q:?}"
                );
            }
        }
    }
}

/// An open floor takes the sky's radiance times the profile's integral
/// over the whole circle, at every pixel, and that is the open floor
/// that the daylight factor divides by.
#[test]
fn an_open_floor_takes_the_profile_integrated_around_the_circle() {
    let loaded = scene(&format!(
        "Scene(canvas: (40, 30), origin: (-1e6, 3e5), floor: Color((1, 1, 1)),
               lights: [Sky(intensity: 0.3, north: 10, profile: {})])",
        profile_text(&SOUTH)
    ));
    // The trapezoid rule between the knots, around the circle.
    let around: f64 = (0..SOUTH.len())
        .map(|k| {
            let (a0, f0) = SOUTH[k];
            let (a1, f1) = SOUTH[(k + 1) % SOUTH.len()];
            0.5 * (f0 + f1) * (a1 - a0).rem_euclid(360.0).to_radians()
        })
        .sum();
    let exact = 0.3 * around;
    let image = render(&loaded.scene, &options(1, 2)).image;
    for p in &image.pixels {
        assert!(
            (p[0] as f64 - exact).abs() <= 1e-5 * exact,
            "{p:?} against {exact}"
        );
    }
    let open = loaded.sky.expect("a sky alone");
    assert!(
        (open - exact).abs() <= 1e-9 * exact,
        "{open} against {exact}"
    );
}

/// Under a profiled sky, light tracing and the default path tracing agree
/// per block within 5 standard errors over 24 seeds in a turned room with
/// a mirror (the sky in it in closed form), a rough mirror (next-event
/// estimation and path rays weighed against each other) and a glass prism
/// (its light through the glass by paths and aimed photons), with
/// bounces.
#[test]
fn light_tracing_agrees_with_path_tracing_under_a_profiled_sky() {
    let sky = format!(
        "Sky(intensity: 0.5, north: 25, profile: {})",
        profile_text(&SOUTH)
    );
    let (text, _) = room(17.0, None, &sky);
    let text = text
        .replace(
            "walls: [",
            "walls: [Wall(a: (20.0, 40.0), b: (30.0, 47.0), material: Mirror()), \
             Wall(a: (26.0, 28.0), b: (38.0, 26.0), material: Rough(roughness: 0.5)), ",
        )
        .replace(
            "lights: [",
            "glass: [Glass(points: [(36, 30), (46, 34), (38, 42)], ior: 1.5)], lights: [",
        );
    agree_per_block("profiled sky", &text, 700);
}

/// A profile's bad knots are refused where they stand.
#[test]
fn a_bad_profile_is_refused_at_its_line_and_column() {
    let cases = [
        ("[(0, -1)]", "expected a finite number >= 0"),
        (
            "[(0, 1), (360, 2)]",
            "two knots of a profile stand at one direction",
        ),
        ("[]", "at least one knot"),
        ("[(0, 1), (90)]", ""),
    ];
    for (profile, expected) in cases {
        let text = format!(
            "Scene(canvas: (8, 8), floor: Color((1, 1, 1)),\n  lights: [Sky(profile: {profile})])"
        );
        assert_refused_on_line_2(&text, "sky.ron", expected, profile);
    }
}

/// A profile of zeros loads, and `check` warns that the sky gives no
/// light; one factor above zero does not.
#[test]
fn a_profile_of_zeros_is_warned_of() {
    let text = |profile: &str| {
        format!(
            "Scene(canvas: (8, 8), floor: Color((1, 1, 1)),\n  lights: [Sky(profile: {profile})])"
        )
    };
    let dark = scene(&text("[(0, 0), (180, 0)]"));
    assert!(
        dark.warnings
            .iter()
            .any(|w| w.message.contains("profile is 0 at every azimuth") && w.line == 2),
        "{:?}",
        dark.warnings
    );
    let lit = scene(&text("[(0, 0), (180, 0.5)]"));
    assert!(lit.warnings.is_empty(), "{:?}", lit.warnings);
}
