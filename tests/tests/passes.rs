//! A render taken pass by pass (`flatray_tracer::Progressive`) gives, after
//! any pass, the image, path counts and noise estimate of a single render
//! of the samples reached, to the bit; and it refuses a pass that a single
//! render would not take. On scenes that use every per-pass fill: the caustic pass
//! (mirrors), the onward memo (three bounces), the light table (many
//! lights), and the light tracer.

use flatray_tests::{render, render_on, workspace_root};
use flatray_tracer::{Integrator, Progressive, RenderOptions, next_pass_end};

fn load(name: &str) -> flatray_io::Loaded {
    flatray_io::load(&workspace_root().join(format!("scenes/{name}.ron")))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Drives `options` pass by pass to `samples` (the last pass short of the
/// schedule where `samples` is not on it), checking the image after every
/// pass against a single render of that many samples.
fn check_passes(name: &str, options: RenderOptions, samples: u32) {
    let loaded = load(name);
    let mut progressive = Progressive::new(&loaded.scene, &options);
    while progressive.samples() < samples {
        let end = progressive
            .next_end()
            .unwrap_or_else(|| panic!("{name}: no pass may follow"))
            .min(samples);
        assert!(progressive.pass(end, &|_| {}), "{name}: pass to {end}");
        let passes = progressive.rendered();
        let single = render(&loaded.scene, &{
            let mut options = options;
            options.samples = end;
            options
        });
        assert!(
            passes.image == single.image,
            "{name}: the image after the pass to {end} spp is not the single render's"
        );
        // The work differs (a single render shares a pixel's culling and
        // shadow rays between its passes); what the paths did does not.
        assert_eq!(
            passes.stats.physics, single.stats.physics,
            "{name}: {end} spp"
        );
        assert_eq!(passes.stats.noise, single.stats.noise, "{name}: {end} spp");
    }
}

#[test]
fn passes_give_the_single_render_at_every_step() {
    // Mirrors and a pane: the caustic pass, two bounces.
    let first_flat = load("first-flat").options;
    check_passes(
        "first-flat",
        {
            let mut options = first_flat;
            options.scale = 0.2;
            options
        },
        100,
    );
    // Three bounces, 17 lights: the onward memo and the light table.
    let apartment = load("apartment").options;
    check_passes(
        "apartment",
        {
            let mut options = apartment;
            options.scale = 0.12;
            options.bounces = 3;
            options
        },
        40,
    );
    // The light tracer's photons, pass by pass.
    let room = load("room").options;
    check_passes(
        "room",
        {
            let mut options = room;
            options.scale = 0.1;
            options.integrator = Integrator::Light;
            options
        },
        35,
    );
}

/// A pass that ends short of the schedule is the last one; a pass must
/// add samples and may not go past the schedule.
#[test]
fn a_short_pass_is_the_last() {
    let loaded = load("room");
    let options = {
        let mut options = loaded.options;
        options.scale = 0.05;
        options
    };
    let mut progressive = Progressive::new(&loaded.scene, &options);
    assert_eq!(progressive.next_end(), Some(16));
    assert!(!progressive.pass(17, &|_| {}), "past the first pass's end");
    assert!(!progressive.pass(0, &|_| {}), "no samples");
    assert!(progressive.pass(16, &|_| {}));
    assert_eq!(progressive.next_end(), Some(next_pass_end(16)));
    assert!(progressive.pass(20, &|_| {}));
    assert_eq!(progressive.samples(), 20);
    assert_eq!(progressive.next_end(), None);
    assert!(!progressive.pass(32, &|_| {}));
    assert_eq!(progressive.samples(), 20);
}

/// The passes' sums do not depend on the threads: one thread and two give
/// the same image at a sample count of several passes.
#[test]
fn passes_do_not_depend_on_the_threads() {
    let loaded = load("bathroom");
    let options = {
        let mut options = loaded.options;
        options.samples = 70;
        options.scale = 0.2;
        options
    };
    let one = render_on(&loaded.scene, &options, 1);
    let two = render_on(&loaded.scene, &options, 2);
    assert!(one.image == two.image);
    assert_eq!(one.stats, two.stats);
}
