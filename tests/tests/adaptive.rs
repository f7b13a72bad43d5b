//! Adaptive passes (`docs/model.md`, "Adaptive passes"): from the third
//! pass on, a pass takes only the pixels whose estimated error, with
//! their neighbours', is high. The renders stay deterministic, the passes
//! taken one at a time give the single render's bits, dark pixels stop
//! at the first two passes, and the images agree with plain renders block
//! by block (5 standard errors over 16 fixed seeds each): the decisions,
//! made from each pixel's own samples, bias nothing measurable.

use flatray_tests::{block_stats, render, render_on, workspace_root};
use flatray_tracer::{ADAPT_FROM, FIRST_PASS, Progressive, RenderOptions};

fn room() -> (flatray_tracer::Scene, RenderOptions) {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron"))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut options = loaded.options;
    options.scale = 0.2;
    options.samples = 128;
    options.adaptive = true;
    (loaded.scene, options)
}

#[test]
fn adaptive_renders_are_the_same_on_any_thread_count_and_pass_by_pass() {
    let (scene, options) = room();
    let one = render_on(&scene, &options, 1);
    let two = render_on(&scene, &options, 2);
    assert_eq!(one.image, two.image);
    assert_eq!(one.samples, two.samples);
    let mut progressive = Progressive::new(&scene, &options);
    while let Some(end) = progressive.next_end() {
        if end > options.samples {
            break;
        }
        assert!(progressive.pass(end, &|_| {}));
    }
    let stepped = progressive.rendered();
    assert_eq!(stepped.image, one.image);
    assert_eq!(stepped.samples, one.samples);
    assert_eq!(stepped.stats.noise, one.stats.noise);
}

#[test]
fn pixels_with_little_noise_stop_after_the_first_passes() {
    let (scene, options) = room();
    let rendered = render(&scene, &options);
    let first = 2 * FIRST_PASS;
    assert_eq!(ADAPT_FROM, 2);
    // 32, then the third pass's 32 or not, the fourth's 64 or not.
    assert!(
        rendered
            .samples
            .iter()
            .all(|&n| [first, 64, 96, 128].contains(&n))
    );
    let stopped = rendered.samples.iter().filter(|&&n| n == first).count();
    let full = rendered.samples.iter().filter(|&&n| n == 128).count();
    let pixels = rendered.samples.len();
    // The room's dark parts (outside its walls, behind the mirror) stop;
    // its lit floor goes on.
    assert!(stopped > pixels / 10, "{stopped} of {pixels} stopped");
    assert!(full > pixels / 4, "{full} of {pixels} took every pass");
    // A pixel whose neighbours and itself received no light at all takes
    // nothing more.
    let (w, h) = (
        rendered.image.width as usize,
        rendered.image.height as usize,
    );
    let dark = |x: usize, y: usize| rendered.image.pixels[y * w + x] == [0.0; 3];
    let mut dark_seen = 0;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            if (y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| dark(i, j))) {
                assert_eq!(rendered.samples[y * w + x], first, "({x}, {y})");
                dark_seen += 1;
            }
        }
    }
    assert!(dark_seen > 40, "{dark_seen} dark pixels");
    // Without adaptive passes every pixel takes every sample.
    let mut plain = options;
    plain.adaptive = false;
    assert!(render(&scene, &plain).samples.iter().all(|&n| n == 128));
}

#[test]
fn adaptive_renders_agree_with_plain_renders_block_by_block() {
    let (scene, options) = room();
    let mut options = options;
    options.samples = 64;
    let adaptive = block_stats(&scene, options, 5, 16, 500);
    // The same estimator without the adaptive decisions: the pixels' own
    // path samples, not lines (whose noise is far lower and which, unlike
    // a handful of samples, find the room's light through a corner's
    // crack at every seed).
    let mut plain = options;
    plain.adaptive = false;
    plain.floor_lines = false;
    let plain = block_stats(&scene, plain, 5, 16, 500);
    let mut checked = 0;
    for (b, ((ma, sa), (mp, sp))) in adaptive.iter().zip(&plain).enumerate() {
        let se = (sa * sa + sp * sp).sqrt();
        assert!(
            (ma - mp).abs() <= 5.0 * se + 1e-9 * mp.abs(),
            "block {b}: adaptive {ma}, plain {mp}, 5 SE = {}",
            5.0 * se
        );
        checked += 1;
    }
    assert!(checked >= 300, "{checked} blocks");
}
