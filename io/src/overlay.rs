//! Walls drawn over a tone-mapped image, so that a render shows its plan:
//! anti-aliased lines in a colour that tells the material (diffuse walls
//! in their own colour, mirrors silver-blue, rough mirrors greyer, panes in their tint, glass
//! pale cyan, emitting walls warm yellow).

use flatray_geometry::DVec2;
use flatray_tracer::Scene;

/// The colour (sRGB, 0 to 1) a wall is drawn in.
fn wall_colour(scene: &Scene, index: usize) -> [f64; 3] {
    if scene.light_of_wall(index as u32).is_some() {
        return [1.0, 0.85, 0.3];
    }
    let material = &scene.walls()[index].material;
    if let Some(albedo) = material.diffuse_albedo() {
        return match albedo {
            // Darkened a little, so that a white wall shows on a white floor.
            Some(a) => [a.x, a.y, a.z].map(|c| (0.15 + 0.7 * c).clamp(0.0, 1.0)),
            None => [0.9, 0.9, 0.88],
        };
    }
    if let Some(tint) = material.pane_tint() {
        return [0.3 + 0.5 * tint.x, 0.5 + 0.5 * tint.y, 0.55 + 0.45 * tint.z];
    }
    if material.is_mirror() {
        [0.7, 0.82, 1.0]
    } else if material.is_glossy() {
        [0.62, 0.7, 0.85]
    } else {
        // Glass.
        [0.6, 0.95, 0.95]
    }
}

/// Draws every wall of `scene`, `width` pixels wide, over the 8-bit RGB
/// `bytes` of an image of `size` pixels covering the scene's canvas: first
/// a dark halo a pixel wider, then the wall's colour, so that walls show
/// on light and dark floors alike.
pub fn draw_walls(bytes: &mut [u8], size: (u32, u32), scene: &Scene, width: f64) {
    draw(bytes, size, scene, width + 1.0, Some(([0.0; 3], 0.6)));
    draw(bytes, size, scene, width, None);
}

/// One pass: each wall in its colour, or all in `fixed` (a colour and an
/// opacity).
fn draw(
    bytes: &mut [u8],
    size: (u32, u32),
    scene: &Scene,
    width: f64,
    fixed: Option<([f64; 3], f64)>,
) {
    let (w, h) = (size.0 as i64, size.1 as i64);
    if bytes.len() < (w * h * 3) as usize {
        return;
    }
    let step = DVec2::new(
        size.0 as f64 / scene.canvas().width as f64,
        size.1 as f64 / scene.canvas().height as f64,
    );
    let to_pixels = |p: DVec2| (p - scene.canvas().origin) * step;
    let half = 0.5 * width;
    for (index, wall) in scene.walls().iter().enumerate() {
        let (colour, opacity) = fixed.unwrap_or((wall_colour(scene, index), 1.0));
        let colour = colour.map(|c| c * 255.0);
        if let Some(arc) = wall.shape.as_arc() {
            draw_arc(bytes, (w, h), arc, to_pixels, step, half, (colour, opacity));
            continue;
        }
        let (a, b) = (to_pixels(wall.shape.a()), to_pixels(wall.shape.b()));
        if !(a.is_finite() && b.is_finite()) {
            continue;
        }
        let edge = b - a;
        let length = edge.length();
        // Along the major axis, one step per pixel; across it, the pixels
        // within reach of the line.
        let steep = edge.y.abs() > edge.x.abs();
        let (major_a, major_b) = if steep { (a.y, b.y) } else { (a.x, b.x) };
        let (low, high) = (
            major_a.min(major_b) - half - 1.0,
            major_a.max(major_b) + half + 1.0,
        );
        let limit = if steep { h } else { w };
        let first = (low.floor() as i64).max(0);
        let last = (high.ceil() as i64).min(limit - 1);
        let reach = (half + 1.5).ceil() as i64;
        let mut i = first;
        while i <= last {
            let centre_major = i as f64 + 0.5;
            // Where the line crosses this row (or column).
            let t = if major_b != major_a {
                ((centre_major - major_a) / (major_b - major_a)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let on = a + edge * t;
            let minor = if steep { on.x } else { on.y };
            let centre = minor.floor() as i64;
            for j in centre - reach..=centre + reach {
                let (x, y) = if steep { (j, i) } else { (i, j) };
                if x < 0 || y < 0 || x >= w || y >= h {
                    continue;
                }
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let distance = if length > 0.0 {
                    let u = ((p - a).dot(edge) / (length * length)).clamp(0.0, 1.0);
                    p.distance(a + edge * u)
                } else {
                    p.distance(a)
                };
                blend(
                    bytes,
                    ((y * w + x) * 3) as usize,
                    colour,
                    (half, distance, opacity),
                );
            }
            i += 1;
        }
    }
}

/// Most pixels an arc's box may cover: a larger one is drawn in part.
const MAX_ARC_PIXELS: i64 = 1 << 24;

/// Draws `arc` (in world units, drawn through `to_pixels`) as a line
/// `2 half` pixels wide: each pixel of its box by its distance to the arc
/// (to its point at the pixel's angle, or the nearer end), so that its edge is as smooth as a straight wall's.
fn draw_arc(
    bytes: &mut [u8],
    (w, h): (i64, i64),
    arc: &flatray_geometry::Arc,
    to_pixels: impl Fn(DVec2) -> DVec2,
    step: DVec2,
    half: f64,
    (colour, opacity): ([f64; 3], f64),
) {
    let (lo, hi) = arc.bounds();
    let (lo, hi) = (to_pixels(lo), to_pixels(hi));
    if !(lo.is_finite() && hi.is_finite()) {
        return;
    }
    let reach = half + 1.5;
    let x0 = ((lo.x - reach).floor() as i64).max(0);
    let y0 = ((lo.y - reach).floor() as i64).max(0);
    let x1 = ((hi.x + reach).ceil() as i64).min(w - 1);
    let y1 = ((hi.y + reach).ceil() as i64).min(h - 1);
    if x1 < x0 || y1 < y0 || (x1 - x0 + 1).saturating_mul(y1 - y0 + 1) > MAX_ARC_PIXELS {
        return;
    }
    let (a, b) = (to_pixels(arc.a), to_pixels(arc.b));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            // The pixel's centre in world units, for the arc's angle test.
            let world = arc.center + (p - to_pixels(arc.center)) / step;
            // Its nearest point by angle: on the circle, or an end.
            let on = to_pixels(arc.point_at(arc.position_of(world)));
            let distance = p.distance(on).min(p.distance(a)).min(p.distance(b));
            blend(
                bytes,
                ((y * w + x) * 3) as usize,
                colour,
                (half, distance, opacity),
            );
        }
    }
}

/// Blends `colour` into the pixel at byte `k` by how much of it a line
/// `2 half` wide covers, its centre `distance` from the line's middle,
/// times `opacity`.
#[inline]
fn blend(bytes: &mut [u8], k: usize, colour: [f64; 3], (half, distance, opacity): (f64, f64, f64)) {
    let coverage = (half + 0.5 - distance).clamp(0.0, 1.0) * opacity;
    if coverage > 0.0 {
        for c in 0..3 {
            let old = bytes[k + c] as f64;
            bytes[k + c] = (old + (colour[c] - old) * coverage).round() as u8;
        }
    }
}

/// The glyphs [`draw_label`] writes, 3 wide and 5 high, a row per entry
/// (bit 2 is the left column).
const GLYPHS: [(char, [u8; 5]); 14] = [
    ('0', [7, 5, 5, 5, 7]),
    ('1', [2, 6, 2, 2, 7]),
    ('2', [7, 1, 7, 4, 7]),
    ('3', [7, 1, 7, 1, 7]),
    ('4', [5, 5, 7, 1, 1]),
    ('5', [7, 4, 7, 1, 7]),
    ('6', [7, 4, 7, 5, 7]),
    ('7', [7, 1, 1, 1, 1]),
    ('8', [7, 5, 7, 5, 7]),
    ('9', [7, 5, 7, 1, 7]),
    (':', [0, 2, 0, 2, 0]),
    ('-', [0, 0, 7, 0, 0]),
    ('.', [0, 0, 0, 0, 2]),
    (' ', [0, 0, 0, 0, 0]),
];

/// Writes `text` (digits, `:`, `-`, `.` and spaces; other characters are
/// left out) in white on a black box at the top-left corner of 8-bit RGB
/// rows `bytes` of `size`, each glyph cell `scale` pixels: a frame's time
/// stamp. Whatever falls outside the image is not drawn.
pub fn draw_label(bytes: &mut [u8], size: (u32, u32), text: &str, scale: u32) {
    let (width, height) = (size.0 as usize, size.1 as usize);
    let scale = scale.max(1) as usize;
    let glyphs: Vec<&[u8; 5]> = text
        .chars()
        .filter_map(|c| GLYPHS.iter().find(|(g, _)| *g == c).map(|(_, rows)| rows))
        .collect();
    // One cell of margin about the text, one between glyphs.
    let cells_x = 4 * glyphs.len() + 1;
    let mut set = |x: usize, y: usize, v: u8| {
        if x < width && y < height {
            let k = 3 * (y * width + x);
            if let Some(p) = bytes.get_mut(k..k + 3) {
                p.fill(v);
            }
        }
    };
    for cy in 0..7 {
        for cx in 0..cells_x {
            let on = (1..6).contains(&cy)
                && cx >= 1
                && (cx - 1) % 4 < 3
                && glyphs
                    .get((cx - 1) / 4)
                    .is_some_and(|rows| rows[cy - 1] >> (2 - (cx - 1) % 4) & 1 == 1);
            let v = if on { 255 } else { 0 };
            for y in cy * scale..(cy + 1) * scale {
                for x in cx * scale..(cx + 1) * scale {
                    set(x, y, v);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatray_geometry::Segment;
    use flatray_tracer::{Canvas, Floor, Material, Rgb, Wall};

    #[test]
    fn a_wall_is_drawn_along_its_line_and_nowhere_else() {
        let wall = |a: (f64, f64), b: (f64, f64), material| Wall {
            shape: Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1)).into(),
            material,
        };
        let scene = Scene::new(
            Canvas {
                width: 40,
                height: 20,
                origin: DVec2::ZERO,
            },
            Floor::Color(Rgb::ONE),
            0.5,
            vec![
                wall((2.0, 5.0), (38.0, 5.0), Material::Mirror { tint: Rgb::ONE }),
                wall(
                    (10.0, 8.0),
                    (30.0, 18.0),
                    Material::Diffuse { albedo: None },
                ),
            ],
            Vec::new(),
        )
        .expect("a valid scene");
        // At half scale: 20 x 10 pixels.
        let mut bytes = vec![0u8; 20 * 10 * 3];
        draw_walls(&mut bytes, (20, 10), &scene, 1.5);
        let at = |x: usize, y: usize| &bytes[(y * 20 + x) * 3..(y * 20 + x) * 3 + 3];
        // The mirror at y = 2.5 pixels: full colour on rows 2 (centre 2.5).
        assert_eq!(at(10, 2), &[179, 209, 255]);
        // The diagonal passes (10, 6.5) in pixels.
        assert!(at(10, 6)[0] > 60, "{:?}", at(10, 6));
        // Far from both walls, untouched.
        assert_eq!(at(2, 8), &[0, 0, 0]);
        assert_eq!(at(18, 0), &[0, 0, 0]);
    }
}

#[cfg(test)]
mod label_tests {
    use super::*;

    /// "1" at scale 1: its column of bits where the glyph has them, a
    /// black box about it, and the image beyond untouched.
    #[test]
    fn a_label_draws_its_glyphs_in_a_black_box() {
        let (w, h) = (10u32, 9u32);
        let mut bytes = vec![100u8; (3 * w * h) as usize];
        draw_label(&mut bytes, (w, h), "1", 1);
        let at = |x: u32, y: u32| bytes[(3 * (y * w + x)) as usize];
        // The glyph's rows sit at y 1 to 5, its columns at x 1 to 3.
        let rows = [2u8, 6, 2, 2, 7];
        for (j, row) in rows.iter().enumerate() {
            for i in 0..3 {
                let on = row >> (2 - i) & 1 == 1;
                assert_eq!(
                    at(1 + i, 1 + j as u32),
                    if on { 255 } else { 0 },
                    "({i}, {j})"
                );
            }
        }
        assert_eq!(at(0, 0), 0);
        assert_eq!(at(4, 6), 0);
        assert_eq!(at(5, 0), 100, "beyond the box");
        assert_eq!(at(0, 7), 100, "beyond the box");
        // Larger than the image: drawn where it falls inside, no panic.
        draw_label(&mut bytes, (w, h), "12:30 - 2026", 4);
    }
}
