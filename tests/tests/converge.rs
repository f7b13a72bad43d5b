//! `flatray converge` on a small scene: the files exist and agree with each
//! other, and the unbiased configurations' error falls at least as
//! 1/sqrt(samples).
//! The scene has no mirror, so light tracing and the path-traced reference
//! estimate the same image (with a mirror, light tracing also sees point
//! lights in it, which the reference cannot).

use std::path::PathBuf;

use flatray_tests::{Run, TempDir, flatray};

const SCENE: &str = "Scene(canvas: (48, 40), floor: Color((0.9, 0.9, 0.9)),
    walls: [
        Wall(a: (5, 5), b: (43, 5), material: Diffuse(albedo: (0.9, 0.2, 0.2))),
        Wall(a: (43, 5), b: (43, 35)),
        Wall(a: (12, 14), b: (22, 22), material: Transparent(tint: (0.5, 0.8, 1.0))),
        Wall(a: (4, 33), b: (24, 35)),
    ],
    lights: [
        Point(at: (10.5, 11.2), intensity: 5.0),
        Line(a: (25, 9), b: (35, 9), intensity: 0.5),
    ],
    render: (bounces: 2))";

/// `flatray converge` on the small scene, written into `dir`, with the
/// study in `dir/study`: the scene's path, the study's and the run.
fn study(dir: &TempDir, args: &[&str]) -> (PathBuf, PathBuf, Run) {
    let scene = dir.write("small.ron", SCENE);
    let out = dir.path().join("study");
    let mut all = vec![
        "converge",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    all.extend_from_slice(args);
    let run = flatray(&all);
    assert_eq!(run.code, 0, "{run:?}");
    (scene, out, run)
}

#[test]
fn converge_writes_agreeing_files_and_measures_a_half_slope() {
    let dir = TempDir::new("converge");
    let (scene, out, run) = study(&dir, &["--reference-spp", "2048", "--max-spp", "64"]);

    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let markdown = std::fs::read_to_string(out.join("convergence.md")).unwrap();
    let png = std::fs::read(out.join("convergence.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"), "the chart is a PNG");
    let chart = image::load_from_memory(&png).unwrap();
    assert_eq!((chart.width(), chart.height()), (900, 600));

    // CSV: one row per configuration and rung of the ladder 1..64; the
    // table and stdout give relMSE (the last column), the default.
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 5 * 7, "{csv}");
    for config in ["path-cache", "path-samples", "path", "original", "light"] {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r[0] == config)
            .map(|r| (r[1].parse().unwrap(), r[9].parse().unwrap()))
            .collect();
        assert_eq!(points.len(), 7);
        let slope = flatray_tracer::metrics::log_log_slope(&points).unwrap();
        // The Markdown table shows the same fitted slope as the CSV gives.
        let line = markdown
            .lines()
            .find(|l| l.starts_with(&format!("| {config} |")))
            .unwrap();
        assert!(
            line.contains(&format!("| {slope:.2} |")),
            "{line} vs {slope:.2}"
        );
        // And stdout prints it too.
        assert!(
            run.stdout.contains(&format!("slope {slope:>5.2}")),
            "{}",
            run.stdout
        );
        match config {
            // Unbiased, with the floor's directions stratified over each
            // pixel's samples: error falls at least as samples^(-1/2), and
            // faster over this ladder (the stratification's gain grows with
            // the samples until the unstratified parts dominate).
            "path" | "original" => {
                assert!((-0.8..=-0.45).contains(&slope), "{config}: slope {slope}")
            }
            // With the memo (along lines, the default, or by path
            // samples): the memo's bias may flatten it a little; its
            // onward part gathers more stratified directions per wall bin
            // as the samples grow, which steepens it over this ladder, as
            // do the lines' directions, stratified over the whole image.
            "path-cache" | "path-samples" => {
                assert!((-1.0..=-0.35).contains(&slope), "{config}: slope {slope}")
            }
            // Independent photons: samples^(-1/2); the light tracer's
            // different estimate of the pixel holding the point light may
            // flatten it a little.
            _ => assert!((-0.6..=-0.3).contains(&slope), "{config}: slope {slope}"),
        }
    }

    // A second run reuses the saved reference instead of rendering it.
    let reference = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            name.starts_with("reference-2048spp-") && name.ends_with(".exr")
        })
        .unwrap();
    let before = std::fs::metadata(&reference).unwrap().modified().unwrap();
    let again = flatray(&[
        "converge",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--reference-spp",
        "2048",
        "--max-spp",
        "2",
        "--configs",
        "path",
        "--error-metric",
        "rms",
        "--quiet",
    ]);
    assert_eq!(again.code, 0, "{again:?}");
    assert_eq!(
        std::fs::metadata(&reference).unwrap().modified().unwrap(),
        before
    );
    // With `--error-metric rms` the table is of the relative RMSE (the
    // CSV's seventh column).
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let points: Vec<(f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .map(|r| (r[1].parse().unwrap(), r[6].parse().unwrap()))
        .collect();
    let slope = flatray_tracer::metrics::log_log_slope(&points).unwrap();
    let markdown = std::fs::read_to_string(out.join("convergence.md")).unwrap();
    assert!(markdown.contains("Error: relative RMSE"), "{markdown}");
    assert!(
        markdown.contains(&format!("| path | {slope:.2} |")),
        "{markdown}"
    );

    // The same reference given with `--reference` keeps its noise, read
    // from the file saved beside it, and the errors lose it as before.
    let given = dir.path().join("given");
    let run = flatray(&[
        "converge",
        scene.to_str().unwrap(),
        "--out",
        given.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--max-spp",
        "2",
        "--configs",
        "path",
        "--quiet",
    ]);
    assert_eq!(run.code, 0, "{run:?}");
    let noise_line = |folder: &std::path::Path| {
        std::fs::read_to_string(folder.join("convergence.md"))
            .unwrap()
            .lines()
            .find(|l| l.contains("Reference:"))
            .and_then(|l| l.split(" % relMSE)").next())
            .and_then(|head| head.rsplit(' ').next())
            .map(str::to_string)
            .unwrap()
    };
    assert_eq!(noise_line(&given), noise_line(&out));
    assert_ne!(noise_line(&given), "0.000");
}

/// The adaptive configuration is path tracing with the cache whose later
/// passes go only where the noise is, each pixel's indirect light from its
/// own path samples: up to 32 spp (the passes every pixel takes) it does
/// the same work as `path-samples`, and past that its error stays of the
/// same size.
#[test]
fn converge_measures_the_adaptive_passes() {
    let dir = TempDir::new("converge-adaptive");
    let (_, out, run) = study(
        &dir,
        &[
            "--reference-spp",
            "1024",
            "--max-spp",
            "256",
            "--configs",
            "path-samples,adaptive",
        ],
    );
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let row = |config: &str, samples: u32| -> (f64, f64) {
        let fields: Vec<&str> = csv
            .lines()
            .find(|l| l.starts_with(&format!("{config},{samples},")))
            .unwrap_or_else(|| panic!("no {config} at {samples} in {csv}"))
            .split(',')
            .collect();
        (fields[3].parse().unwrap(), fields[6].parse().unwrap())
    };
    for samples in [1, 2, 4, 8, 16, 32] {
        let (plain, adaptive) = (row("path-samples", samples).0, row("adaptive", samples).0);
        assert!(
            (adaptive / plain - 1.0).abs() < 0.02,
            "{samples} spp: {adaptive} rays against {plain}"
        );
    }
    for samples in [64, 128, 256] {
        let (plain, adaptive) = (row("path-samples", samples).1, row("adaptive", samples).1);
        assert!(
            adaptive < 1.5 * plain,
            "{samples} spp: {adaptive} against {plain}"
        );
    }
    assert!(run.stdout.contains("adaptive"), "{}", run.stdout);
}
