//! The render plan: snapshots of what each scene runs and skips, counts
//! that prove a skipped effect costs nothing, and images that do not change
//! when every effect is forced on where it contributes nothing.

use flatray_tests::{render, scene, workspace_root};
use flatray_tracer::{Plan, RenderOptions, Stats};

/// The plan as text, without the one part that depends on the processor
/// (how ray queries run: AVX or not).
fn plan_text(scene: &flatray_tracer::Scene, options: &RenderOptions) -> String {
    let queries = scene.segments().describe();
    Plan::new(scene, options)
        .to_string()
        .replace(&queries, "<this processor's ray queries>")
}

fn plan_of_file(name: &str) -> String {
    let loaded = flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron"))).unwrap();
    plan_text(&loaded.scene, &loaded.options)
}

#[test]
fn plans_of_the_example_scenes() {
    for name in [
        "room",
        "colour-bleed",
        "soft-shadow",
        "lens",
        "prism",
        "first-flat",
        "round-room",
    ] {
        insta::assert_snapshot!(format!("plan-{name}"), plan_of_file(name));
    }
}

/// Test scenes, each missing something.
const DIRECT_ONLY: &str = "Scene(canvas: (40, 30), floor: Color((0.8, 0.8, 0.8)),
    lights: [Point(at: (10, 10), intensity: 3.0), Line(a: (20, 5), b: (30, 8), intensity: 0.5)],
    render: (bounces: 2))";
const CLEAR_PANES: &str = "Scene(canvas: (40, 30), floor: Color((0.8, 0.8, 0.8)),
    walls: [Wall(a: (5, 5), b: (35, 5), material: Transparent()), Wall(a: (35, 5), b: (35, 25), material: Transparent())],
    lights: [Point(at: (20, 15), intensity: 3.0)],
    render: (bounces: 3))";
const BLACK_WALLS: &str = "Scene(canvas: (40, 30), floor: Color((0.8, 0.8, 0.8)),
    walls: [Wall(a: (5, 5), b: (35, 5), material: Diffuse(albedo: (0, 0, 0))), Wall(a: (35, 5), b: (35, 25), material: Mirror(tint: (0, 0, 0)))],
    lights: [Point(at: (20, 15), intensity: 3.0), Line(a: (2, 28), b: (12, 28))],
    render: (bounces: 2))";
const NO_MIRROR: &str = "Scene(canvas: (40, 30), floor: Color((0.8, 0.8, 0.8)),
    walls: [Wall(a: (5, 5), b: (35, 5), material: Diffuse(albedo: (0.9, 0.2, 0.2))), Wall(a: (35, 5), b: (35, 25))],
    lights: [Point(at: (20, 15), intensity: 3.0), Line(a: (2, 28), b: (12, 28))],
    render: (bounces: 2))";

#[test]
fn plans_of_test_scenes() {
    for (name, text) in [
        ("direct-only", DIRECT_ONLY),
        ("clear-panes", CLEAR_PANES),
        ("black-walls", BLACK_WALLS),
        ("no-mirror", NO_MIRROR),
    ] {
        let loaded = scene(text);
        insta::assert_snapshot!(
            format!("plan-{name}"),
            plan_text(&loaded.scene, &loaded.options)
        );
    }
}

fn stats_of(text: &str, force: bool) -> (flatray_tracer::Image, Stats) {
    let loaded = scene(text);
    let rendered = render(&loaded.scene, &{
        let mut options = loaded.options;
        options.samples = 4;
        options = options.with_reference(force);
        options
    });
    (rendered.image, rendered.stats)
}

#[test]
fn skipped_effects_cast_no_rays_and_count_no_events() {
    // No wall at all: no shadow ray, no bounce, no memo.
    let (_, s) = stats_of(DIRECT_ONLY, false);
    assert_eq!(
        (
            s.work.shadow_rays,
            s.work.bounce_rays,
            s.work.memo_entries,
            s.work.memo_lookups,
            s.work.floor_memo_reuses
        ),
        (0, 0, 0, 0, 0)
    );
    assert!(s.physics.camera_samples > 0);
    // Clear panes occlude nothing and reflect nothing.
    let (_, s) = stats_of(CLEAR_PANES, false);
    assert_eq!(
        (
            s.work.shadow_rays,
            s.work.bounce_rays,
            s.physics.transparent_passes,
            s.work.memo_entries
        ),
        (0, 0, 0, 0)
    );
    // Black walls occlude but reflect nothing: shadows, no paths.
    let (_, s) = stats_of(BLACK_WALLS, false);
    assert!(s.work.shadow_rays > 0);
    assert_eq!(
        (
            s.work.bounce_rays,
            s.physics.mirror_reflections,
            s.work.emission_tests,
            s.work.memo_lookups
        ),
        (0, 0, 0, 0)
    );
    // No mirror: paths run, but nothing looks for line lights in mirrors.
    let (_, s) = stats_of(NO_MIRROR, false);
    assert!(s.work.bounce_rays > 0 && s.work.memo_lookups > 0);
    assert_eq!(
        (
            s.physics.mirror_reflections,
            s.work.emission_tests,
            s.physics.transparent_passes
        ),
        (0, 0, 0)
    );
    // Its second wall takes the floor's albedo: colour bleeding runs.
    assert!(s.work.floor_albedo_reads > 0);
    // The same scenes forced: the skipped work is there to be skipped.
    for text in [DIRECT_ONLY, CLEAR_PANES, BLACK_WALLS] {
        let (_, forced) = stats_of(text, true);
        assert!(
            forced.work.shadow_rays > 0 && forced.work.bounce_rays > 0,
            "{forced:?}"
        );
    }
    let (_, forced) = stats_of(NO_MIRROR, true);
    assert!(forced.work.emission_tests > 0);
}

#[test]
fn the_light_tracer_casts_no_shadow_ray_and_reads_no_memo() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    let options = {
        let mut options = loaded.options;
        options.samples = 1;
        options.scale = 0.2;
        options.integrator = flatray_tracer::Integrator::Light;
        options
    };
    let plan = Plan::new(&loaded.scene, &options);
    assert!(!plan.shadows && !plan.wall_memo && !plan.floor_memo);
    let stats = render(&loaded.scene, &options).stats;
    assert_eq!(
        (
            stats.work.shadow_rays,
            stats.work.memo_entries,
            stats.work.memo_lookups,
            stats.work.floor_memo_reuses
        ),
        (0, 0, 0, 0)
    );
    assert!(stats.physics.light_paths > 0 && stats.physics.mirror_reflections > 0);
}

#[test]
fn images_are_bit_identical_with_and_without_the_plan() {
    for text in [DIRECT_ONLY, CLEAR_PANES, BLACK_WALLS, NO_MIRROR] {
        let (planned, _) = stats_of(text, false);
        let (forced, _) = stats_of(text, true);
        assert!(planned == forced, "the plan changed the image of {text}");
    }
    // The example rooms at one bounce, where the path's shortcut for a
    // diffuse first hit read from the memo runs (forced, it does not).
    for name in ["room", "colour-bleed"] {
        let loaded =
            flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron"))).unwrap();
        let render_with = |force| {
            let options = {
                let mut options = loaded.options;
                options.samples = 8;
                options.scale = 0.2;
                options.bounces = 1;
                options = options.with_reference(force);
                options
            };
            render(&loaded.scene, &options)
        };
        let (planned, forced) = (render_with(false), render_with(true));
        assert!(planned.stats.work.memo_lookups > 0, "{name}");
        assert!(
            planned.image == forced.image,
            "the plan changed the image of {name}"
        );
    }
}
