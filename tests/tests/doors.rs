//! Doors and windows: a closed door and a shut window let no light
//! through in turned rooms, under every integrator and bounce count; an
//! open door and an open window do; a door is a bound between rooms
//! whether open or shut; a generated apartment's rooms are found one by
//! one, on the grid and turned off it.

use flatray_geometry::DVec2;
use flatray_tests::{options, render, scene};
use flatray_tracer::Integrator;

/// Two rooms turned by `degrees` about (60, 40): west (x 10..60) with a
/// lamp, east (x 60..110), a partition at x = 60 with a door from
/// y = 30 to 50, and a window in the east room's east wall from y = 25
/// to 55 under a sky. Gives the text and a point deep in the east room.
fn plan(degrees: f64, door_open: bool, shutter: f64) -> (String, DVec2) {
    let (s, c) = degrees.to_radians().sin_cos();
    let at = |x: f64, y: f64| {
        let (x, y) = (x - 60.0, y - 40.0);
        DVec2::new(60.0 + c * x - s * y, 40.0 + s * x + c * y)
    };
    let p = |x: f64, y: f64| {
        let q = at(x, y);
        format!("({:.6}, {:.6})", q.x, q.y)
    };
    let wall =
        |a: (f64, f64), b: (f64, f64)| format!("Wall(a: {}, b: {}),", p(a.0, a.1), p(b.0, b.1));
    let walls = [
        wall((10.0, 10.0), (110.0, 10.0)),
        wall((110.0, 10.0), (110.0, 25.0)),
        wall((110.0, 55.0), (110.0, 70.0)),
        wall((110.0, 70.0), (10.0, 70.0)),
        wall((10.0, 70.0), (10.0, 10.0)),
        wall((60.0, 10.0), (60.0, 30.0)),
        wall((60.0, 50.0), (60.0, 70.0)),
    ]
    .join("\n        ");
    let text = format!(
        r#"Scene(
    canvas: (120, 80),
    floor: Color((0.8, 0.8, 0.8)),
    walls: [{walls}],
    doors: [Door(a: {}, b: {}, open: {door_open})],
    windows: [Window(a: {}, b: {}, shutter: {shutter})],
    lights: [
        Point(at: {}, intensity: 4),
        Sky(intensity: 0.05),
    ],
    rooms: [Room(name: "west", at: {}), Room(name: "east", at: {})],
)"#,
        p(60.0, 30.0),
        p(60.0, 50.0),
        p(110.0, 25.0),
        p(110.0, 55.0),
        p(30.0, 40.0),
        p(30.0, 40.0),
        p(90.0, 40.0),
    );
    (text, at(90.0, 40.0))
}

/// The largest value over the 5 x 5 pixels about `centre`.
fn brightest_about(image: &flatray_tracer::Image, centre: DVec2) -> f32 {
    let mut most = 0.0f32;
    for dy in -2..=2 {
        for dx in -2..=2 {
            let (x, y) = (centre.x as i64 + dx, centre.y as i64 + dy);
            let v = image.get(x as u32, y as u32);
            most = most.max(v[0].max(v[1]).max(v[2]));
        }
    }
    most
}

#[test]
fn a_closed_door_and_a_shut_window_let_no_light_through() {
    for degrees in [0.0, 17.0, 90.0] {
        let (text, east) = plan(degrees, false, 1.0);
        let loaded = scene(&text);
        for integrator in [Integrator::Path, Integrator::Original, Integrator::Light] {
            for bounces in 0..=3 {
                let mut o = options(8, bounces, 1);
                o.integrator = integrator;
                let image = render(&loaded.scene, &o).image;
                assert_eq!(
                    brightest_about(&image, east),
                    0.0,
                    "{degrees}°, {integrator:?}, {bounces} bounces"
                );
            }
        }
    }
}

#[test]
fn an_open_door_or_an_open_window_lets_light_in() {
    for degrees in [0.0, 17.0] {
        for (door_open, shutter) in [(true, 1.0), (false, 0.5), (false, 0.0)] {
            let (text, east) = plan(degrees, door_open, shutter);
            let loaded = scene(&text);
            let image = render(&loaded.scene, &options(8, 2, 1)).image;
            assert!(
                brightest_about(&image, east) > 0.0,
                "{degrees}°, door open {door_open}, shutter {shutter}"
            );
        }
    }
}

#[test]
fn a_door_bounds_two_rooms_open_or_shut() {
    for door_open in [true, false] {
        let (text, _) = plan(17.0, door_open, 0.0);
        let loaded = scene(&text);
        assert_eq!(loaded.doors.len(), 1);
        let rooms =
            flatray_io::rooms::find(&loaded.scene, (120, 80), &loaded.rooms, &loaded.doors, 0.0)
                .expect("two rooms");
        let areas: Vec<f64> = rooms.rooms.iter().map(|r| r.area).collect();
        // 50 x 60 each, give or take the turned walls' pixels.
        for area in areas {
            assert!(
                (area / 3000.0 - 1.0).abs() < 0.05,
                "door open {door_open}: {area}"
            );
        }
        // Without the door's line an open door joins them.
        if door_open {
            let joined = flatray_io::rooms::find(&loaded.scene, (120, 80), &loaded.rooms, &[], 0.0);
            assert!(joined.is_err());
        }
    }
}

/// Generated apartments (`flatray generate`) of 4, 9 and 16 rooms under
/// several seeds, whose doors are `Door` elements (open): every room of
/// the grid is a region of its own, and the outside one more; the rooms
/// share the grid about evenly (the inner grid lines move by up to a
/// fifth of a room). Without the doors, their gaps join rooms (fewer
/// regions of a room's size), unless the door width closes the gaps.
#[test]
fn the_rooms_of_a_generated_apartment_are_found_one_by_one() {
    for rooms in [4u32, 9, 16] {
        for seed in 1..=3 {
            let apartment = flatray_io::generate::Apartment {
                rooms,
                seed,
                ..Default::default()
            };
            let loaded = scene(&apartment.to_ron());
            let (w, h) = flatray_tracer::image_size(&loaded.scene, 0.5);
            assert!(!loaded.doors.is_empty());
            let found = flatray_io::rooms::find(&loaded.scene, (w, h), &[], &loaded.doors, 0.0)
                .expect("regions");
            let inside: Vec<f64> = found
                .rooms
                .iter()
                .filter(|r| !r.open)
                .map(|r| r.area)
                .collect();
            let what = format!("{rooms} rooms, seed {seed}");
            // Furniture drawn closed encloses small regions of its own:
            // the rooms are the regions of over a quarter of a room's
            // share of the grid, and the small ones hold little of it.
            let total: f64 = inside.iter().sum();
            let share = total / rooms as f64;
            let big: Vec<f64> = inside
                .iter()
                .copied()
                .filter(|&a| a > 0.25 * share)
                .collect();
            assert_eq!(big.len(), rooms as usize, "{what}: {inside:?}");
            assert!(
                total - big.iter().sum::<f64>() < 0.05 * total,
                "{what}: {inside:?}"
            );
            assert_eq!(
                found.rooms.iter().filter(|r| r.open).count(),
                1,
                "{what}: the outside"
            );
            for area in &big {
                assert!(
                    (0.5..=1.6).contains(&(area / share)),
                    "{what}: {area} of {share}"
                );
            }
            let rooms_of = |doors: &[_], width: f64| {
                let found = flatray_io::rooms::find(&loaded.scene, (w, h), &[], doors, width)
                    .expect("regions");
                found
                    .rooms
                    .iter()
                    .filter(|r| !r.open && r.area > 0.25 * share)
                    .count()
            };
            let joined = rooms_of(&[], 0.0);
            assert!(
                joined < rooms as usize,
                "{what}: {joined} rooms without the doors"
            );
            // A door width a little over the generator's doors (24 units)
            // closes their gaps without them.
            assert_eq!(
                rooms_of(&[], 25.0),
                rooms as usize,
                "{what}: by the door width"
            );
        }
    }
}

/// A generated apartment turned about its centre by angles off the grid
/// has the rooms of the plan as drawn: as many, each about as large, the
/// outside one more, and a door width over the doors' closes their gaps
/// without the doors as it does on the grid (the door rule asks for
/// walls' ends on one line, at any angle).
#[test]
fn the_rooms_of_a_turned_generated_apartment_are_those_of_the_plan() {
    use flatray_geometry::{Segment, Shape};
    use flatray_tracer::{Canvas, Floor, Scene, Wall};

    let areas = |scene: &Scene, doors: &[Segment], width: f64| {
        let size = flatray_tracer::image_size(scene, 0.5);
        let found = flatray_io::rooms::find(scene, size, &[], doors, width).expect("regions");
        let outside = found.rooms.iter().filter(|r| r.open).count();
        let mut inside: Vec<f64> = found
            .rooms
            .iter()
            .filter(|r| !r.open)
            .map(|r| r.area)
            .collect();
        inside.sort_by(f64::total_cmp);
        (inside, outside)
    };
    for rooms in [9u32, 16] {
        let apartment = flatray_io::generate::Apartment {
            rooms,
            seed: 2,
            ..Default::default()
        };
        let loaded = scene(&apartment.to_ron());
        let plan = &loaded.scene;
        let (flat, _) = areas(plan, &loaded.doors, 0.0);
        let share = flat.iter().sum::<f64>() / rooms as f64;
        let big =
            |a: &[f64]| -> Vec<f64> { a.iter().copied().filter(|&x| x > 0.25 * share).collect() };
        let flat = big(&flat);
        assert_eq!(
            flat.len(),
            rooms as usize,
            "{rooms} rooms on the grid: {flat:?}"
        );
        let (width, height) = (plan.canvas().width as f64, plan.canvas().height as f64);
        let centre = plan.canvas().origin + 0.5 * DVec2::new(width, height);
        let side = width.hypot(height).ceil();
        for degrees in [17.0f64, 62.0] {
            let (s, c) = degrees.to_radians().sin_cos();
            let turn = |p: DVec2| {
                let q = p - centre;
                centre + DVec2::new(c * q.x - s * q.y, s * q.x + c * q.y)
            };
            let turn_segment = |g: &Segment| Segment::new(turn(g.a), turn(g.b));
            let walls: Vec<Wall> = plan
                .walls()
                .iter()
                .map(|w| match &w.shape {
                    Shape::Segment(g) => Wall::segment(turn(g.a), turn(g.b), w.material),
                    Shape::Arc(_) => panic!("a generated plan has no arcs"),
                })
                .collect();
            let canvas = Canvas {
                width: side as u32,
                height: side as u32,
                origin: centre - 0.5 * DVec2::splat(side),
            };
            let turned = Scene::new(
                canvas,
                Floor::Color(flatray_tracer::Rgb::ONE),
                0.5,
                walls,
                Vec::new(),
            )
            .expect("a valid scene");
            let doors: Vec<Segment> = loaded.doors.iter().map(turn_segment).collect();
            let what = format!("{rooms} rooms turned {degrees}°");
            let (inside, outside) = areas(&turned, &doors, 0.0);
            assert_eq!(outside, 1, "{what}: the outside");
            let found = big(&inside);
            assert_eq!(found.len(), rooms as usize, "{what}: {inside:?}");
            // Sorted by area, each room as large as its match on the grid,
            // to within the pixels along its walls.
            for (a, b) in found.iter().zip(&flat) {
                assert!(
                    (a / b - 1.0).abs() < 0.08,
                    "{what}: {found:?} against {flat:?}"
                );
            }
            let (by_width, _) = areas(&turned, &[], 25.0);
            assert_eq!(
                big(&by_width).len(),
                rooms as usize,
                "{what}: by the door width"
            );
            let (joined, _) = areas(&turned, &[], 0.0);
            assert!(
                big(&joined).len() < rooms as usize,
                "{what}: without the doors"
            );
        }
    }
}
