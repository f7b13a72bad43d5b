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

/// `flatray render ARGS -q -o OUT`, started in the background, quiet.
fn spawn_render(args: &[&str], out: &Path) -> std::process::Child {
    flatray()
        .arg("render")
        .args(args)
        .args(["-q", "-o"])
        .arg(out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// Sends `signal` to `child` and waits for it.
fn interrupt(mut child: std::process::Child, signal: &str) -> std::process::ExitStatus {
    let killed = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait().unwrap()
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
    // The target is a directory: refused before rendering, and the
    // directory and its content are untouched.
    let target = dir.join("out.png");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), "old").unwrap();
    let output = flatray()
        .args(["render", scene.to_str().unwrap(), "-q", "-o"])
        .arg(&target)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2), "{output:?}");
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

const SMALL: &str = "Scene(canvas: (8, 8), floor: Color((1, 1, 1)), lights: [Point(at: (4, 4))])";

/// With no `-o`, the image goes to the scene's name with `.png` in the
/// working folder: for a scene named `scene.png` there, that is the scene
/// itself, which is refused and kept.
#[test]
fn the_default_output_never_replaces_the_scene() {
    let dir = scratch("default-out");
    std::fs::write(dir.join("scene.png"), SMALL).unwrap();
    let output = flatray()
        .current_dir(&dir)
        .args(["render", "scene.png", "-q"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    assert_eq!(
        std::fs::read_to_string(dir.join("scene.png")).unwrap(),
        SMALL
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Standard output that cannot be written (a full disk) fails the
/// command, with a message on standard error.
#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_output_fails_the_command() {
    let dir = scratch("full");
    let scene = dir.join("s.ron");
    std::fs::write(&scene, SMALL).unwrap();
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let output = flatray()
        .args(["check", scene.to_str().unwrap()])
        .stdout(full)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1), "{output:?}");
    assert!(
        String::from_utf8_lossy(&output.stderr).contains("standard output"),
        "{output:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGINT or SIGTERM during a render: exit 130, no image, no temporary
/// file. A temporary file that a killed run left (its process gone) is
/// removed by the next write in that folder.
#[cfg(target_os = "linux")]
#[test]
fn an_interrupted_render_exits_130_and_leaves_nothing() {
    let dir = scratch("interrupt");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    for signal in ["-INT", "-TERM"] {
        let out = dir.join("room.png");
        let child = spawn_render(&[room.to_str().unwrap(), "--spp", "100000"], &out);
        std::thread::sleep(std::time::Duration::from_millis(700));
        let status = interrupt(child, signal);
        assert_eq!(status.code(), Some(130), "{signal}: {status:?}");
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "{signal}");
    }
    // A killed run's leftover: a process number that is not running.
    let stale = dir.join(".flatray-4194304-0.tmp");
    std::fs::write(&stale, "half an image").unwrap();
    let scene = dir.join("s.ron");
    std::fs::write(&scene, SMALL).unwrap();
    let output = flatray()
        .args(["render", scene.to_str().unwrap(), "-q", "-o"])
        .arg(dir.join("s.png"))
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    assert!(!stale.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Inputs that once ran out of memory, under a 2 GiB address-space limit:
/// each ends cleanly (exit 0, or 2 with a message), never with an
/// allocation failure or a signal.
#[cfg(target_os = "linux")]
#[test]
fn inputs_that_would_exhaust_memory_end_cleanly_under_a_limit() {
    let dir = scratch("ulimit");
    let write = |name: &str, text: String| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    let tiny_bins = write(
        "bins.ron",
        "Scene(canvas: (100, 10), floor: Color((0.5, 0.5, 0.5)), walls: [Wall(a: (10, 5), b: (90, 5))],
           lights: [Point(at: (50, 2))], render: (cache_bin: 1e-9))"
            .to_string(),
    );
    let long_walls = write(
        "long.ron",
        format!(
            "Scene(canvas: (50, 50), floor: Tiles(size: 3), walls: [{}], lights: [Point(at: (25, 25))])",
            (0..20000)
                .map(|k| format!(
                    "Wall(a: ({}, -1000), b: ({}, 1000))",
                    k as f64 * 0.002,
                    k as f64 * 0.002 + 1.0
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let crossing = write(
        "crossing.ron",
        format!(
            "Scene(canvas: (50, 50), floor: Color((0.5, 0.5, 0.5)), walls: [{}], lights: [Point(at: (25, 25))])",
            (0..5000)
                .map(|k| {
                    let x = k as f64 * 0.0097;
                    if k % 2 == 0 {
                        format!("Wall(a: ({x}, 0.5), b: ({}, 49.5))", 49.0 - x)
                    } else {
                        format!("Wall(a: (0.5, {x}), b: (49.5, {}))", 49.0 - x)
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let many_lights = write(
        "lights.ron",
        format!(
            "Scene(canvas: (1500, 1500), floor: Color((0.5, 0.5, 0.5)), walls: [Wall(a: (1, 1), b: (2, 600))], lights: [{}])",
            (0..4000)
                .map(|k| format!("Point(at: ({}, {}))", 10 + k % 1400, 10 + (k / 1400) * 500))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let out = dir.join("out.png");
    let out = out.to_str().unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec!["render", &tiny_bins, "-q", "--spp", "1", "-o", out],
        vec!["check", &long_walls],
        vec!["render", &long_walls, "-q", "--spp", "1", "-o", out],
        vec!["render", &crossing, "-q", "--spp", "1", "-o", out],
        vec!["plan", &many_lights],
        vec![
            "render",
            &many_lights,
            "-q",
            "--spp",
            "1",
            "--scale",
            "0.05",
            "-o",
            out,
        ],
        vec!["converge", &tiny_bins, "-q", "--scale", "1e9", "--out", out],
    ];
    for args in cases {
        let output = Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 2097152 && exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_flatray"))
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        let code = output.status.code();
        assert!(
            code == Some(0) || (code == Some(2) && stderr.starts_with("error: ")),
            "{args:?}: {code:?} {stderr}"
        );
        assert!(!stderr.contains("memory allocation"), "{args:?}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Help and usage errors written to a pipe carry no escape codes; help
/// opens with what flatray does and shows examples.
#[test]
fn help_in_a_pipe_is_plain_text() {
    for args in [
        vec!["--help"],
        vec!["render", "--help"],
        vec!["render", "--no-such-flag"],
    ] {
        let output = flatray().args(&args).output().unwrap();
        for stream in [&output.stdout, &output.stderr] {
            assert!(
                !stream.contains(&0x1b),
                "{args:?}: {}",
                String::from_utf8_lossy(stream)
            );
        }
    }
    let output = flatray().arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&output.stdout);
    assert!(help.starts_with("Lights a floor plan"), "{help}");
    assert!(
        help.contains("Examples:") && help.contains("flatray import"),
        "{help}"
    );
}

/// A scene error shows the line with a caret under the column, and a
/// hint for a colour written without its inner parentheses.
#[test]
fn a_scene_error_shows_its_line_a_caret_and_a_hint() {
    let dir = scratch("caret");
    let scene = dir.join("s.ron");
    std::fs::write(
        &scene,
        "Scene(\n  canvas: (10, 10),\n  floor: Color(0.8, 0.75, 0.65),\n)",
    )
    .unwrap();
    let output = flatray()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        lines[0].starts_with(&format!("error: {}:3:", scene.display())),
        "{stderr}"
    );
    assert_eq!(
        lines[2], " 3 |   floor: Color(0.8, 0.75, 0.65),",
        "{stderr}"
    );
    let column: usize = lines[0].split(':').nth(3).unwrap().trim().parse().unwrap();
    assert_eq!(lines[3].find('^'), Some(4 + column), "{stderr}");
    assert!(stderr.contains("hint: a colour is a tuple"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `check` counts lights as the file lists them: an emitting wall is a
/// wall that emits, not one more light.
#[test]
fn check_counts_what_the_file_lists() {
    let dir = scratch("counts");
    let scene = dir.join("s.ron");
    std::fs::write(
        &scene,
        "Scene(canvas: (10, 10), floor: Color((1, 1, 1)),
           walls: [Wall(a: (1, 1), b: (9, 1)), Wall(a: (1, 5), b: (9, 5), emit: (intensity: 1))],
           lights: [Point(at: (5, 3)), Point(at: (5, 7)), Line(a: (1, 8), b: (9, 8), solid: true),
                    Directional(direction: (1, 1))])",
    )
    .unwrap();
    let output = flatray()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains("ok (2 walls (1 emitting), 4 lights, 0 glass bodies, canvas 10 x 10)"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Shell completions and the manual page come from the flag definitions.
#[test]
fn completions_and_the_manual_are_generated() {
    let output = flatray().args(["completions", "bash"]).output().unwrap();
    assert_eq!(output.status.code(), Some(0));
    let script = String::from_utf8_lossy(&output.stdout);
    assert!(
        script.contains("flatray") && script.contains("--spp"),
        "{script}"
    );
    let output = flatray().arg("man").output().unwrap();
    assert_eq!(output.status.code(), Some(0));
    let page = String::from_utf8_lossy(&output.stdout);
    assert!(
        page.starts_with(".ie") || page.contains(".TH flatray"),
        "{page}"
    );
}

/// By default `plan` and `--stats` speak of effects and costs; how the
/// work is done (culling, shared rays, ray queries) needs --verbose.
#[test]
fn internals_need_verbose() {
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    let plain = flatray()
        .args(["plan", room.to_str().unwrap()])
        .output()
        .unwrap();
    let plain = String::from_utf8_lossy(&plain.stdout).into_owned();
    let verbose = flatray()
        .args(["plan", "-v", room.to_str().unwrap()])
        .output()
        .unwrap();
    let verbose = String::from_utf8_lossy(&verbose.stdout).into_owned();
    for internal in [
        "ray queries",
        "walls culled by direction",
        "share shadow rays",
    ] {
        assert!(!plain.contains(internal), "{plain}");
        assert!(verbose.contains(internal), "{verbose}");
    }
    assert!(
        plain.contains("cache: wall irradiance") && plain.contains("mirrors"),
        "{plain}"
    );
    let dir = scratch("verbose");
    let out = dir.join("room.png");
    let stats = |extra: &[&str]| {
        let output = flatray()
            .args([
                "render",
                room.to_str().unwrap(),
                "--scale",
                "0.1",
                "--spp",
                "1",
                "--stats",
            ])
            .args(extra)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        String::from_utf8_lossy(&output.stdout).into_owned()
    };
    let (plain, verbose) = (stats(&[]), stats(&["--verbose"]));
    assert!(
        plain.contains("shadow rays") && !plain.contains("walls tested"),
        "{plain}"
    );
    assert!(
        verbose.contains("walls tested") && verbose.contains("arc has no wall"),
        "{verbose}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--cache on|off|direct` decide what the plan caches: with two bounces,
/// light going on from walls only for `on`.
#[test]
fn the_cache_flag_says_what_is_cached() {
    let flat = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/first-flat.ron");
    let line = |cache: &str| {
        let output = flatray()
            .args(["plan", flat.to_str().unwrap(), "--cache", cache])
            .output()
            .unwrap();
        assert!(output.status.success(), "{output:?}");
        let text = String::from_utf8_lossy(&output.stdout).into_owned();
        let find = |effect: &str| {
            text.lines()
                .find(|l| l.contains(effect))
                .unwrap_or_else(|| panic!("no {effect} in {text}"))
                .to_string()
        };
        (
            find("cache: wall irradiance"),
            find("cache: light between walls"),
        )
    };
    let (walls, onward) = line("on");
    assert!(walls.starts_with("runs") && onward.starts_with("runs"));
    let (walls, onward) = line("direct");
    assert!(walls.starts_with("runs") && onward.starts_with("skipped"));
    assert!(onward.contains("--cache direct"), "{onward}");
    let (walls, onward) = line("off");
    assert!(walls.starts_with("skipped") && onward.starts_with("skipped"));
}

/// With `--write-passes`, an interrupted render keeps the image of its
/// last finished pass (a whole image, written atomically), where without
/// it nothing is written; `--write-passes` alone is a usage error.
#[cfg(target_os = "linux")]
#[test]
fn written_passes_survive_an_interrupt() {
    let dir = scratch("passes");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    let out = dir.join("room.png");
    let alone = flatray()
        .args([
            "render",
            room.to_str().unwrap(),
            "-q",
            "--write-passes",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(alone.status.code(), Some(2), "{alone:?}");
    let child = flatray()
        .args(["render", room.to_str().unwrap(), "--scale", "0.4"])
        .args(["--target-error", "0.001", "--write-passes", "-q", "-o"])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The first passes take well under a second at this size.
    let started = std::time::Instant::now();
    while !out.exists() && started.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // Let a pass or two more finish after the first file appears.
    std::thread::sleep(std::time::Duration::from_millis(300));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(130));
    // The message says what the kept file holds.
    let stderr = String::from_utf8_lossy(&output.stderr);
    let said = format!("{} holds the last finished pass: ", out.display());
    let spp: u32 = stderr
        .split(&said)
        .nth(1)
        .and_then(|rest| rest.split(" spp").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(spp >= 16 && spp.is_power_of_two(), "{stderr}");
    let image = std::fs::read(&out).unwrap();
    // A whole PNG: its signature, and its end chunk last.
    assert!(image.starts_with(b"\x89PNG\r\n\x1a\n"));
    assert!(image.ends_with(&[0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82]));
    // Nothing else is left in the folder.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A floor image that is not a regular file (a device that never ends, a
/// pipe that nobody writes) is refused before a byte is read, under a
/// 100 MiB limit on the process's data (which a read of `/dev/zero` would
/// exhaust in a fraction of a second): exit 2 with a message, no hang.
#[cfg(target_os = "linux")]
#[test]
fn a_floor_image_that_is_not_a_file_is_refused_within_100_mib() {
    let dir = scratch("not-a-file");
    let fifo = dir.join("floor.png");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let scene = |floor: &str| {
        let path = dir.join(format!("s{}.ron", floor.len()));
        std::fs::write(
            &path,
            format!(
                "Scene(canvas: (20, 20), floor: Image({floor:?}), lights: [Point(at: (10, 10))])"
            ),
        )
        .unwrap();
        path
    };
    let plain = dir.join("plain.ron");
    std::fs::write(&plain, SMALL).unwrap();
    let limited = |args: &[&str]| {
        let mut child = Command::new("sh")
            .arg("-c")
            .arg("ulimit -d 102400 && exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_flatray"))
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let started = std::time::Instant::now();
        while child.try_wait().unwrap().is_none() {
            if started.elapsed().as_secs() > 60 {
                let _ = child.kill();
                panic!("{args:?}: still running after 60 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        child.wait_with_output().unwrap()
    };
    // The limit leaves room for a render of its own.
    let out = dir.join("o.png");
    let ok = limited(&[
        "render",
        plain.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(ok.status.code(), Some(0), "{ok:?}");
    for floor in ["/dev/zero", fifo.to_str().unwrap()] {
        let path = scene(floor);
        for command in ["check", "render"] {
            let args = match command {
                "check" => vec![command, path.to_str().unwrap()],
                _ => vec![command, path.to_str().unwrap(), "-q"],
            };
            let run = limited(&args);
            let stderr = String::from_utf8_lossy(&run.stderr);
            assert_eq!(run.status.code(), Some(2), "{floor} {command}: {stderr}");
            assert!(stderr.contains("not a regular file"), "{floor}: {stderr}");
            assert!(!stderr.contains("memory"), "{floor}: {stderr}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `generate` and `import` never replace a file without `--force`.
#[test]
fn generate_and_import_keep_an_existing_scene() {
    let dir = scratch("force");
    let target = dir.join("mine.ron");
    std::fs::write(&target, "// my own work\n").unwrap();
    let mask =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/import/house-mask.png");
    for args in [
        vec!["generate", "--rooms", "2", "-o"],
        vec!["import", mask.to_str().unwrap(), "-o"],
    ] {
        let run = flatray().args(&args).arg(&target).output().unwrap();
        assert_eq!(run.status.code(), Some(2), "{args:?} {run:?}");
        assert!(String::from_utf8_lossy(&run.stderr).contains("without --force"));
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            "// my own work\n"
        );
        let run = flatray()
            .args(&args)
            .arg(&target)
            .arg("--force")
            .output()
            .unwrap();
        assert_eq!(run.status.code(), Some(0), "{args:?} {run:?}");
        assert!(std::fs::read_to_string(&target).unwrap().contains("Scene("));
        std::fs::write(&target, "// my own work\n").unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Negative numbers are values, given the range message; more threads
/// than cores are warned of; `--verbose` alone prints the statistics; the
/// summary's plurals are right.
#[test]
fn flags_say_what_is_wrong_with_their_values() {
    let dir = scratch("flags");
    let scene = dir.join("s.ron");
    std::fs::write(&scene, SMALL).unwrap();
    let out = dir.join("o.png");
    let run = |extra: &[&str]| {
        flatray()
            .args([
                "render",
                scene.to_str().unwrap(),
                "-q",
                "-o",
                out.to_str().unwrap(),
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    for (flag, value, expected) in [
        (
            "--scale",
            "-1",
            "--scale: expected a finite number > 0, found -1",
        ),
        ("--exposure", "-2", "--exposure: expected a number > 0"),
        ("--time", "-3", "--time: expected seconds > 0, found -3"),
    ] {
        let r = run(&[flag, value]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(expected), "{flag}: {stderr}");
        assert!(!stderr.contains("'-- "), "{flag}: {stderr}");
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let r = run(&["--threads", &(cores * 4).to_string()]);
    assert_eq!(r.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&r.stderr).contains("more threads than cores"));
    let r = run(&["--threads", "1"]);
    assert!(!String::from_utf8_lossy(&r.stderr).contains("warning"));
    let r = run(&["--verbose"]);
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        stdout.contains("\nplan\n") && stdout.contains("seconds"),
        "{stdout}"
    );
    let r = run(&["--bounces", "1"]);
    assert!(String::from_utf8_lossy(&r.stdout).contains(", 1 bounce)"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every subcommand's help shows examples, and each has a manual page.
#[test]
fn every_subcommand_has_examples_and_a_manual_page() {
    for sub in [
        "render",
        "check",
        "plan",
        "converge",
        "import",
        "generate",
        "completions",
        "man",
    ] {
        let help = flatray().args([sub, "--help"]).output().unwrap();
        let text = String::from_utf8_lossy(&help.stdout);
        assert!(text.contains("Examples:"), "{sub}: {text}");
        let page = flatray().args(["man", sub]).output().unwrap();
        assert_eq!(page.status.code(), Some(0), "{sub}");
        let page = String::from_utf8_lossy(&page.stdout);
        assert!(
            page.contains(&format!(".TH flatray-{sub} 1")),
            "{sub}: {page}"
        );
    }
    let wrong = flatray().args(["man", "rendr"]).output().unwrap();
    assert_eq!(wrong.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&wrong.stderr).contains("did you mean `render`?"));
}

/// `--adaptive --write-spp MAP.png`: the image, and beside it a grey map
/// of the samples each pixel took, white for the most; the summary gives
/// the mean. A map that is not a PNG, or that is the image, is refused
/// before anything is rendered.
#[test]
fn adaptive_renders_write_a_map_of_their_samples() {
    let dir = scratch("spp-map");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    let (out, map) = (dir.join("room.png"), dir.join("spp.png"));
    let output = flatray()
        .args([
            "render",
            room.to_str().unwrap(),
            "--scale",
            "0.2",
            "--spp",
            "128",
        ])
        .args(["--adaptive", "--write-spp"])
        .arg(&map)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("(at most 128) spp"), "{stdout}");
    let grey = image::open(&map).unwrap().to_luma8();
    assert_eq!(grey.dimensions(), (100, 100));
    let (darkest, lightest) = grey
        .pixels()
        .fold((255u8, 0u8), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    // White where pixels took every pass, grey where they stopped at 32.
    assert_eq!(lightest, 255);
    assert!(darkest < 200, "{darkest}");
    for bad in [dir.join("spp.exr"), out.clone()] {
        let refused = flatray()
            .args([
                "render",
                room.to_str().unwrap(),
                "--scale",
                "0.1",
                "--write-spp",
            ])
            .arg(&bad)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(refused.status.code(), Some(2), "{refused:?}");
        let stderr = String::from_utf8_lossy(&refused.stderr);
        assert!(stderr.contains("--write-spp"), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The frames an animated PNG says it has (its `acTL` chunk), and how
/// many frame controls (`fcTL`) it holds.
fn apng_frames(bytes: &[u8]) -> (u32, usize) {
    let (mut declared, mut controls, mut at) = (0, 0, 8);
    while at + 8 <= bytes.len() {
        let length = u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let kind = &bytes[at + 4..at + 8];
        if kind == b"acTL" {
            declared = u32::from_be_bytes(bytes[at + 8..at + 12].try_into().unwrap());
        }
        if kind == b"fcTL" {
            controls += 1;
        }
        at += 12 + length;
    }
    (declared, controls)
}

#[test]
fn day_writes_a_frame_for_each_time_and_refuses_what_it_cannot_do() {
    let dir = scratch("day");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let daylight = scenes.join("daylight.ron");
    let out = dir.join("day.png");
    let day = |scene: &Path, extra: &[&str], out: &Path| {
        flatray()
            .arg("day")
            .arg(scene)
            .args(extra)
            .args(["--scale", "0.1", "--spp", "1", "--quiet", "-o"])
            .arg(out)
            .output()
            .unwrap()
    };
    let output = day(
        &daylight,
        &["--from", "08:00", "--to", "10:15", "--every", "45m"],
        &out,
    );
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let said = String::from_utf8_lossy(&output.stdout);
    assert!(
        said.contains("4 frames, 08:00 to 10:15 every 45 min"),
        "{said}"
    );
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(apng_frames(&bytes), (4, 4));
    // The frames differ as the sun moves: the first (08:00, before
    // sunrise in Paris in December) against the last.
    use image::AnimationDecoder;
    let decoder = image::codecs::png::PngDecoder::new(std::io::Cursor::new(&bytes)).unwrap();
    let frames = decoder
        .apng()
        .unwrap()
        .into_frames()
        .collect_frames()
        .unwrap();
    assert_eq!(frames.len(), 4);
    assert_eq!(frames[0].buffer().dimensions(), (40, 30));
    assert_ne!(frames[0].buffer(), frames[3].buffer());

    // A scene with no Sun, an output that is no PNG, times the wrong way
    // round: exit 2, and nothing written.
    for (scene, extra, name, expected) in [
        (
            scenes.join("room.ron"),
            vec![],
            "room.png",
            "no Sun(date: .., time: .., ..) light",
        ),
        (daylight.clone(), vec![], "day.exr", "animated PNG"),
        (
            daylight.clone(),
            vec!["--from", "12:00", "--to", "09:00"],
            "late.png",
            "is before --from",
        ),
        (
            daylight.clone(),
            vec!["--every", "0m"],
            "none.png",
            "whole number of minutes",
        ),
    ] {
        let target = dir.join(name);
        let output = day(&scene, &extra, &target);
        assert_eq!(output.status.code(), Some(2), "{output:?}");
        let message = String::from_utf8_lossy(&output.stderr);
        assert!(message.contains(expected), "{message}");
        assert!(!target.exists(), "{name} written");
    }
}
