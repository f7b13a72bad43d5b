//! No pixel of a light transport image is below zero: rotated, non-convex
//! rooms with arcs, lamps close to walls' ends and to an arc's end, every
//! integrator, every cache mode, both ways of taking the floor's indirect
//! light, and 0 to 3 bounces. The wall memo's checked reads
//! (`docs/model.md`, "The wall memo") are where a render could go below
//! zero: a read checked where the memo holds more than the light there.

use std::f64::consts::PI;

use flatray_tests::{options, render, scene};
use flatray_tracer::{Integrator, RenderOptions};

/// A point of the plane turned by `angle` about `centre`.
fn turn((x, y): (f64, f64), centre: (f64, f64), angle: f64) -> (f64, f64) {
    let (dx, dy) = (x - centre.0, y - centre.1);
    let (s, c) = angle.sin_cos();
    (centre.0 + c * dx - s * dy, centre.1 + s * dx + c * dy)
}

/// An L-shaped room, turned by `angle`, with an arc for its west wall and
/// a wall half across the middle; four lamps, each a fraction of a unit
/// from a corner, the arc's end or the inner wall's free end.
fn l_room(angle: f64) -> String {
    let c = (50.0, 50.0);
    let t = |p: (f64, f64)| turn(p, c, angle);
    let corners = [
        (20.0, 20.0),
        (80.0, 20.0),
        (80.0, 50.0),
        (55.0, 50.0),
        (55.0, 80.0),
        (20.0, 80.0),
    ];
    let mut walls = Vec::new();
    for k in 0..corners.len() {
        let (a, b) = (t(corners[k]), t(corners[(k + 1) % corners.len()]));
        if k == 5 {
            let through = t((13.0, 50.0));
            walls.push(format!(
                "Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}))",
                a.0, a.1, through.0, through.1, b.0, b.1
            ));
        } else {
            walls.push(format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}), material: Diffuse(albedo: (0.8, 0.7, 0.6)))",
                a.0, a.1, b.0, b.1
            ));
        }
    }
    let (a, b) = (t((37.0, 50.0)), t((55.0, 50.0)));
    walls.push(format!(
        "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}))",
        a.0, a.1, b.0, b.1
    ));
    let lamps = [(20.6, 20.4), (79.5, 49.4), (20.4, 79.3), (37.2, 50.6)]
        .map(|p| {
            let p = t(p);
            format!("Point(at: ({:?}, {:?}), intensity: 12.0)", p.0, p.1)
        })
        .join(", ");
    format!(
        "Scene(canvas: (100, 100), floor: Color((0.8, 0.8, 0.8)), walls: [{}], lights: [{lamps}])",
        walls.join(", ")
    )
}

/// A turned hexagon whose every other side bows in as an arc, a column
/// inside it; a spot aimed along a wall from near its end, a lamp close
/// to an arc's end, and a short line light close to a corner.
fn hexagon(angle: f64) -> String {
    let c = (50.0, 50.0);
    let corner = |k: usize| {
        let a = angle + k as f64 * PI / 3.0;
        (c.0 + 38.0 * a.cos(), c.1 + 38.0 * a.sin())
    };
    let mut walls = Vec::new();
    for k in 0..6 {
        let (a, b) = (corner(k), corner(k + 1));
        if k % 2 == 1 {
            let mid = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
            let through = (mid.0 + (c.0 - mid.0) * 0.15, mid.1 + (c.1 - mid.1) * 0.15);
            walls.push(format!(
                "Wall(a: ({:?}, {:?}), through: ({:?}, {:?}), b: ({:?}, {:?}))",
                a.0, a.1, through.0, through.1, b.0, b.1
            ));
        } else {
            walls.push(format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}))",
                a.0, a.1, b.0, b.1
            ));
        }
    }
    let column = turn((62.0, 44.0), c, angle);
    walls.push(format!(
        "Wall(center: ({:?}, {:?}), radius: 3.0)",
        column.0, column.1
    ));
    // Just inside corner 0, 1 and 3 (towards the centre).
    let inside = |k: usize, by: f64| {
        let p = corner(k);
        (p.0 + (c.0 - p.0) * by, p.1 + (c.1 - p.1) * by)
    };
    let (s, near_arc, l0) = (inside(0, 0.02), inside(1, 0.015), inside(3, 0.03));
    let along = (corner(5).0 - corner(0).0, corner(5).1 - corner(0).1);
    let l1 = (l0.0 + 0.1 * (c.0 - l0.0), l0.1 + 0.1 * (c.1 - l0.1));
    format!(
        "Scene(canvas: (100, 100), floor: Color((0.8, 0.8, 0.8)), walls: [{}],
            lights: [Spot(at: ({:?}, {:?}), direction: ({:?}, {:?}), cone: 50.0, intensity: 20.0),
                     Point(at: ({:?}, {:?}), intensity: 10.0),
                     Line(a: ({:?}, {:?}), b: ({:?}, {:?}), intensity: 1.0)])",
        walls.join(", "),
        s.0,
        s.1,
        along.0,
        along.1,
        near_arc.0,
        near_arc.1,
        l0.0,
        l0.1,
        l1.0,
        l1.1
    )
}

/// Every way of rendering: integrator, cache mode and the floor's
/// indirect light, with these bounces.
fn ways(bounces: u32) -> Vec<(String, RenderOptions)> {
    let mut ways = Vec::new();
    for integrator in [Integrator::Path, Integrator::Original, Integrator::Light] {
        for cache in ["on", "direct", "off"] {
            for lines in [true, false] {
                if integrator == Integrator::Light && (cache != "on" || !lines) {
                    continue;
                }
                let mut o = options(4, bounces, 3);
                o.integrator = integrator;
                o.memo.enabled = cache != "off";
                o.memo.onward = cache == "on";
                o.floor_lines = lines;
                let name = format!(
                    "{} --cache {cache} --indirect {} --bounces {bounces}",
                    integrator.name(),
                    if lines { "lines" } else { "samples" }
                );
                ways.push((name, o));
            }
        }
    }
    ways
}

#[test]
fn no_pixel_is_below_zero_in_turned_rooms_with_arcs_and_lamps_by_walls_ends() {
    let mut failures = Vec::new();
    for (room, text) in [
        ("L room at 23°", l_room(23f64.to_radians())),
        ("L room at -61°", l_room(-61f64.to_radians())),
        ("hexagon at 11°", hexagon(11f64.to_radians())),
    ] {
        let loaded = scene(&text);
        for bounces in 0..=3 {
            for (way, o) in ways(bounces) {
                let image = render(&loaded.scene, &o).image;
                let min = image
                    .pixels
                    .iter()
                    .flatten()
                    .fold(f32::INFINITY, |m, &v| m.min(v));
                assert!(min.is_finite(), "{room}, {way}: a pixel not finite");
                if min < 0.0 {
                    failures.push(format!("{room}, {way}: minimum {min}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
