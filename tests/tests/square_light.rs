//! Points, spots and suns averaged over each pixel's square in closed form
//! (`docs/model.md`, "Direct light in closed form"): a shadow edge across
//! a pixel leaves lit exactly the area it should, at one sample a pixel
//! and whatever the seed; and path tracing, which takes the squares, agrees
//! with light tracing, which never does, block by block (5 standard errors
//! over fixed seeds), in a turned, non-convex room under every falloff.

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, options, render, scene};
use flatray_tracer::Integrator;

/// A point light at (1, 1) under the constant kernel, and a wall from
/// (3, 2) to (3, 6): the lower edge of its shadow, the ray `y - 1 =
/// (x - 1) / 2`, crosses the pixel `[6, 7] x [3, 4]` and leaves lit the
/// part below it, of area `int_5^6 (u / 2 - 2) du = 0.75` (with `u = x -
/// 1`). The pixel `[6, 7] x [1, 2]` is lit whole. At one sample a pixel,
/// the first takes 0.75 of the second, to the image's rounding, from any
/// seed; and behind a pane of tint 0.4, `0.75 + 0.25 * 0.4`.
#[test]
fn a_shadow_edge_across_a_pixel_leaves_lit_the_area_by_hand() {
    for (material, expected) in [
        ("", 0.75),
        (", material: Transparent(tint: (0.4, 0.4, 0.4))", 0.85),
    ] {
        let scene = scene(&format!(
            "Scene(canvas: (12, 8), floor: Color((1, 1, 1)), falloff: Constant,
                   walls: [Wall(a: (3, 2), b: (3, 6){material})],
                   lights: [Point(at: (1, 1), intensity: 1.0)])"
        ))
        .scene;
        let images: Vec<_> = [1, 2, 3]
            .into_iter()
            .map(|seed| render(&scene, &options(1, 0, seed)).image)
            .collect();
        for image in &images {
            let at = |x: u32, y: u32| image.get(x, y)[1] as f64;
            let ratio = at(6, 3) / at(6, 1);
            assert!(
                (ratio - expected).abs() < 1e-6,
                "{material}: {ratio} against {expected}"
            );
            assert_eq!(image.pixels, images[0].pixels, "{material}");
        }
    }
}

/// A room turned by 0.3 radians, non-convex (a stub into it), with a
/// window of tinted glass in one wall and a gap in another; a point light,
/// a spot and the sun shining in at the gap; under `falloff`.
fn room(falloff: &str) -> flatray_tracer::Scene {
    let (s, c) = 0.3f64.sin_cos();
    let centre = DVec2::new(24.0, 24.0);
    let at = |x: f64, y: f64| centre + DVec2::new(c * x - s * y, s * x + c * y);
    let wall = |a: DVec2, b: DVec2, material: &str| {
        format!(
            "Wall(a: ({}, {}), b: ({}, {}){material})",
            a.x, a.y, b.x, b.y
        )
    };
    let walls = [
        wall(at(-18.0, -18.0), at(18.0, -18.0), ""),
        wall(at(18.0, -18.0), at(18.0, -4.0), ""),
        wall(
            at(18.0, -4.0),
            at(18.0, 6.0),
            ", material: Transparent(tint: (0.9, 0.5, 0.2))",
        ),
        wall(at(18.0, 6.0), at(18.0, 18.0), ""),
        wall(at(18.0, 18.0), at(-18.0, 18.0), ""),
        // A gap from y = 4 to y = 10 in the left wall lets the sun in.
        wall(at(-18.0, 18.0), at(-18.0, 10.0), ""),
        wall(at(-18.0, 4.0), at(-18.0, -18.0), ""),
        // The stub, and a free wall at an odd angle.
        wall(at(-18.0, -2.0), at(-4.0, -2.0), ""),
        wall(at(2.0, 6.0), at(9.0, 11.0), ""),
    ];
    let (p, spot, direction) = (
        at(6.0, -10.0),
        at(-12.0, 12.0),
        at(1.0, -0.4) - at(0.0, 0.0),
    );
    let sun = at(1.0, 0.2) - at(0.0, 0.0);
    scene(&format!(
        "Scene(canvas: (48, 48), floor: Color((0.8, 0.8, 0.8)), falloff: {falloff},
               walls: [{}],
               lights: [Point(at: ({}, {}), intensity: 3.0),
                        Spot(at: ({}, {}), direction: ({}, {}), cone: 40, softness: 15, intensity: 4.0),
                        Directional(direction: ({}, {}), intensity: 0.2)])",
        walls.join(", "),
        p.x,
        p.y,
        spot.x,
        spot.y,
        direction.x,
        direction.y,
        sun.x,
        sun.y,
    ))
    .scene
}

/// Path tracing (points, spots and the sun over each pixel's square) and
/// light tracing agree block by block, with the direct light alone and
/// with two bounces, under every falloff.
#[test]
fn path_tracing_with_the_squares_agrees_with_light_tracing() {
    for falloff in [
        "Flatland",
        "Window(range: 40.0)",
        "InverseSquare",
        "Constant",
    ] {
        let scene = room(falloff);
        for bounces in [0, 2] {
            let agreement = Agreement {
                block: 8,
                runs: 12,
                first_seed: 500,
                k: 5.0,
                min_blocks: 20,
            };
            let mut options = options(8, bounces, 0);
            options.scale = 1.0;
            options.integrator = Integrator::Path;
            agreement.check(
                &format!("{falloff}, D = {bounces}"),
                &scene,
                options,
                |_| true,
            );
        }
    }
}
