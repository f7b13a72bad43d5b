//! The wall memo converges to the model: its bins average the irradiance
//! over a pixel of wall (the irradiance at each bin's centre), a bias
//! where the light on a wall has an edge (at corners, under sun and spot)
//! that more samples alone would not take away. One read in 16 is
//! checked by next-event estimation (`flatray_cache::checked`), unbiased, so
//! the default's error at the corners keeps falling with the samples.

use flatray_tests::{block_stats, scene};
use flatray_tracer::{MemoOptions, RenderOptions};

/// A rotated room: sunlight through a window, a spot into a corner, a
/// line light along a wall, two bounces.
const ROOM: &str = "Scene(canvas: (64, 64), floor: Color((0.8, 0.8, 0.8)),
    walls: [Wall(a: (32, 2), b: (62, 32)), Wall(a: (62, 32), b: (32, 62)),
            Wall(a: (32, 62), b: (2, 32)), Wall(a: (2, 32), b: (12, 22)),
            Wall(a: (12, 22), b: (22, 12), material: Transparent(tint: (0.9, 0.95, 1.0))),
            Wall(a: (22, 12), b: (32, 2)),
            Wall(a: (30, 30), b: (36, 36), material: Diffuse(albedo: Some((0.3, 0.6, 0.3))))],
    lights: [Directional(direction: (1.0, 0.7), intensity: 0.8),
             Spot(at: (24, 40), direction: (1, 0.6), cone: 30, softness: 8, intensity: 20.0),
             Line(a: (40, 52), b: (50, 42), intensity: 0.6)])";

const BLOCK: u32 = 6;

/// The blocks inside the room's four corners.
const CORNERS: [(u32, u32); 4] = [(5, 1), (9, 5), (5, 9), (1, 5)];

fn corner_blocks(stats: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let per_row = 64 / BLOCK;
    CORNERS
        .iter()
        .map(|&(bx, by)| stats[(by * per_row + bx) as usize])
        .collect()
}

fn options(samples: u32, memo: bool) -> RenderOptions {
    {
        let mut options = RenderOptions::default();
        options.samples = samples;
        options.bounces = 2;
        options.memo = MemoOptions::default();
        options.memo.enabled = memo;
        options
    }
}

/// At 1024 samples, the memo's corners agree with paths that cast every
/// shadow ray, within 5 standard errors (16 runs each, fixed seeds); from
/// 16 to 256 samples their RMS error against that reference falls by more
/// than 2 (4 for an unbiased estimator; a bias of the memo's size stops it
/// near 1).
#[test]
fn the_memo_converges_at_corners_under_sun_spot_and_line_light() {
    let loaded = scene(ROOM);
    let room = &loaded.scene;
    let reference = corner_blocks(&block_stats(room, options(1024, false), BLOCK, 16, 500));
    let memo = corner_blocks(&block_stats(room, options(1024, true), BLOCK, 16, 700));
    for (k, (r, m)) in reference.iter().zip(&memo).enumerate() {
        let se = (r.1 * r.1 + m.1 * m.1).sqrt();
        assert!(
            (r.0 - m.0).abs() <= 5.0 * se,
            "corner {k}: memo {} against {} (se {se})",
            m.0,
            r.0
        );
    }
    // RMS error over runs and corners, relative to the reference.
    let rms = |samples: u32| {
        let runs = 8;
        let mut sum = 0.0;
        for seed in 0..runs {
            let blocks = corner_blocks(&block_stats(
                room,
                options(samples, true),
                BLOCK,
                1,
                900 + seed,
            ));
            for (b, r) in blocks.iter().zip(&reference) {
                sum += ((b.0 - r.0) / r.0).powi(2);
            }
        }
        (sum / (runs as f64 * 4.0)).sqrt()
    };
    let (coarse, fine) = (rms(16), rms(256));
    assert!(
        fine < coarse / 2.0,
        "RMS error {coarse} at 16 samples, {fine} at 256"
    );
}
