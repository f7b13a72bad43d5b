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

/// The message for `text` (one line of `check`'s standard error) and the
/// line and column it points at.
fn message(text: &str) -> (usize, usize, String) {
    let dir = TempDir::new("message");
    let path = dir.write("m.ron", text);
    let run = flatray(&["check", path.to_str().unwrap_or_default()]);
    assert_eq!(run.code, 2, "{run:?}");
    let first = run.stderr.lines().next().unwrap_or_default().to_string();
    let rest = first
        .strip_prefix(&format!("error: {}:", path.display()))
        .unwrap_or_else(|| panic!("{first}"));
    let mut parts = rest.splitn(3, ':');
    let line = parts.next().and_then(|l| l.parse().ok()).unwrap_or(0);
    let column = parts.next().and_then(|c| c.parse().ok()).unwrap_or(0);
    (
        line,
        column,
        parts.next().unwrap_or_default().trim().to_string(),
    )
}

const HEAD: &str = "Scene(\n    canvas: (100, 100),\n    floor: Color((0.5, 0.5, 0.5)),\n";

/// A missing comma is reported at the end of the value it should follow,
/// not at the start of the next line.
#[test]
fn a_missing_comma_points_where_the_comma_belongs() {
    let (line, column, m) =
        message("Scene(\n    canvas: (100, 100)\n    floor: Color((0.5, 0.5, 0.5)),\n)");
    assert_eq!((line, column), (2, 23), "{m}");
    assert!(m.starts_with("expected a comma after this value"), "{m}");
    // After a comment that ends the line, still at the value.
    let (line, column, _) = message(
        "Scene(\n    canvas: (100, 100) // the size\n    floor: Color((0.5, 0.5, 0.5)),\n)",
    );
    assert_eq!((line, column), (2, 23));
}

/// A `Wall(` left open reads the next wall as one of its fields: the
/// message says a `)` is missing, where it is missing.
#[test]
fn a_missing_parenthesis_says_so() {
    let (line, _, m) = message(&format!(
        "{HEAD}    walls: [\n        Wall(a: (1, 1), b: (50, 50),\n        Wall(a: (1, 1), b: (50, 60)),\n    ],\n)"
    ));
    assert_eq!(line, 5, "{m}");
    assert!(m.contains("expected `)` here to close `Wall(...)`"), "{m}");
}

/// Canvas sides, samples and bounces are whole numbers, and a fraction
/// says so (the parser alone says "Expected comma").
#[test]
fn a_fraction_where_a_whole_number_belongs_says_so() {
    let (line, column, m) =
        message("Scene(\n    canvas: (360.5, 240),\n    floor: Color((0.5, 0.5, 0.5)),\n)");
    assert_eq!((line, column), (2, 14));
    assert!(
        m.contains("expected a whole number for `canvas`, found `360.5`"),
        "{m}"
    );
    let (_, _, m) = message(&format!("{HEAD}    render: (samples: 2.5),\n)"));
    assert!(m.contains("whole number for `samples`"), "{m}");
}

/// `#` is no comment in RON: the message says comments are `//`.
#[test]
fn a_hash_comment_is_explained() {
    let (line, column, m) = message(&format!("# my room\n{HEAD})"));
    assert_eq!((line, column), (1, 1));
    assert!(m.contains("comments start with `//`"), "{m}");
}

/// A positional value inside a variant that takes named fields.
#[test]
fn a_value_without_its_name_asks_for_the_name() {
    let (_, _, m) = message(&format!("{HEAD}    render: (tonemap: Reinhard(4)),\n)"));
    assert!(
        m.contains("expected a named field inside `Reinhard(...)`"),
        "{m}"
    );
    assert!(!m.contains("raw identifier"), "{m}");
}

/// A variant without its parentheses, and a colour given by name.
#[test]
fn a_variant_without_parentheses_and_a_colour_by_name() {
    let (_, _, m) = message(&format!(
        "{HEAD}    walls: [Wall(a: (1, 1), b: (50, 50), material: Mirror)],\n)"
    ));
    assert!(m.contains("as `Mirror()`"), "{m}");
    let (_, column, m) = message(&format!(
        "{HEAD}    lights: [Point(at: (5, 5), color: \"orange\")],\n)"
    ));
    assert!(m.contains("expected a colour `(r, g, b)`"), "{m}");
    assert!(m.contains("\"orange\""), "{m}");
    assert_eq!(column, 39, "at the string, not the space before it");
}

/// Misspelt fields and variants get a suggestion, and no internal type
/// name reaches the user.
#[test]
fn misspellings_get_a_suggestion_in_the_formats_words() {
    for (text, expected) in [
        (
            "    lights: [Point(at: (5, 5), intensty: 2)],\n",
            "unknown field `intensty` in `Point`: did you mean `intensity`?",
        ),
        (
            "    walls: [Wall(a: (1, 1), b: (5, 5), material: Miror())],\n",
            "unknown material `Miror`: did you mean `Mirror`?",
        ),
        (
            "    lights: [Pont(at: (5, 5))],\n",
            "unknown light `Pont`: did you mean `Point`?",
        ),
        (
            "    render: (integrator: Paths),\n",
            "unknown integrator `Paths`: did you mean `Path`?",
        ),
        (
            "    render: (sample: 2),\n",
            "unknown field `sample` in `Render`: did you mean `samples`?",
        ),
    ] {
        let (_, _, m) = message(&format!("{HEAD}{text})"));
        assert!(m.contains(expected), "{m}");
        assert!(!m.contains("Spec"), "an internal name: {m}");
    }
    let (_, _, m) = message("Scene(canvas: (10, 10), floor: Colour((0.5, 0.5, 0.5)))");
    assert!(
        m.contains("unknown floor `Colour`: did you mean `Color`?"),
        "{m}"
    );
    // Nothing near: no suggestion, the list of what is expected.
    let (_, _, m) = message(&format!("{HEAD}    lights: [Lamp(at: (5, 5))],\n)"));
    assert!(!m.contains("did you mean"), "{m}");
    assert!(m.contains("expected one of `Point`"), "{m}");
}

/// A plan for `flatray import` given to `render` or `check` says what it
/// is and how to import it, by its content or, when that says nothing,
/// by its name; a file that is a scene is one whatever its name.
#[test]
fn a_plan_given_as_a_scene_points_to_import() {
    let dir = TempDir::new("plan-as-scene");
    let svg = dir.write(
        "plan.svg",
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\" height=\"10\"/>",
    );
    let tmx = dir.write("level.tmx", "{}");
    let scene = dir.write(
        "scene.svg",
        "Scene(canvas: (10, 10), floor: Color((0.5, 0.5, 0.5)), lights: [Point(at: (5, 5))])",
    );
    for (path, what) in [(&svg, "an SVG drawing"), (&tmx, "a Tiled map (TMX)")] {
        let run = flatray(&["render", path.to_str().unwrap_or_default(), "-q"]);
        assert_eq!(run.code, 2, "{run:?}");
        assert!(
            run.stderr
                .contains(&format!("this is {what}, not a scene file")),
            "{run:?}"
        );
        assert!(run.stderr.contains("flatray import"), "{run:?}");
    }
    let run = flatray(&["check", scene.to_str().unwrap_or_default()]);
    assert_eq!(run.code, 0, "{run:?}");
}

/// The render block sets what the command line sets: the caustic pass,
/// the light choice and the cache's three modes.
#[test]
fn the_render_block_takes_caustics_lights_and_the_cache_modes() {
    let dir = TempDir::new("render-block");
    let plan = |render: &str| {
        let path = dir.write(
            "s.ron",
            &format!(
                "Scene(canvas: (40, 40), floor: Color((0.5, 0.5, 0.5)), walls: [Wall(a: (5, 5), b: (35, 5), material: Mirror()), Wall(a: (5, 30), b: (35, 30))], lights: [Point(at: (20, 20))], render: ({render}))"
            ),
        );
        let run = flatray(&["plan", path.to_str().unwrap_or_default(), "--json"]);
        assert_eq!(run.code, 0, "{render}: {run:?}");
        serde_json::from_str::<serde_json::Value>(&run.stdout).unwrap_or_default()
    };
    let settings = |render: &str| plan(render)["settings"].clone();
    assert_eq!(settings("")["cache"], "on");
    assert_eq!(settings("cache: Direct")["cache"], "direct");
    assert_eq!(settings("cache: Off")["cache"], "off");
    assert_eq!(settings("cache: false")["cache"], "off");
    assert_eq!(settings("cache: true")["cache"], "on");
    assert_eq!(settings("")["caustics"], true);
    assert_eq!(settings("caustics: false")["caustics"], false);
    let chosen = |render: &str| {
        plan(render)["effects"]
            .as_array()
            .and_then(|e| {
                e.iter()
                    .find(|e| e["name"] == "shadow rays to chosen lights")
                    .map(|e| e["runs"].clone())
            })
            .unwrap_or_default()
    };
    assert_eq!(chosen(""), false);
    assert_eq!(chosen("lights: Table"), true);
    let run = flatray(&[
        "check",
        dir.write(
            "bad.ron",
            "Scene(canvas: (4, 4), floor: Color((0.5, 0.5, 0.5)), render: (cache: Sometimes))",
        )
        .to_str()
        .unwrap_or_default(),
    ]);
    assert_eq!(run.code, 2);
    assert!(
        run.stderr
            .contains("`On`, `Off`, `Direct`, `true` or `false`"),
        "{run:?}"
    );
}

#[test]
fn a_rough_mirror_out_of_range() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Tiles(size: 2), walls: [\n  Wall(a: (1, 1), b: (9, 1)),\n  Wall(a: (1, 5), b: (9, 5), material: Rough(roughness: 1.5)),\n])",
        3,
        "roughness",
    );
    check_rejected(
        "Scene(canvas: (10, 10), floor: Tiles(size: 2), walls: [\n  Wall(a: (1, 5), b: (9, 5), material: Rough(roughness: -0.1)),\n])",
        2,
        "from 0 (a mirror) to 1",
    );
}

#[test]
fn rough_glass_out_of_range() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Tiles(size: 2), glass: [\n  Glass(points: [(1, 1), (9, 1), (5, 8)], roughness: 1.5),\n])",
        2,
        "from 0 (smooth glass) to 1",
    );
}

#[test]
fn a_beam_along_its_own_segment_or_of_no_length() {
    check_rejected(
        "Scene(canvas: (10, 10), floor: Tiles(size: 2), lights: [\n  Point(at: (5, 5)),\n  Beam(a: (1, 1), b: (9, 1), direction: (-2, 0)),\n])",
        3,
        "no width",
    );
    check_rejected(
        "Scene(canvas: (10, 10), floor: Tiles(size: 2), lights: [\n  Beam(a: (1, 1), b: (1, 1), direction: (0, 1)),\n])",
        2,
        "use a Laser",
    );
}

#[test]
fn a_spectrum_that_is_no_spectrum() {
    // A temperature out of range, a colour beside a spectrum, a table
    // whose wavelengths go back, and one with no light in the range.
    for (light, expected) in [
        (
            "Point(at: (5, 5), spectrum: Blackbody(50))",
            "100 to 100000 kelvin",
        ),
        (
            "Point(at: (5, 5), color: (1, 0, 0), spectrum: Lamp(Neon))",
            "not both",
        ),
        (
            "Line(a: (1, 1), b: (9, 1), spectrum: Table([(500, 1), (450, 1)]))",
            "must increase",
        ),
        (
            "Point(at: (5, 5), spectrum: Table([(900, 1), (1000, 1)]))",
            "no light from 380 to 780 nm",
        ),
    ] {
        check_rejected(
            &format!(
                "Scene(canvas: (10, 10), floor: Tiles(size: 2), lights: [\n  Point(at: (2, 2)),\n  {light},\n])"
            ),
            3,
            expected,
        );
    }
    check_rejected(
        "Scene(canvas: (10, 10), floor: Tiles(size: 2), lights: [\n  Point(at: (5, 5), spectrum: Lamp(Argon)),\n])",
        2,
        "Sodium",
    );
}
