//! The real `flatray` binary, run as a user would.

use std::path::Path;
use std::process::Command;

fn flatray() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flatray"))
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("flatray-bin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn renders_the_example_room_to_png_and_exr() {
    let dir = scratch("room");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    for name in ["room.png", "room.exr"] {
        let out = dir.join(name);
        let output = flatray()
            .args([
                "render",
                room.to_str().unwrap(),
                "--scale",
                "0.1",
                "--spp",
                "2",
                "--stats",
                "-o",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(output.status.code(), Some(0), "{output:?}");
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(
            stdout.starts_with(&format!("wrote {}", out.display())),
            "{stdout}"
        );
        assert!(stdout.contains("shadow rays"), "{stdout}");
        // Not a terminal: no progress bar on stderr.
        assert!(output.stderr.is_empty(), "{output:?}");
        assert!(std::fs::metadata(&out).unwrap().len() > 100);
    }
    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_scene_exits_with_2_and_a_located_message() {
    let dir = scratch("bad");
    let scene = dir.join("bad.ron");
    std::fs::write(
        &scene,
        "Scene(\n  canvas: (10, 10),\n  flor: Color((1, 1, 1)),\n)",
    )
    .unwrap();
    let output = flatray()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!("{}:3:", scene.display())),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failed_write_keeps_the_older_image() {
    let dir = scratch("keep");
    let scene = dir.join("s.ron");
    std::fs::write(
        &scene,
        "Scene(canvas: (8, 8), floor: Color((1, 1, 1)), lights: [Point(at: (4, 4))])",
    )
    .unwrap();
    // The target is a directory: the rename fails, and the directory and
    // its content are untouched.
    let target = dir.join("out.png");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), "old").unwrap();
    let output = flatray()
        .args(["render", scene.to_str().unwrap(), "-q", "-o"])
        .arg(&target)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1), "{output:?}");
    assert_eq!(std::fs::read_to_string(target.join("keep")).unwrap(), "old");
    let leftovers = std::fs::read_dir(&dir).unwrap().filter(|e| {
        e.as_ref()
            .unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".tmp")
    });
    assert_eq!(leftovers.count(), 0);
    let _ = std::fs::remove_dir_all(&dir);
}
