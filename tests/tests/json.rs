//! `--json`: `check`, `plan` and `render` print one JSON object each,
//! with the fields `docs/cli.md` lists.

use flatray_tests::{TempDir, flatray};
use serde_json::Value;

fn parsed(args: &[&str]) -> (i32, Value) {
    let run = flatray(args);
    let value = serde_json::from_str(&run.stdout)
        .unwrap_or_else(|e| panic!("{args:?}: not one JSON object ({e}): {run:?}"));
    (run.code, value)
}

const ROOM: &str = "Scene(canvas: (40, 30), floor: Color((0.5, 0.5, 0.5)),
    walls: [Wall(a: (5, 5), b: (35, 5), material: Mirror()), Wall(a: (5, 25), b: (35, 25), emit: (intensity: 0.2))],
    lights: [Point(at: (20, 15)), Point(at: (900, 15))])";

#[test]
fn check_json_lists_each_scene() {
    let dir = TempDir::new("json-check");
    let good = dir.write("good.ron", ROOM);
    let bad = dir.write(
        "bad.ron",
        "Scene(\n  canvas: (10, 10)\n  floor: Color((1, 1, 1)),\n)",
    );
    let (good, bad) = (
        good.to_str().unwrap_or_default(),
        bad.to_str().unwrap_or_default(),
    );
    let (code, v) = parsed(&["check", "--json", good, bad]);
    assert_eq!(code, 2);
    assert_eq!(v["format"], 1);
    let scenes = v["scenes"].as_array().cloned().unwrap_or_default();
    assert_eq!(scenes.len(), 2, "{v}");
    let s = &scenes[0];
    assert_eq!(s["path"], good);
    assert_eq!(s["ok"], true);
    assert_eq!(
        (s["walls"].clone(), s["emitting_walls"].clone()),
        (2.into(), 1.into())
    );
    assert_eq!(
        (s["lights"].clone(), s["glass"].clone()),
        (2.into(), 0.into())
    );
    assert_eq!(s["canvas"], serde_json::json!([40, 30]));
    let warnings = s["warnings"].as_array().cloned().unwrap_or_default();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0]["line"], 3);
    assert!(
        warnings[0]["message"]
            .as_str()
            .unwrap_or_default()
            .contains("outside the canvas")
    );
    let e = &scenes[1]["error"];
    assert_eq!(scenes[1]["ok"], false);
    assert_eq!(
        (e["line"].clone(), e["column"].clone()),
        (2.into(), 19.into()),
        "{e}"
    );
    assert!(
        e["message"]
            .as_str()
            .unwrap_or_default()
            .starts_with("expected a comma"),
        "{e}"
    );
    // A file that cannot be read points nowhere.
    let (_, v) = parsed(&["check", "--json", "/no/such/scene.ron"]);
    assert_eq!(v["scenes"][0]["error"]["line"], Value::Null);
}

#[test]
fn plan_json_has_the_settings_and_every_effect() {
    let dir = TempDir::new("json-plan");
    let path = dir.write("s.ron", ROOM);
    let path = path.to_str().unwrap_or_default();
    let (code, v) = parsed(&[
        "plan",
        "--json",
        path,
        "--bounces",
        "2",
        "--cache",
        "direct",
    ]);
    assert_eq!(code, 0);
    assert_eq!(v["scene"], path);
    let settings = &v["settings"];
    assert_eq!(settings["integrator"], "path");
    assert_eq!(settings["bounces"], 2);
    assert_eq!(settings["specular"], 32);
    assert_eq!(settings["cache"], "direct");
    assert_eq!(settings["caustics"], true);
    let effects = v["effects"].as_array().cloned().unwrap_or_default();
    // The same effects, in the same order, as the verbose text.
    let text = flatray(&[
        "plan",
        "--verbose",
        path,
        "--bounces",
        "2",
        "--cache",
        "direct",
    ])
    .stdout;
    assert_eq!(effects.len(), text.lines().count());
    for (effect, line) in effects.iter().zip(text.lines()) {
        let name = effect["name"].as_str().unwrap_or_default();
        assert!(line.contains(name), "{line} / {name}");
        assert_eq!(line.starts_with("runs"), effect["runs"] == true, "{line}");
        assert!(effect["why"].is_string() && effect["internal"].is_boolean());
    }
    let mirrors = effects
        .iter()
        .find(|e| e["name"] == "mirrors")
        .cloned()
        .unwrap_or_default();
    assert_eq!(mirrors["runs"], true);
    assert_eq!(v["warnings"].as_array().map(Vec::len), Some(1));
}

#[test]
fn render_json_has_the_image_the_counts_and_the_seconds() {
    let dir = TempDir::new("json-render");
    let path = dir.write("s.ron", ROOM);
    let out = dir.path().join("s.png");
    let (code, v) = parsed(&[
        "render",
        path.to_str().unwrap_or_default(),
        "--spp",
        "4",
        "-q",
        "--json",
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(code, 0, "{v}");
    assert!(out.exists());
    assert_eq!(v["output"], out.to_str().unwrap_or_default());
    assert_eq!(
        (v["width"].clone(), v["height"].clone()),
        (40.into(), 30.into())
    );
    assert_eq!(
        (v["samples"].clone(), v["passes"].clone()),
        (4.into(), 1.into())
    );
    assert_eq!(v["physics"]["camera_samples"], 40 * 30 * 4);
    let rays = v["work"]["rays"].as_u64().unwrap_or_default();
    let parts = v["work"]["shadow_rays"].as_u64().unwrap_or_default()
        + v["work"]["bounce_rays"].as_u64().unwrap_or_default();
    assert!(rays > 0 && rays == parts, "{v}");
    let noise = v["noise"]["relative"].as_f64().unwrap_or_default();
    assert!(noise > 0.0 && noise < 1.0, "{v}");
    // relMSE's root, from its sum over pixels and channels.
    let relmse = v["noise"]["relmse"].as_f64().unwrap_or_default();
    let pixels = v["noise"]["pixels"].as_f64().unwrap_or_default();
    let sum = v["noise"]["relative_squared"].as_f64().unwrap_or_default();
    assert!(
        relmse > 0.0 && (relmse - (sum / (3.0 * pixels)).sqrt()).abs() < 1e-12,
        "{v}"
    );
    assert_eq!(
        v["noise"]["relative_per_channel"].as_array().map(Vec::len),
        Some(3)
    );
    assert_eq!(v["plan"]["settings"]["bounces"], 1);
    assert!(
        v["plan"]["effects"]
            .as_array()
            .is_some_and(|e| !e.is_empty())
    );
    let seconds = &v["seconds"];
    for key in ["load", "render", "write", "total"] {
        assert!(
            seconds[key].as_f64().is_some_and(|s| s >= 0.0),
            "{key}: {v}"
        );
    }
    // Taken in passes: the samples reached and the passes.
    let (code, v) = parsed(&[
        "render",
        path.to_str().unwrap_or_default(),
        "--time",
        "0.5",
        "-q",
        "--json",
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(code, 0);
    assert!(v["passes"].as_u64().is_some_and(|p| p >= 1), "{v}");
    assert!(v["samples"].as_u64().is_some_and(|s| s >= 16), "{v}");
}
