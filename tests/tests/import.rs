//! `flatray import`: floor plans from an Inkscape SVG, a Tiled map (TMX
//! and JSON) and a wall mask become scenes whose walls are checked by
//! coordinates, whose closed rooms do not leak, and which render as the
//! hand-written scene with the same walls does.

use std::path::{Path, PathBuf};

use flatray_geometry::DVec2;
use flatray_io::import::{ImportOptions, Imported, ImportedLight, WallKind, import};
use flatray_tests::{TempDir, flatray, render, workspace_root};
use flatray_tracer::RenderOptions;

fn fixture(name: &str) -> PathBuf {
    workspace_root().join("tests/fixtures/import").join(name)
}

fn imported(path: &Path, options: &ImportOptions) -> Imported {
    import(path, options).unwrap_or_else(|e| panic!("{e}"))
}

/// The imported scene parses as a scene file.
fn scene_of(plan: &Imported) -> flatray_io::Loaded {
    flatray_io::parse(&plan.to_ron(), Path::new("imported.ron"), Path::new("."))
        .unwrap_or_else(|e| panic!("the imported scene does not load: {e}\n{}", plan.to_ron()))
}

fn near(a: DVec2, b: DVec2) -> bool {
    a.distance(b) < 1e-3
}

/// Whether the walls hold a wall from `a` to `b` (either way round).
fn has_wall(plan: &Imported, a: DVec2, b: DVec2) -> Option<WallKind> {
    plan.walls
        .iter()
        .find(|w| (near(w.a, a) && near(w.b, b)) || (near(w.a, b) && near(w.b, a)))
        .map(|w| w.kind)
}

#[test]
fn an_inkscape_svg_imports_with_units_transforms_and_marks() {
    let plan = imported(&fixture("flat.svg"), &ImportOptions::default());
    // 200 x 150 mm at 96 dpi.
    assert_eq!(plan.canvas, (756, 567));
    let mm = 96.0 / 25.4;
    let p = |x: f64, y: f64| DVec2::new(x * mm, y * mm);
    // The rectangle, in a layer translated by (10, 10), with its colour;
    // its top edge cut where the window lies on it.
    assert!(has_wall(&plan, p(10.0, 10.0), p(190.0, 10.0)).is_none());
    assert!(has_wall(&plan, p(10.0, 10.0), p(40.0, 10.0)).is_some());
    let kind = has_wall(&plan, p(80.0, 10.0), p(190.0, 10.0));
    assert!(
        matches!(kind, Some(WallKind::Diffuse(Some(c))) if (c[0] - 0.6867).abs() < 1e-3),
        "{kind:?}"
    );
    assert!(has_wall(&plan, p(190.0, 140.0), p(10.0, 140.0)).is_some());
    // The partition in a nested group, its colour from a CSS class, with
    // a door between its two subpaths.
    assert!(has_wall(&plan, p(100.0, 10.0), p(100.0, 65.0)).is_some());
    assert!(has_wall(&plan, p(100.0, 85.0), p(100.0, 140.0)).is_some());
    assert!(has_wall(&plan, p(100.0, 65.0), p(100.0, 85.0)).is_none());
    // A layer with id "mirrors", a layer with id "windows".
    assert_eq!(
        has_wall(&plan, p(20.0, 30.0), p(20.0, 90.0)),
        Some(WallKind::Mirror)
    );
    assert!(matches!(
        has_wall(&plan, p(40.0, 10.0), p(80.0, 10.0)),
        Some(WallKind::Pane(_))
    ));
    // The curve, flattened: its pieces join end to end, from its start
    // to its end, each point within the tolerance of the true curve.
    let sofa: Vec<_> = plan
        .walls
        .iter()
        .filter(|w| w.source == "path-sofa")
        .collect();
    assert!(sofa.len() >= 4, "{} pieces", sofa.len());
    assert!(near(sofa[0].a, p(130.0, 110.0)) && near(sofa[sofa.len() - 1].b, p(170.0, 110.0)));
    for pair in sofa.windows(2) {
        assert_eq!(pair[0].b, pair[1].a);
    }
    // Lamps at their circles' centres, intensities from the attributes
    // (the group's, and the element's own that overrides it).
    let lamps: Vec<(DVec2, f64)> = plan
        .lights
        .iter()
        .filter_map(|l| match l {
            ImportedLight::Point { at, intensity, .. } => Some((*at, *intensity)),
            _ => None,
        })
        .collect();
    assert_eq!(lamps.len(), 2);
    assert!(
        near(lamps[0].0, p(50.0, 70.0)) && lamps[0].1 == 30.0,
        "{lamps:?}"
    );
    assert!(
        near(lamps[1].0, p(150.0, 50.0)) && lamps[1].1 == 12.5,
        "{lamps:?}"
    );
    // The glass body, closed, with its index.
    assert_eq!(plan.glass.len(), 1);
    assert_eq!(plan.glass[0].points.len(), 3);
    assert_eq!(plan.glass[0].ior, 1.6);
    // The text is listed, not dropped silently.
    assert!(
        plan.warnings.iter().any(|w| w.contains("<text>")),
        "{:?}",
        plan.warnings
    );
    let loaded = scene_of(&plan);
    assert_eq!(loaded.scene.lights().len(), 2);
}

#[test]
fn a_tiled_map_imports_the_same_from_tmx_and_json() {
    let tmx = imported(&fixture("level.tmx"), &ImportOptions::default());
    let json = imported(&fixture("level.json"), &ImportOptions::default());
    for plan in [&tmx, &json] {
        assert_eq!(plan.canvas, (320, 240));
        let p = DVec2::new;
        // The rectangle object, the polyline, the mirror by property.
        assert!(has_wall(plan, p(16.0, 16.0), p(304.0, 16.0)).is_some());
        assert!(has_wall(plan, p(16.0, 224.0), p(16.0, 16.0)).is_some());
        assert!(has_wall(plan, p(160.0, 16.0), p(160.0, 96.0)).is_some());
        assert_eq!(
            has_wall(plan, p(40.0, 200.0), p(88.0, 152.0)),
            Some(WallKind::Mirror)
        );
        // The polygon turned 30 degrees clockwise about its position.
        let (s, c) = 30f64.to_radians().sin_cos();
        let corner = p(232.0 + 16.0 * c, 150.0 + 16.0 * s);
        assert!(
            matches!(
                has_wall(plan, p(232.0, 150.0), corner),
                Some(WallKind::Diffuse(Some(_)))
            ),
            "{:?}",
            plan.walls
        );
        // Lights in a group layer offset by (8, 4), with properties.
        match &plan.lights[0] {
            ImportedLight::Point {
                at,
                intensity,
                color,
                ..
            } => {
                assert!(near(*at, p(80.0, 104.0)), "{at}");
                assert_eq!(*intensity, 40.0);
                assert!((color[1] - 0.6038).abs() < 1e-3, "{color:?}");
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            &plan.lights[1],
            ImportedLight::Line { a, b, intensity, .. }
                if near(*a, p(208.0, 184.0)) && near(*b, p(268.0, 184.0)) && *intensity == 0.5
        ));
        // The ellipse and the tile layer are listed.
        assert!(
            plan.warnings.iter().any(|w| w.contains("ellipse")),
            "{:?}",
            plan.warnings
        );
        assert!(
            plan.warnings.iter().any(|w| w.contains("tile layer")),
            "{:?}",
            plan.warnings
        );
        scene_of(plan);
    }
    assert_eq!(tmx.walls, json.walls);
    assert_eq!(tmx.lights, json.lights);
}

#[test]
fn a_wall_mask_traces_closed_outlines_with_its_door_and_diagonal() {
    let plan = imported(&fixture("house-mask.png"), &ImportOptions::default());
    assert_eq!(plan.canvas, (160, 120));
    let p = DVec2::new;
    // The outer walls' outline, around the door gap at x = 70..90.
    assert!(has_wall(&plan, p(10.0, 10.0), p(150.0, 10.0)).is_some());
    assert!(has_wall(&plan, p(70.0, 106.0), p(70.0, 110.0)).is_some());
    assert!(has_wall(&plan, p(90.0, 110.0), p(90.0, 106.0)).is_some());
    // The diagonal wall: its staircase simplified to four walls.
    let diagonal: Vec<_> = plan
        .walls
        .iter()
        .filter(|w| w.source == "outline 1")
        .collect();
    assert_eq!(diagonal.len(), 4, "{diagonal:?}");
    // Every outline is closed: each wall ends where the next begins.
    let mut by_source: std::collections::BTreeMap<&str, Vec<_>> = Default::default();
    for w in &plan.walls {
        by_source.entry(w.source.as_str()).or_default().push(w);
    }
    for (source, walls) in by_source {
        for k in 0..walls.len() {
            assert_eq!(walls[k].b, walls[(k + 1) % walls.len()].a, "{source}");
        }
    }
    // The yellow blob is a lamp at its centre.
    assert!(matches!(
        plan.lights.as_slice(),
        [ImportedLight::Point { at, .. }] if near(*at, p(122.0, 72.0))
    ));
    scene_of(&plan);
}

/// Every pixel whose centre is well inside a closed imported room is
/// exactly dark when the only light is outside it.
fn assert_dark_inside(name: &str, plan: &Imported, inside: impl Fn(DVec2) -> bool) {
    let loaded = scene_of(plan);
    for bounces in [0, 2] {
        let options = {
            let mut options = RenderOptions::default();
            options.samples = 4;
            options.bounces = bounces;
            options
        };
        let image = render(&loaded.scene, &options).image;
        let mut count = 0;
        for y in 0..image.height {
            for x in 0..image.width {
                if inside(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                    count += 1;
                    assert_eq!(
                        image.get(x, y),
                        [0.0; 3],
                        "{name}, D = {bounces}: ({x}, {y})"
                    );
                }
            }
        }
        assert!(count > 200, "{name}: {count} pixels inside");
        assert!(
            image.pixels.iter().any(|p| p[0] > 0.0),
            "{name}: nothing lit"
        );
    }
}

#[test]
fn imported_closed_rooms_do_not_leak() {
    let dir = TempDir::new("import-leak");
    // A square room turned by 17 degrees, the lamp outside.
    let svg = dir.write(
        "room.svg",
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">
  <g transform="rotate(17 50 50)"><rect id="room" x="25" y="25" width="50" height="50" style="fill:none;stroke:#000"/></g>
  <circle id="lamp" cx="8" cy="92" r="1" style="fill:#fff"/>
</svg>"##,
    );
    let plan = imported(&svg, &ImportOptions::default());
    let (s, c) = 17f64.to_radians().sin_cos();
    assert_dark_inside("svg", &plan, |p| {
        let q = p - DVec2::splat(50.0);
        (c * q.x + s * q.y).abs() < 23.0 && (-s * q.x + c * q.y).abs() < 23.0
    });
    // A Tiled polygon room, turned, the light outside.
    let tmx = dir.write(
        "room.tmx",
        r#"<map width="10" height="10" tilewidth="10" tileheight="10">
 <objectgroup name="walls"><object id="1" x="30" y="20" rotation="23"><polygon points="0,0 50,0 50,50 0,50"/></object></objectgroup>
 <objectgroup name="lights"><object id="2" x="5" y="95"><point/></object></objectgroup>
</map>"#,
    );
    let plan = imported(&tmx, &ImportOptions::default());
    let (s, c) = 23f64.to_radians().sin_cos();
    assert_dark_inside("tiled", &plan, |p| {
        let q = p - DVec2::new(30.0, 20.0);
        let (u, v) = (c * q.x + s * q.y, -s * q.x + c * q.y);
        u > 2.0 && u < 48.0 && v > 2.0 && v < 48.0
    });
    // The mask's outer walls closed (no door), the lamp outside.
    let (w, h) = (100u32, 100u32);
    let mut pixels = vec![255u8; (w * h * 3) as usize];
    for y in 0..h {
        for x in 0..w {
            let ring = (20..80).contains(&x)
                && (20..80).contains(&y)
                && !((23..77).contains(&x) && (23..77).contains(&y));
            // A diagonal stroke crossing the ring's corner.
            let diagonal = x + 2 >= y && x <= y + 2 && (10..40).contains(&x);
            let lamp = (5..8).contains(&x) && (90..93).contains(&y);
            let k = ((y * w + x) * 3) as usize;
            if ring || diagonal {
                pixels[k..k + 3].copy_from_slice(&[0, 0, 0]);
            } else if lamp {
                pixels[k..k + 3].copy_from_slice(&[255, 255, 0]);
            }
        }
    }
    let mask = dir.path().join("mask.png");
    image::save_buffer(&mask, &pixels, w, h, image::ExtendedColorType::Rgb8)
        .unwrap_or_else(|e| panic!("{e}"));
    let plan = imported(&mask, &ImportOptions::default());
    assert_dark_inside("mask", &plan, |p| {
        p.x > 41.0 && p.x < 76.0 && p.y > 24.0 && p.y < 76.0
    });
}

/// The same walls imported from an SVG and written by hand render the
/// same image, bit for bit.
#[test]
fn an_imported_scene_renders_as_the_hand_written_one() {
    let dir = TempDir::new("import-round-trip");
    let svg = dir.write(
        "plan.svg",
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="80" height="60">
  <g transform="translate(5,5)">
    <polyline id="wall" points="5,5 65,5 65,45 5,45 5,5" style="fill:none;stroke:#ff0000"/>
    <line id="mirror" x1="40" y1="10" x2="40" y2="30" style="stroke:#888"/>
  </g>
  <circle id="lamp" cx="25" cy="30" r="1" style="fill:#ffffff" data-flatray-intensity="20"/>
</svg>"##,
    );
    let plan = imported(&svg, &ImportOptions::default());
    let by_hand = flatray_tests::scene(
        "Scene(canvas: (80, 60), floor: Color((0.8, 0.8, 0.8)), walls: [
            Wall(a: (10, 10), b: (70, 10), material: Diffuse(albedo: (1, 0, 0))),
            Wall(a: (70, 10), b: (70, 50), material: Diffuse(albedo: (1, 0, 0))),
            Wall(a: (70, 50), b: (10, 50), material: Diffuse(albedo: (1, 0, 0))),
            Wall(a: (10, 50), b: (10, 10), material: Diffuse(albedo: (1, 0, 0))),
            Wall(a: (45, 15), b: (45, 35), material: Mirror()),
        ], lights: [Point(at: (25, 30), intensity: 20)])",
    );
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 8;
        options.bounces = 2;
        options
    };
    let a = render(&scene_of(&plan).scene, &options).image;
    let b = render(&by_hand.scene, &options).image;
    assert!(a == b, "the imported scene renders differently");
}

#[test]
fn the_command_line_imports_and_renders_and_refuses_bad_plans() {
    let dir = TempDir::new("import-cli");
    let out = dir.path().join("flat.ron");
    let run = flatray(&[
        "import",
        fixture("flat.svg").to_str().unwrap_or_default(),
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(run.stdout.contains("18 walls"), "{run:?}");
    assert!(
        run.stderr.contains(
            "note: the window line7 lies on the wall rect1: the wall is cut there and the window put in the gap"
        ),
        "{run:?}"
    );
    assert!(
        run.stderr
            .contains("warning: not imported: 1 <text> element"),
        "{run:?}"
    );
    let png = dir.path().join("flat.png");
    let run = flatray(&[
        "render",
        out.to_str().unwrap_or_default(),
        "-q",
        "--spp",
        "1",
        "--scale",
        "0.1",
        "-o",
        png.to_str().unwrap_or_default(),
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    // Malformed plans: exit 2, with a location where the reader has one.
    for (name, text, location) in [
        (
            "bad.svg",
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\">\n  <rect x=\"1\"\n</svg>",
            ":3:",
        ),
        (
            "bad.tmx",
            "<map width=\"2\" height=\"2\">\n<objectgroup name=\"walls\">\n</map>",
            ":3:",
        ),
        (
            "bad.json",
            "{\"layers\": [\n  {\"type\": \"objectgroup\",,}\n]}",
            ":2:",
        ),
        ("bad.txt", "not a plan", ""),
        // Well formed, but a coordinate that no scene can hold.
        (
            "nan.tmx",
            "<map width=\"2\" height=\"2\" tilewidth=\"16\" tileheight=\"16\">\n<objectgroup name=\"walls\"><object id=\"1\" x=\"NaN\" y=\"5\"><polyline points=\"0,0 10,0\"/></object></objectgroup>\n</map>",
            ": the plan does not make a valid scene",
        ),
    ] {
        let plan = dir.write(name, text);
        let target = dir.path().join("never.ron");
        let run = flatray(&[
            "import",
            plan.to_str().unwrap_or_default(),
            "-o",
            target.to_str().unwrap_or_default(),
        ]);
        assert_eq!(run.code, 2, "{name}: {run:?}");
        assert!(
            run.stderr
                .contains(&format!("{}{location}", plan.display())),
            "{name}: {run:?}"
        );
        assert!(!target.exists());
    }
    // The plan itself is never the output.
    let svg = dir.write(
        "self.svg",
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\" height=\"10\"/>",
    );
    let run = flatray(&[
        "import",
        svg.to_str().unwrap_or_default(),
        "-o",
        svg.to_str().unwrap_or_default(),
    ]);
    assert_eq!(run.code, 2, "{run:?}");
}

/// `--floor-image` takes the drawing's linked bitmap as the floor, written
/// beside the scene.
#[test]
fn an_svg_bitmap_becomes_the_floor_when_asked() {
    let dir = TempDir::new("import-floor");
    let mut floor = flatray_tracer::Image::new(8, 6);
    floor.pixels.iter_mut().for_each(|p| *p = [0.5, 0.25, 0.1]);
    flatray_io::write_png(
        &floor,
        flatray_io::ToneMap::Clamp,
        &dir.path().join("tiles.png"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let svg = dir.write(
        "plan.svg",
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="80" height="60">
  <image xlink:href="tiles.png" x="0" y="0" width="80" height="60"/>
  <line id="wall" x1="10" y1="10" x2="70" y2="10" style="stroke:#000"/>
</svg>"#,
    );
    let out = dir.path().join("scene.ron");
    let run = flatray(&[
        "import",
        svg.to_str().unwrap_or_default(),
        "--floor-image",
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    let written = dir.path().join("scene-floor.png");
    assert!(written.exists(), "{run:?}");
    let loaded = flatray_io::load(&out).unwrap_or_else(|e| panic!("{e}"));
    assert!(matches!(
        loaded.scene.floor(),
        flatray_tracer::Floor::Image {
            width: 8,
            height: 6,
            ..
        }
    ));
    // Without the flag the bitmap is listed as not imported.
    let run = flatray(&[
        "import",
        svg.to_str().unwrap_or_default(),
        "--force",
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert!(run.stderr.contains("<image>"), "{run:?}");
}

/// A window or door drawn on a wall's line opens the wall: the wall is
/// cut at its ends (a window stays in the gap, a door leaves it open),
/// whichever way either runs, at any angle; a door on no wall is no wall.
#[test]
fn windows_and_doors_drawn_on_a_wall_cut_it() {
    let dir = TempDir::new("import-openings");
    let (s, c) = 0.37f64.sin_cos();
    let turn = |x: f64, y: f64| (200.0 + c * x - s * y, 150.0 + s * x + c * y);
    let line = |id: &str, a: (f64, f64), b: (f64, f64)| {
        let (p, q) = (turn(a.0, a.1), turn(b.0, b.1));
        format!(
            r#"<line id="{id}" x1="{}" y1="{}" x2="{}" y2="{}" style="stroke:#ffffff"/>"#,
            p.0, p.1, q.0, q.1
        )
    };
    let svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="400" height="300">{}{}{}{}</svg>"#,
        line("wall-a", (-100.0, 0.0), (100.0, 0.0)),
        line("window-1", (50.0, 0.0), (-20.0, 0.0)),
        line("door-1", (60.0, 0.0), (80.0, 0.0)),
        line("door-2", (-100.0, 50.0), (-80.0, 50.0)),
    );
    let path = dir.write("plan.svg", &svg);
    let plan = imported(&path, &ImportOptions::default());
    let point = |x: f64| {
        let (px, py) = turn(x, 0.0);
        DVec2::new(px, py)
    };
    let walls: Vec<(f64, f64, WallKind)> = plan
        .walls
        .iter()
        .map(|w| {
            let along = |p: DVec2| (p - point(0.0)).dot(point(1.0) - point(0.0));
            (along(w.a), along(w.b), w.kind)
        })
        .collect();
    let diffuse: Vec<(f64, f64)> = walls
        .iter()
        .filter(|w| matches!(w.2, WallKind::Diffuse(_)))
        .map(|w| (w.0, w.1))
        .collect();
    // usvg computes in single precision.
    let close = |x: f64, y: f64| (x - y).abs() < 1e-4;
    assert_eq!(diffuse.len(), 3, "{walls:?}");
    for (k, (a, b)) in [(-100.0, -20.0), (50.0, 60.0), (80.0, 100.0)]
        .iter()
        .enumerate()
    {
        assert!(
            close(diffuse[k].0, *a) && close(diffuse[k].1, *b),
            "{walls:?}"
        );
    }
    assert_eq!(
        walls
            .iter()
            .filter(|w| matches!(w.2, WallKind::Pane(_)))
            .count(),
        1
    );
    assert_eq!(plan.notes.len(), 2, "{:?}", plan.notes);
    assert!(
        plan.warnings
            .iter()
            .any(|w| w.contains("door-2: a door lies on no wall")),
        "{:?}",
        plan.warnings
    );
    // The written scene has nothing lying on anything.
    let warnings = scene_of(&plan).warnings;
    assert!(
        !warnings
            .iter()
            .any(|w| w.message.contains("lies on top of")),
        "{warnings:?}"
    );
}

/// The imported flat is dark outside but for the light its window lets
/// out: every pixel more than 2 px beyond its outer walls, beside and
/// below it, is exactly 0 (its window, in the top wall, lights only what
/// lies above that wall's line), at 0 to 3 bounces.
#[test]
fn the_imported_flat_is_dark_outside_but_through_its_window() {
    let plan = imported(&fixture("flat.svg"), &ImportOptions::default());
    let loaded = scene_of(&plan);
    let mm = 96.0 / 25.4;
    for bounces in [0, 1, 3] {
        let image = render(&loaded.scene, &{
            let mut options = loaded.options;
            options.samples = 4;
            options.bounces = bounces;
            options.scale = 0.25;
            options
        })
        .image;
        let world = |x: u32, y: u32| DVec2::new(x as f64 + 0.5, y as f64 + 0.5) * 4.0 / mm;
        let (mut outside, mut above) = (0, 0.0);
        for y in 0..image.height {
            for x in 0..image.width {
                let p = world(x, y);
                let v = image.get(x, y);
                // Two pixels, in millimetres.
                let m = 2.0 * 4.0 / mm;
                let beside = p.y > 10.0 && (p.x < 10.0 - m || p.x > 190.0 + m);
                if beside || p.y > 140.0 + m {
                    outside += 1;
                    assert_eq!(v, [0.0; 3], "D = {bounces}: light outside at ({x}, {y})");
                } else if p.y < 10.0 - m {
                    above += v[0] as f64;
                }
            }
        }
        assert!(outside > 500, "{outside}");
        if bounces > 0 {
            assert!(above > 0.0, "D = {bounces}: no light through the window");
        }
    }
}

/// Circles, round ellipses and a path's arc command become arcs (usvg
/// draws each as cubic curves of a quarter turn at most; each is an arc
/// to within the tolerance, its points on the drawn circle), an ellipse
/// that is no circle is flattened into segments within the tolerance, a
/// glass circle becomes glass bounded by arcs, and the scene loads; the
/// round room keeps the lamp's light out.
#[test]
fn svg_circles_ellipses_and_arc_commands_become_arcs() {
    let plan = imported(&fixture("round.svg"), &ImportOptions::default());
    let on_circle = |c: DVec2, r: f64| {
        move |w: &&flatray_io::import::ImportedWall| {
            [w.a, w.b, w.through.unwrap_or(w.a)]
                .iter()
                .all(|p| (p.distance(c) - r).abs() < 1e-3)
        }
    };
    let arcs_of = |source: &str| -> Vec<&flatray_io::import::ImportedWall> {
        plan.walls.iter().filter(|w| w.source == source).collect()
    };
    // The room: a circle of quarter arcs.
    let room = arcs_of("wall-room");
    assert_eq!(room.len(), 4, "{room:?}");
    assert!(room.iter().all(|w| w.through.is_some()));
    assert!(room.iter().all(on_circle(DVec2::new(80.0, 100.0), 60.0)));
    // The column, an ellipse of equal radii.
    let column = arcs_of("wall-column");
    assert!(!column.is_empty() && column.iter().all(|w| w.through.is_some()));
    assert!(column.iter().all(on_circle(DVec2::new(220.0, 60.0), 12.0)));
    // The bay: half a circle of radius 40 about (210, 110).
    let bay = arcs_of("wall-bay");
    assert!(
        !bay.is_empty() && bay.iter().all(|w| w.through.is_some()),
        "{bay:?}"
    );
    assert!(bay.iter().all(on_circle(DVec2::new(210.0, 110.0), 40.0)));
    // The rug is no circle: segments, within the tolerance of the oval.
    let rug = arcs_of("wall-rug");
    assert!(
        rug.len() > 8 && rug.iter().all(|w| w.through.is_none()),
        "{rug:?}"
    );
    // The rod: glass of arcs.
    assert_eq!(plan.glass.len(), 1);
    assert!(plan.glass[0].through.iter().all(Option::is_some));
    assert_eq!(plan.glass[0].through.len(), plan.glass[0].points.len());
    // The scene loads and holds the arcs as arcs.
    let loaded = scene_of(&plan);
    let arcs = loaded
        .scene
        .walls()
        .iter()
        .filter(|w| w.shape.as_arc().is_some())
        .count();
    assert!(arcs >= 4 + 4 + 2 + 4, "{arcs} arcs");
    // No light gets into the round room from the lamp outside.
    assert_dark_inside("round room", &plan, |p| {
        p.distance(DVec2::new(80.0, 100.0)) < 57.0
    });
}

/// A Tiled ellipse object whose width is its height is a circle of two
/// arcs (glass too, by its material), turned with its object; one that
/// is not is a polygon, with a warning.
#[test]
fn tiled_ellipses_become_circles_or_polygons() {
    let dir = TempDir::new("tiled-ellipses");
    let path = dir.write(
        "round.tmx",
        r#"<?xml version="1.0" encoding="UTF-8"?>
<map version="1.10" orientation="orthogonal" width="20" height="15" tilewidth="16" tileheight="16">
 <objectgroup id="1" name="walls">
  <object id="1" name="column" x="100" y="50" width="40" height="40" rotation="30"><ellipse/></object>
  <object id="2" name="rod" x="200" y="100" width="20" height="20"><properties><property name="material" value="glass"/></properties><ellipse/></object>
  <object id="3" name="rug" x="40" y="150" width="60" height="20"><ellipse/></object>
 </objectgroup>
 <objectgroup id="2" name="lights">
  <object id="4" name="lamp" x="20" y="20"><point/></object>
 </objectgroup>
</map>"#,
    );
    let plan = imported(&path, &ImportOptions::default());
    let column: Vec<_> = plan
        .walls
        .iter()
        .filter(|w| w.source.contains("column"))
        .collect();
    assert_eq!(column.len(), 2, "{column:?}");
    // The circle's centre: the box's centre turned 30 degrees about the
    // object's position.
    let (s, c) = 30f64.to_radians().sin_cos();
    let centre = DVec2::new(100.0 + 20.0 * c - 20.0 * s, 50.0 + 20.0 * s + 20.0 * c);
    for w in &column {
        let m = w.through.expect("an arc");
        for p in [w.a, w.b, m] {
            assert!(
                (p.distance(centre) - 20.0).abs() < 1e-9,
                "{p} off the circle"
            );
        }
    }
    assert_eq!(plan.glass.len(), 1);
    assert_eq!(plan.glass[0].points.len(), 2);
    let rug: Vec<_> = plan
        .walls
        .iter()
        .filter(|w| w.source.contains("rug"))
        .collect();
    assert!(rug.len() >= 8 && rug.iter().all(|w| w.through.is_none()));
    assert!(
        plan.warnings
            .iter()
            .any(|w| w.contains("rug") && w.contains("not a circle")),
        "{:?}",
        plan.warnings
    );
    scene_of(&plan);
}
