//! Rough glass: a glass body whose edges spread the light they reflect and
//! refract. Roughness 0 is smooth glass to the bit; a furnace with a rough
//! glass body inside holds the closed form outside and inside the glass
//! (no light lost, and none trapped); light and path tracing agree on a
//! rotated room with a rough lens.

use std::f64::consts::TAU;

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, block_stats, render, scene};
use flatray_tracer::{Integrator, RenderOptions};

fn polygon_points(n: usize, centre: DVec2, radius: f64, turn: f64) -> Vec<DVec2> {
    (0..n)
        .map(|k| {
            let a = turn + TAU * k as f64 / n as f64;
            centre + radius * DVec2::new(a.cos(), a.sin())
        })
        .collect()
}

fn walls(points: &[DVec2], extra: &str) -> String {
    (0..points.len())
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % points.len()]);
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){extra})",
                a.x, a.y, b.x, b.y
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn glass(points: &[DVec2], extra: &str) -> String {
    let list = points
        .iter()
        .map(|p| format!("({:?}, {:?})", p.x, p.y))
        .collect::<Vec<_>>()
        .join(", ");
    format!("Glass(points: [{list}]{extra})")
}

/// Glass of roughness 0, in the scene format, renders the same bits as
/// glass that gives none, with every default on (the caustic pass, the
/// memo, the fast paths); a rough one differs.
#[test]
fn roughness_zero_is_smooth_glass_bit_for_bit() {
    let lens = std::fs::read_to_string(flatray_tests::workspace_root().join("scenes/lens.ron"))
        .unwrap_or_default();
    assert!(lens.contains("ior: 1.5)"));
    let options = {
        let mut options = RenderOptions::default();
        options.scale = 0.25;
        options.samples = 16;
        options
    };
    let smooth = render(&scene(&lens).scene, &options);
    let zero = lens.replace("ior: 1.5)", "ior: 1.5, roughness: 0)");
    assert_eq!(
        render(&scene(&zero).scene, &options).image.pixels,
        smooth.image.pixels
    );
    let rough = lens.replace("ior: 1.5)", "ior: 1.5, roughness: 0.2)");
    assert_ne!(
        render(&scene(&rough).scene, &options).image.pixels,
        smooth.image.pixels
    );
}

/// The flatland furnace around rough glass: every wall of a heptagon
/// emits radiance `L` and reflects nothing, and a rotated square of clear
/// rough glass (index 1.5) stands inside. A floor point outside the glass
/// receives `2 pi L`, and one inside `1.5 x 2 pi L` (in the plane `L / n`
/// is invariant along a ray): exactly when every event keeps the light it
/// carries and the glass traps none. Smooth glass traps the directions
/// that meet each face of a square beyond the critical angle, which no
/// light from outside reaches, so inside it is darker; rough glass turns
/// them out. Both integrators, on the mean over the blocks wholly outside
/// and wholly inside the glass, within 3 standard errors over
/// independent seeds.
#[test]
fn a_furnace_around_rough_glass_loses_and_traps_nothing() {
    let l_e = 0.25;
    let centre = DVec2::new(32.0, 32.0);
    let room = walls(
        &polygon_points(7, centre, 30.0, 0.3),
        &format!(", material: Diffuse(albedo: (0, 0, 0)), emit: (intensity: {l_e})"),
    );
    // A square of half-diagonal 17, turned: blocks of 8 within 10 of the
    // centre are inside it.
    let square = polygon_points(4, centre, 17.0, 0.2);
    let inside_glass = |p: DVec2| {
        (0..4).all(|k| {
            let (a, b) = (square[k], square[(k + 1) % 4]);
            (b - a).perp_dot(p - a) > 0.0
        })
    };
    let block = 8;
    let corners = |b: usize| {
        let (x, y) = ((b % 8 * block) as f64, (b / 8 * block) as f64);
        [(0.0, 0.0), (8.0, 0.0), (0.0, 8.0), (8.0, 8.0)].map(|(dx, dy)| DVec2::new(x + dx, y + dy))
    };
    let inner: Vec<usize> = (0..64)
        .filter(|&b| corners(b).iter().all(|&p| inside_glass(p)))
        .collect();
    let outer: Vec<usize> = (0..64)
        .filter(|&b| {
            corners(b)
                .iter()
                .all(|&p| !inside_glass(p) && p.distance(centre) <= 26.5)
        })
        .collect();
    assert!(inner.len() >= 4 && outer.len() >= 8, "{inner:?} {outer:?}");
    let expected = TAU * l_e;
    for roughness in [0.1, 0.3, 0.7] {
        let text = format!(
            "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{room}], glass: [{}])",
            glass(&square, &format!(", ior: 1.5, roughness: {roughness}"))
        );
        let loaded = scene(&text);
        for integrator in [Integrator::Path, Integrator::Light] {
            let options = {
                let mut options = RenderOptions::default();
                options.samples = 4;
                options.bounces = 0;
                options.specular = 400;
                options.integrator = integrator;
                options
            };
            let stats = block_stats(&loaded.scene, options, block as u32, 16, 9000);
            for (blocks, factor, name) in [(&outer, 1.0, "outside"), (&inner, 1.5, "inside")] {
                let per = 3.0 * (block * block) as f64 * blocks.len() as f64;
                let mean = blocks.iter().map(|&b| stats[b].0).sum::<f64>() / per;
                // Paths cross blocks: the blocks' errors are added, not
                // assumed independent, which only widens the bound.
                let se = blocks.iter().map(|&b| stats[b].1).sum::<f64>() / per;
                assert!(
                    (mean - factor * expected).abs() <= 3.0 * se + 1e-6 * expected,
                    "{integrator:?}, roughness {roughness}, {name}: {mean}, expected {}, 3 SE = {}",
                    factor * expected,
                    3.0 * se
                );
            }
        }
    }
}

/// A rotated, non-convex room with a rough biconvex lens, a lamp and a
/// line light: light and path tracing agree on every block within 5
/// standard errors.
#[test]
fn light_and_path_tracing_agree_with_a_rough_lens() {
    let centre = DVec2::new(32.0, 32.0);
    let mut room: Vec<DVec2> = polygon_points(6, centre, 30.0, 0.37);
    // A notch: the room is not convex.
    room.insert(3, centre + DVec2::new(-6.0, 9.0));
    let room = walls(&room, ", material: Diffuse(albedo: (0.6, 0.6, 0.6))");
    // A biconvex lens of two arcs of radius 18 and half-height 12, its
    // axis turned by 0.5 rad.
    let axis = DVec2::new(0.5f64.cos(), 0.5f64.sin());
    let (lens_centre, radius, half) = (DVec2::new(34.0, 30.0), 18.0f64, 12.0f64);
    let bulge = |v: f64| (radius * radius - v * v).sqrt() - (radius * radius - half * half).sqrt();
    let mut lens = Vec::new();
    for k in 0..12 {
        let v = -half + 2.0 * half * k as f64 / 12.0;
        lens.push(DVec2::new(bulge(v), v));
    }
    for k in 0..12 {
        let v = half - 2.0 * half * k as f64 / 12.0;
        lens.push(DVec2::new(-bulge(v), v));
    }
    let lens: Vec<DVec2> = lens.iter().map(|&p| lens_centre + axis.rotate(p)).collect();
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{room}],
               lights: [Point(at: (20.3, 22.6), intensity: 2.0),
                        Line(a: (44, 50), b: (50, 44), intensity: 0.3)],
               glass: [{}])",
        glass(&lens, ", ior: 1.5, roughness: 0.3")
    );
    let loaded = scene(&text);
    let block = 8;
    let light_block = (22 / block * (64 / block) + 20 / block) as usize;
    let agreement = Agreement {
        block,
        runs: 24,
        first_seed: 4000,
        k: 5.0,
        min_blocks: 20,
    };
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 8;
        options.bounces = 1;
        options
    };
    agreement.check("rough lens room", &loaded.scene, options, |b| {
        b != light_block
    });
}
