//! Line and circle lights seen through one glass edge in closed form
//! (`docs/model.md`, "Lights through one glass edge"): path tracing, which
//! takes them at every receiver inside glass and skips them on path rays
//! right after that one refraction, agrees with light tracing, which never
//! does, block by block (5 standard errors over fixed seeds), in a turned,
//! non-convex glass body with a wall in the way, under two falloffs.

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, options, scene};
use flatray_tracer::{Integrator, Plan};

/// A glass arrow (non-convex, seven edges) turned by 0.4 radians, a
/// circle light and a one-sided line light outside it, and an opaque wall
/// between the circle and part of the glass; under `falloff`.
fn arrow(falloff: &str) -> flatray_tracer::Scene {
    let (s, c) = 0.4f64.sin_cos();
    let centre = DVec2::new(24.0, 26.0);
    let at = |x: f64, y: f64| centre + DVec2::new(c * x - s * y, s * x + c * y);
    let points: Vec<String> = [
        (-14.0, -5.0),
        (2.0, -5.0),
        (2.0, -12.0),
        (15.0, 0.0),
        (2.0, 12.0),
        (2.0, 5.0),
        (-14.0, 5.0),
    ]
    .iter()
    .map(|&(x, y)| {
        let p = at(x, y);
        format!("({}, {})", p.x, p.y)
    })
    .collect();
    let (circle, (la, lb)) = (at(-4.0, -17.0), (at(-10.0, 15.0), at(10.0, 19.0)));
    let (wa, wb) = (at(-8.0, -9.0), at(-1.0, -10.0));
    scene(&format!(
        "Scene(canvas: (48, 48), floor: Color((0.8, 0.8, 0.8)), falloff: {falloff},
               walls: [Wall(a: ({}, {}), b: ({}, {}))],
               glass: [Glass(points: [{}], ior: 1.5)],
               lights: [Circle(at: ({}, {}), radius: 2.5, intensity: 1.0),
                        Line(a: ({}, {}), b: ({}, {}), one_sided: true, intensity: 0.5)])",
        wa.x,
        wa.y,
        wb.x,
        wb.y,
        points.join(", "),
        circle.x,
        circle.y,
        la.x,
        la.y,
        lb.x,
        lb.y,
    ))
    .scene
}

#[test]
fn path_tracing_through_glass_edges_agrees_with_light_tracing() {
    for falloff in ["Flatland", "InverseSquare"] {
        let scene = arrow(falloff);
        let mut options = options(8, 1, 0);
        options.scale = 1.0;
        options.integrator = Integrator::Path;
        assert!(
            Plan::new(&scene, &options).closed_forms.glass_lights.runs,
            "the closed form runs"
        );
        let agreement = Agreement {
            block: 8,
            runs: 12,
            first_seed: 700,
            k: 5.0,
            min_blocks: 20,
        };
        agreement.check(falloff, &scene, options, |_| true);
    }
}

/// The point `(x, y)` of the room's frame, turned by 0.25 radians about
/// the canvas's centre, as the scene format writes it.
fn at(x: f64, y: f64) -> String {
    let (s, c) = 0.25f64.sin_cos();
    let p = DVec2::new(24.0, 24.0) + DVec2::new(c * x - s * y, s * x + c * y);
    format!("({}, {})", p.x, p.y)
}

/// A turned room of diffuse, coloured and mirror walls (one rough), a
/// circle light and a solid line light, with `column` among its walls and
/// `glass` as its glass bodies.
fn room(column: &str, glass: &str) -> flatray_tracer::Scene {
    let text = format!(
        "Scene(canvas: (48, 48), floor: Color((0.8, 0.8, 0.8)),
                   walls: [Wall(a: {}, b: {}),
                           Wall(a: {}, b: {}, material: Mirror()),
                           Wall(a: {}, b: {}, material: Diffuse(albedo: (0.9, 0.3, 0.2))),
                           Wall(a: {}, b: {}, material: Rough(roughness: 0.3)),
                           Wall(a: {}, b: {}, emit: (intensity: 0.3)){column}],
                   glass: [{glass}],
                   lights: [Circle(at: {}, radius: 2.0, intensity: 1.5)])",
        at(-19.0, -19.0),
        at(19.0, -19.0),
        at(19.0, -19.0),
        at(19.0, 19.0),
        at(19.0, 19.0),
        at(-19.0, 19.0),
        at(-19.0, 19.0),
        at(-19.0, -19.0),
        at(-6.0, -17.0),
        at(4.0, -17.0),
        at(-12.0, -10.0),
    );
    scene(&text).scene
}

/// The room with a glass triangle: with no arc, the closed forms take one
/// mirror and one glass edge and photons the longer runs; with a round
/// column of mirror (an arc), no closed form runs and photons take every
/// run. Path tracing agrees with light tracing block by block, with two
/// bounces.
#[test]
fn photons_and_paths_share_lines_and_circles_after_glass() {
    let glass = format!(
        "Glass(points: [{}, {}, {}], ior: 1.5)",
        at(-8.0, 6.0),
        at(6.0, 2.0),
        at(-2.0, 14.0)
    );
    for column in [
        "",
        ", Wall(center: (30, 14), radius: 2.5, material: Mirror())",
    ] {
        let scene = room(column, &glass);
        let mut options = options(8, 2, 0);
        options.scale = 1.0;
        options.integrator = Integrator::Path;
        let plan = Plan::new(&scene, &options);
        assert!(plan.area_photons && plan.caustics, "{column}");
        assert_eq!(
            plan.closed_forms.glass_lights.runs,
            column.is_empty(),
            "{column}"
        );
        let agreement = Agreement {
            block: 8,
            runs: 12,
            first_seed: 900,
            k: 5.0,
            min_blocks: 20,
        };
        agreement.check(column, &scene, options, |_| true);
    }
}

/// The room without glass: the closed form takes the lights in the flat
/// mirror from the floor and the diffuse walls, and path rays off the
/// rough mirror still find them in it (a glossy wall's next-event
/// estimation takes nothing through a mirror). Path tracing agrees with
/// light tracing block by block, with two bounces.
#[test]
fn a_rough_mirror_sees_the_lights_in_a_flat_mirror() {
    let scene = room("", "");
    let mut options = options(8, 2, 0);
    options.scale = 1.0;
    options.integrator = Integrator::Path;
    let plan = Plan::new(&scene, &options);
    assert!(plan.closed_forms.mirror_lights.runs && !plan.area_photons);
    let agreement = Agreement {
        block: 8,
        runs: 12,
        first_seed: 1100,
        k: 5.0,
        min_blocks: 20,
    };
    agreement.check("no glass", &scene, options, |_| true);
}
