//! Beams and lasers: parallel light from a segment, and a single ray.
//! A beam on an open floor gives its irradiance inside its strip and
//! nothing outside; a laser's track, straight and after a mirror, lights
//! exactly the pixels geometry says, by its power times the track's
//! length in each; and both integrators agree where their light bounces.

use flatray_geometry::{DVec2, clip_to_box};
use flatray_tests::{Agreement, pixel_moments, render, scene};
use flatray_tracer::{Integrator, RenderOptions};

/// The length of the segment `a b` inside the unit pixel at `(x, y)`.
fn length_in_pixel(a: DVec2, b: DVec2, x: u32, y: u32) -> f64 {
    let lo = DVec2::new(x as f64, y as f64);
    clip_to_box(a, b - a, 0.0, 1.0, lo, lo + DVec2::ONE)
        .map_or(0.0, |(t0, t1)| (t1 - t0).max(0.0) * (b - a).length())
}

/// A slanted beam on an open floor: every pixel's value is the
/// irradiance times the share of the pixel inside the strip downstream
/// of the segment (a fine midpoint rule), within 5 standard errors of a
/// jittered sample's spread; exactly the irradiance inside and 0
/// outside. Path tracing by default.
#[test]
fn a_beam_lights_its_strip_and_nothing_else() {
    let (e, a, b) = (0.8, DVec2::new(6.0, 10.0), DVec2::new(30.0, 4.0));
    let direction = DVec2::new(0.35, 1.0).normalize();
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)),
               lights: [Beam(a: ({}, {}), b: ({}, {}), direction: ({}, {}), intensity: {e})])",
        a.x, a.y, b.x, b.y, direction.x, direction.y
    );
    let loaded = scene(&text);
    let samples = 256;
    let options = {
        let mut options = RenderOptions::default();
        options.samples = samples;
        options
    };
    let image = render(&loaded.scene, &options).image;
    let lit = |p: DVec2| {
        let edge = b - a;
        let denom = direction.perp_dot(edge);
        let from_a = p - a;
        let t = from_a.perp_dot(edge) / denom;
        let u = direction.perp_dot(from_a) / denom;
        if t > 0.0 && (0.0..=1.0).contains(&u) {
            e
        } else {
            0.0
        }
    };
    let (mut inside, mut outside) = (0, 0);
    for y in 0..64 {
        for x in 0..64 {
            let (mean, spread) = pixel_moments(x, y, 64, lit);
            let value = image.get(x, y)[1] as f64;
            let se = spread / (samples as f64).sqrt();
            assert!(
                (value - mean).abs() <= 5.0 * se + 1e-6,
                "pixel ({x}, {y}): {value}, expected {mean}, 5 SE = {}",
                5.0 * se
            );
            if spread == 0.0 {
                if (mean - e).abs() < 1e-12 {
                    inside += 1;
                } else {
                    outside += 1;
                }
            }
        }
    }
    assert!(inside > 500 && outside > 500, "{inside} {outside}");
}

/// A laser crosses the floor, meets a mirror and ends at a black wall:
/// each pixel gets the laser's power times the length of the track (the
/// incoming and the reflected ray) inside it, and every other pixel
/// nothing, for the default render (the caustic pass) and for light
/// tracing. Every photon of a laser follows the same track, so the
/// values are exact to rounding.
#[test]
fn a_lasers_track_after_a_mirror_lands_where_geometry_says() {
    let (power, at) = (3.0, DVec2::new(4.5, 10.25));
    let direction = DVec2::new(1.0, 0.45).normalize();
    // A mirror across the room at a slant, and a black wall at the top.
    let (m0, m1) = (DVec2::new(50.0, 2.0), DVec2::new(58.0, 60.0));
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)),
               walls: [Wall(a: ({}, {}), b: ({}, {}), material: Mirror()),
                       Wall(a: (0, 62), b: (64, 62), material: Diffuse(albedo: (0, 0, 0)))],
               lights: [Laser(at: ({}, {}), direction: ({}, {}), intensity: {power})])",
        m0.x, m0.y, m1.x, m1.y, at.x, at.y, direction.x, direction.y
    );
    let loaded = scene(&text);
    // The track by hand: to the mirror, reflected, to the wall y = 62.
    let edge = m1 - m0;
    let t = (m0 - at).perp_dot(edge) / direction.perp_dot(edge);
    let hit = at + direction * t;
    let normal = edge.perp().normalize();
    let reflected = direction - 2.0 * direction.dot(normal) * normal;
    let end = hit + reflected * ((62.0 - hit.y) / reflected.y);
    assert!(reflected.y > 0.0 && end.x > 0.0 && end.x < 64.0, "{end}");
    for integrator in [Integrator::Path, Integrator::Light] {
        let options = {
            let mut options = RenderOptions::default();
            options.samples = 1;
            options.integrator = integrator;
            options
        };
        let image = render(&loaded.scene, &options).image;
        let mut lit = 0;
        for y in 0..64 {
            for x in 0..64 {
                let expected =
                    power * (length_in_pixel(at, hit, x, y) + length_in_pixel(hit, end, x, y));
                let value = image.get(x, y)[0] as f64;
                assert!(
                    (value - expected).abs() <= 1e-4 * power,
                    "{integrator:?}, pixel ({x}, {y}): {value}, expected {expected}"
                );
                lit += usize::from(expected > 0.0);
            }
        }
        assert!(lit > 80, "{lit}");
    }
}

/// A rotated, non-convex room of grey walls with a mirror, lit by a
/// slanted beam and a laser that ends on a diffuse wall: light and path
/// tracing agree on every block within 5 standard errors, with one and
/// two bounces (the laser's spot on a wall lights the room only by the
/// caustic pass's bins there).
#[test]
fn light_and_path_tracing_agree_on_beams_and_lasers() {
    let centre = DVec2::new(32.0, 32.0);
    let mut room: Vec<DVec2> = (0..6)
        .map(|k| {
            let a = 0.29 + std::f64::consts::TAU * k as f64 / 6.0;
            centre + 29.0 * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    room.insert(2, centre + DVec2::new(4.0, 12.0));
    let mut walls: Vec<String> = (0..room.len())
        .map(|k| {
            let (a, b) = (room[k], room[(k + 1) % room.len()]);
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}), material: Diffuse(albedo: (0.6, 0.6, 0.6)))",
                a.x, a.y, b.x, b.y
            )
        })
        .collect();
    walls[4] = walls[4].replace("Diffuse(albedo: (0.6, 0.6, 0.6))", "Mirror()");
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Beam(a: (20, 14), b: (34, 18), direction: (0.3, 1), intensity: 0.5),
                        Laser(at: (30.2, 40.7), direction: (-1, 0.2), intensity: 20)])",
        walls.join(", ")
    );
    let loaded = scene(&text);
    for bounces in [1, 2] {
        let agreement = Agreement {
            block: 8,
            runs: 24,
            first_seed: 6000 + bounces as u64,
            k: 5.0,
            min_blocks: 20,
        };
        let options = {
            let mut options = RenderOptions::default();
            options.samples = 8;
            options.bounces = bounces;
            options
        };
        agreement.check("beam and laser room", &loaded.scene, options, |_| true);
    }
}
