//! `flatray measure`, run as a user would: a room's figures against the
//! fluence of a line light integrated by hand, the stated uncertainty
//! against the true error of many independent measurements, and the
//! CSV's rows against the figures and the map.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn flatray() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flatray"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flatray-measure-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A CSV row of the grid: x, y, room, E, se.
type Row = (f64, f64, String, f64, f64);

/// `flatray measure` of `text` with `args`: its JSON and its CSV rows.
fn measure(dir: &Path, text: &str, args: &[&str]) -> (Value, Vec<Row>) {
    let scene = dir.join("scene.ron");
    let csv = dir.join("grid.csv");
    std::fs::write(&scene, text).unwrap();
    let output = flatray()
        .arg("measure")
        .arg(&scene)
        .args(["--json", "--quiet", "--csv"])
        .arg(&csv)
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: Value = serde_json::from_slice(&output.stdout).unwrap();
    let rows = std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            (
                f[0].parse().unwrap(),
                f[1].parse().unwrap(),
                f[2].to_string(),
                f[3].parse().unwrap(),
                f[4].parse().unwrap(),
            )
        })
        .collect();
    (json, rows)
}

fn figure(room: &Value, name: &str) -> (f64, f64) {
    (
        room[name]["value"].as_f64().unwrap(),
        room[name]["se"].as_f64().unwrap(),
    )
}

/// A 10 m by 5 m room (200 x 100 units of 5 cm), black walls on the
/// canvas's edge, a two-sided line light of intensity `I` from (50, 40)
/// to (150, 40), no bounces: the fluence at `p` is `I` times the angle
/// the line subtends there. EN 12464-1 gives a 1 m grid (20 units): 10 by
/// 5 cells, each the mean of that angle over its square.
#[test]
fn a_line_lit_room_measures_the_fluence_integrated_by_hand() {
    const I: f64 = 0.01;
    let text = format!(
        r#"Scene(
    canvas: (200, 100),
    floor: Color((1, 1, 1)),
    walls: [
        Wall(a: (0, 0), b: (200, 0), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (200, 0), b: (200, 100), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (200, 100), b: (0, 100), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (0, 100), b: (0, 0), material: Diffuse(albedo: (0, 0, 0))),
    ],
    lights: [Line(a: (50, 40), b: (150, 40), intensity: {I})],
    render: (samples: 16, bounces: 0),
    units: (metres_per_unit: 0.05),
    rooms: [Room(name: "hall", at: (20, 70))],
)"#
    );
    let dir = scratch("hand");
    let (json, rows) = measure(&dir, &text, &["--batches", "8"]);
    let room = &json["rooms"][0];
    assert_eq!(room["name"], "hall");
    assert_eq!(room["spacing"].as_f64().unwrap(), 20.0);
    assert_eq!(rows.len(), 50, "10 x 5 cells");
    // Each cell's mean by the midpoint rule, 4 x 4 points per unit.
    let angle = |x: f64, y: f64| {
        let (a, b) = ((50.0 - x, 40.0 - y), (150.0 - x, 40.0 - y));
        let cross = a.0 * b.1 - a.1 * b.0;
        let dot = a.0 * b.0 + a.1 * b.1;
        cross.abs().atan2(dot)
    };
    let cell = |cx: f64, cy: f64| {
        let n = 80;
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                let x = cx - 10.0 + (i as f64 + 0.5) * 20.0 / n as f64;
                let y = cy - 10.0 + (j as f64 + 0.5) * 20.0 / n as f64;
                sum += I * angle(x, y);
            }
        }
        sum / (n * n) as f64
    };
    let expected: Vec<f64> = rows.iter().map(|r| cell(r.0, r.1)).collect();
    // Every grid point within 4 of its standard errors (and the midpoint
    // rule's 0.2 %).
    for (r, e) in rows.iter().zip(&expected) {
        assert!(
            (r.3 - e).abs() <= 4.0 * r.4 + 2e-3 * e,
            "({}, {}): {} ± {} against {e}",
            r.0,
            r.1,
            r.3,
            r.4
        );
    }
    let e_avg = expected.iter().sum::<f64>() / expected.len() as f64;
    let e_min = expected.iter().copied().fold(f64::INFINITY, f64::min);
    let e_max = expected.iter().copied().fold(0.0, f64::max);
    for (name, want) in [
        ("e_avg", e_avg),
        ("e_min", e_min),
        ("e_max", e_max),
        ("u0", e_min / e_avg),
    ] {
        let (value, se) = figure(room, name);
        assert!(
            (value - want).abs() <= 4.0 * se + 2e-3 * want,
            "{name}: {value} ± {se} against {want}"
        );
    }
    // On the line the angle is pi: the brightest cells see nearly that.
    assert!(e_max > 0.8 * I * PI);
}

/// An L-shaped room turned by 20 degrees, bright walls, three bounces, a
/// lamp and a line light, rendered with `seed`.
fn l_room(seed: u64) -> String {
    let (s, c) = 20f64.to_radians().sin_cos();
    let at = |x: f64, y: f64| {
        let (x, y) = (x - 60.0, y - 60.0);
        format!("({:.4}, {:.4})", 60.0 + c * x - s * y, 60.0 + s * x + c * y)
    };
    let outline = [
        (20.0, 20.0),
        (100.0, 20.0),
        (100.0, 60.0),
        (60.0, 60.0),
        (60.0, 100.0),
        (20.0, 100.0),
    ];
    let walls: Vec<String> = (0..outline.len())
        .map(|k| {
            let (a, b) = (outline[k], outline[(k + 1) % outline.len()]);
            format!(
                "Wall(a: {}, b: {}, material: Diffuse(albedo: (0.8, 0.8, 0.8))),",
                at(a.0, a.1),
                at(b.0, b.1)
            )
        })
        .collect();
    format!(
        r#"Scene(
    canvas: (120, 120),
    floor: Color((0.8, 0.8, 0.8)),
    walls: [{}],
    lights: [
        Point(at: {}, intensity: 3),
        Line(a: {}, b: {}, intensity: 0.02),
    ],
    render: (samples: 16, bounces: 3, seed: {seed}),
    units: (metres_per_unit: 0.1),
    rooms: [Room(name: "L", at: {})],
)"#,
        walls.join("\n        "),
        at(85.0, 40.0),
        at(25.0, 90.0),
        at(25.0, 60.0),
        at(40.0, 40.0)
    )
}

/// The L-shaped room ([`l_room`]): many measurements of a few samples
/// each, their stated standard errors against their spread about a
/// reference of many samples.
#[test]
fn the_stated_uncertainty_is_the_true_error() {
    let text = l_room;
    let dir = scratch("honest");
    let (reference, reference_rows) = measure(&dir, &text(1000), &["--spp", "2048"]);
    let runs = 20;
    let (mut point_error, mut point_stated) = (0.0, 0.0);
    let mut figures = [(0.0, 0.0); 3];
    let names = ["e_avg", "e_min", "u0"];
    for seed in 0..runs {
        let (json, rows) = measure(&dir, &text(seed), &["--spp", "16"]);
        assert_eq!(rows.len(), reference_rows.len());
        for (r, q) in rows.iter().zip(&reference_rows) {
            assert_eq!((r.0, r.1), (q.0, q.1));
            point_error += (r.3 - q.3).powi(2) - q.4 * q.4;
            point_stated += r.4 * r.4;
        }
        for (k, name) in names.iter().enumerate() {
            let (value, se) = figure(&json["rooms"][0], name);
            let (want, want_se) = figure(&reference["rooms"][0], name);
            figures[k].0 += (value - want).powi(2) - want_se * want_se;
            figures[k].1 += se * se;
        }
    }
    // Over 20 runs of about 40 points the pooled ratio has a standard
    // error of a few per cent: 0.7 to 1.4 is many of them.
    let ratio = (point_error / point_stated).sqrt();
    assert!((0.7..=1.4).contains(&ratio), "grid points: {ratio}");
    // A room's figure over 20 runs: the ratio's standard error is about
    // 16 %; 0.55 to 1.6 is about 3 of them.
    for (k, name) in names.iter().enumerate() {
        let ratio = (figures[k].0.max(0.0) / figures[k].1).sqrt();
        assert!((0.55..=1.6).contains(&ratio), "{name}: {ratio}");
    }
}

/// The CSV holds one row per grid point of every room, in the room's
/// figures: its E values' least, mean and most are E_min, E_avg, E_max.
#[test]
fn the_grid_rows_make_the_rooms_figures_and_the_map_is_written() {
    let dir = scratch("rows");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/daylight.ron"),
    )
    .unwrap();
    let map = dir.join("map.png");
    let (json, rows) = measure(
        &dir,
        &text,
        &[
            "--spp",
            "8",
            "--scale",
            "0.5",
            "--map",
            map.to_str().unwrap(),
        ],
    );
    let rooms = json["rooms"].as_array().unwrap();
    assert_eq!(rooms.len(), 2);
    // The living room is all of x 20..240, y 20..280: the sofa's ends
    // near the south window's do not close a door across the corner.
    let living = rooms[0]["area"].as_f64().unwrap();
    assert!((living / (220.0 * 260.0) - 1.0).abs() < 0.02, "{living}");
    let bedroom = rooms[1]["area"].as_f64().unwrap();
    assert!((bedroom / (140.0 * 260.0) - 1.0).abs() < 0.02, "{bedroom}");
    for room in rooms {
        let name = room["name"].as_str().unwrap();
        let es: Vec<f64> = rows.iter().filter(|r| r.2 == name).map(|r| r.3).collect();
        assert_eq!(es.len() as u64, room["points"].as_u64().unwrap(), "{name}");
        let mean = es.iter().sum::<f64>() / es.len() as f64;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
        assert!(close(mean, figure(room, "e_avg").0), "{name}");
        let min = es.iter().copied().fold(f64::INFINITY, f64::min);
        let max = es.iter().copied().fold(0.0, f64::max);
        assert!(close(min, figure(room, "e_min").0), "{name}");
        assert!(close(max, figure(room, "e_max").0), "{name}");
    }
    let png = image::open(&map).unwrap().to_rgb8();
    // The plan at half scale, and the legend beside it.
    assert_eq!(png.width(), 200 + 150);
}

/// Rooms that cannot be measured as named say why, where, and write
/// nothing.
#[test]
fn bad_rooms_are_refused_with_their_place_and_nothing_is_written() {
    let dir = scratch("bad");
    let scene = dir.join("scene.ron");
    let map = dir.join("map.png");
    let run = |text: &str| {
        std::fs::write(&scene, text).unwrap();
        flatray()
            .arg("measure")
            .arg(&scene)
            .args(["--quiet", "--map"])
            .arg(&map)
            .output()
            .unwrap()
    };
    // One region (no wall between them) named twice.
    let output = run(r#"Scene(
    canvas: (40, 20),
    floor: Color((1, 1, 1)),
    lights: [Point(at: (20, 10), intensity: 1)],
    rooms: [Room(name: "a", at: (5, 5)), Room(name: "b", at: (35, 5))],
)"#);
    assert!(!output.status.success());
    let message = String::from_utf8_lossy(&output.stderr);
    assert!(
        message.contains(r#"rooms "a" and "b" are one region"#),
        "{message}"
    );
    assert!(!map.exists());
    // A room's point off the canvas: its line and column.
    let output = run(r#"Scene(
    canvas: (40, 20),
    floor: Color((1, 1, 1)),
    lights: [Point(at: (20, 10), intensity: 1)],
    rooms: [
        Room(name: "a", at: (50, 5)),
    ],
)"#);
    assert!(!output.status.success());
    let message = String::from_utf8_lossy(&output.stderr);
    assert!(message.contains("scene.ron:6:9"), "{message}");
    assert!(message.contains("lies off the canvas"), "{message}");
    assert!(!map.exists());
}

/// Under a sky alone, a 10 m by 5 m room of black walls with a 2 m
/// opening in its north wall, no bounces: a point's daylight factor is
/// the angle the opening subtends there over `2 pi`, and the room's is
/// the mean of its grid cells'. A door width of 3 m closes the opening
/// for the rooms (the room stays one room, not the outdoors).
#[test]
fn the_daylight_factor_is_the_angle_of_sky_over_a_full_turn() {
    let text = r#"Scene(
    canvas: (240, 140),
    floor: Color((1, 1, 1)),
    walls: [
        Wall(a: (20, 20), b: (100, 20), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (140, 20), b: (220, 20), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (220, 20), b: (220, 120), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (220, 120), b: (20, 120), material: Diffuse(albedo: (0, 0, 0))),
        Wall(a: (20, 120), b: (20, 20), material: Diffuse(albedo: (0, 0, 0))),
    ],
    lights: [
        Sky(color: (1, 1, 1), intensity: 0.1),
        Sun(date: "2026-06-21", time: "12:00", zone: 2, latitude: 48.85, longitude: 2.35,
            intensity: 3),
    ],
    render: (samples: 8, bounces: 0),
    units: (metres_per_unit: 0.05),
    rooms: [Room(name: "hall", at: (60, 90))],
)"#;
    let dir = scratch("daylight");
    let (json, rows) = measure(&dir, text, &["--door-width", "60", "--sun-off"]);
    let room = &json["rooms"][0];
    assert_eq!(rows.len(), 50, "10 x 5 cells: the opening is closed");
    let angle = |x: f64, y: f64| {
        let (a, b) = ((100.0 - x, 20.0 - y), (140.0 - x, 20.0 - y));
        let cross = a.0 * b.1 - a.1 * b.0;
        (cross.abs().atan2(a.0 * b.0 + a.1 * b.1)) / (2.0 * PI)
    };
    let n = 80;
    let cells: Vec<f64> = rows
        .iter()
        .map(|r| {
            let mut sum = 0.0;
            for j in 0..n {
                for i in 0..n {
                    let x = r.0 - 10.0 + (i as f64 + 0.5) * 20.0 / n as f64;
                    let y = r.1 - 10.0 + (j as f64 + 0.5) * 20.0 / n as f64;
                    sum += angle(x, y);
                }
            }
            100.0 * sum / (n * n) as f64
        })
        .collect();
    let want = cells.iter().sum::<f64>() / cells.len() as f64;
    let (value, se) = figure(room, "daylight_factor");
    assert!(
        (value - want).abs() <= 4.0 * se + 2e-3 * want,
        "{value} ± {se} against {want}"
    );
    // With the sun on, there is no daylight factor.
    let (json, _) = measure(&dir, text, &["--door-width", "60"]);
    assert!(json["rooms"][0]["daylight_factor"].is_null());
}

/// `--target-error 0.5` on the L-shaped room from 1 spp a batch: the
/// samples double until every figure's standard error is within 0.5 %
/// of it, and the figures then agree with a reference of many samples
/// within 4 of their standard errors (stopping at the target biases
/// nothing that the batches' independence does not cover).
#[test]
fn a_target_error_renders_until_every_room_figure_meets_it() {
    let dir = scratch("target");
    let (reference, _) = measure(&dir, &l_room(1000), &["--spp", "2048"]);
    let (json, _) = measure(&dir, &l_room(7), &["--spp", "8", "--target-error", "0.5"]);
    assert_eq!(json["target_error"]["percent"].as_f64(), Some(0.5));
    assert_eq!(json["target_error"]["met"].as_bool(), Some(true));
    let spp = json["batch_spp"].as_u64().unwrap();
    assert!(spp > 1 && spp.is_power_of_two(), "{spp} spp a batch");
    // Without the target, the same start misses it: the rounds were needed.
    let (start, _) = measure(&dir, &l_room(7), &["--spp", "8"]);
    assert!(start["target_error"].is_null());
    let missed = ["e_avg", "e_min", "u0"].iter().any(|name| {
        let (value, se) = figure(&start["rooms"][0], name);
        se > 0.005 * value
    });
    assert!(missed, "8 spp already meets 0.5 %: the test shows nothing");
    for name in ["e_avg", "e_min", "u0"] {
        let (value, se) = figure(&json["rooms"][0], name);
        let (want, want_se) = figure(&reference["rooms"][0], name);
        assert!(se <= 0.005 * value, "{name}: {value} ± {se}");
        assert!(
            (value - want).abs() <= 4.0 * (se * se + want_se * want_se).sqrt(),
            "{name}: {value} ± {se} against {want} ± {want_se}"
        );
    }
    // A target that is no per cent is refused, naming the flag.
    let scene = dir.join("scene.ron");
    for bad in ["0", "-1", "nan", "inf"] {
        let output = flatray()
            .args(["measure", "--quiet", &format!("--target-error={bad}")])
            .arg(&scene)
            .output()
            .unwrap();
        assert!(!output.status.success(), "{bad} accepted");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains("--target-error"), "{bad}: {stderr}");
    }
}

/// In lumens (`units: (light: Lumens(storey: H))`), under the 2.5D
/// reading: a lamp of flux `F` sends `F / H` lm per metre of height, and
/// the floor's fluence is in lux. Worked out in metres, apart from the
/// renderer's own units: a two-sided Lambertian line of length `L` sends
/// `4 I L` per metre of height at radiance `I`, so `I = F / (4 H L)` and
/// a point sees `I` times the angle the line subtends; a point lamp
/// gives `F / (2 pi H r)` at `r` metres. A room 10 m by 5 m turned by 30
/// degrees, black walls, no bounces; the grid's cells against their
/// means by the midpoint rule, within 4 standard errors.
#[test]
fn lumens_give_lux_under_the_two_and_a_half_d_reading() {
    const METRES: f64 = 0.05;
    const STOREY: f64 = 2.5;
    const FLUX: f64 = 800.0;
    let (s, c) = 30f64.to_radians().sin_cos();
    let turn = |x: f64, y: f64| {
        let (x, y) = (x - 100.0, y - 50.0);
        (120.0 + c * x - s * y, 120.0 + s * x + c * y)
    };
    let back = |x: f64, y: f64| {
        let (x, y) = (x - 120.0, y - 120.0);
        (100.0 + c * x + s * y, 50.0 - s * x + c * y)
    };
    let p = |(x, y): (f64, f64)| format!("({x:.6}, {y:.6})");
    let corners = [(0.0, 0.0), (200.0, 0.0), (200.0, 100.0), (0.0, 100.0)];
    let walls: Vec<String> = (0..4)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            format!(
                "Wall(a: {}, b: {}, material: Diffuse(albedo: (0, 0, 0))),",
                p(turn(a.0, a.1)),
                p(turn(b.0, b.1))
            )
        })
        .collect();
    let scene = |light: &str| {
        format!(
            r#"Scene(
    canvas: (240, 240),
    floor: Color((1, 1, 1)),
    walls: [{}],
    lights: [{light}],
    render: (samples: 32, bounces: 0),
    units: (metres_per_unit: {METRES}, light: Lumens(storey: {STOREY})),
    rooms: [Room(name: "hall", at: {})],
)"#,
            walls.join("\n        "),
            p(turn(20.0, 80.0))
        )
    };
    // The room's own frame: a line from (50, 40) to (150, 40), a point at
    // (100, 60).
    let line_text = scene(&format!(
        "Line(a: {}, b: {}, intensity: {FLUX})",
        p(turn(50.0, 40.0)),
        p(turn(150.0, 40.0))
    ));
    let point_at = (100.0, 60.0);
    let point_text = scene(&format!(
        "Point(at: {}, intensity: {FLUX})",
        p(turn(point_at.0, point_at.1))
    ));
    let radiance = FLUX / (4.0 * STOREY * 100.0 * METRES);
    let line = |x: f64, y: f64| {
        let (a, b) = ((50.0 - x, 40.0 - y), (150.0 - x, 40.0 - y));
        radiance * (a.0 * b.1 - a.1 * b.0).abs().atan2(a.0 * b.0 + a.1 * b.1)
    };
    let point = |x: f64, y: f64| {
        let r = ((x - point_at.0).powi(2) + (y - point_at.1).powi(2)).sqrt() * METRES;
        FLUX / (std::f64::consts::TAU * STOREY * r)
    };
    let dir = scratch("lumens");
    for (text, lux, name) in [
        (&line_text, &line as &dyn Fn(f64, f64) -> f64, "line"),
        (&point_text, &point, "point"),
    ] {
        let (json, rows) = measure(&dir, text, &[]);
        // Cells are whole pixels (of one unit): of the spacing rounded
        // down or up, told apart by where their centres fall.
        let spacing = json["rooms"][0]["spacing"].as_f64().unwrap();
        let half_of = |at: f64| {
            let odd = spacing.floor() as i64 % 2 == 1;
            let on_half = (at - at.floor() - 0.5).abs() < 1e-9;
            0.5 * if on_half == odd {
                spacing.floor()
            } else {
                spacing.ceil()
            }
        };
        let mut compared = 0;
        let inside = |(x, y): (f64, f64)| (0.0..=200.0).contains(&x) && (0.0..=100.0).contains(&y);
        for r in &rows {
            // The grid's cells are squares of the canvas: those wholly in
            // the room, each's mean by the midpoint rule over its square
            // (cells near the point lamp, where 1 / r is steep, left out).
            let (hx, hy) = (half_of(r.0), half_of(r.1));
            let whole = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .all(|&(i, j)| inside(back(r.0 + hx * i, r.1 + hy * j)));
            let (cx, cy) = back(r.0, r.1);
            if !whole || (name == "point" && (cx - point_at.0).hypot(cy - point_at.1) < 30.0) {
                continue;
            }
            let n = 60;
            let mut sum = 0.0;
            for j in 0..n {
                for i in 0..n {
                    let x = r.0 - hx + (i as f64 + 0.5) * 2.0 * hx / n as f64;
                    let y = r.1 - hy + (j as f64 + 0.5) * 2.0 * hy / n as f64;
                    let (x, y) = back(x, y);
                    sum += lux(x, y);
                }
            }
            let want = sum / (n * n) as f64;
            assert!(
                (r.3 - want).abs() <= 4.0 * r.4 + 3e-3 * want,
                "{name} ({cx:.1}, {cy:.1}): {} ± {} lx against {want} lx",
                r.3,
                r.4
            );
            compared += 1;
        }
        assert!(compared >= 15, "{name}: {compared} cells");
    }
    // The same lamp in the renderer's own units differs: the units are read.
    let relative = line_text.replace(", light: Lumens(storey: 2.5)", "");
    assert_ne!(relative, line_text);
    let (json, _) = measure(&dir, &relative, &[]);
    let (e, _) = figure(&json["rooms"][0], "e_avg");
    assert!(e > 10.0 * radiance, "{e}");
    // A lamp whose falloff is not the physical one has no flux in lumens.
    let bad = point_text.replace("intensity: 800)", "intensity: 800, falloff: InverseSquare)");
    let path = dir.join("bad.ron");
    std::fs::write(&path, &bad).unwrap();
    let output = flatray()
        .args(["measure", "--quiet"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("light 0") && stderr.contains("falloff"),
        "{stderr}"
    );
    // A directional light's intensity is the illuminance of a surface
    // facing it: an open floor across its rays takes exactly that.
    let open = format!(
        r#"Scene(
    canvas: (100, 100),
    floor: Color((1, 1, 1)),
    walls: [],
    lights: [Directional(direction: (0.6, 0.8), intensity: 500)],
    render: (samples: 4, bounces: 0),
    units: (metres_per_unit: {METRES}, light: Lumens(storey: {STOREY})),
)"#
    );
    let (json, _) = measure(&dir, &open, &[]);
    let (e, se) = figure(&json["rooms"][0], "e_avg");
    assert!((e - 500.0).abs() <= 4.0 * se + 1e-9 * 500.0, "{e} ± {se}");
}
