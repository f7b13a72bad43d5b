//! Closed forms 1 to 3 of `model.md` for direct light, read back from the
//! EXR output. Each statistical check states its tolerance in standard
//! errors of the pixel's jittered mean, computed by quadrature.

use flatray_geometry::{DVec2, Segment};
use flatray_tests::{TempDir, pixel_moments, render, scene};
use flatray_tracer::RenderOptions;
use flatray_tracer::sampling::subtended_angle;

/// Renders `text` to EXR and reads it back.
fn render_to_exr(text: &str, options: RenderOptions) -> flatray_tracer::Image {
    let loaded = scene(text);
    let rendered = render(&loaded.scene, &options);
    let dir = TempDir::new("direct");
    let path = dir.path().join("out.exr");
    flatray_io::write_exr(&rendered.image, &path).unwrap();
    let back = flatray_io::read_exr(&path).unwrap();
    assert_eq!(
        back, rendered.image,
        "EXR must store the linear values untouched"
    );
    back
}

/// Every pixel whose centre `skip` does not exclude matches `exact` within
/// 5 standard errors of its mean over `samples` jittered points, and at
/// least `min_checked` pixels are checked.
fn assert_matches(
    image: &flatray_tracer::Image,
    samples: u32,
    skip: impl Fn(DVec2) -> bool,
    min_checked: usize,
    exact: impl Fn(DVec2) -> f64,
) {
    let mut checked = 0;
    for y in 0..image.height {
        for x in 0..image.width {
            if skip(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                continue;
            }
            let (mean, sd) = pixel_moments(x, y, 24, &exact);
            let se = sd / (samples as f64).sqrt();
            let got = image.get(x, y)[0] as f64;
            // f32 storage and quadrature add a small relative error.
            let tolerance = 5.0 * se + 1e-5 * mean.abs();
            assert!(
                (got - mean).abs() <= tolerance,
                "pixel ({x}, {y}): got {got}, exact mean {mean}, 5 SE = {}",
                5.0 * se
            );
            checked += 1;
        }
    }
    assert!(checked >= min_checked, "only {checked} pixels checked");
}

#[test]
fn closed_form_1_point_light_gives_the_mean_of_one_over_r() {
    let samples = 64;
    let light = DVec2::new(40.3, 31.7);
    let image = render_to_exr(
        "Scene(canvas: (80, 64), floor: Color((1, 1, 1)),
               lights: [Point(at: (40.3, 31.7), intensity: 2.5)])",
        {
            let mut options = RenderOptions::default();
            options.samples = samples;
            options.bounces = 0;
            options
        },
    );
    assert_matches(
        &image,
        samples,
        |p| p.distance(light) < 2.0,
        1000,
        |p| 2.5 / p.distance(light).max(0.5),
    );
}

#[test]
fn closed_form_1_holds_with_bounces_when_nothing_reflects() {
    let samples = 16;
    let light = DVec2::new(10.5, 50.25);
    let image = render_to_exr(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)),
               lights: [Point(at: (10.5, 50.25))])",
        {
            let mut options = RenderOptions::default();
            options.samples = samples;
            options.bounces = 3;
            options
        },
    );
    assert_matches(
        &image,
        samples,
        |p| p.distance(light) < 2.0,
        1000,
        |p| 1.0 / p.distance(light).max(0.5),
    );
}

#[test]
fn closed_form_2_line_light_gives_intensity_times_subtended_angle() {
    let samples = 32;
    let light = Segment::new(DVec2::new(20.0, 30.5), DVec2::new(55.0, 22.0));
    let image = render_to_exr(
        "Scene(canvas: (80, 64), floor: Color((1, 1, 1)),
               lights: [Line(a: (20, 30.5), b: (55, 22), intensity: 0.7)])",
        {
            let mut options = RenderOptions::default();
            options.samples = samples;
            options.bounces = 0;
            options
        },
    );
    // Skip pixels the light crosses, where the subtended angle jumps.
    let near_light = |p: DVec2| {
        let along = (p - light.a).dot(light.edge()) / light.edge().length_squared();
        p.distance(light.point_at(along.clamp(0.0, 1.0))) < 2.0
    };
    assert_matches(&image, samples, near_light, 4000, |p| {
        0.7 * subtended_angle(p, &light)
    });
}

/// A closed square room whose corners are shared endpoints at coordinates
/// no binary float holds exactly, rotated by `angle`, with a point light
/// and a line light outside.
fn closed_room(angle_degrees: f64) -> String {
    let centre = DVec2::new(50.1, 50.3);
    let (s, c) = angle_degrees.to_radians().sin_cos();
    let corner = |x: f64, y: f64| centre + DVec2::new(c * x - s * y, s * x + c * y);
    let k = [
        corner(-30.1, -30.7),
        corner(30.3, -30.7),
        corner(30.3, 30.9),
        corner(-30.1, 30.9),
    ];
    let walls: Vec<String> = (0..4)
        .map(|i| {
            let (a, b) = (k[i], k[(i + 1) % 4]);
            format!("Wall(a: ({:?}, {:?}), b: ({:?}, {:?}))", a.x, a.y, b.x, b.y)
        })
        .collect();
    format!(
        "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: (2.3, 3.1), intensity: 100.0),
                        Line(a: (97, 2), b: (99, 98), intensity: 100.0),
                        Directional(direction: (0.3, 1.0), intensity: 100.0)])",
        walls.join(", ")
    )
}

#[test]
fn closed_form_3_no_direct_light_leaks_into_a_closed_room() {
    for angle in [0.0, 17.0, 45.0] {
        let loaded = scene(&closed_room(angle));
        let rendered = render(&loaded.scene, &{
            let mut options = RenderOptions::default();
            options.samples = 8;
            options.bounces = 0;
            options
        });
        let inside = |x: u32, y: u32| {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            // Well inside the square in its own frame.
            let (s, c) = (-angle).to_radians().sin_cos();
            let q = p - DVec2::new(50.1, 50.3);
            let local = DVec2::new(c * q.x - s * q.y, s * q.x + c * q.y);
            local.x.abs() < 28.0 && local.y.abs() < 28.0
        };
        let mut inside_count = 0;
        let mut outside_lit = 0;
        for y in 0..100 {
            for x in 0..100 {
                let v = rendered.image.get(x, y);
                if inside(x, y) {
                    inside_count += 1;
                    assert_eq!(v, [0.0; 3], "angle {angle}: light leaked into ({x}, {y})");
                } else if v[0] > 0.0 {
                    outside_lit += 1;
                }
            }
        }
        assert!(inside_count > 2500);
        assert!(outside_lit > 1000, "the lights must light the outside");
    }
}

/// The part of the unit pixel at `(x, y)` on the side of the line through
/// `a` and `b` where `cross(b - a, p - a) > 0`: the square clipped by the
/// half-plane (Sutherland-Hodgman), its area by the shoelace formula.
fn area_left_of(x: u32, y: u32, a: DVec2, b: DVec2) -> f64 {
    let (x, y) = (x as f64, y as f64);
    let square = [
        DVec2::new(x, y),
        DVec2::new(x + 1.0, y),
        DVec2::new(x + 1.0, y + 1.0),
        DVec2::new(x, y + 1.0),
    ];
    let side = |p: DVec2| (b - a).perp_dot(p - a);
    let mut clipped = Vec::new();
    for k in 0..4 {
        let (p, q) = (square[k], square[(k + 1) % 4]);
        let (sp, sq) = (side(p), side(q));
        if sp > 0.0 {
            clipped.push(p);
        }
        if (sp > 0.0) != (sq > 0.0) {
            clipped.push(p + (q - p) * (sp / (sp - sq)));
        }
    }
    let n = clipped.len();
    (0..n)
        .map(|k| clipped[k].perp_dot(clipped[(k + 1) % n]))
        .sum::<f64>()
        .abs()
        * 0.5
}

/// The floor memo's direct light is exact at shadow edges: a point
/// light's mean over each pixel's square is computed, not sampled
/// (`estimators::square`), so the relative RMS error over the pixels a shadow
/// edge crosses is the image's rounding at any number of samples, one
/// included. A point light of constant falloff behind a mirror, its
/// shadow edge at an odd angle: the image is exactly the lit fraction of
/// each pixel (a path off the mirror finds no light), clipped by hand.
#[test]
fn the_floor_memo_is_exact_at_shadow_edges() {
    let (light, end) = (DVec2::new(10.3, 30.2), DVec2::new(30.0, 40.9));
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), falloff: Constant,
           walls: [Wall(a: (30, -1000), b: ({:?}, {:?}), material: Mirror())],
           lights: [Point(at: ({:?}, {:?}))])",
        end.x, end.y, light.x, light.y
    );
    let loaded = scene(&text);
    // Beyond the wall, the lit part is below the line from the light
    // through the wall's end (y grows down).
    let lit = |x: u32, y: u32| area_left_of(x, y, light, end);
    let edge: Vec<(u32, u32, f64)> = (0..64)
        .flat_map(|y| (31..64).map(move |x| (x, y)))
        .map(|(x, y)| (x, y, lit(x, y)))
        .filter(|&(_, _, f)| f > 0.02 && f < 0.98)
        .collect();
    assert!(edge.len() > 30, "{} edge pixels", edge.len());
    let error = |samples: u32| {
        let options = {
            let mut options = RenderOptions::default();
            options.samples = samples;
            options.bounces = 1;
            options.seed = 5;
            options
        };
        let image = render(&loaded.scene, &options).image;
        let (mut squares, mut total) = (0.0, 0.0);
        for &(x, y, exact) in &edge {
            squares += (image.get(x, y)[0] as f64 - exact).powi(2);
            total += exact;
        }
        (squares / edge.len() as f64).sqrt() / (total / edge.len() as f64)
    };
    let errors: Vec<f64> = [1, 4, 64].into_iter().map(error).collect();
    // The image is f32: about 6e-8 of rounding.
    assert!(
        errors.iter().all(|&e| e < 1e-6),
        "relative RMS error at 1, 4, 64 spp: {errors:?}"
    );
}
