//! Every picture the docs show is what its documented command makes:
//! `docs/images/render.sh` holds one command (or an import and its
//! render) per picture, and this test runs each of its `flatray` lines
//! and compares what they write with the picture in `docs/images`, pixel
//! for pixel (a render is the same bits on every machine, thread count
//! and kernel). The pictures that are not renders (the live view's
//! screenshots, the Python batch's contact sheet) are taken by the steps
//! the script ends with; here they are only checked to be named there.
//!
//! After a change that changes what a picture shows, run
//! `docs/images/render.sh` and look at the pictures it wrote.

use std::path::{Path, PathBuf};

use flatray_tests::flatray;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

/// The script's `flatray` lines, as argument lists, with its `$out` and
/// `$work` folders put at `out` and `work`.
fn steps(script: &str, out: &Path, work: &Path) -> Vec<Vec<String>> {
    script
        .lines()
        .filter(|l| l.starts_with("flatray "))
        .map(|line| {
            line.replace("\"$out/", &format!("{}/", out.display()))
                .replace("\"$work/", &format!("{}/", work.display()))
                .replace('"', "")
                .split_whitespace()
                .skip(1)
                .map(str::to_string)
                .collect()
        })
        .collect()
}

/// The pixels of a PNG.
fn pixels(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

#[test]
fn every_picture_in_the_docs_is_what_its_command_makes() {
    let root = root();
    // The script's paths are the repository's; this test is alone in its
    // process, so the working folder is its own to set.
    std::env::set_current_dir(&root).unwrap();
    let script = std::fs::read_to_string("docs/images/render.sh").unwrap();
    let scratch = std::env::temp_dir().join(format!("flatray-pictures-{}", std::process::id()));
    let (out, work) = (scratch.join("out"), scratch.join("work"));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&work).unwrap();

    let steps = steps(&script, &out, &work);
    assert!(steps.len() >= 25, "{} steps", steps.len());
    for args in &steps {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let run = flatray(&args);
        assert_eq!(run.code, 0, "flatray {}: {run:?}", args.join(" "));
    }

    // Every picture the script renders matches the one in docs/images.
    let mut made: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .collect();
    made.sort();
    let mut differ = Vec::new();
    for name in &made {
        let (new, old) = (
            pixels(&out.join(name)),
            pixels(&root.join("docs/images").join(name)),
        );
        if new.dimensions() != old.dimensions() {
            differ.push(format!(
                "{name}: {:?} made, {:?} in docs/images",
                new.dimensions(),
                old.dimensions()
            ));
            continue;
        }
        let changed = new
            .pixels()
            .zip(old.pixels())
            .filter(|(a, b)| a != b)
            .count();
        if changed > 0 {
            differ.push(format!("{name}: {changed} pixels differ"));
        }
    }
    assert!(
        differ.is_empty(),
        "pictures that are not what docs/images/render.sh makes (run it, and look): {differ:?}"
    );

    // Every picture in docs/images is made by the script: rendered above,
    // or taken by one of its last steps.
    let taken = [
        "serve.png",
        "serve-conflict.png",
        "serve-optics.png",
        "serve-measure.png",
        "serve-doors.png",
        "python-batch.png",
        "import-tavern-map.png",
        "import-corridor-map.png",
    ];
    // The maps' own pictures are the floor images their imports wrote.
    for (name, floor) in [
        ("import-tavern-map.png", "tavern-floor.png"),
        ("import-corridor-map.png", "corridor-floor.png"),
    ] {
        assert!(
            pixels(&work.join(floor)) == pixels(&root.join("docs/images").join(name)),
            "docs/images/{name} is not the floor image the import wrote"
        );
    }
    for name in taken {
        assert!(
            script.contains(&format!("\"$out/{name}\""))
                || (name.starts_with("serve") && script.contains("FLATRAY_SCREENSHOTS=\"$out\"")),
            "{name} is not taken by docs/images/render.sh"
        );
    }
    for entry in std::fs::read_dir(root.join("docs/images")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap_or_default();
        if name.ends_with(".png") {
            assert!(
                made.contains(&name) || taken.contains(&name.as_str()),
                "docs/images/{name} is made by no step of docs/images/render.sh"
            );
        }
    }

    // Every picture the docs show is there.
    let mut docs: Vec<PathBuf> = vec![root.join("README.md")];
    for entry in std::fs::read_dir(root.join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            docs.push(path);
        }
    }
    for doc in docs {
        let text = std::fs::read_to_string(&doc).unwrap();
        for (k, _) in text.match_indices("images/") {
            let name: String = text[k + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || "-_.".contains(*c))
                .collect();
            if name.ends_with(".png") {
                assert!(
                    root.join("docs/images").join(&name).exists(),
                    "{} shows images/{name}, which is not there",
                    doc.display()
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
}
