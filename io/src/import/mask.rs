//! Wall masks: an image whose dark pixels are walls. The outline of every
//! dark region is traced along pixel edges into closed loops, simplified
//! (Douglas-Peucker) and written as walls that share their endpoints
//! exactly, so no light leaks through a traced wall. Pure yellow blobs
//! (red and green above 200, blue below 80) are lamps at their centres.

use std::path::Path;

use flatray_geometry::DVec2;

use crate::load::ImageFailure;

use super::{
    ImportError, ImportOptions, Imported, ImportedFloor, ImportedLight, ImportedWall,
    LAMP_INTENSITY, WallKind, invalid, simplify_loop,
};

/// At most this many pixels in a mask.
const MAX_MASK_PIXELS: u64 = 1 << 26;

/// Reads a wall mask.
pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    let decoded = crate::load::decode_within(bytes, MAX_MASK_PIXELS)
        .map_err(|failure| {
            let message = match failure {
                ImageFailure::TooLarge(width, height) => format!(
                    "the mask is {width} x {height} pixels, more than the {MAX_MASK_PIXELS} flatray reads"
                ),
                ImageFailure::Unreadable(e) => format!("not a readable image: {e}"),
            };
            invalid(path, None, message)
        })?
        .to_rgba8();
    let (width, height) = decoded.dimensions();
    let (w, h) = (width as usize, height as usize);
    let pixel = |x: usize, y: usize| decoded.get_pixel(x as u32, y as u32).0;
    let lamp = |[r, g, b, a]: [u8; 4]| a > 127 && r > 200 && g > 200 && b < 80;
    let dark = |[r, g, b, a]: [u8; 4]| {
        let luma = 0.2126 * r as f64 + 0.7152 * g as f64 + 0.0722 * b as f64;
        a > 127 && luma < 128.0
    };
    let wall: Vec<bool> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| dark(pixel(x, y)))
        .collect();
    let is_wall = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && (x as usize) < w
            && (y as usize) < h
            && wall[y as usize * w + x as usize]
    };
    let loops = trace(w as i64, h as i64, &is_wall);
    let scale = options.scale_or(1.0);
    // Simplified in mask pixels.
    let tolerance = options.tolerance;
    let mut walls = Vec::new();
    for (k, outline) in loops.iter().enumerate() {
        // A loop too small to simplify (a pixel, a one-pixel line) keeps
        // its traced corners: a wall never vanishes.
        let simple = match simplify_loop(outline, tolerance) {
            simple if simple.len() >= 3 => simple,
            _ => outline.clone(),
        };
        if simple.len() < 3 {
            continue;
        }
        for i in 0..simple.len() {
            let (a, b) = (simple[i] * scale, simple[(i + 1) % simple.len()] * scale);
            walls.push(ImportedWall {
                a,
                b,
                through: None,
                kind: WallKind::Diffuse(None),
                emit: None,
                source: format!("outline {k}"),
            });
        }
    }
    let lights = blobs(w, h, &|x, y| lamp(pixel(x, y)))
        .into_iter()
        .enumerate()
        .map(|(k, centre)| ImportedLight::Point {
            at: centre * scale,
            color: [1.0, 1.0, 1.0],
            intensity: LAMP_INTENSITY,
            range: None,
            source: format!("yellow blob {k}"),
        })
        .collect();
    Ok(Imported {
        source: String::new(),
        kind: "wall mask",
        origin: DVec2::ZERO,
        plan_unit: scale,
        canvas: (
            ((width as f64 * scale).ceil() as u32).max(1),
            ((height as f64 * scale).ceil() as u32).max(1),
        ),
        floor: ImportedFloor::Color([0.8, 0.8, 0.8]),
        walls,
        lights,
        glass: Vec::new(),
        warnings: Vec::new(),
        notes: Vec::new(),
        mapping: Vec::new(),
        floor_file: None,
    })
}

/// The outlines of the regions where `is_wall` holds, as closed loops of
/// pixel corners with collinear runs merged. Each boundary edge keeps the
/// wall on its right; where two wall pixels touch only at a corner, the
/// loop turns so as to keep them apart (each its own loop, sharing that
/// corner point exactly). Memory: two bytes per pixel corner.
fn trace(w: i64, h: i64, is_wall: &dyn Fn(i64, i64) -> bool) -> Vec<Vec<DVec2>> {
    // Unit steps by code; a corner has at most two edges leaving it.
    const STEPS: [(i64, i64); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];
    const NONE: u8 = u8::MAX;
    let columns = w + 1;
    let index = |(x, y): (i64, i64)| (y * columns + x) as usize;
    let mut leaving = vec![[NONE; 2]; ((w + 1) * (h + 1)) as usize];
    let mut add = |corner: (i64, i64), code: u8| {
        let slots = &mut leaving[index(corner)];
        if slots[0] == NONE {
            slots[0] = code;
        } else {
            slots[1] = code;
        }
    };
    for y in 0..h {
        for x in 0..w {
            if !is_wall(x, y) {
                continue;
            }
            // Clockwise around the pixel (y down): wall on the right.
            if !is_wall(x, y - 1) {
                add((x, y), 0);
            }
            if !is_wall(x + 1, y) {
                add((x + 1, y), 1);
            }
            if !is_wall(x, y + 1) {
                add((x + 1, y + 1), 2);
            }
            if !is_wall(x - 1, y) {
                add((x, y + 1), 3);
            }
        }
    }
    // Takes an edge leaving `corner`: the one `prefer` names if there, else
    // any.
    let take = |leaving: &mut Vec<[u8; 2]>, corner: (i64, i64), prefer: Option<u8>| -> Option<u8> {
        let slots = &mut leaving[index(corner)];
        let k = match prefer {
            Some(code) if slots[1] == code => 1,
            _ if slots[0] != NONE => 0,
            _ if slots[1] != NONE => 1,
            _ => return None,
        };
        let code = slots[k];
        slots[k] = NONE;
        Some(code)
    };
    let mut loops = Vec::new();
    for y in 0..=h {
        for x in 0..=w {
            let start = (x, y);
            while let Some(first) = take(&mut leaving, start, None) {
                let mut corners = vec![start];
                let step = STEPS[first as usize];
                let mut at = (start.0 + step.0, start.1 + step.1);
                let mut heading = first;
                while at != start {
                    // Turn right where two regions touch, else the one way.
                    let right = (heading + 1) % 4;
                    let Some(code) = take(&mut leaving, at, Some(right)) else {
                        break;
                    };
                    if code != heading {
                        corners.push(at);
                    }
                    heading = code;
                    let step = STEPS[code as usize];
                    at = (at.0 + step.0, at.1 + step.1);
                }
                if heading == first && corners.len() > 1 {
                    // The start lies mid-run: not a corner.
                    corners.remove(0);
                }
                if corners.len() >= 3 {
                    loops.push(
                        corners
                            .into_iter()
                            .map(|(x, y)| DVec2::new(x as f64, y as f64))
                            .collect(),
                    );
                }
            }
        }
    }
    loops
}

/// The centres of the 4-connected regions where `inside` holds.
fn blobs(w: usize, h: usize, inside: &dyn Fn(usize, usize) -> bool) -> Vec<DVec2> {
    let mut seen = vec![false; w * h];
    let mut centres = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if seen[y * w + x] || !inside(x, y) {
                continue;
            }
            let mut stack = vec![(x, y)];
            seen[y * w + x] = true;
            let (mut sum, mut count) = (DVec2::ZERO, 0.0);
            while let Some((px, py)) = stack.pop() {
                sum += DVec2::new(px as f64 + 0.5, py as f64 + 0.5);
                count += 1.0;
                let neighbours = [
                    (px.wrapping_sub(1), py),
                    (px + 1, py),
                    (px, py.wrapping_sub(1)),
                    (px, py + 1),
                ];
                for (nx, ny) in neighbours {
                    if nx < w && ny < h && !seen[ny * w + nx] && inside(nx, ny) {
                        seen[ny * w + nx] = true;
                        stack.push((nx, ny));
                    }
                }
            }
            centres.push(sum / count);
        }
    }
    centres
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_ring_traces_to_two_loops_of_four_corners() {
        // A 6 x 6 ring of wall one pixel thick.
        let is_wall = |x: i64, y: i64| {
            (0..6).contains(&x) && (0..6).contains(&y) && (x == 0 || y == 0 || x == 5 || y == 5)
        };
        let mut loops = trace(6, 6, &is_wall);
        loops.sort_by_key(|l| l.len());
        assert_eq!(loops.len(), 2);
        for l in &loops {
            assert_eq!(l.len(), 4, "{l:?}");
        }
        let xs: Vec<f64> = loops.iter().flat_map(|l| l.iter().map(|p| p.x)).collect();
        assert!(xs.contains(&0.0) && xs.contains(&6.0) && xs.contains(&1.0) && xs.contains(&5.0));
    }

    #[test]
    fn pixels_touching_at_a_corner_make_two_loops_sharing_it() {
        let is_wall = |x: i64, y: i64| (x, y) == (0, 0) || (x, y) == (1, 1);
        let loops = trace(2, 2, &is_wall);
        assert_eq!(loops.len(), 2, "{loops:?}");
        let shared = DVec2::new(1.0, 1.0);
        assert!(loops.iter().all(|l| l.contains(&shared)));
    }
}
