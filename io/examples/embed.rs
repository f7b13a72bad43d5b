//! An embedder's program: a scene built in code, rendered, written as a
//! linear EXR.
//!
//!     cargo run --release -p flatray-io --example embed -- room.exr
//!
//! `cargo test` builds and runs it too (into a temporary folder).

use std::path::{Path, PathBuf};

use flatray_geometry::{DVec2, Segment};
use flatray_tracer::{
    Canvas, Falloff, Floor, Light, LightShape, Material, RenderOptions, Rgb, Scene, Wall,
};

/// A room of four walls turned by 20 degrees, one of them a mirror, lit
/// by a lamp: rendered with 64 samples a pixel and two bounces, and
/// written to `out`. Returns the render's estimate of its own noise.
fn render_room(out: &Path) -> Result<f64, Box<dyn std::error::Error>> {
    let canvas = Canvas {
        width: 240,
        height: 180,
        origin: DVec2::ZERO,
    };
    let (centre, turn) = (
        DVec2::new(120.0, 90.0),
        DVec2::from_angle(20f64.to_radians()),
    );
    let corner = |x: f64, y: f64| centre + turn.rotate(DVec2::new(x, y));
    let corners = [
        corner(-90.0, -60.0),
        corner(90.0, -60.0),
        corner(90.0, 60.0),
        corner(-90.0, 60.0),
    ];
    let walls = (0..4)
        .map(|k| Wall {
            shape: Segment::new(corners[k], corners[(k + 1) % 4]).into(),
            material: if k == 1 {
                Material::Mirror { tint: Rgb::ONE }
            } else {
                Material::Diffuse {
                    albedo: Some(Rgb::new(0.8, 0.7, 0.6)),
                }
            },
        })
        .collect();
    let lamp = Light {
        profile: None,
        shape: LightShape::Point {
            at: corner(-40.0, 10.0),
        },
        color: Rgb::new(1.0, 0.9, 0.8),
        intensity: 2.0,
        falloff: Falloff::Flatland,
        spectrum: None,
    };
    // Every value is checked here: a NaN, a colour above 1 or a wall of
    // no length is an error naming the item, not a broken render.
    let scene = Scene::new(
        canvas,
        Floor::Color(Rgb::splat(0.7)),
        0.5,
        walls,
        vec![lamp],
    )?;

    let mut options = RenderOptions::default();
    options.samples = 64;
    options.bounces = 2;
    let rendered = flatray_tracer::render(&scene, &options, &|_| {});
    flatray_io::write_exr(&rendered.image, out)?;
    rendered
        .stats
        .noise
        .relative()
        .ok_or_else(|| "no noise estimate".into())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from("room.exr"), PathBuf::from);
    let noise = render_room(&out)?;
    println!("wrote {} (noise {:.2} %)", out.display(), 100.0 * noise);
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_example_renders_and_writes_its_room() {
        let folder = std::env::temp_dir().join(format!("flatray-embed-{}", std::process::id()));
        std::fs::create_dir_all(&folder).unwrap();
        let out = folder.join("room.exr");
        let noise = super::render_room(&out).unwrap();
        assert!(noise > 0.0 && noise < 0.2, "{noise}");
        let image = flatray_io::read_exr(&out).unwrap();
        assert_eq!((image.width, image.height), (240, 180));
        // Lit inside the room, dark in the canvas's corner outside it.
        assert!(image.get(120, 90)[0] > 0.0);
        assert_eq!(image.get(0, 0), [0.0; 3]);
        std::fs::remove_dir_all(folder).unwrap();
    }
}
