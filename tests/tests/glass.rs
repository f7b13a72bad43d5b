//! Glass: Snell and Fresnel against closed forms, dispersion through a
//! prism, and the two integrators agreeing where glass is lit by a line
//! light.

use flatray_geometry::{DVec2, Ray, Segment, intersect, reflect, refract};
use flatray_tests::{TempDir, flatray, scene};
use flatray_tracer::optics::{cauchy, choose, fresnel};
use flatray_tracer::sampling::Stream;
use flatray_tracer::{Integrator, MemoOptions, RenderOptions, Scene};

#[test]
fn a_ray_through_a_parallel_slab_leaves_parallel_and_offset_by_the_closed_form() {
    // A slab of index 1.5 and thickness 2 between y = 0 and y = -2.
    let (n, thickness) = (1.5, 2.0);
    let top = Segment::new(DVec2::new(-100.0, 0.0), DVec2::new(100.0, 0.0));
    let bottom = Segment::new(
        DVec2::new(-100.0, -thickness),
        DVec2::new(100.0, -thickness),
    );
    for degrees in [5.0f64, 20.0, 40.0, 70.0] {
        let i = degrees.to_radians();
        let d = DVec2::new(i.sin(), -i.cos());
        let origin = DVec2::new(0.0, 3.0);
        let entry = intersect(&Ray::new(origin, d), &top).unwrap();
        let p1 = origin + d * entry.t;
        let inside = refract(d, top.normal(), 1.0 / n).unwrap();
        let exit = intersect(&Ray::new(p1, inside), &bottom).unwrap();
        let p2 = p1 + inside * exit.t;
        let out = refract(inside, bottom.normal(), n).unwrap();
        // Parallel to how it entered.
        assert!((out - d).length() < 1e-12, "{degrees}: {out} vs {d}");
        // Offset: t sin(i - r) / cos(r), r the refraction angle.
        let r = (i.sin() / n).asin();
        let expected = thickness * (i - r).sin() / r.cos();
        let offset = flatray_geometry::cross(d, p2 - p1).abs();
        assert!(
            (offset - expected).abs() < 1e-12,
            "{degrees}: offset {offset}, expected {expected}"
        );
    }
}

#[test]
fn edges_reflect_the_fresnel_fraction_and_conserve_power() {
    // Many choices at one edge: the reflected fraction is F within 5
    // standard errors, and each outcome carries the whole power, so the
    // power leaving equals the power arriving.
    let normal = DVec2::new(0.0, 1.0);
    for (n1, n2, degrees) in [
        (1.0, 1.5, 0.0),
        (1.0, 1.5, 60.0),
        (1.5, 1.0, 30.0),
        (1.0, 1.5, 85.0),
    ] {
        let a = f64::to_radians(degrees);
        let d = DVec2::new(a.sin(), -a.cos());
        let f = fresnel(n1, n2, d.dot(normal));
        let mut stream = Stream::new(3, 1, 4);
        let draws = 200_000;
        let mut reflected = 0usize;
        for _ in 0..draws {
            let (out, r) = choose(n1, n2, d, normal, stream.uniform());
            assert!((out.length() - 1.0).abs() < 1e-12);
            if r {
                reflected += 1;
                assert!((out - reflect(d, normal)).length() < 1e-12);
            } else {
                assert!(out.y < 0.0, "refracted light goes on through");
            }
        }
        let fraction = reflected as f64 / draws as f64;
        let se = (f * (1.0 - f) / draws as f64).sqrt();
        assert!(
            (fraction - f).abs() <= 5.0 * se + 1e-12,
            "{n1} -> {n2} at {degrees}: {fraction} vs {f}"
        );
        if degrees == 0.0 {
            assert!((f - ((n1 - n2) / (n1 + n2)).powi(2)).abs() < 1e-15);
        }
    }
    // Beyond the critical angle everything reflects.
    let a = 45.0f64.to_radians();
    let (_, r) = choose(1.5, 1.0, DVec2::new(a.sin(), -a.cos()), normal, 0.999_999);
    assert!(r);
}

#[test]
fn a_prism_bends_two_wavelengths_by_snell_with_cauchy() {
    // An equilateral prism, apex up; a ray at 50 degrees to the first
    // face's normal. The minimum-deviation formula generalises to
    // deviation = i + e - A with sin(r1) = sin(i) / n, r2 = A - r1,
    // sin(e) = n sin(r2).
    let apex = 60f64.to_radians();
    let (ior, b) = (1.6, 0.05);
    let left = Segment::new(DVec2::new(0.0, 0.0), DVec2::new(0.5, 3f64.sqrt() / 2.0));
    let right = Segment::new(DVec2::new(0.5, 3f64.sqrt() / 2.0), DVec2::new(1.0, 0.0));
    let mut exits = Vec::new();
    for wavelength in [0.45, 0.65] {
        let n = cauchy(ior, b, wavelength);
        let outward = -left.normal() * left.normal().dot(DVec2::new(0.5, 0.3) - left.a).signum();
        let i = 50f64.to_radians();
        // Incoming direction making angle i with the inward normal.
        let inward = -outward;
        // Tilted towards the prism's base, so the ray reaches the right
        // face below the apex.
        let tangent = DVec2::new(-inward.y, inward.x);
        let d = inward * i.cos() + tangent * i.sin();
        let hit_point = left.point_at(0.5);
        let inside = refract(d, left.normal(), 1.0 / n).unwrap();
        let exit = intersect(&Ray::new(hit_point, inside), &right).unwrap();
        let out = refract(inside, right.normal(), n).unwrap();
        let deviation = d.angle_to(out).abs();
        let r1 = (i.sin() / n).asin();
        let r2 = apex - r1;
        let e = (n * r2.sin()).asin();
        let expected = i + e - apex;
        assert!(
            (deviation - expected).abs() < 1e-9,
            "{wavelength}: {deviation} vs {expected}"
        );
        assert!(exit.t > 0.0);
        exits.push(deviation);
    }
    // Blue bends more than red.
    assert!(exits[0] > exits[1] + 0.01, "{exits:?}");
}

const BLOCK: u32 = 8;
const RUNS: u64 = 24;

fn block_stats(scene: &Scene, options: RenderOptions) -> Vec<(f64, f64)> {
    flatray_tests::block_stats(scene, options, BLOCK, RUNS, 500)
}

/// Glass lit by a line light: no light path is delta at both ends, so path
/// tracing (through emission met after glass) and light tracing must agree,
/// block by block, within 5 standard errors (t with 23 degrees of freedom).
#[test]
fn light_and_path_tracing_agree_on_glass_lit_by_a_line_light() {
    let text = "Scene(canvas: (64, 48), floor: Color((1, 1, 1)),
        walls: [Wall(a: (2, 44), b: (62, 44), material: Diffuse(albedo: (0.6, 0.6, 0.6)))],
        lights: [Line(a: (8, 6), b: (20, 4), intensity: 1.0)],
        glass: [Glass(points: [(24, 12), (44, 14), (40, 34), (26, 30)], ior: 1.5, absorption: (0.0, 0.02, 0.05), dispersion: 0.01)])";
    let loaded = scene(text);
    let options = |integrator| {
        let mut options = RenderOptions::default();
        options.samples = 8;
        options.bounces = 4;
        options.integrator = integrator;
        options.memo = MemoOptions::default();
        options.memo.enabled = false;
        options
    };
    let light = block_stats(&loaded.scene, options(Integrator::Light));
    let path = block_stats(&loaded.scene, options(Integrator::Path));
    // The blocks the light crosses differ by definition at the light.
    let mut checked = 0;
    for (b, ((ml, sl), (mp, sp))) in light.iter().zip(&path).enumerate() {
        let (bx, by) = (b as u32 % 8, b as u32 / 8);
        if by == 0 && bx <= 2 {
            continue;
        }
        let se = (sl * sl + sp * sp).sqrt();
        assert!(
            (ml - mp).abs() <= 5.0 * se + 1e-9,
            "block {b}: light {ml}, path {mp}, 5 SE = {}",
            5.0 * se
        );
        checked += 1;
    }
    assert!(checked > 40);
}

#[test]
fn bad_glass_is_refused_with_a_location() {
    let dir = TempDir::new("glass");
    for (text, expected) in [
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n glass: [Glass(points: [(1, 1), (5, 1)])])",
            "at least 3 points",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n glass: [Glass(points: [(1, 1), (5, 5), (5, 1), (1, 5)])])",
            "intersects itself",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n glass: [Glass(points: [(1, 1), (5, 1), (3, 4)], ior: 0.5)])",
            "index of refraction",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n glass: [Glass(points: [(1, 1), (5, 1), (3, 4)]),\n Glass(points: [(2, 2), (6, 2), (4, 5)])])",
            "must not overlap",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)), walls: [Wall(a: (0, 1), b: (9, 1))],\n glass: [Glass(points: [(1, 1), (5, 1), (3, 4)])])",
            "lies along wall 0",
        ),
        (
            // Along a tilted wall, off its line by the rounding of the
            // decimals only.
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)), walls: [Wall(a: (1, 1), b: (8, 4))],\n glass: [Glass(points: [(2.4, 1.6), (5.2, 2.8), (3, 5)])])",
            "lies along wall 0",
        ),
    ] {
        let path = dir.write("bad.ron", text);
        let run = flatray(&["check", path.to_str().unwrap()]);
        assert_eq!(run.code, 2, "{run:?}");
        assert!(
            run.stderr.contains(":2:") || run.stderr.contains(":3:"),
            "{}",
            run.stderr
        );
        assert!(run.stderr.contains(expected), "{}", run.stderr);
    }
}
