//! Images are a pure function of (scene, options): bit-identical for any
//! number of threads, and for any order in which tiles finish.

use flatray_tests::{render_on, workspace_root};
use flatray_tracer::{Integrator, RenderOptions};

#[test]
fn one_thread_and_several_threads_give_bit_identical_images() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    for (integrator, memo) in [
        (Integrator::Path, true),
        (Integrator::Path, false),
        (Integrator::Original, true),
    ] {
        let options = RenderOptions {
            samples: 3,
            bounces: 2,
            scale: 0.3,
            integrator,
            memo: flatray_tracer::MemoOptions {
                enabled: memo,
                ..loaded.options.memo
            },
            ..loaded.options
        };
        let one = render_on(&loaded.scene, &options, 1);
        for threads in [2, 5] {
            let many = render_on(&loaded.scene, &options, threads);
            assert_eq!(
                one.image, many.image,
                "{integrator:?}, memo {memo}, {threads} threads"
            );
            assert_eq!(
                one.stats, many.stats,
                "{integrator:?}, memo {memo}, {threads} threads"
            );
        }
        assert!(one.image.pixels.iter().any(|p| p[0] > 0.0));
    }
}

#[test]
fn a_different_seed_gives_a_different_image() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    let options = RenderOptions {
        samples: 2,
        scale: 0.2,
        ..loaded.options
    };
    let a = render_on(&loaded.scene, &options, 2);
    let b = render_on(&loaded.scene, &RenderOptions { seed: 1, ..options }, 2);
    assert_ne!(a.image, b.image);
}

#[test]
fn a_pixel_sample_can_be_rerendered_alone() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    // Without the memo, a pixel is the mean of its samples alone.
    let options = RenderOptions {
        samples: 1,
        scale: 0.1,
        exposure: 1.0,
        memo: flatray_tracer::MemoOptions {
            enabled: false,
            ..loaded.options.memo
        },
        ..loaded.options
    };
    let whole = render_on(&loaded.scene, &options, 2);
    let size = (whole.image.width, whole.image.height);
    let (x, y) = (23, 17);
    let mut stats = flatray_tracer::Stats::default();
    let fluence = flatray_tracer::pixel_sample(&loaded.scene, &options, size, x, y, 0, &mut stats);
    let centre = loaded.scene.canvas.origin + (glam::DVec2::new(x as f64, y as f64) + 0.5) * 10.0;
    let albedo = loaded.scene.floor.albedo_at(&loaded.scene.canvas, centre);
    let value = fluence * albedo;
    assert_eq!(
        whole.image.get(x, y),
        [value.x as f32, value.y as f32, value.z as f32]
    );
}
