//! A laser's spot on a diffuse wall lies where its ray hit: the light the
//! wall sends back to the floor is centred on the hit, and symmetric about
//! the wall's normal there, wherever in a caustic bin the hit falls
//! (`docs/model.md`, "The caustic pass": a deposit is shared between the
//! two bins about the hit, and a read blends them alike).

use flatray_tests::{options, render, scene};
use flatray_tracer::{Image, Integrator, RenderOptions};

const WIDTH: u32 = 160;
/// The wall runs along `y = WALL`, the laser comes down onto it at `x`.
const WALL: f64 = 10.0;

fn laser_on_a_wall(x: f64) -> String {
    format!(
        "Scene(canvas: ({WIDTH}, 60), floor: Color((1, 1, 1)),
               walls: [Wall(a: (0, {WALL}), b: ({WIDTH}, {WALL}), material: Diffuse(albedo: (0.8, 0.8, 0.8)))],
               lights: [Laser(at: ({x}, 55), direction: (0, -1), intensity: 40.0)])"
    )
}

/// The light the wall sends to the floor: the render at one bounce less
/// the render at none (the laser's own track on the floor is the same in
/// both, and cancels).
fn from_the_wall(x: f64, o: &RenderOptions) -> Image {
    let loaded = scene(&laser_on_a_wall(x));
    let once = render(&loaded.scene, o).image;
    let direct = render(&loaded.scene, &{
        let mut o = *o;
        o.bounces = 0;
        o
    })
    .image;
    Image {
        width: once.width,
        height: once.height,
        pixels: once
            .pixels
            .iter()
            .zip(&direct.pixels)
            .map(|(a, b)| std::array::from_fn(|c| a[c] - b[c]))
            .collect(),
    }
}

/// The weight of the pixel column centred at `c` in the window of
/// columns `[lo, hi]` of the plane: the share of the pixel inside it.
fn share(c: f64, lo: f64, hi: f64) -> f64 {
    ((c + 0.5).min(hi) - (c - 0.5).max(lo)).max(0.0)
}

/// The centroid along the wall of the light in rows 2 to 20 pixels from
/// the wall, over columns within 20 of `x`; and the light in columns 10 to
/// 40 pixels from `x` on its left and on its right.
fn spot(image: &Image, x: f64) -> (f64, f64, f64) {
    let (mut moment, mut total, mut left, mut right) = (0.0, 0.0, 0.0, 0.0);
    for row in (WALL as u32 + 2)..(WALL as u32 + 20) {
        for column in 0..image.width {
            let v = image.get(column, row)[1] as f64;
            let c = column as f64 + 0.5;
            let w = share(c, x - 20.0, x + 20.0);
            moment += w * v * (c - x);
            total += w * v;
            left += share(c, x - 40.0, x - 10.0) * v;
            right += share(c, x + 10.0, x + 40.0) * v;
        }
    }
    (x + moment / total, left, right)
}

#[test]
fn a_lasers_spot_on_a_wall_is_where_it_hit_wherever_in_a_bin() {
    // Bins of one pixel along the wall, from x = 0: the hits lie 0.4 and
    // 0.2 before a bin's centre, and 0.12 and 0.38 past one.
    let hits = [80.1, 80.3, 80.62, 80.88];
    let mut failures = Vec::new();
    for (integrator, samples) in [(Integrator::Path, 64), (Integrator::Light, 64)] {
        for &x in &hits {
            // Eight seeds: the spread of the left-right difference.
            let runs: Vec<(f64, f64, f64)> = (0..8)
                .map(|seed| {
                    let mut o = options(samples, 1, seed);
                    o.integrator = integrator;
                    spot(&from_the_wall(x, &o), x)
                })
                .collect();
            let n = runs.len() as f64;
            let centre = runs.iter().map(|r| r.0).sum::<f64>() / n;
            if (centre - x).abs() > 0.1 {
                failures.push(format!(
                    "{}: hit at {x}, spot fitted at {centre:.3} ({:+.3} px)",
                    integrator.name(),
                    centre - x
                ));
            }
            // Left against right, relative: within 5 standard errors of
            // the mean over the seeds. (A spot at its bin's centre, 0.4
            // pixel off, is 4.5 % brighter on one side, 4.4 standard
            // errors at these samples: the centroid is the sharper test.)
            let asymmetry: Vec<f64> = runs.iter().map(|r| (r.1 - r.2) / (r.1 + r.2)).collect();
            let mean = asymmetry.iter().sum::<f64>() / n;
            let var = asymmetry.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n).sqrt();
            if mean.abs() > 5.0 * se {
                failures.push(format!(
                    "{}: hit at {x}, left over right {:+.2} % (5 SE {:.2} %)",
                    integrator.name(),
                    100.0 * mean,
                    500.0 * se
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
