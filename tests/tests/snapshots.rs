//! Snapshots of small deterministic renders of the example scenes: the
//! PNG itself, the physics statistics (paths by how they ended, events)
//! and the noise estimate; never the work counters, which the fast paths
//! change. An accidental change to the output fails here and is reviewed
//! with `cargo insta review`.

use flatray_tests::{render, workspace_root};
use flatray_tracer::RenderOptions;

fn snapshot_scene(name: &str, options: impl FnOnce(RenderOptions) -> RenderOptions) {
    let loaded = flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron"))).unwrap();
    let options = options(loaded.options);
    let rendered = render(&loaded.scene, &options);
    let png = flatray_io::png_bytes(&rendered.image, loaded.tonemap).unwrap();
    insta::assert_binary_snapshot!(&format!("{name}.png"), png);
    let stats = &rendered.stats;
    insta::assert_snapshot!(
        format!("{name}-stats"),
        format!("{}\nnoise: {}", stats.physics, stats.noise)
    );
}

#[test]
fn room() {
    snapshot_scene("room", |o| {
        let mut options = o;
        options.samples = 4;
        options.scale = 0.2;
        options.seed = 7;
        options
    });
}

#[test]
fn soft_shadow() {
    snapshot_scene("soft-shadow", |o| {
        let mut options = o;
        options.samples = 4;
        options.scale = 0.3;
        options.seed = 7;
        options
    });
}
