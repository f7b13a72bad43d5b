//! The linter: `check` (and `plan`, and `render`) warn, at the item's line
//! and column, about what makes a render wrong or wasteful without being
//! an error. One test per warning, each on a scene with that one fault
//! and its twin without it; and no warning on any example scene.

use flatray_tests::{TempDir, flatray};

/// The warnings `check` prints for `text`, as (line, message).
fn warnings(text: &str) -> Vec<(usize, String)> {
    let dir = TempDir::new("lint");
    let path = dir.write("s.ron", text);
    let run = flatray(&["check", path.to_str().unwrap_or_default()]);
    assert_eq!(run.code, 0, "{run:?}");
    let prefix = format!("{}:", path.display());
    run.stderr
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix(&prefix)?;
            let (line, rest) = rest.split_once(':')?;
            let (_, message) = rest.split_once(": warning: ")?;
            Some((line.parse().ok()?, message.to_string()))
        })
        .collect()
}

/// A scene of one room, with `walls`, `lights`, `glass` and `render`
/// inserted, one item a line from line 5 on.
fn scene(walls: &[&str], lights: &[&str], glass: &[&str], render: &str) -> String {
    let list = |items: &[&str]| {
        items
            .iter()
            .map(|i| format!("        {i},\n"))
            .collect::<String>()
    };
    format!(
        "Scene(\n    canvas: (100, 100),\n    floor: Color((0.5, 0.5, 0.5)),\n    walls: [\n{}    ],\n    lights: [\n{}    ],\n    glass: [\n{}    ],\n    render: ({render}),\n)",
        list(walls),
        list(lights),
        list(glass)
    )
}

const WALL: &str = "Wall(a: (10, 10), b: (90, 10))";
const LAMP: &str = "Point(at: (50, 50))";

fn only(found: Vec<(usize, String)>, line: usize, contains: &str) {
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, line, "{found:?}");
    assert!(found[0].1.contains(contains), "{found:?}");
}

#[test]
fn no_lights() {
    let text = "Scene(\n    canvas: (10, 10),\n    floor: Color((0.5, 0.5, 0.5)),\n)";
    only(warnings(text), 1, "no lights");
    // An emitting wall is a light.
    let lit = "Scene(canvas: (10, 10), floor: Color((0.5, 0.5, 0.5)), walls: [Wall(a: (1, 1), b: (9, 1), emit: ())])";
    assert!(warnings(lit).is_empty());
    assert!(warnings(&scene(&[WALL], &[LAMP], &[], "")).is_empty());
    // The render says its image is black, not that its noise needs samples.
    let dir = TempDir::new("lint-black");
    let path = dir.write("s.ron", text);
    let out = dir.path().join("o.png");
    let run = flatray(&[
        "render",
        path.to_str().unwrap_or_default(),
        "-q",
        "--spp",
        "4",
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(
        run.stdout.contains("noise none: the image is black"),
        "{run:?}"
    );
}

#[test]
fn a_wall_wholly_outside_the_canvas() {
    let far = "Wall(a: (500, 10), b: (600, 10))";
    only(
        warnings(&scene(&[WALL, far], &[LAMP], &[], "")),
        6,
        "wall 1 lies wholly outside the canvas",
    );
    // One that crosses the canvas's edge is inside enough.
    let edge = "Wall(a: (50, 60), b: (600, 60))";
    assert!(warnings(&scene(&[WALL, edge], &[LAMP], &[], "")).is_empty());
}

#[test]
fn glass_wholly_outside_the_canvas() {
    let far = "Glass(points: [(225, 25), (240, 25), (240, 40)])";
    let near = "Glass(points: [(25, 25), (40, 25), (40, 40)])";
    only(
        warnings(&scene(&[WALL], &[LAMP], &[near, far], "")),
        12,
        "glass 1 lies wholly outside",
    );
}

#[test]
fn a_light_outside_the_canvas() {
    let far = "Point(at: (5000, 50))";
    only(
        warnings(&scene(&[WALL], &[LAMP, far], &[], "")),
        9,
        "light 1 at (5000, 50) lies outside the canvas",
    );
    let far_line = "Line(a: (200, 200), b: (300, 200))";
    only(
        warnings(&scene(&[WALL], &[LAMP, far_line], &[], "")),
        9,
        "light 1 lies wholly outside",
    );
    // The sun comes from outside by definition.
    let sun = "Directional(direction: (1, 1))";
    assert!(warnings(&scene(&[WALL], &[LAMP, sun], &[], "")).is_empty());
}

#[test]
fn a_window_or_a_mirror_along_a_wall() {
    let pane = "Wall(a: (20, 10), b: (40, 10), material: Transparent())";
    only(
        warnings(&scene(&[WALL, pane], &[LAMP], &[], "")),
        6,
        "the pane lets no light through",
    );
    let mirror = "Wall(a: (20, 10), b: (40, 10), material: Mirror())";
    only(
        warnings(&scene(&[WALL, mirror], &[LAMP], &[], "")),
        6,
        "the mirror is what light meets",
    );
    // Beside the wall, not on it.
    let beside = "Wall(a: (20, 11), b: (40, 11), material: Mirror())";
    assert!(warnings(&scene(&[WALL, beside], &[LAMP], &[], "")).is_empty());
}

#[test]
fn duplicate_walls() {
    let reversed = "Wall(a: (90, 10), b: (10, 10))";
    only(
        warnings(&scene(&[WALL, reversed], &[LAMP], &[], "")),
        6,
        "the same wall twice",
    );
}

#[test]
fn glass_that_light_cannot_cross() {
    let glass = "Glass(points: [(25, 25), (40, 25), (40, 40)])";
    only(
        warnings(&scene(&[WALL], &[LAMP], &[glass], "specular: 1")),
        11,
        "no light crosses the glass",
    );
    assert!(warnings(&scene(&[WALL], &[LAMP], &[glass], "specular: 2")).is_empty());
}

#[test]
fn a_light_on_a_wall_or_inside_glass() {
    let on = "Point(at: (30, 10))";
    only(
        warnings(&scene(&[WALL], &[on], &[], "")),
        8,
        "light 0 lies on wall 0",
    );
    let spot = "Spot(at: (30, 10), direction: (0, 1), cone: 40)";
    only(
        warnings(&scene(&[WALL], &[spot], &[], "")),
        8,
        "lights both sides",
    );
    let glass = "Glass(points: [(25, 25), (60, 25), (60, 60)])";
    let inside = "Point(at: (50, 35))";
    only(
        warnings(&scene(&[WALL], &[inside], &[glass], "")),
        8,
        "light 0 lies inside glass 0",
    );
    let ring = "Circle(at: (50, 12), radius: 5)";
    only(
        warnings(&scene(&[WALL], &[ring], &[], "")),
        8,
        "wall 0 crosses circle light 0",
    );
    let clear = "Circle(at: (50, 30), radius: 5)";
    assert!(warnings(&scene(&[WALL], &[clear], &[], "")).is_empty());
}

/// `plan` and `render` print the same warnings as `check`.
#[test]
fn plan_and_render_warn_too() {
    let dir = TempDir::new("lint-all");
    let path = dir.write(
        "s.ron",
        &scene(&[WALL], &[LAMP, "Point(at: (5000, 50))"], &[], "samples: 1"),
    );
    let path = path.to_str().unwrap_or_default();
    let out = dir.path().join("o.png");
    for args in [
        vec!["plan", path],
        vec![
            "render",
            path,
            "-q",
            "--scale",
            "0.2",
            "-o",
            out.to_str().unwrap_or_default(),
        ],
    ] {
        let run = flatray(&args);
        assert_eq!(run.code, 0, "{run:?}");
        assert!(
            run.stderr.contains(":9:9: warning: light 1 at (5000, 50)"),
            "{args:?}: {run:?}"
        );
    }
}

/// `check` takes several files, reports each, and exits 2 when any is
/// refused.
#[test]
fn check_takes_several_files() {
    let dir = TempDir::new("lint-many");
    let good = dir.write("good.ron", &scene(&[WALL], &[LAMP], &[], ""));
    let bad = dir.write("bad.ron", "Scene(canvas: (10, 10))");
    let (good, bad) = (
        good.to_str().unwrap_or_default(),
        bad.to_str().unwrap_or_default(),
    );
    let run = flatray(&["check", good, bad, good]);
    assert_eq!(run.code, 2, "{run:?}");
    assert_eq!(
        run.stdout
            .matches(": ok (1 wall, 1 light, 0 glass bodies")
            .count(),
        2,
        "{run:?}"
    );
    assert!(run.stderr.contains(&format!("error: {bad}:1:")), "{run:?}");
    assert!(run.stderr.contains("1 of 3 scenes refused"), "{run:?}");
    assert_eq!(flatray(&["check", good, good]).code, 0);
}

/// The example scenes are clean: a warning there is a mistake in the
/// example or a linter that cries wolf.
#[test]
fn no_example_scene_gets_a_warning() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut scenes = Vec::new();
    for folder in ["scenes"] {
        let mut stack = vec![root.join(folder)];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
                let path = entry.path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "ron") {
                    scenes.push(path);
                }
            }
        }
    }
    assert!(scenes.len() >= 10, "{scenes:?}");
    for path in scenes {
        let run = flatray(&["check", path.to_str().unwrap_or_default()]);
        assert_eq!(run.code, 0, "{}: {run:?}", path.display());
        assert!(
            !run.stderr.contains("warning"),
            "{}: {}",
            path.display(),
            run.stderr
        );
    }
}

/// The four walls of a square of side `side` about `(cx, cy)`, turned by
/// `turn` radians, with `gap` units left open in the middle of one side.
fn square(cx: f64, cy: f64, side: f64, turn: f64, gap: f64) -> Vec<String> {
    let (s, c) = turn.sin_cos();
    let at = |x: f64, y: f64| {
        let (x, y) = (x - cx, y - cy);
        (cx + c * x - s * y, cy + s * x + c * y)
    };
    let h = side / 2.0;
    let corners = [
        at(cx - h, cy - h),
        at(cx + h, cy - h),
        at(cx + h, cy + h),
        at(cx - h, cy + h),
    ];
    let mut walls = Vec::new();
    for k in 0..4 {
        let (a, b) = (corners[k], corners[(k + 1) % 4]);
        if k == 0 && gap > 0.0 {
            let m = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
            let t = gap / 2.0 / side;
            let p = (m.0 - (b.0 - a.0) * t, m.1 - (b.1 - a.1) * t);
            let q = (m.0 + (b.0 - a.0) * t, m.1 + (b.1 - a.1) * t);
            walls.push(format!("Wall(a: {a:?}, b: {p:?})"));
            walls.push(format!("Wall(a: {q:?}, b: {b:?})"));
        } else {
            walls.push(format!("Wall(a: {a:?}, b: {b:?})"));
        }
    }
    walls
}

#[test]
fn a_light_sealed_in_a_small_loop_of_walls() {
    let lamp = "Point(at: (30, 40), intensity: 5)";
    let other = "Point(at: (80, 80), intensity: 5)";
    // A round column around the lamp, and a turned box around it, shared
    // corners and all.
    let column = "Wall(center: (30, 40), radius: 6)";
    only(
        warnings(&scene(&[column], &[lamp, other], &[], "")),
        8,
        "light 0 appears sealed inside a closed loop of walls",
    );
    for turn in [0.0, 0.3, std::f64::consts::FRAC_PI_4] {
        let walls = square(30.0, 40.0, 16.0, turn, 0.0);
        let walls: Vec<&str> = walls.iter().map(String::as_str).collect();
        let found = warnings(&scene(&walls, &[lamp, other], &[], ""));
        only(found, 11, "light 0 appears sealed");
        // A gap of 4 units lets the light out.
        let open = square(30.0, 40.0, 16.0, turn, 4.0);
        let open: Vec<&str> = open.iter().map(String::as_str).collect();
        assert!(
            warnings(&scene(&open, &[lamp, other], &[], "")).is_empty(),
            "{turn}"
        );
    }
    // A pane in the loop, or glass, lets light through.
    let pane = "Wall(a: (22, 32), b: (38, 32), material: Transparent(tint: (0.5, 0.5, 1)))";
    let mut walls = square(30.0, 40.0, 16.0, 0.0, 0.0);
    walls[0] = pane.to_string();
    let walls: Vec<&str> = walls.iter().map(String::as_str).collect();
    assert!(warnings(&scene(&walls, &[lamp, other], &[], "")).is_empty());
    // A lamp closely boxed, nearer its walls than the grid's cells.
    let tight = "Wall(center: (30, 40), radius: 0.2)";
    let tiny = "Point(at: (30, 40), intensity: 5)";
    only(
        warnings(&scene(&[tight], &[tiny, other], &[], "")),
        8,
        "light 0 appears sealed",
    );
    // The scene's own closed room, or a bay of it, is meant.
    let room = square(50.0, 50.0, 96.0, 0.2, 0.0);
    let room: Vec<&str> = room.iter().map(String::as_str).collect();
    assert!(warnings(&scene(&room, &[LAMP], &[], "")).is_empty());
}

#[test]
fn a_spot_whose_cone_reads_as_radians() {
    let spot = "Spot(at: (50, 50), direction: (1, 0), cone: 0.5)";
    only(
        warnings(&scene(&[WALL], &[spot], &[], "")),
        8,
        "a cone of 0.5 radians is written `cone: 28.6`",
    );
    let wide = "Spot(at: (50, 50), direction: (1, 0), cone: 30)";
    assert!(warnings(&scene(&[WALL], &[wide], &[], "")).is_empty());
}
