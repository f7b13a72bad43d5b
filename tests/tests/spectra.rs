//! Lamps with a spectrum. A lamp's lines leave a dispersive prism where
//! Snell's law at each line's index puts them; a lamp with a spectrum and
//! no dispersive glass renders its colour's image to the bit; light and
//! path tracing agree on a lamp of lines behind a dispersive prism; and a
//! 6504 K blackbody on a white floor is white.

use flatray_geometry::{DVec2, refract};
use flatray_tests::{Agreement, render, scene};
use flatray_tracer::optics::cauchy;
use flatray_tracer::spectrum::Lamp;
use flatray_tracer::{Integrator, RenderOptions, Rgb};

/// The prism of these tests: index 1.6 at 550 nm, Cauchy B 0.05.
const PRISM: [(f64, f64); 3] = [(150.0, 200.0), (250.0, 200.0), (200.0, 80.0)];
const IOR: f64 = 1.6;
const DISPERSION: f64 = 0.05;

/// Where a ray from `at` along `dir` leaves the prism, for wavelength
/// `nm`, by Snell's law at the two faces it crosses: the exit point and
/// direction.
fn through_prism(at: DVec2, dir: DVec2, nm: f64) -> (DVec2, DVec2) {
    let n = cauchy(IOR, DISPERSION, nm / 1000.0);
    let p: Vec<DVec2> = PRISM.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
    // The first face met, then the next face met from inside.
    let meet = |from: DVec2, d: DVec2, skip: Option<usize>| {
        (0..3)
            .filter(|&k| Some(k) != skip)
            .filter_map(|k| {
                let (a, b) = (p[k], p[(k + 1) % 3]);
                let e = b - a;
                let denom = d.perp_dot(e);
                let t = (a - from).perp_dot(e) / denom;
                let u = (a - from).perp_dot(d) / denom;
                (t > 1e-9 && (0.0..=1.0).contains(&u)).then_some((t, k))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .expect("the ray meets the prism")
    };
    let normal = |k: usize| (p[(k + 1) % 3] - p[k]).perp().normalize();
    let (t1, k1) = meet(at, dir, None);
    let x1 = at + dir * t1;
    let inside = refract(dir, normal(k1), 1.0 / n).expect("enters");
    let (t2, k2) = meet(x1, inside, Some(k1));
    let x2 = x1 + inside * t2;
    let out = refract(inside, normal(k2), n).expect("leaves");
    (x2, out)
}

fn prism_scene(light: &str) -> String {
    let points = PRISM
        .iter()
        .map(|(x, y)| format!("({x}, {y})"))
        .collect::<Vec<_>>()
        .join(", ");
    format!(
        "Scene(canvas: (400, 260), floor: Color((1, 1, 1)), lights: [{light}],
               glass: [Glass(points: [{points}], ior: {IOR}, dispersion: {DISPERSION})])"
    )
}

/// The brightness down column `x` of an image, row by row.
fn column(image: &flatray_tracer::Image, x: u32) -> Vec<f64> {
    (0..image.height)
        .map(|y| image.get(x, y).iter().map(|&c| c.abs() as f64).sum())
        .collect()
}

/// A laser of a sodium lamp's light and one of a mercury lamp's cross a
/// dispersive prism: down a column past the prism, each lamp's light
/// peaks where Snell's law at the index of each of its lines puts the
/// ray (sodium's D lines as one, mercury's 436 nm and 546 nm lines
/// apart), within a pixel; between the lines there is no light. The
/// default render (the caustic pass) and light tracing.
#[test]
fn a_lamps_lines_leave_a_prism_where_snells_law_puts_them() {
    let (at, dir) = (DVec2::new(20.0, 150.0), DVec2::new(1.0, -0.12).normalize());
    let x = 360;
    let y_at = |nm: f64| {
        let (p, d) = through_prism(at, dir, nm);
        p.y + d.y * ((x as f64 + 0.5 - p.x) / d.x)
    };
    for (lamp, lines) in [("Sodium", vec![589.2]), ("Mercury", vec![435.833, 546.074])] {
        let text = prism_scene(&format!(
            "Laser(at: ({}, {}), direction: ({}, {}), intensity: 10, spectrum: Lamp({lamp}))",
            at.x, at.y, dir.x, dir.y
        ));
        for integrator in [Integrator::Path, Integrator::Light] {
            let options = {
                let mut options = RenderOptions::default();
                options.samples = 8;
                options.bounces = 0;
                options.integrator = integrator;
                options
            };
            let image = render(&scene(&text).scene, &options).image;
            let profile = column(&image, x);
            for &nm in &lines {
                let expected = y_at(nm);
                // The centroid within three pixels of the prediction.
                let (lo, hi) = ((expected - 3.0) as usize, (expected + 4.0) as usize);
                let (sum, weighted) = (lo..hi).fold((0.0, 0.0), |(s, w), y| {
                    (s + profile[y], w + profile[y] * (y as f64 + 0.5))
                });
                assert!(sum > 0.0, "{lamp} {integrator:?}: no light near {expected}");
                let centroid = weighted / sum;
                assert!(
                    (centroid - expected).abs() < 1.0,
                    "{lamp} {nm} nm, {integrator:?}: light at {centroid}, Snell's law says {expected}"
                );
            }
            if lines.len() == 2 {
                // Dark between mercury's blue and green lines (but for its
                // faint 491.6 nm line).
                let (a, b) = (y_at(lines[0]), y_at(lines[1]));
                let faint = y_at(491.604);
                let between: f64 = ((a.min(b) + 3.0) as usize..(a.max(b) - 2.0) as usize)
                    .filter(|&y| (y as f64 + 0.5 - faint).abs() > 3.0)
                    .map(|y| profile[y])
                    .sum();
                let peak = profile.iter().cloned().fold(0.0, f64::max);
                assert!(
                    between < 0.01 * peak,
                    "{integrator:?}: {between} between the lines"
                );
            }
        }
    }
}

/// A lamp with a spectrum in a scene whose glass does not disperse (a
/// mirror, a pane and a clear prism) renders the same bits as a lamp of
/// its colour, with every default on: a spectrum costs nothing there.
#[test]
fn a_spectrum_without_dispersion_renders_its_colour_bit_for_bit() {
    let text = |light: &str| {
        format!(
            "Scene(canvas: (96, 64), floor: Color((0.9, 0.9, 0.9)),
                   walls: [Wall(a: (5, 5), b: (90, 8), material: Mirror()),
                           Wall(a: (60, 20), b: (62, 60), material: Transparent(tint: (0.8, 0.9, 1))),
                           Wall(a: (2, 60), b: (40, 62), material: Diffuse(albedo: (0.7, 0.5, 0.3)))],
                   lights: [{light}, Line(a: (80, 40), b: (85, 50), intensity: 0.5, spectrum: Lamp(Neon))],
                   glass: [Glass(points: [(30, 30), (45, 30), (38, 45)], ior: 1.5)],
                   render: (samples: 16, bounces: 2))"
        )
    };
    let spectral = scene(&text(
        "Point(at: (20, 20), intensity: 4, spectrum: Blackbody(2700))",
    ))
    .scene;
    // The same lights given their spectra's colours, with no spectrum.
    let mut parts = spectral.parts();
    for light in &mut parts.lights {
        assert!(light.spectrum.is_some());
        light.spectrum = None;
    }
    // The colours lie outside [0, 1] (luminance 1), which a scene file
    // cannot give: built without the checks.
    let rgb = parts.build_unchecked();
    let options = RenderOptions::default();
    let options = {
        let mut options = options;
        options.samples = 16;
        options.bounces = 2;
        options
    };
    let (a, b) = (render(&spectral, &options), render(&rgb, &options));
    assert_eq!(a.image.pixels, b.image.pixels);
    assert_eq!(a.stats.physics, b.stats.physics);
    // And a warm white: more red than blue.
    let colour = spectral.lights()[0].color;
    assert!(colour.x > colour.y && colour.y > colour.z, "{colour}");
}

/// A rotated room of black walls with a dispersive prism, a line lamp of
/// mercury's lines and a point lamp of neon's behind it: light tracing
/// and path tracing (with its caustic pass) agree on every block within
/// 5 standard errors, so the wavelengths paths draw, the lamps' values
/// at them and the photons' colours agree.
#[test]
fn light_and_path_tracing_agree_on_lamps_of_lines_behind_a_prism() {
    let centre = DVec2::new(32.0, 32.0);
    let room: Vec<DVec2> = (0..5)
        .map(|k| {
            let a = 0.43 + std::f64::consts::TAU * k as f64 / 5.0;
            centre + 30.0 * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    let walls = (0..5)
        .map(|k| {
            let (a, b) = (room[k], room[(k + 1) % 5]);
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}), material: Diffuse(albedo: (0, 0, 0)))",
                a.x, a.y, b.x, b.y
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{walls}],
               lights: [Line(a: (14, 24), b: (16, 34), intensity: 1.5, spectrum: Lamp(Mercury)),
                        Point(at: (20, 44), intensity: 3, spectrum: Lamp(Neon))],
               glass: [Glass(points: [(26, 20), (44, 30), (27, 42)], ior: 1.6, dispersion: 0.05)])"
    );
    let loaded = scene(&text);
    let agreement = Agreement {
        block: 8,
        runs: 24,
        first_seed: 8000,
        k: 5.0,
        min_blocks: 20,
    };
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 128;
        options.bounces = 0;
        options
    };
    // The blocks that hold a lamp: a point lamp's own pixel is its
    // kernel's clamp, which the two estimate alike but noisily.
    let lamps = [(2usize, 5usize), (1, 3), (1, 4), (2, 3), (2, 4)];
    agreement.check("prism and lamps of lines", &loaded.scene, options, |b| {
        !lamps.contains(&(b % 8, b / 8))
    });
}

/// A 6504 K blackbody lamp on a white floor lights it white to within
/// 5 % per channel (sRGB's white is D65, 0.005 off the Planckian locus),
/// and as bright as a white lamp of the same intensity to within 0.1 %.
#[test]
fn a_6504_kelvin_lamp_on_a_white_floor_is_white() {
    let text = |light: &str| {
        format!(
            "Scene(canvas: (32, 32), floor: Color((1, 1, 1)), lights: [Point(at: (16, 16), {light})])"
        )
    };
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 4;
        options
    };
    let warm = render(&scene(&text("spectrum: Blackbody(6504)")).scene, &options).image;
    let white = render(&scene(&text("intensity: 1")).scene, &options).image;
    let p = warm.get(5, 7);
    let w = white.get(5, 7);
    let rgb = Rgb::new(p[0] as f64, p[1] as f64, p[2] as f64) / w[1] as f64;
    assert!((rgb - Rgb::ONE).abs().max_element() < 0.05, "{rgb}");
    let luminance = 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z;
    assert!((luminance - 1.0).abs() < 1e-3, "{luminance}");
    // Lamp's lines are public: the lamps the format names.
    assert!(
        Lamp::Sodium
            .lines()
            .iter()
            .any(|&(nm, _)| (nm - 588.995).abs() < 1e-9)
    );
}
