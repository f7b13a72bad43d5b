//! Renders a procedural maze of about N walls and reports the time: the
//! documented command behind the large-scene figures of
//! `docs/performance.md`.
//!
//!     cargo run --release -p flatray-benches --bin maze -- [WALLS] [SPP] [OUT.png]
//!
//! Defaults: 100000 walls, 16 samples, 1 bounce, 500 x 500 pixels.

use std::time::Instant;

use flatray_benches::maze;
use flatray_geometry::DVec2;
use flatray_tracer::{
    Canvas, Falloff, Floor, Light, LightShape, Material, RenderOptions, Rgb, Scene, Wall,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let walls: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let samples: u32 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(16);
    let size = 500.0;
    let built = Instant::now();
    let segments = maze(walls, size, 7);
    let count = segments.len();
    let walls: Vec<Wall> = segments
        .into_iter()
        .enumerate()
        .map(|(i, segment)| Wall {
            shape: segment.into(),
            material: Material::Diffuse {
                albedo: Some(if i % 3 == 0 {
                    Rgb::new(0.8, 0.3, 0.2)
                } else {
                    Rgb::splat(0.7)
                }),
            },
        })
        .collect();
    // Lights at cell centres spread over the maze.
    let cells = (count as f64 / 2.0).sqrt().max(1.0);
    let cell = size / cells.ceil();
    let lights: Vec<Light> = (0..16)
        .map(|k| {
            let (i, j) = ((k % 4) as f64, (k / 4) as f64);
            let at = DVec2::new(
                ((i + 0.5) * size / 4.0 / cell).floor() * cell + 0.5 * cell,
                ((j + 0.5) * size / 4.0 / cell).floor() * cell + 0.5 * cell,
            );
            Light {
                profile: None,
                shape: LightShape::Point { at },
                color: Rgb::new(1.0, 0.95, 0.8),
                intensity: 2.0,
                falloff: Falloff::Flatland,
                spectrum: None,
            }
        })
        .collect();
    let canvas = Canvas {
        width: size as u32,
        height: size as u32,
        origin: DVec2::ZERO,
    };
    let scene = Scene::new(canvas, Floor::Color(Rgb::splat(0.85)), 0.5, walls, lights)
        .expect("the maze is a valid scene");
    let build_seconds = built.elapsed().as_secs_f64();
    let options = {
        let mut options = RenderOptions::default();
        options.samples = samples;
        options.bounces = 1;
        options
    };
    let started = Instant::now();
    let rendered = flatray_tracer::render(&scene, &options, &|_| {});
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "{count} walls, {} lights, {samples} spp, 500 x 500: scene built in {build_seconds:.2} s, rendered in {seconds:.2} s ({:.1} M rays/s)",
        scene.lights().len(),
        (rendered.stats.rays() + rendered.stats.work.memo_fill_rays) as f64 / seconds / 1e6
    );
    let w = &rendered.stats.work;
    println!(
        "rays: {} shadow, {} bounce, {} to fill the wall cache, {} to build the light table",
        w.shadow_rays, w.bounce_rays, w.memo_fill_rays, w.light_table_rays
    );
    if let Some(path) = args.get(3) {
        let tonemap = flatray_io::ToneMap::Reinhard {
            white: flatray_io::format::Positive(4.0),
        };
        if let Err(e) = flatray_io::write_png(&rendered.image, tonemap, std::path::Path::new(path))
        {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
