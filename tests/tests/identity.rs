//! The fast paths against the plain model. Every fast path (culling,
//! lanes, shared shadow rays, the floor memo's light-by-light loops, the
//! one-bounce shortcut, the albedo table, the pixel loop compiled for this
//! processor) computes what the model computes, by the same operations in
//! the same order: so every image must be bit-identical with the
//! reference render (`RenderOptions::reference`), and so must the physics
//! statistics, wherever the plan skips no effect. Checked on every scene
//! in `scenes/` and on random rooms of every kind of wall and light.

use flatray_tests::{render, scene, workspace_root};
use flatray_tracer::{
    FastPath, FastPaths, Integrator, LightChoice, MemoOptions, Plan, RenderOptions, Scene,
};
use proptest::prelude::*;

/// Renders `scene` both ways and compares.
fn assert_identical(name: &str, scene: &Scene, options: RenderOptions) {
    let fast = render(scene, &options);
    let reference_options = options.with_reference(true);
    let reference = render(scene, &reference_options);
    assert!(
        fast.image == reference.image,
        "{name}: the fast paths changed the image"
    );
    // Forced on, an effect the plan skips traces paths that add nothing:
    // the physics then differ by those paths alone.
    let (a, b) = (
        Plan::new(scene, &options),
        Plan::new(scene, &reference_options),
    );
    if (a.indirect, a.shadows, a.mirror_emission) == (b.indirect, b.shadows, b.mirror_emission) {
        assert_eq!(fast.stats.physics, reference.stats.physics, "{name}");
    }
    assert_eq!(fast.stats.noise, reference.stats.noise, "{name}");
}

#[test]
fn every_example_scene_renders_the_same_with_and_without_fast_paths() {
    let mut names: Vec<_> = std::fs::read_dir(workspace_root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    names.sort();
    assert!(names.len() >= 6);
    for path in names {
        let loaded = flatray_io::load(&path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        for (bounces, memo) in [(loaded.options.bounces, true), (3, false), (1, true)] {
            let options = {
                let mut options = loaded.options;
                options.samples = 8;
                options.scale = 0.2;
                options.bounces = bounces;
                options.memo.enabled = memo;
                options
            };
            let label = format!("{name}, {bounces} bounces, memo {memo}");
            assert_identical(&label, &loaded.scene, options);
            if bounces == loaded.options.bounces && memo {
                // And each fast path left out alone.
                let fast = render(&loaded.scene, &options).image;
                for path in FastPath::ALL {
                    let without = options.with_fast_paths(FastPaths::ALL.without(path));
                    assert!(
                        render(&loaded.scene, &without).image == fast,
                        "{label}: without {path:?}, the image changed"
                    );
                }
            }
            if options.integrator != Integrator::Light {
                // And the light tracer, which has no fast path of its own
                // but shares the lights and materials.
                let light = {
                    let mut options = options;
                    options.integrator = Integrator::Light;
                    options.samples = 1;
                    options
                };
                assert_identical(&format!("{label}, light tracing"), &loaded.scene, light);
            }
        }
    }
}

/// A room of `n` corners on a star around (24, 24) turned by `turn`, each
/// wall of a material from `materials`, an interior stub, and lights.
fn random_room(
    corners: &[(f64, f64)],
    materials: &[u8],
    lights: &[(u8, f64, f64)],
    floor_tiles: bool,
) -> String {
    let n = corners.len();
    let point = |k: usize| {
        let (angle, radius) = corners[k];
        let a = std::f64::consts::TAU * k as f64 / n as f64 + angle;
        (24.0 + radius * a.cos(), 24.0 + radius * a.sin())
    };
    let material = |m: u8| match m % 6 {
        0 | 1 => "",
        2 => ", material: Diffuse(albedo: Some((0.7, 0.3, 0.2)))",
        3 => ", material: Mirror(tint: (0.9, 0.9, 0.95))",
        4 => ", material: Transparent(tint: (0.6, 0.8, 0.9))",
        _ => ", material: Diffuse(albedo: Some((0.0, 0.0, 0.0)))",
    };
    let mut walls: Vec<String> = (0..n)
        .map(|k| {
            let (a, b) = (point(k), point((k + 1) % n));
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){})",
                a.0,
                a.1,
                b.0,
                b.1,
                material(materials[k % materials.len()])
            )
        })
        .collect();
    walls.push(format!(
        "Wall(a: (20.5, 22.25), b: (27.75, 26.5){})",
        material(materials[n % materials.len()])
    ));
    let lights: Vec<String> = lights
        .iter()
        .map(|&(kind, x, y)| {
            let (x, y) = (14.0 + x * 20.0, 14.0 + y * 20.0);
            match kind % 6 {
                0 => format!("Point(at: ({x:?}, {y:?}), intensity: 8.0)"),
                1 => format!(
                    "Spot(at: ({x:?}, {y:?}), direction: (0.6, 0.8), cone: 50, softness: 20, intensity: 8.0)"
                ),
                2 => format!(
                    "Line(a: ({x:?}, {y:?}), b: ({:?}, {:?}), intensity: 0.8)",
                    x + 3.0,
                    y + 1.5
                ),
                3 => format!(
                    "Line(a: ({x:?}, {y:?}), b: ({:?}, {:?}), intensity: 0.8, one_sided: true, solid: true)",
                    x - 1.0,
                    y + 4.0
                ),
                4 => "Directional(direction: (0.3, 1.0), intensity: 0.6)".to_string(),
                _ => format!("Circle(at: ({x:?}, {y:?}), radius: 1.75, intensity: 0.8)"),
            }
        })
        .collect();
    let floor = if floor_tiles {
        "Tiles(size: 5.0, grout_width: 1.0, tile: (0.8, 0.7, 0.6), grout: (0.2, 0.2, 0.2))"
    } else {
        "Color((0.8, 0.8, 0.8))"
    };
    format!(
        "Scene(canvas: (48, 48), floor: {floor}, walls: [{}], lights: [{}])",
        walls.join(", "),
        lights.join(", ")
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn random_rooms_render_the_same_with_and_without_fast_paths(
        corners in prop::collection::vec((0.0..0.4f64, 12.0..22.0f64), 3..9),
        materials in prop::collection::vec(0u8..6, 1..10),
        lights in prop::collection::vec((0u8..6, 0.0..1.0f64, 0.0..1.0f64), 1..5),
        bounces in 1u32..4,
        memo in any::<bool>(),
        tiles in any::<bool>(),
        table in any::<bool>(),
        scale in prop::sample::select(vec![0.5, 1.0, 1.3]),
        seed in 0u64..1000,
    ) {
        let text = random_room(&corners, &materials, &lights, tiles);
        let loaded = scene(&text);
        let options = {
 let mut options = RenderOptions::default();
 options.samples = 5;
 options.bounces = bounces;
 options.scale = scale;
 options.seed = seed;
 options.memo = MemoOptions::default();
 options.memo.enabled = memo;
            // The lights chosen by a table, as a scene of many lights
            // would have them.
            options.light_choice = if table { LightChoice::Table } else { LightChoice::Auto };
 options
};
        assert_identical(&text, &loaded.scene, options);
        let original = {
 let mut options = options;
 options.integrator = Integrator::Original;
 options
};
        assert_identical(&text, &loaded.scene, original);
    }
}
