//! A pixel's value is its mean albedo times its mean fluence: the floor's
//! pattern is averaged over the pixel's square, exactly, so a grout line
//! narrower than a pixel shows with its coverage, and an image's mean does
//! not depend on the scale it is rendered at. Sunlight without walls
//! gives every point the same fluence, so the closed forms hold to the
//! image's f32 rounding.

use flatray_tests::{render, scene};

const SUN: f64 = 0.5;

fn tiles(size: f64, variation: f64) -> String {
    format!(
        "Scene(canvas: (200, 120), floor: Tiles(size: {size}, grout_width: 1.0, tile: (0.8, 0.7, 0.6), grout: (0.2, 0.25, 0.3), variation: {variation}),
            lights: [Directional(direction: (0.3, 1.0), intensity: {SUN})])"
    )
}

/// The length of `[x0, x1]` that lies in grout along one axis: bands of
/// width 1 centred on the multiples of `size`.
fn grout_length(x0: f64, x1: f64, size: f64) -> f64 {
    let first = (x0 / size).floor() as i64 - 1;
    let last = (x1 / size).ceil() as i64 + 1;
    (first..=last)
        .map(|k| {
            let c = k as f64 * size;
            ((c + 0.5).min(x1) - (c - 0.5).max(x0)).max(0.0)
        })
        .sum()
}

#[test]
fn a_grout_line_narrower_than_a_pixel_shows_with_its_coverage_in_every_row() {
    // Tiles of 10.3: grout lines at every offset within the pixels.
    let size = 10.3;
    let loaded = scene(&tiles(size, 0.0));
    let (tile, grout) = ([0.8, 0.7, 0.6], [0.2, 0.25, 0.3]);
    for scale in [1.0, 0.5, 0.25] {
        let image = render(&loaded.scene, &{
            let mut options = loaded.options;
            options.scale = scale;
            options.samples = 1;
            options
        })
        .image;
        let side = 1.0 / scale;
        let mut grout_pixels = 0;
        for y in 0..image.height {
            for x in 0..image.width {
                let (x0, y0) = (x as f64 * side, y as f64 * side);
                // A tile is the product of its two axes' intervals.
                let fx = 1.0 - grout_length(x0, x0 + side, size) / side;
                let fy = 1.0 - grout_length(y0, y0 + side, size) / side;
                let covered = fx * fy;
                if covered < 0.99 {
                    grout_pixels += 1;
                }
                let got = image.get(x, y);
                for c in 0..3 {
                    let want = SUN * (tile[c] * covered + grout[c] * (1.0 - covered));
                    assert!(
                        (got[c] as f64 - want).abs() <= 1e-6,
                        "scale {scale}, pixel ({x}, {y}), channel {c}: {} against {want} (tile coverage {covered})",
                        got[c]
                    );
                }
            }
        }
        // Every column and row that a grout line crosses shows it.
        assert!(grout_pixels as u32 >= image.height * 19, "{grout_pixels}");
    }
}

#[test]
fn a_tile_floor_has_the_same_mean_at_every_scale() {
    // The tutorial's tiles: 20 units, grout 1, varied shades.
    let loaded = scene(&tiles(20.0, 0.15));
    let mean_at = |scale: f64| {
        let image = render(&loaded.scene, &{
            let mut options = loaded.options;
            options.scale = scale;
            options.samples = 1;
            options
        })
        .image;
        let n = image.pixels.len() as f64;
        let sum: f64 = image.pixels.iter().flatten().map(|&v| v as f64).sum();
        sum / n
    };
    let full = mean_at(1.0);
    for scale in [0.5, 0.25, 0.125 * 0.8] {
        let mean = mean_at(scale);
        assert!(
            (mean - full).abs() <= 1e-6 * full,
            "scale {scale}: mean {mean}, at scale 1 {full}"
        );
    }
}
