//! Careless and hostile input, run through the command line in-process:
//! inputs are never overwritten, errors name the right line, values that
//! would overflow are refused, budgets hold, and nothing stale is reused.
//! (Cases that need the real binary, a working folder, signals or a
//! memory limit are in `cli/tests/binary.rs`.)

use std::path::Path;

use flatray_tests::{TempDir, flatray};

fn s(p: &Path) -> &str {
    p.to_str()
        .unwrap_or_else(|| panic!("not UTF-8: {}", p.display()))
}

const ROOM: &str = "Scene(canvas: (20, 20), floor: Color((0.5, 0.5, 0.5)),
    walls: [Wall(a: (5, 5), b: (15, 6))], lights: [Point(at: (10, 12))])";

/// Case 1: the output is the scene file itself: refused, the scene kept.
#[test]
fn an_output_that_is_the_scene_is_refused() {
    let dir = TempDir::new("out-is-scene");
    let scene = dir.write("scene.png", ROOM);
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&scene)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("is an input"), "{run:?}");
    assert_eq!(std::fs::read_to_string(&scene).ok().as_deref(), Some(ROOM));
    // The same file by another path.
    let other = dir.path().join(".").join("scene.png");
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&other)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert_eq!(std::fs::read_to_string(&scene).ok().as_deref(), Some(ROOM));
}

/// Case 2: the output is the scene's floor image: refused, the image kept.
#[test]
fn an_output_that_is_the_floor_image_is_refused() {
    let dir = TempDir::new("out-is-floor");
    let floor = dir.path().join("floor.png");
    let image = flatray_tracer::Image::new(4, 4);
    flatray_io::write_png(&image, flatray_io::ToneMap::Clamp, &floor)
        .unwrap_or_else(|e| panic!("{e}"));
    let before = std::fs::read(&floor).ok();
    let scene = dir.write("s.ron", "Scene(floor: Image(\"floor.png\"))");
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&floor)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("floor.png"), "{run:?}");
    assert_eq!(std::fs::read(&floor).ok(), before);
}

/// Case 3: a read-only image is not replaced, and keeps its mode; a
/// writable one is replaced and keeps its mode.
#[cfg(unix)]
#[test]
fn a_read_only_output_is_respected_and_modes_are_kept() {
    use std::os::unix::fs::PermissionsExt;
    let dir = TempDir::new("read-only");
    let scene = dir.write("s.ron", ROOM);
    let out = dir.write("out.png", "old");
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o444))
        .unwrap_or_else(|e| panic!("{e}"));
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&out)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("read-only"), "{run:?}");
    assert_eq!(std::fs::read_to_string(&out).ok().as_deref(), Some("old"));
    let mode = |p: &Path| {
        std::fs::metadata(p)
            .map(|m| m.permissions().mode() & 0o777)
            .ok()
    };
    assert_eq!(mode(&out), Some(0o444));
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600))
        .unwrap_or_else(|e| panic!("{e}"));
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&out)]);
    assert_eq!(run.code, 0, "{run:?}");
    assert_eq!(mode(&out), Some(0o600));
    assert!(
        std::fs::read(&out)
            .map(|b| b.starts_with(b"\x89PNG"))
            .unwrap_or(false)
    );
}

/// Cases 4 and 7: a wall memo whose bins would outgrow its budget (a bin
/// of 1e-9 pixel; walls that cross each other thousands of times) is
/// switched off by the plan, which says so; the render then completes.
#[test]
fn a_wall_memo_over_its_budget_is_switched_off() {
    let dir = TempDir::new("memo-budget");
    let tiny_bins = dir.write(
        "bins.ron",
        "Scene(canvas: (100, 10), floor: Color((0.5, 0.5, 0.5)), walls: [Wall(a: (10, 5), b: (90, 5))],
           lights: [Point(at: (50, 2))], render: (cache_bin: 1e-9))",
    );
    // 4,000 walls, each crossing about 2,000 others: four million spans
    // (the memo keeps one sum over the lights per bin, so the lights do
    // not count).
    let mut walls = Vec::new();
    for k in 0..2000 {
        let x = 1.0 + k as f64 * 0.0235;
        walls.push(format!("Wall(a: ({x}, 0.5), b: ({}, 49.5))", 49.0 - x));
        walls.push(format!("Wall(a: (0.5, {x}), b: (49.5, {}))", 49.0 - x));
    }
    let crossing = dir.write(
        "crossing.ron",
        &format!(
            "Scene(canvas: (50, 50), floor: Color((0.5, 0.5, 0.5)), walls: [{}],
               lights: [{}])",
            walls.join(", "),
            (0..4)
                .map(|k| format!("Point(at: ({}.5, {}.5))", 2 + k % 46, 2 + (k * 7) % 46))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    for scene in [&tiny_bins, &crossing] {
        let run = flatray(&["plan", s(scene)]);
        assert_eq!(run.code, 0, "{run:?}");
        let line = run
            .stdout
            .lines()
            .find(|l| l.contains("cache: wall irradiance"))
            .unwrap_or_default();
        assert!(
            line.starts_with("skipped") && line.contains("budget"),
            "{}: {line}",
            scene.display()
        );
        let out = dir.path().join("out.png");
        let run = flatray(&["render", s(scene), "-q", "--spp", "1", "-o", s(&out)]);
        assert_eq!(run.code, 0, "{run:?}");
    }
}

/// Case 5: a floor image larger than flatray reads is refused from its
/// header, before it is decoded, naming its size.
#[test]
fn a_floor_image_over_the_limit_is_refused_before_decoding() {
    let dir = TempDir::new("huge-floor");
    let (width, height) = (4200u32, 4000u32);
    let bytes = vec![0u8; (width * height * 3) as usize];
    let floor = dir.path().join("huge.png");
    image::save_buffer(
        &floor,
        &bytes,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let scene = dir.write(
        "s.ron",
        "Scene(\n  canvas: (10, 10),\n  floor: Image(\"huge.png\"),\n)",
    );
    let run = flatray(&["check", s(&scene)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(
        run.stderr.contains(":3:10:") && run.stderr.contains("4200 x 4000"),
        "{run:?}"
    );
}

/// Case 6: many long walls that take the floor's albedo share a budget of
/// albedo cells; the scene loads and renders.
#[test]
fn many_long_walls_taking_the_floor_colour_load() {
    let dir = TempDir::new("albedo-cells");
    let walls: Vec<String> = (0..3000)
        .map(|k| {
            format!(
                "Wall(a: ({}, -1000), b: ({}, 1000))",
                k as f64 * 0.01,
                k as f64 * 0.01 + 3.0
            )
        })
        .collect();
    let scene = dir.write(
        "s.ron",
        &format!(
            "Scene(canvas: (30, 30), floor: Tiles(size: 3), walls: [{}], lights: [Point(at: (15, 15))])",
            walls.join(", ")
        ),
    );
    let loaded = flatray_io::load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let cells = loaded.scene.albedo_cells();
    assert!(
        cells <= flatray_tracer::scene::ALBEDO_CELLS_BUDGET,
        "{cells} albedo cells"
    );
    let out = dir.path().join("out.png");
    let run = flatray(&["render", s(&scene), "-q", "--spp", "1", "-o", s(&out)]);
    assert_eq!(run.code, 0, "{run:?}");
}

/// Case 8: the floor memo's masks over their budget of (pixel, light)
/// cells are not built; the plan says so.
#[test]
fn coherence_masks_over_their_budget_are_not_built() {
    let dir = TempDir::new("mask-budget");
    let lights: Vec<String> = (0..4000)
        .map(|k| format!("Point(at: ({}, {}))", 10 + k % 680, 10 + (k / 680) * 97))
        .collect();
    let scene = dir.write(
        "s.ron",
        &format!(
            "Scene(canvas: (700, 700), floor: Color((0.5, 0.5, 0.5)), walls: [Wall(a: (1, 1), b: (2, 600))],
               lights: [{}], render: (bounces: 1))",
            lights.join(", ")
        ),
    );
    // Every light (the plan would choose them by a table, which needs no
    // masks).
    let run = flatray(&["plan", "--verbose", "--lights", "every", s(&scene)]);
    assert_eq!(run.code, 0, "{run:?}");
    let line = run
        .stdout
        .lines()
        .find(|l| l.contains("floor strata share"))
        .unwrap_or_default();
    assert!(
        line.starts_with("skipped") && line.contains("budget"),
        "{line}"
    );
}

/// Case 9: `converge` refuses an image larger than flatray renders, as
/// `render` does, before allocating anything.
#[test]
fn converge_refuses_an_image_too_large() {
    let dir = TempDir::new("converge-size");
    let scene = dir.write("s.ron", ROOM);
    let out = dir.path().join("study");
    let run = flatray(&[
        "converge",
        s(&scene),
        "--scale",
        "1e9",
        "-q",
        "--out",
        s(&out),
    ]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("more than flatray renders"), "{run:?}");
}

/// Case 10: an error in the n-th item of a list names that item's line,
/// also after a comment that holds the item's kind.
#[test]
fn an_error_in_a_later_item_names_its_own_line() {
    let dir = TempDir::new("item-lines");
    let cases = [
        (
            "Scene(canvas: (100, 80), floor: Color((0.5, 0.5, 0.5)), lights: [\n  Spot(at: (5, 5), direction: (1, 0), cone: 30),\n  Spot(at: (9, 9), direction: (1, 0), cone: 200),\n])",
            3,
            "cone",
        ),
        (
            "Scene(canvas: (100, 80), floor: Color((0.5, 0.5, 0.5)),\n  // Line(a: (0, 0), b: (0, 0)) is not allowed\n  lights: [\n    Point(at: (1, 1)),\n    Line(a: (3, 3), b: (4, 4)),\n    Line(a: (5, 5), b: (5, 5)),\n  ])",
            6,
            "two different endpoints",
        ),
        (
            "Scene(canvas: (100, 80), floor: Color((0.5, 0.5, 0.5)), glass: [\n  Glass(points: [(10, 10), (20, 10), (15, 20)]),\n  /* Glass( */ Glass(points: [(50, 50), (60, 50)]),\n])",
            3,
            "at least 3 points",
        ),
    ];
    for (text, line, expected) in cases {
        let scene = dir.write("s.ron", text);
        let run = flatray(&["check", s(&scene)]);
        assert_eq!(run.code, 2, "{run:?}");
        let prefix = format!("error: {}:{line}:", scene.display());
        assert!(
            run.stderr.starts_with(&prefix) && run.stderr.contains(expected),
            "expected {prefix:?} and {expected:?}: {:?}",
            run.stderr
        );
    }
}

/// Case 11: a scene that cannot be read as text (UTF-16, random bytes, a
/// folder) is a bad scene: exit 2, with a message.
#[test]
fn an_unreadable_scene_is_a_bad_scene() {
    let dir = TempDir::new("unreadable");
    let utf16: Vec<u8> = "\u{feff}Scene(canvas: (10, 10))"
        .encode_utf16()
        .flat_map(u16::to_le_bytes)
        .collect();
    let random: Vec<u8> = (0..200u32)
        .map(|k| (k.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    let utf16_path = dir.path().join("utf16.ron");
    let random_path = dir.path().join("random.ron");
    for (path, bytes) in [(&utf16_path, &utf16), (&random_path, &random)] {
        std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{e}"));
    }
    let folder = dir.path().join("folder.ron");
    std::fs::create_dir_all(&folder).unwrap_or_else(|e| panic!("{e}"));
    for path in [&utf16_path, &random_path, &folder] {
        for command in ["check", "plan"] {
            let run = flatray(&[command, s(path)]);
            assert_eq!(run.code, 2, "{command} {}: {run:?}", path.display());
            assert!(run.stderr.contains(s(path)), "{run:?}");
        }
    }
    let run = flatray(&["check", s(&utf16_path)]);
    assert!(run.stderr.contains("UTF-8"), "{run:?}");
}

/// Case 13: a UTF-8 byte-order mark is accepted.
#[test]
fn a_byte_order_mark_is_accepted() {
    let dir = TempDir::new("bom");
    let scene = dir.write("s.ron", &format!("\u{feff}{ROOM}"));
    let run = flatray(&["check", s(&scene)]);
    assert_eq!(run.code, 0, "{run:?}");
}

/// Case 14: values valid as numbers but large enough to overflow a pixel
/// are refused with their location.
#[test]
fn values_that_would_overflow_are_refused() {
    let dir = TempDir::new("huge-values");
    for (text, expected) in [
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  lights: [Point(at: (5, 5), intensity: 1e308)])",
            "intensity",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  render: (exposure: 1e308))",
            "exposure",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  walls: [Wall(a: (1, 1), b: (1e308, 5))])",
            "coordinates",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  small_radius: 1e-300)",
            "small radius",
        ),
        (
            "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),\n  render: (specular: 5000))",
            "mirror and glass events in a row",
        ),
    ] {
        let scene = dir.write("s.ron", text);
        let run = flatray(&["check", s(&scene)]);
        assert_eq!(run.code, 2, "{text}: {run:?}");
        let prefix = format!("error: {}:2:", scene.display());
        assert!(
            run.stderr.starts_with(&prefix) && run.stderr.contains(expected),
            "{text}: {:?}",
            run.stderr
        );
    }
    let scene = dir.write("s.ron", ROOM);
    let out = dir.path().join("out.png");
    let run = flatray(&[
        "render",
        s(&scene),
        "-q",
        "--exposure",
        "1e308",
        "-o",
        s(&out),
    ]);
    assert_eq!(run.code, 2, "{run:?}");
    // The largest values allowed give finite pixels.
    let scene = dir.write(
        "max.ron",
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)), falloff: InverseSquare, small_radius: 1e-6,
           lights: [Point(at: (5.5, 5.5), intensity: 1e9)], render: (exposure: 1e9))",
    );
    let exr = dir.path().join("max.exr");
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&exr)]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(!run.stderr.contains("warning"), "{run:?}");
    let image = flatray_io::read_exr(&exr).unwrap_or_else(|e| panic!("{e}"));
    assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
}

/// Case 16: an output name as long as a name can be still works: the
/// temporary file's name is short.
#[test]
fn a_long_output_name_works() {
    let dir = TempDir::new("long-name");
    let scene = dir.write("s.ron", ROOM);
    let out = dir.path().join(format!("{}.png", "n".repeat(250)));
    let run = flatray(&["render", s(&scene), "-q", "-o", s(&out)]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(out.exists());
}

/// Case 17: an output in a missing folder, or that is a folder, is
/// refused before rendering.
#[test]
fn an_output_that_cannot_be_written_is_refused_before_rendering() {
    let dir = TempDir::new("bad-output");
    let scene = dir.write("s.ron", ROOM);
    let folder = dir.path().join("x.png");
    std::fs::create_dir_all(&folder).unwrap_or_else(|e| panic!("{e}"));
    for out in [dir.path().join("missing/out.png"), folder] {
        // A render this large would take minutes: refused at once.
        let run = flatray(&["render", s(&scene), "-q", "--spp", "1048576", "-o", s(&out)]);
        assert_eq!(run.code, 2, "{run:?}");
        assert!(run.stderr.contains(s(&out)), "{run:?}");
    }
}

/// Case 18: `converge` never takes another scene's reference, nor one
/// whose noise estimate is missing.
#[test]
fn converge_keys_its_reference_by_scene_and_settings() {
    let dir = TempDir::new("converge-cache");
    let out = dir.path().join("study");
    let a = dir.write("a.ron", ROOM);
    let b = dir.write(
        "b.ron",
        "Scene(canvas: (20, 20), floor: Color((0.5, 0.5, 0.5)), lights: [Point(at: (3, 3), intensity: 9)])",
    );
    let study = |scene: &Path| {
        let run = flatray(&[
            "converge",
            s(scene),
            "-q",
            "--out",
            s(&out),
            "--reference-spp",
            "8",
            "--max-spp",
            "2",
            "--configs",
            "path",
        ]);
        assert_eq!(run.code, 0, "{run:?}");
        run.stdout
    };
    let references = || -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .map(|d| {
                d.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.starts_with("reference") && n.ends_with(".exr"))
                    .collect()
            })
            .unwrap_or_default();
        names.sort();
        names
    };
    study(&a);
    study(&b);
    assert_eq!(references().len(), 2, "{:?}", references());
    // The same scene again reuses its own.
    study(&a);
    assert_eq!(references().len(), 2, "{:?}", references());
    // Without its noise estimate a reference is rendered again.
    for name in references() {
        let noise = out.join(&name).with_extension("noise.txt");
        std::fs::remove_file(&noise).unwrap_or_else(|e| panic!("{e}"));
    }
    let report = study(&a);
    assert!(!report.contains("relative noise 0.000 %"), "{report}");
}

/// Case 19: a glass body wholly inside another is refused.
#[test]
fn glass_inside_glass_is_refused() {
    let dir = TempDir::new("nested-glass");
    let scene = dir.write(
        "s.ron",
        "Scene(canvas: (100, 100), floor: Color((1, 1, 1)), glass: [\n  Glass(points: [(10, 10), (90, 10), (90, 90), (10, 90)]),\n  Glass(points: [(40, 40), (60, 40), (50, 60)]),\n])",
    );
    let run = flatray(&["check", s(&scene)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(
        run.stderr.contains(":3:") && run.stderr.contains("inside"),
        "{run:?}"
    );
}

/// The small messages a newcomer meets: each says what was meant.
#[test]
fn messages_say_what_was_meant() {
    let dir = TempDir::new("messages");
    let scene = dir.write("room.ron", ROOM);
    let out = dir.path().join("o.png");
    // `--samples`, the scene's own word, is `--spp`.
    let run = flatray(&["render", s(&scene), "-q", "--samples", "2", "-o", s(&out)]);
    assert_eq!(run.code, 0, "{run:?}");
    // A huge scale is said at its size, not at the largest u32.
    let run = flatray(&["render", s(&scene), "-q", "--scale", "1e9", "-o", s(&out)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("20000000000 x 20000000000"), "{run:?}");
    // `Some(...)` around a value that is written bare.
    let some = dir.write(
        "some.ron",
        "Scene(canvas: (20, 20), floor: Color((0.5, 0.5, 0.5)),\n    lights: [Point(at: (10, 12), color: Some((1, 1, 1)))])",
    );
    let run = flatray(&["check", s(&some)]);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(
        run.stderr.contains(
            ":2:41: write the value for `color` bare, as `color: (...)`, without `Some(...)`"
        ),
        "{run:?}"
    );
    // A manual page's synopsis is the command as typed, and offers only
    // its own flags.
    let run = flatray(&["man", "render"]);
    assert_eq!(run.code, 0, "{run:?}");
    let synopsis = run
        .stdout
        .split(".SH SYNOPSIS")
        .nth(1)
        .and_then(|r| r.split(".SH").next())
        .unwrap_or_default();
    assert!(synopsis.contains(r"\fBflatray render\fR"), "{synopsis}");
    assert!(!synopsis.contains("version"), "{synopsis}");
    assert!(
        run.stdout.contains(".TH flatray-render 1"),
        "the page's name"
    );
    // Plurals.
    let glass = dir.write(
        "glass.ron",
        "Scene(canvas: (100, 100), floor: Color((0.5, 0.5, 0.5)), lights: [Point(at: (10, 12))],
         glass: [Glass(points: [(20, 20), (40, 20), (30, 40)]), Glass(points: [(60, 60), (80, 60), (70, 80)])])",
    );
    let run = flatray(&["plan", s(&glass)]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(run.stdout.contains("2 glass bodies"), "{run:?}");
    assert!(!run.stdout.contains("bodys"), "{run:?}");
}
