//! `render --draw-walls`: the walls drawn over the PNG, and nothing else
//! changed.

use flatray_tests::{TempDir, flatray};

#[test]
fn drawn_walls_change_only_the_pixels_along_them() {
    let dir = TempDir::new("draw-walls");
    let scene = dir.write(
        "s.ron",
        "Scene(canvas: (60, 40), floor: Color((0.5, 0.5, 0.5)),
           walls: [Wall(a: (10, 20), b: (50, 20), material: Mirror()),
                   Wall(a: (30, 5), b: (45, 15), material: Diffuse(albedo: (0.9, 0.1, 0.1)))],
           lights: [Point(at: (20, 30), intensity: 30)])",
    );
    let plain = dir.path().join("plain.png");
    let drawn = dir.path().join("drawn.png");
    for (out, extra) in [(&plain, None), (&drawn, Some("--draw-walls"))] {
        let mut args = vec!["render", scene.to_str().unwrap_or_default(), "-q", "-o"];
        args.push(out.to_str().unwrap_or_default());
        args.extend(extra);
        let run = flatray(&args);
        assert_eq!(run.code, 0, "{run:?}");
    }
    let read = |p: &std::path::Path| image::open(p).unwrap_or_else(|e| panic!("{e}")).to_rgb8();
    let (a, b) = (read(&plain), read(&drawn));
    let mut changed = 0;
    for (x, y, pixel) in b.enumerate_pixels() {
        let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
        let near_mirror = (10.0 - 3.0..=50.0 + 3.0).contains(&px) && (py - 20.0).abs() < 3.0;
        let near_diagonal = (28.0..=47.0).contains(&px) && (3.0..=17.0).contains(&py);
        if pixel != a.get_pixel(x, y) {
            changed += 1;
            assert!(
                near_mirror || near_diagonal,
                "({x}, {y}) changed, away from every wall"
            );
        }
    }
    assert!(changed > 60, "{changed} pixels drawn");
    // The mirror's own line is silver-blue, bluer than it is red.
    let on = b.get_pixel(30, 20).0;
    assert!(on[2] > on[0], "{on:?}");
    // Not on an EXR.
    let exr = dir.path().join("x.exr");
    let run = flatray(&[
        "render",
        scene.to_str().unwrap_or_default(),
        "-q",
        "--draw-walls",
        "-o",
        exr.to_str().unwrap_or_default(),
    ]);
    assert_eq!(run.code, 2, "{run:?}");
}
