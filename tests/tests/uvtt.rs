//! Universal VTT maps (`flatray import MAP.dd2vtt`): the example maps
//! import with their walls, doors, windows, lights and floor at the map's
//! scale; a turned tavern leaks no light through its shut door or the
//! corners where its runs of wall meet; WebP and oversized images become
//! PNG floors; and every kind of bad file gets a message that names the
//! bad value by its JSON path, with nothing written.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use flatray_geometry::DVec2;
use flatray_io::import::{Doors, ImportOptions, Imported, ImportedFloor, ImportedLight, WallKind};
use flatray_tests::{TempDir, flatray, render, workspace_root};
use flatray_tracer::RenderOptions;
use serde_json::{Value, json};

fn map(name: &str) -> PathBuf {
    workspace_root().join("scenes/maps").join(name)
}

fn imported(path: &Path, options: &ImportOptions) -> Imported {
    flatray_io::import::import(path, options).unwrap_or_else(|e| panic!("{e}"))
}

fn count(plan: &Imported, what: &str) -> usize {
    plan.walls
        .iter()
        .filter(|w| w.source.contains(what))
        .count()
}

fn png_size(bytes: &[u8]) -> (u32, u32) {
    let image = image::load_from_memory(bytes).unwrap();
    (image.width(), image.height())
}

#[test]
fn the_example_maps_import_with_their_walls_portals_lights_and_floor() {
    let tavern = imported(&map("tavern.dd2vtt"), &ImportOptions::default());
    // 14 x 10 cells at 64 pixels a cell.
    assert_eq!(tavern.canvas, (896, 640));
    assert_eq!(tavern.kind, "Universal VTT map");
    // 12 walls from the runs of line_of_sight, 8 from the bar and the
    // table, the two shut doors; the three windows as panes.
    assert_eq!(count(&tavern, "objects_line_of_sight"), 8);
    assert_eq!(count(&tavern, "a door, shut"), 2);
    assert_eq!(count(&tavern, "a window"), 3);
    assert_eq!(tavern.walls.len(), 12 + 8 + 2 + 3);
    for wall in &tavern.walls {
        let pane = matches!(wall.kind, WallKind::Pane(_));
        assert_eq!(pane, wall.source.contains("a window"), "{wall:?}");
    }
    // The kitchen's door, from (9, 4) to (9, 5) cells.
    assert!(tavern.walls.iter().any(|w| w.source.contains("portals[1]")
        && w.a == DVec2::new(576.0, 256.0)
        && w.b == DVec2::new(576.0, 320.0)));
    // Lights keep their place, colour and reach.
    assert_eq!(tavern.lights.len(), 3);
    let ImportedLight::Point {
        at,
        color,
        intensity,
        range,
        ..
    } = &tavern.lights[0]
    else {
        panic!("{:?}", tavern.lights[0]);
    };
    assert_eq!(*at, DVec2::new(2.5 * 64.0, 7.5 * 64.0));
    assert_eq!(*range, Some(6.0 * 64.0));
    assert_eq!(*intensity, 2.0 * 1.5);
    // ff9a3c: red full, green above blue.
    assert!(
        color[0] == 1.0 && color[1] > color[2] && color[2] > 0.0,
        "{color:?}"
    );
    // The floor is the map's own image, pixel for pixel at the map's scale.
    let ImportedFloor::Image(name) = &tavern.floor else {
        panic!("{:?}", tavern.floor);
    };
    assert_eq!(name, "tavern-floor.png");
    let (_, bytes) = tavern.floor_file.as_ref().unwrap();
    assert_eq!(png_size(bytes), (896, 640));
    let text = std::fs::read_to_string(map("tavern.dd2vtt")).unwrap();
    let embedded = serde_json::from_str::<Value>(&text).unwrap()["image"]
        .as_str()
        .map(|s| base64::engine::general_purpose::STANDARD.decode(s).unwrap())
        .unwrap();
    assert_eq!(bytes, &embedded);
    assert!(tavern.mapping.iter().any(|m| m.contains("2 doors shut")
        && m.contains("3 windows")
        && m.contains("walls and panes")));
    assert!(
        tavern
            .warnings
            .iter()
            .any(|w| w.contains("environment.ambient_light"))
    );

    // Half the scale: half the canvas, the same image stretched over it.
    let half = imported(
        &map("tavern.dd2vtt"),
        &ImportOptions {
            scale: Some(32.0),
            ..ImportOptions::default()
        },
    );
    assert_eq!(half.canvas, (448, 320));
    assert_eq!(png_size(&half.floor_file.as_ref().unwrap().1), (896, 640));
    assert!(matches!(half.lights[0], ImportedLight::Point { range: Some(r), .. } if r == 192.0));

    // The corridor: the cave's rough wall is 24 walls of one run.
    let corridor = imported(&map("corridor.uvtt"), &ImportOptions::default());
    assert_eq!(corridor.canvas, (880, 360));
    assert_eq!(count(&corridor, "line_of_sight[6]"), 24);
    assert_eq!(count(&corridor, "a door, shut"), 1);
    assert_eq!(corridor.lights.len(), 4);
    assert_eq!(
        png_size(&corridor.floor_file.as_ref().unwrap().1),
        (880, 360)
    );
    // Both load and pass `check` without a warning.
    let dir = TempDir::new("uvtt-examples");
    for (mut plan, name) in [(tavern, "tavern.ron"), (corridor, "corridor.ron")] {
        let out = dir.path().join(name);
        plan.write(&out, &map("none"), false).unwrap();
        let run = flatray(&["check", out.to_str().unwrap()]);
        assert_eq!(run.code, 0, "{run:?}");
        assert!(!run.stderr.contains("warning"), "{run:?}");
    }
}

/// The tavern's geometry turned by 23 degrees about its middle and moved
/// into a larger map, without its image.
fn turned_tavern(dir: &TempDir) -> PathBuf {
    let text = std::fs::read_to_string(map("tavern.dd2vtt")).unwrap();
    let mut value: Value = serde_json::from_str(&text).unwrap();
    let (s, c) = 23f64.to_radians().sin_cos();
    let turn = |p: &mut Value| {
        let (x, y) = (
            p["x"].as_f64().unwrap() - 7.0,
            p["y"].as_f64().unwrap() - 5.0,
        );
        p["x"] = json!(c * x - s * y + 8.0);
        p["y"] = json!(s * x + c * y + 7.0);
    };
    for key in ["line_of_sight", "objects_line_of_sight"] {
        for run in value[key].as_array_mut().unwrap() {
            run.as_array_mut().unwrap().iter_mut().for_each(turn);
        }
    }
    for portal in value["portals"].as_array_mut().unwrap() {
        turn(&mut portal["position"]);
        portal["bounds"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .for_each(turn);
    }
    for light in value["lights"].as_array_mut().unwrap() {
        turn(&mut light["position"]);
    }
    value["resolution"]["map_size"] = json!({"x": 16, "y": 14});
    value.as_object_mut().unwrap().remove("image");
    let path = dir.path().join("turned.dd2vtt");
    std::fs::write(&path, value.to_string()).unwrap();
    path
}

/// Where a canvas pixel of the turned tavern (16 pixels a cell) lies in
/// the tavern's own cells.
fn tavern_cell(pixel: DVec2) -> DVec2 {
    let (s, c) = 23f64.to_radians().sin_cos();
    let q = pixel / 16.0 - DVec2::new(8.0, 7.0);
    DVec2::new(c * q.x + s * q.y + 7.0, -s * q.x + c * q.y + 5.0)
}

#[test]
fn a_turned_tavern_leaks_no_light_through_its_shut_door_or_its_corners() {
    let dir = TempDir::new("uvtt-leak");
    let path = turned_tavern(&dir);
    let in_kitchen = |p: DVec2| {
        let t = tavern_cell(p);
        t.x > 9.1 && t.x < 12.9 && t.y > 1.1 && t.y < 8.9
    };
    let in_hall = |p: DVec2| {
        let t = tavern_cell(p);
        t.x > 1.2 && t.x < 8.8 && t.y > 5.2 && t.y < 8.8
    };
    for doors in [Doors::AsDrawn, Doors::Open] {
        let plan = imported(
            &path,
            &ImportOptions {
                scale: Some(16.0),
                doors,
                ..ImportOptions::default()
            },
        );
        assert_eq!(plan.canvas, (256, 224));
        let loaded = flatray_io::parse(&plan.to_ron(), Path::new("turned.ron"), Path::new("."))
            .unwrap_or_else(|e| panic!("{e}"));
        for bounces in [0, 2] {
            let mut options = RenderOptions::default();
            options.samples = 4;
            options.bounces = bounces;
            let image = render(&loaded.scene, &options).image;
            let (mut kitchen, mut kitchen_sum, mut hall_sum) = (0usize, 0.0f64, 0.0f64);
            for y in 0..image.height {
                for x in 0..image.width {
                    let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let value = image.get(x, y);
                    if in_kitchen(p) {
                        kitchen += 1;
                        kitchen_sum += value.iter().map(|&v| v as f64).sum::<f64>();
                        if doors == Doors::AsDrawn {
                            assert_eq!(value, [0.0; 3], "bounces {bounces}: ({x}, {y})");
                        }
                    }
                    if in_hall(p) {
                        hall_sum += value[0] as f64;
                    }
                }
            }
            assert!(kitchen > 2000, "{kitchen} pixels in the kitchen");
            assert!(hall_sum > 100.0, "the hall is lit: {hall_sum}");
            if doors == Doors::Open {
                // Through the open door the kitchen gets light.
                assert!(kitchen_sum / kitchen as f64 > 1e-3, "{kitchen_sum}");
            }
        }
    }
}

/// A small map of one room (2 x 2 cells inside a 4 x 4 map) with the
/// given image, as JSON text.
fn room_map(image: Option<String>, extra: Value) -> String {
    let mut value = json!({
        "format": 0.3,
        "resolution": {"map_origin": {"x": 0, "y": 0}, "map_size": {"x": 4, "y": 3}, "pixels_per_grid": 10},
        "line_of_sight": [[{"x": 1, "y": 1}, {"x": 3, "y": 1}, {"x": 3, "y": 2}, {"x": 1, "y": 2}, {"x": 1, "y": 1}]],
        "objects_line_of_sight": [],
        "portals": [],
        "lights": [{"position": {"x": 2, "y": 1.5}, "range": 2, "intensity": 1, "color": "ffffffff", "shadows": true}],
    });
    if let Some(image) = image {
        value["image"] = json!(image);
    }
    if let (Value::Object(map), Value::Object(more)) = (&mut value, extra) {
        map.extend(more);
    }
    value.to_string()
}

fn encode(image: &image::RgbImage, format: image::ImageFormat) -> String {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, format).unwrap();
    base64::engine::general_purpose::STANDARD.encode(bytes.into_inner())
}

#[test]
fn a_webp_image_becomes_a_png_floor_and_a_large_one_is_reduced_to_fit() {
    let dir = TempDir::new("uvtt-images");
    let picture = image::RgbImage::from_fn(40, 30, |x, y| {
        image::Rgb([(x * 6) as u8, (y * 8) as u8, ((x + y) * 3) as u8])
    });
    let path = dir.write(
        "webp.uvtt",
        &room_map(Some(encode(&picture, image::ImageFormat::WebP)), json!({})),
    );
    let plan = imported(&path, &ImportOptions::default());
    let (name, bytes) = plan.floor_file.as_ref().unwrap();
    assert_eq!(name, "webp-floor.png");
    assert!(bytes.starts_with(b"\x89PNG"));
    // Lossless WebP: the same pixels.
    assert_eq!(image::load_from_memory(bytes).unwrap().to_rgb8(), picture);

    // 4097 x 4097 is more than a floor image holds (2^24 pixels): halved,
    // each texel the mean of its 2 x 2 block in linear light.
    let side = 4097;
    let big = image::RgbImage::from_fn(side, side, |x, _| {
        image::Rgb(if x % 2 == 0 { [255; 3] } else { [0; 3] })
    });
    let path = dir.write(
        "big.dd2vtt",
        &room_map(
            Some(encode(&big, image::ImageFormat::Png)),
            json!({"resolution": {"map_origin": {"x": 0, "y": 0}, "map_size": {"x": 4097, "y": 4097}, "pixels_per_grid": 1}}),
        ),
    );
    let plan = imported(&path, &ImportOptions::default());
    let floor = image::load_from_memory(&plan.floor_file.as_ref().unwrap().1)
        .unwrap()
        .to_rgb8();
    assert_eq!(floor.dimensions(), (2049, 2049));
    // Half white, half black in linear light is 0.5, sRGB 188.
    assert_eq!(floor.get_pixel(10, 10).0, [188; 3]);
    // The last column holds only white texels.
    assert_eq!(floor.get_pixel(2048, 10).0, [255; 3]);
    assert!(
        plan.mapping
            .iter()
            .any(|m| m.contains("reduced to 2049 x 2049"))
    );
    assert_eq!(plan.canvas, (4097, 4097));
}

/// A PNG's signature, header and an empty data chunk: a picture of
/// `w x h` pixels by its header, with no pixels.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut header = Vec::new();
    header.extend(w.to_be_bytes());
    header.extend(h.to_be_bytes());
    header.extend([8, 2, 0, 0, 0]);
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    for (kind, data) in [(&b"IHDR"[..], &header[..]), (b"IDAT", &[])] {
        let mut body = kind.to_vec();
        body.extend(data);
        bytes.extend((data.len() as u32).to_be_bytes());
        bytes.extend(&body);
        bytes.extend(crc32(&body).to_be_bytes());
    }
    bytes
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn every_kind_of_bad_map_gets_a_located_message_and_nothing_is_written() {
    let dir = TempDir::new("uvtt-bad");
    let b64 = |bytes: &[u8]| base64::engine::general_purpose::STANDARD.encode(bytes);
    let good = room_map(None, json!({}));
    let with = |extra: Value| room_map(None, extra);
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "not JSON",
            "{\"resolution\": {\n  \"map_size\": }".to_string(),
            ":2:",
        ),
        (
            "a NaN",
            good.replace("\"range\":2", "\"range\":NaN"),
            "a number that is not finite (NaN)",
        ),
        (
            "no resolution",
            "{\"pixels_per_grid\": 1, \"line_of_sight\": []}".to_string(),
            "resolution: missing: expected the map's size and grid",
        ),
        (
            "a grid of no pixels",
            good.replace("\"pixels_per_grid\":10", "\"pixels_per_grid\":0"),
            "resolution.pixels_per_grid: expected a number of pixels > 0",
        ),
        (
            "a size that is text",
            good.replace("\"map_size\":{\"x\":4", "\"map_size\":{\"x\":\"four\""),
            "resolution.map_size.x: expected a number, found the string \"four\"",
        ),
        (
            "a wall of one point",
            with(
                json!({"line_of_sight": [[{"x": 0, "y": 0}, {"x": 1, "y": 0}], [{"x": 2, "y": 2}]]}),
            ),
            "line_of_sight[1]: a wall needs at least two points, found 1",
        ),
        (
            "a point without y",
            with(json!({"objects_line_of_sight": [[{"x": 0, "y": 0}, {"x": 1}]]})),
            "objects_line_of_sight[0][1].y: missing",
        ),
        (
            "a coordinate out of reach",
            with(json!({"line_of_sight": [[{"x": 0, "y": 0}, {"x": 1e12, "y": 0}]]})),
            "line_of_sight[0][1].x: expected a coordinate within",
        ),
        (
            "a portal's bound that is not a number",
            with(json!({"portals": [
                {"bounds": [{"x": 1, "y": 1}, {"x": 2, "y": 1}], "closed": true},
                {"bounds": [{"x": 1, "y": 2}, {"x": true, "y": 2}], "closed": true}
            ]})),
            "portals[1].bounds[1].x: expected a number, found true",
        ),
        (
            "a portal of zero width",
            with(
                json!({"portals": [{"bounds": [{"x": 1, "y": 1}, {"x": 1, "y": 1}], "closed": true}]}),
            ),
            "portals[0].bounds: the portal has zero width",
        ),
        (
            "a portal of one bound",
            with(json!({"portals": [{"bounds": [{"x": 1, "y": 1}], "closed": true}]})),
            "portals[0].bounds: expected two points (the portal's ends), found 1",
        ),
        (
            "a portal neither closed nor open",
            with(
                json!({"portals": [{"bounds": [{"x": 1, "y": 1}, {"x": 2, "y": 1}], "closed": "yes"}]}),
            ),
            "portals[0].closed: expected true or false",
        ),
        (
            "a colour that is not one",
            good.replace("\"color\":\"ffffffff\"", "\"color\":\"warm\""),
            "lights[0].color: expected a colour as hex ARGB",
        ),
        (
            "a negative range",
            good.replace("\"range\":2", "\"range\":-2"),
            "lights[0].range: expected a reach of 0 to 1e9 grid cells, found -2",
        ),
        (
            "an image that is not base64",
            room_map(Some("not base64 at all!".to_string()), json!({})),
            "image: not base64",
        ),
        (
            "a payload that is not an image",
            room_map(Some(b64(b"<html>a web page</html>")), json!({})),
            "image: the base64 payload is not a PNG or WebP image (its first bytes are 3c 68 74 6d)",
        ),
        (
            "an image too large",
            room_map(Some(b64(&png_header(9000, 9000))), json!({})),
            "image: the map image is 9000 x 9000 pixels, more than the 67108864 the import reads",
        ),
        (
            "an image cut short",
            room_map(Some(b64(&png_header(40, 30))), json!({})),
            "image: the map image cannot be decoded",
        ),
    ];
    for (what, text, expected) in cases {
        let plan = dir.write("bad.dd2vtt", &text);
        let target = dir.path().join("never.ron");
        let run = flatray(&[
            "import",
            plan.to_str().unwrap(),
            "-o",
            target.to_str().unwrap(),
        ]);
        assert_eq!(run.code, 2, "{what}: {run:?}");
        assert!(
            run.stderr.contains(&format!("{}", plan.display())) && run.stderr.contains(expected),
            "{what}: expected {expected:?} in {}",
            run.stderr
        );
        assert!(!target.exists(), "{what}");
        assert!(!dir.path().join("bad-floor.png").exists(), "{what}");
    }
    // The good map imports, by any of the format's extensions, and a
    // `.json` that names `pixels_per_grid` is read as one too (a Tiled
    // map's JSON has no such key).
    for name in ["good.dd2vtt", "good.uvtt", "good.df2vtt", "good.json"] {
        let plan = dir.write(name, &good);
        let out = dir.path().join("good.ron");
        let run = flatray(&[
            "import",
            plan.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--force",
        ]);
        assert_eq!(run.code, 0, "{name}: {run:?}");
        assert!(run.stdout.contains("4 walls, 1 light"), "{name}: {run:?}");
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(
            text.contains("from the Universal VTT map"),
            "{name}: {text}"
        );
    }
}

#[test]
fn the_command_line_writes_the_scene_and_the_floor_and_replaces_neither() {
    let dir = TempDir::new("uvtt-cli");
    let out = dir.path().join("tavern.ron");
    let tavern = map("tavern.dd2vtt");
    let args = [
        "import",
        tavern.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    let run = flatray(&args);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(run.stdout.contains("25 walls, 3 lights"), "{run:?}");
    assert!(
        run.stderr
            .contains("note: portals: 2 doors shut (opaque walls), 3 windows (clear panes)"),
        "{run:?}"
    );
    let floor = dir.path().join("tavern-floor.png");
    assert_eq!(png_size(&std::fs::read(&floor).unwrap()), (896, 640));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("floor: Image(\"tavern-floor.png\")"));
    // Again: both files exist, neither is replaced.
    let written = std::fs::read(&floor).unwrap();
    std::fs::write(&floor, b"mine").unwrap();
    let run = flatray(&args);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("the file exists"), "{run:?}");
    assert_eq!(std::fs::read(&floor).unwrap(), b"mine");
    std::fs::write(&floor, written).unwrap();
    // Without lights, with every door open.
    let dark = dir.path().join("dark.ron");
    let run = flatray(&[
        "import",
        map("tavern.dd2vtt").to_str().unwrap(),
        "--lights",
        "none",
        "--doors",
        "open",
        "-o",
        dark.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(run.stdout.contains("23 walls, 0 lights"), "{run:?}");
    // Each scene's floor image is named for it.
    assert!(dir.path().join("dark-floor.png").is_file());
    assert!(
        run.stderr
            .contains("--lights none, so the map's 3 lights are not imported"),
        "{run:?}"
    );
    // Open portals read as doors: the three windows become open doors too.
    let doors = dir.path().join("doors.ron");
    let run = flatray(&[
        "import",
        map("tavern.dd2vtt").to_str().unwrap(),
        "--open-portals",
        "doors",
        "-o",
        doors.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    assert!(
        run.stderr
            .contains("2 doors shut (opaque walls), 3 doors open (gaps in their walls)"),
        "{run:?}"
    );
    let png = dir.path().join("tavern.png");
    let run = flatray(&[
        "render",
        out.to_str().unwrap(),
        "-q",
        "--spp",
        "1",
        "--scale",
        "0.25",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(run.code, 0, "{run:?}");
}

/// Where a map's wall runs on under its portals, each portal cuts the
/// wall: a shut door and a window go into the gap, an open door leaves it
/// open, and no two walls lie on top of each other.
#[test]
fn portals_on_a_wall_that_runs_on_cut_it() {
    let dir = TempDir::new("uvtt-cut");
    let path = dir.write(
        "cut.uvtt",
        &room_map(
            None,
            json!({"portals": [
                {"bounds": [{"x": 1.5, "y": 1}, {"x": 2, "y": 1}], "closed": true},
                {"bounds": [{"x": 2.5, "y": 2}, {"x": 1.5, "y": 2}], "closed": false}
            ]}),
        ),
    );
    let p = |x: f64, y: f64| DVec2::new(x * 10.0, y * 10.0);
    let has = |plan: &Imported, a: DVec2, b: DVec2| {
        plan.walls
            .iter()
            .filter(|w| (w.a == a && w.b == b) || (w.a == b && w.b == a))
            .map(|w| w.kind)
            .collect::<Vec<_>>()
    };
    for doors in [Doors::AsDrawn, Doors::Open] {
        let mut plan = imported(
            &path,
            &ImportOptions {
                doors,
                ..ImportOptions::default()
            },
        );
        // The top wall, cut around the door.
        assert_eq!(has(&plan, p(1.0, 1.0), p(1.5, 1.0)).len(), 1, "{plan:?}");
        assert_eq!(has(&plan, p(2.0, 1.0), p(3.0, 1.0)).len(), 1, "{plan:?}");
        let door = has(&plan, p(1.5, 1.0), p(2.0, 1.0));
        match doors {
            Doors::Open => assert!(door.iter().all(|k| *k == WallKind::OpenDoor), "{door:?}"),
            _ => assert_eq!(door, vec![WallKind::ShutDoor]),
        }
        // The bottom wall, cut around the window, which is in the gap.
        assert_eq!(has(&plan, p(1.0, 2.0), p(1.5, 2.0)).len(), 1, "{plan:?}");
        assert_eq!(has(&plan, p(2.5, 2.0), p(3.0, 2.0)).len(), 1, "{plan:?}");
        assert!(matches!(
            has(&plan, p(2.5, 2.0), p(1.5, 2.0))[..],
            [WallKind::Pane(_)]
        ));
        let out = dir.path().join("cut.ron");
        plan.write(&out, &path, true).unwrap();
        let run = flatray(&["check", out.to_str().unwrap()]);
        assert_eq!(run.code, 0, "{run:?}");
        assert!(!run.stderr.contains("warning"), "{run:?}");
        let scene = std::fs::read_to_string(&out).unwrap();
        assert_eq!(
            scene.matches("Wall(").count(),
            if doors == Doors::Open { 7 } else { 8 },
            "{scene}"
        );
    }
}

/// Every value of a map replaced, one at a time, by each kind of JSON
/// value: the import never panics, and what it refuses it refuses naming
/// the replaced value's path (or, for a size no canvas holds, saying so).
#[test]
fn any_value_of_a_map_replaced_by_any_other_is_imported_or_named() {
    fn leaves(value: &Value, path: String, out: &mut Vec<String>) {
        match value {
            Value::Object(map) => {
                for (k, v) in map {
                    let child = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    leaves(v, child, out);
                }
            }
            Value::Array(items) => {
                for (i, v) in items.iter().enumerate() {
                    leaves(v, format!("{path}[{i}]"), out);
                }
            }
            _ => out.push(path),
        }
    }
    fn at<'a>(value: &'a mut Value, path: &str) -> &'a mut Value {
        let mut v = value;
        for part in path.split('.') {
            let (key, indices) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
            v = &mut v[key];
            for index in indices.split('[').filter(|s| !s.is_empty()) {
                v = &mut v[index.trim_end_matches(']').parse::<usize>().unwrap()];
            }
        }
        v
    }
    let dir = TempDir::new("uvtt-mutations");
    let base: Value = serde_json::from_str(&room_map(
        None,
        json!({"portals": [{"position": {"x": 2, "y": 1}, "bounds": [{"x": 1.5, "y": 1}, {"x": 2, "y": 1}], "rotation": 0, "closed": true, "freestanding": false}],
               "environment": {"baked_lighting": false, "ambient_light": "ff808080"}}),
    ))
    .unwrap();
    let mut paths = Vec::new();
    leaves(&base, String::new(), &mut paths);
    assert!(paths.len() > 30, "{paths:?}");
    let replacements = [
        json!(null),
        json!(true),
        json!(-1),
        json!(0),
        json!(1e300),
        json!("x"),
        json!([]),
        json!({}),
    ];
    let mut refused = 0;
    for path in &paths {
        for replacement in &replacements {
            let mut value = base.clone();
            *at(&mut value, path) = replacement.clone();
            let file = dir.write("m.uvtt", &value.to_string());
            match flatray_io::import::import(&file, &ImportOptions::default()) {
                Ok(plan) => {
                    flatray_io::parse(&plan.to_ron(), Path::new("m.ron"), Path::new("."))
                        .unwrap_or_else(|e| panic!("{path} = {replacement}: {e}"));
                }
                Err(e) => {
                    refused += 1;
                    let message = e.to_string();
                    // The path, or the list or object that holds it.
                    let named = (0..=path.len())
                        .rev()
                        .filter(|&k| k == path.len() || matches!(path.as_bytes()[k], b'.' | b'['))
                        .any(|k| message.contains(&format!(": {}: ", &path[..k])));
                    assert!(
                        named || message.contains("the canvas would be"),
                        "{path} = {replacement}: {message}"
                    );
                }
            }
        }
    }
    assert!(refused > paths.len(), "{refused} refused");
}

/// A map whose origin is not at (0, 0) keeps its coordinates: the scene's
/// canvas starts at the origin, so the walls lie on the picture where
/// the map drew them.
#[test]
fn a_map_origin_becomes_the_scenes_origin() {
    let dir = TempDir::new("uvtt-origin");
    let path = dir.write(
        "origin.uvtt",
        &room_map(
            None,
            json!({"resolution": {"map_origin": {"x": 1, "y": 0.5}, "map_size": {"x": 4, "y": 3}, "pixels_per_grid": 10}}),
        ),
    );
    let plan = imported(&path, &ImportOptions::default());
    assert_eq!(plan.origin, DVec2::new(10.0, 5.0));
    assert_eq!(plan.canvas, (40, 30));
    assert!(plan.walls.iter().any(|w| w.a == DVec2::new(10.0, 10.0)));
    let loaded = flatray_io::parse(&plan.to_ron(), Path::new("o.ron"), Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.scene.canvas().origin, DVec2::new(10.0, 5.0));
}
