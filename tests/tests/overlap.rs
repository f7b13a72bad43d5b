//! Walls that lie on top of each other: a pane, a mirror or a second wall
//! drawn along a wall's line (`docs/robustness.md`, rule 8). Light never
//! crosses an opaque wall because something else lies on it, and the image
//! does not depend on the order the walls are listed in.

use flatray_geometry::DVec2;
use flatray_tests::scene;
use flatray_tracer::{Image, Integrator, MemoOptions, RenderOptions};

/// SplitMix64 over a counter: the cases' numbers, reproducibly.
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut x = self.0;
        x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((x ^ (x >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

const MATERIALS: [&str; 6] = [
    "",
    ", material: Diffuse(albedo: (0.9, 0.4, 0.2))",
    ", material: Mirror()",
    ", material: Mirror(tint: (0.8, 0.9, 1.0))",
    ", material: Transparent()",
    ", material: Transparent(tint: (0.5, 0.8, 0.6))",
];

fn wall(a: DVec2, b: DVec2, material: &str) -> String {
    format!(
        "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){material})",
        a.x, a.y, b.x, b.y
    )
}

/// A room of `corners` (a closed polygon of opaque diffuse walls), with
/// `extra` segments lying along its walls, and lights inside.
struct Case {
    corners: Vec<DVec2>,
    walls: Vec<String>,
}

impl Case {
    /// A rotated room, convex or L-shaped, with 1 to 4 segments along its
    /// walls: duplicates, parts, reversed, sticking out past a corner.
    fn random(numbers: &mut Numbers) -> Case {
        let angle = numbers.next() * std::f64::consts::TAU;
        let (s, c) = angle.sin_cos();
        let centre = DVec2::new(60.0, 60.0);
        let shape: &[(f64, f64)] = if numbers.next() < 0.5 {
            &[(-30.0, -24.0), (30.0, -24.0), (30.0, 24.0), (-30.0, 24.0)]
        } else {
            &[
                (-30.0, -30.0),
                (30.0, -30.0),
                (30.0, 0.0),
                (0.0, 0.0),
                (0.0, 30.0),
                (-30.0, 30.0),
            ]
        };
        let corners: Vec<DVec2> = shape
            .iter()
            .map(|&(x, y)| centre + DVec2::new(c * x - s * y, s * x + c * y))
            .collect();
        let n = corners.len();
        let mut walls: Vec<String> = (0..n)
            .map(|i| {
                let material = if numbers.next() < 0.3 {
                    MATERIALS[1]
                } else {
                    ""
                };
                wall(corners[i], corners[(i + 1) % n], material)
            })
            .collect();
        for _ in 0..1 + numbers.below(4) {
            let i = numbers.below(n);
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            let (u0, u1) = match numbers.below(4) {
                0 => (0.0, 1.0),
                1 => (numbers.next() * 0.5, 0.5 + numbers.next() * 0.5),
                2 => (-0.2 * numbers.next(), 0.3 + numbers.next() * 0.3),
                _ => (0.4 + numbers.next() * 0.3, 1.0 + 0.2 * numbers.next()),
            };
            let (mut p, mut q) = (a + (b - a) * u0, a + (b - a) * u1);
            if numbers.next() < 0.5 {
                std::mem::swap(&mut p, &mut q);
            }
            walls.push(wall(p, q, MATERIALS[numbers.below(MATERIALS.len())]));
        }
        Case { corners, walls }
    }

    fn text(&self, walls: &[String]) -> String {
        let inside = |u: f64, v: f64| {
            // A point inside, between the first corner and the third.
            let p = self.corners[0] + (self.corners[2] - self.corners[0]) * u;
            p + (self.corners[1] - p) * v
        };
        let (p, l0, l1) = (inside(0.3, 0.2), inside(0.25, 0.1), inside(0.4, 0.15));
        format!(
            "Scene(canvas: (120, 120), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: ({:?}, {:?}), intensity: 40.0),
                        Line(a: ({:?}, {:?}), b: ({:?}, {:?}), intensity: 2.0)])",
            walls.join(", "),
            p.x,
            p.y,
            l0.x,
            l0.y,
            l1.x,
            l1.y
        )
    }

    /// Whether `p` lies inside the room (even-odd rule).
    fn contains(&self, p: DVec2) -> bool {
        let v = &self.corners;
        let mut inside = false;
        for i in 0..v.len() {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        inside
    }

    /// Whether `p` lies more than `margin` from every wall of the room.
    fn clear_of_walls(&self, p: DVec2, margin: f64) -> bool {
        let v = &self.corners;
        (0..v.len()).all(|i| {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            let e = b - a;
            let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
            (a + e * t).distance(p) > margin
        })
    }
}

fn configurations() -> Vec<(String, RenderOptions)> {
    let mut out = Vec::new();
    for bounces in 0..=3 {
        for (integrator, name) in [
            (Integrator::Path, "path"),
            (Integrator::Original, "original"),
            (Integrator::Light, "light"),
        ] {
            for memo in [true, false] {
                if integrator != Integrator::Path && memo {
                    continue;
                }
                out.push((format!("{name}, D = {bounces}, memo {memo}"), {
                    let mut options = RenderOptions::default();
                    options.samples = 4;
                    options.bounces = bounces;
                    options.integrator = integrator;
                    options.memo = MemoOptions::default();
                    options.memo.enabled = memo;
                    options
                }));
            }
        }
    }
    out
}

fn render(text: &str, options: &RenderOptions) -> Image {
    flatray_tests::render(&scene(text).scene, options).image
}

/// Every pixel more than 2 px outside the room is exactly 0, for every
/// integrator, 0 to 3 bounces, memo on and off, on 24 rooms with segments
/// of every material lying along their walls.
#[test]
fn no_light_crosses_a_wall_that_another_segment_lies_on() {
    let mut numbers = Numbers(36);
    let configurations = configurations();
    for case_index in 0..24 {
        let case = Case::random(&mut numbers);
        let text = case.text(&case.walls);
        for (name, options) in &configurations {
            let image = render(&text, options);
            let mut outside = 0;
            let mut lit_inside = false;
            for y in 0..image.height {
                for x in 0..image.width {
                    let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let value = image.get(x, y);
                    if case.contains(p) {
                        lit_inside |= value[0] > 0.0;
                    } else if case.clear_of_walls(p, 2.0) {
                        outside += 1;
                        assert_eq!(
                            value, [0.0; 3],
                            "case {case_index} ({name}): light outside at ({x}, {y})\n{text}"
                        );
                    }
                }
            }
            assert!(
                outside > 1000,
                "case {case_index}: {outside} pixels outside"
            );
            assert!(lit_inside, "case {case_index} ({name}): the room is dark");
        }
    }
}

/// The walls that come out of rule 8 are the same whatever the order of
/// the walls that go in (shuffled, reversed), and so is the image, bit for
/// bit, wherever the segments lying along walls are listed among the
/// others. (Reordering the other walls changes which random numbers each
/// wall's estimates draw, not what they estimate.)
#[test]
fn the_image_does_not_depend_on_the_order_of_the_walls() {
    let mut numbers = Numbers(7);
    let configurations = configurations();
    for case_index in 0..12 {
        let case = Case::random(&mut numbers);
        let rooms = case.corners.len();
        let resolved = |walls: &[String]| {
            let mut out: Vec<String> = scene(&case.text(walls))
                .scene
                .walls()
                .iter()
                .map(|w| format!("{:?}", w))
                .collect();
            out.sort();
            out
        };
        let given = resolved(&case.walls);
        let mut shuffled = case.walls.clone();
        for i in (1..shuffled.len()).rev() {
            shuffled.swap(i, numbers.below(i + 1));
        }
        let mut reversed = case.walls.clone();
        reversed.reverse();
        for (order, walls) in [("shuffled", &shuffled), ("reversed", &reversed)] {
            assert_eq!(
                resolved(walls),
                given,
                "case {case_index}: the {order} walls resolve otherwise"
            );
        }
        // The segments along the walls listed first, reversed among
        // themselves, and between the room's walls.
        let (room, extra) = case.walls.split_at(rooms);
        let mut first: Vec<String> = extra.iter().rev().cloned().collect();
        first.extend(room.iter().cloned());
        let mut between: Vec<String> = room.to_vec();
        for (k, e) in extra.iter().enumerate() {
            between.insert((k * 3 + 1) % (between.len() + 1), e.clone());
        }
        for (name, options) in configurations.iter().step_by(2) {
            let image = render(&case.text(&case.walls), options);
            for (order, walls) in [("first", &first), ("between", &between)] {
                let other = render(&case.text(walls), options);
                assert!(
                    image.pixels == other.pixels,
                    "case {case_index} ({name}): the segments listed {order} give another image\n{}",
                    case.text(&case.walls)
                );
            }
        }
    }
}

/// `flatray check` warns, with the location, about each wall that lies on
/// another, and about none in the example scenes.
#[test]
fn check_warns_about_walls_lying_on_walls() {
    let dir = flatray_tests::TempDir::new("overlap-check");
    let path = dir.write(
        "dup.ron",
        "Scene(canvas: (60, 60), floor: Color((1, 1, 1)), walls: [
  Wall(a: (10, 10), b: (50, 10)), Wall(a: (50, 10), b: (50, 50)), Wall(a: (50, 50), b: (10, 50)),
  Wall(a: (10, 50), b: (10, 10)),
  Wall(a: (20, 10), b: (30, 10), material: Transparent()),
  Wall(a: (50, 20), b: (50, 40), material: Mirror()),
  Wall(a: (10, 50), b: (50, 50)),
], lights: [Point(at: (30, 30), intensity: 10)])",
    );
    let run = flatray_tests::flatray(&["check", path.to_str().unwrap_or_default()]);
    assert_eq!(run.code, 0, "{run:?}");
    for expected in [
        "dup.ron:4:3: warning: pane 4 lies on top of wall 0",
        "the pane lets no light through there",
        "dup.ron:5:3: warning: mirror 5 lies on top of wall 1",
        "dup.ron:6:3: warning: wall 6 lies on top of wall 2",
        "it is the same wall twice",
    ] {
        assert!(run.stderr.contains(expected), "{expected}\n{}", run.stderr);
    }
    assert_eq!(run.stderr.lines().count(), 3, "{}", run.stderr);
    let scenes = flatray_tests::workspace_root().join("scenes");
    let mut checked = 0;
    for entry in std::fs::read_dir(&scenes).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "ron") {
            let run = flatray_tests::flatray(&["check", path.to_str().unwrap_or_default()]);
            assert_eq!(run.code, 0, "{run:?}");
            assert!(
                !run.stderr.contains("warning"),
                "{}: {}",
                path.display(),
                run.stderr
            );
            checked += 1;
        }
    }
    assert!(checked >= 8, "{checked} scenes");
}
