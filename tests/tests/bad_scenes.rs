//! Bad scene files: each gives exit code 2 and a message naming the file,
//! line and column, and what was expected. None panics.

use flatray_tests::{TempDir, flatray};

/// Checks `flatray check` and `flatray render` on `text` exit with 2 and a
/// message that starts with `file:line:col:` and contains `expected`.
fn check_rejected(text: &str, line: usize, expected: &str) {
    let dir = TempDir::new("bad");
    let path = dir.write("bad.ron", text);
    let path_str = path.to_string_lossy().into_owned();
    let out = dir.path().join("out.png");
    for args in [
        vec!["check", path_str.as_str()],
        vec![
            "render",
            path_str.as_str(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ],
    ] {
        let run = flatray(&args);
        assert_eq!(run.code, 2, "{args:?}: {run:?}");
        let prefix = format!("error: {path_str}:{line}:");
        assert!(
            run.stderr.starts_with(&prefix),
            "{args:?}: expected {prefix:?}, got {:?}",
            run.stderr
        );
        assert!(
            run.stderr.to_lowercase().contains(&expected.to_lowercase()),
            "{args:?}: expected {expected:?} in {:?}",
            run.stderr
        );
        assert!(!out.exists(), "no image is written for a bad scene");
    }
}

#[test]
fn syntax_error() {
    // The closing parenthesis of `Color(` is missing at the end of line 3.
    check_rejected(
        "Scene(\n  canvas: (10, 10),\n  floor: Color((1, 1, 1)\n  walls: [],\n)",
        3,
        "expected closing",
    );
}

#[test]
fn unknown_field() {
    check_rejected(
        "Scene(\n  canvas: (10, 10),\n  floor: Color((1, 1, 1)),\n  wals: [],\n)",
        4,
        "wals",
    );
}

#[test]
fn unknown_field_in_a_wall() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n walls: [\n  Wall(a: (0, 0), b: (1, 1), albedo: (1, 0, 0)),\n ])",
        3,
        "albedo",
    );
}

#[test]
fn wrong_type() {
    check_rejected(
        "Scene(\n  canvas: (10, 10),\n  floor: Color((1, 1, 1)),\n  render: (samples: \"many\"),\n)",
        4,
        "expected",
    );
}

#[test]
fn missing_floor_image_names_the_path_it_tried() {
    check_rejected(
        "Scene(\n  floor: Image(\"no-such-floor.png\"),\n)",
        2,
        "no-such-floor.png",
    );
}

#[test]
fn nan_coordinate() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  lights: [\n    Point(at: (NaN, 3)),\n  ])",
        3,
        "finite",
    );
}

#[test]
fn infinite_coordinate_in_a_wall() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  walls: [Wall(a: (0, 0),\n b: (inf, 3))])",
        3,
        "finite",
    );
}

#[test]
fn absurd_canvas() {
    check_rejected(
        "Scene(\n  canvas: (100000, 100000),\n  floor: Color((1, 1, 1)),\n)",
        2,
        "canvas",
    );
}

#[test]
fn colour_out_of_range() {
    check_rejected(
        "Scene(canvas: (10, 10),\n  floor: Color((1.5, 1, 1)),\n)",
        2,
        "[0, 1]",
    );
}

#[test]
fn zero_length_wall() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  walls: [Wall(a: (3, 3), b: (3, 3))],\n)",
        2,
        "two different endpoints",
    );
}

#[test]
fn zero_length_line_light() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  lights: [Line(a: (3, 3), b: (3, 3))],\n)",
        2,
        "two different endpoints",
    );
}

#[test]
fn missing_canvas_without_an_image_floor() {
    check_rejected("Scene(\n  floor: Color((1, 1, 1)),\n)", 2, "canvas");
}

#[test]
fn missing_scene_file_is_a_usage_error() {
    let run = flatray(&["check", "/no/such/scene.ron"]);
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("/no/such/scene.ron"), "{run:?}");
}

#[test]
fn bad_flags_are_usage_errors() {
    for args in [
        vec!["render"],
        vec!["render", "x.ron", "--spp", "0"],
        vec!["render", "x.ron", "--spp", "lots"],
        vec!["frobnicate"],
    ] {
        let run = flatray(&args);
        assert_eq!(run.code, 2, "{args:?}: {run:?}");
    }
}

#[test]
fn unknown_output_format_is_refused_before_rendering() {
    let dir = TempDir::new("fmt");
    let scene = dir.write("s.ron", "Scene(canvas: (4, 4), floor: Color((1, 1, 1)))");
    let out = dir.path().join("out.jpg");
    let run = flatray(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains(".png or .exr"), "{run:?}");
}

#[test]
fn garbage_never_panics() {
    let dir = TempDir::new("garbage");
    let texts = [
        "",
        "(",
        "Scene",
        "Scene()",
        "Scene(canvas: (-1, 5), floor: Color((1,1,1)))",
        "Scene(canvas: (5, 5), floor: Tiles(size: 0))",
        "Scene(canvas: (5, 5), floor: Color((1,1,1)), lights: [Spot(at: (1,1), direction: (0,0), cone: 30)])",
        "Scene(canvas: (5, 5), floor: Color((1,1,1)), lights: [Spot(at: (1,1), direction: (1,0), cone: 30, softness: 40)])",
        "Scene(canvas: (5, 5), floor: Color((1,1,1)), render: (samples: 0))",
        "\u{0}\u{1}\u{2}",
        "Scene(canvas: (5, 5), floor: Color((1,1,1)), falloff: Window(range: -1))",
    ];
    for (i, text) in texts.iter().enumerate() {
        let path = dir.write(&format!("g{i}.ron"), text);
        let run = flatray(&["check", path.to_str().unwrap()]);
        assert_eq!(run.code, 2, "{text:?}: {run:?}");
        assert!(
            run.stderr.contains(":1:"),
            "{text:?}: no location in {:?}",
            run.stderr
        );
    }
}
