//! Every render estimates its own noise from two halves of its samples.
//! The estimate is checked against the true error: the relative RMS
//! difference from a reference rendered with 64 times the samples (whose
//! own noise, estimated the same way, is taken out in quadrature), on two
//! scenes and both integrators. Fixed seeds.

use flatray_tests::{render, workspace_root};
use flatray_tracer::metrics::compare;
use flatray_tracer::{Integrator, RenderOptions};

/// The estimate over the true error, for `scene` at `scale` and `samples`.
fn ratio(name: &str, scale: f64, samples: u32, integrator: Integrator) -> f64 {
    let loaded = flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron")))
        .unwrap_or_else(|e| panic!("{e}"));
    let options = |samples: u32, seed: u64| RenderOptions {
        samples,
        seed,
        scale,
        integrator,
        ..loaded.options
    };
    let rendered = render(&loaded.scene, &options(samples, 1));
    let reference = render(&loaded.scene, &options(samples * 64, 2));
    let estimate = rendered
        .stats
        .noise
        .relative()
        .unwrap_or_else(|| panic!("{name}: no estimate"));
    let reference_noise = reference.stats.noise.relative().unwrap_or(0.0);
    let measured = compare(&rendered.image, &reference.image)
        .unwrap_or_else(|| panic!("{name}: black reference"))
        .relative_rmse;
    let truth = (measured * measured - reference_noise * reference_noise).sqrt();
    estimate / truth
}

#[test]
fn the_noise_estimate_agrees_with_the_true_error() {
    for (name, scale, samples, integrator) in [
        ("room", 0.2, 64, Integrator::Path),
        ("first-flat", 0.25, 64, Integrator::Path),
        ("room", 0.2, 2, Integrator::Light),
        ("first-flat", 0.25, 2, Integrator::Light),
    ] {
        let r = ratio(name, scale, samples, integrator);
        assert!(
            (0.7..=1.4).contains(&r),
            "{name}, {integrator:?}, {samples} spp: estimate / true error = {r}"
        );
    }
}

#[test]
fn one_sample_per_pixel_has_no_estimate_and_the_image_does_not_change() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron"))
        .unwrap_or_else(|e| panic!("{e}"));
    let options = RenderOptions {
        samples: 1,
        scale: 0.1,
        ..loaded.options
    };
    let rendered = render(&loaded.scene, &options);
    assert_eq!(rendered.stats.noise.relative(), None);
    assert_eq!(
        rendered.stats.noise.to_string(),
        "not estimated (it takes at least 2 samples per pixel)"
    );
}
