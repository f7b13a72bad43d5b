//! Rooms: the regions of the floor that the walls enclose, found on the
//! grid of an image's pixels.
//!
//! Two neighbouring pixels (left and right, or up and down) are in one
//! room when the straight step between their centres crosses no wall of
//! any material (a pane or a glass edge bounds a room as a diffuse wall
//! does), and the scene's doors, open or shut, bound rooms too. A door's
//! gap drawn without a door is an opening in a wall: the ends of two walls
//! that lie on one line (within 10 degrees), facing each other across a
//! gap narrower than the door width. It is closed by the line between the
//! two ends, so that the rooms on its two sides stay apart. A wider
//! opening, or a gap between walls that do not continue each other (a
//! wall's end and a piece of furniture, or a corner), joins them.

use std::collections::VecDeque;

use flatray_geometry::{DVec2, Ray, Segment, SegmentSet, Skip};
use flatray_tracer::Scene;

/// Most rooms a scene file may name.
pub const MAX_ROOMS: usize = 4096;
/// Most characters in a room's name.
pub const MAX_ROOM_NAME: usize = 64;

/// A room named in the scene file by a point inside it.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedRoom {
    pub name: String,
    pub at: DVec2,
}

/// A room found on the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Room {
    pub name: String,
    /// Its pixels' count.
    pub pixels: usize,
    /// Its area in square world units.
    pub area: f64,
    /// The corners of its pixels' bounding box in world units.
    pub lo: DVec2,
    pub hi: DVec2,
    /// Whether it meets the canvas's edge (it is open to the outside).
    pub open: bool,
}

/// The rooms of an image of `size` pixels: for each pixel, row by row,
/// the index of its room or `None`.
#[derive(Clone, Debug, PartialEq)]
pub struct Rooms {
    pub size: (u32, u32),
    pub rooms: Vec<Room>,
    pub of_pixel: Vec<Option<u32>>,
}

/// Why rooms cannot be found as named.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RoomError {
    /// Two named rooms lie in one region.
    Same { first: String, second: String },
}

impl std::fmt::Display for RoomError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RoomError::Same { first, second } => write!(
                f,
                "rooms {first:?} and {second:?} are one region: no wall parts them, or their opening is wider than the door width"
            ),
        }
    }
}

/// Regions of fewer pixels than this share of the image are slivers
/// (between overlaid walls, inside columns) and not rooms when the rooms
/// are found without names.
const LEAST_ROOM_SHARE: f64 = 0.002;

/// The rooms of `scene` on an image of `size` pixels: the regions about
/// each of `named`, or, when `named` is empty, every region of at least
/// a 0.2 % share of the image, named "room 1", "room 2", ... in reading
/// order of their first pixel (those open to the canvas's edge "outside",
/// "outside 2", ...). `doors` are the scene's doors, open or closed:
/// bounds between rooms. `door_width` is in world units (0: no other
/// gap closes).
pub fn find(
    scene: &Scene,
    size: (u32, u32),
    named: &[NamedRoom],
    doors: &[Segment],
    door_width: f64,
) -> Result<Rooms, RoomError> {
    let (w, h) = (size.0 as usize, size.1 as usize);
    let step = scene.canvas().pixel_step(size);
    let origin = scene.canvas().origin;
    let centre = |x: usize, y: usize| origin + (DVec2::new(x as f64, y as f64) + 0.5) * step;
    let doors = door_lines(scene, doors, door_width);
    let crosses = |a: DVec2, b: DVec2| {
        let d = b - a;
        let len = d.length();
        let ray = Ray::new(a, d / len);
        scene
            .segments()
            .closest_hit(&ray, len, Skip::NONE)
            .is_some()
            || doors.closest_hit(&ray, len, Skip::NONE).is_some()
    };
    // Whether the step right of, and below, each pixel is open.
    let mut right = vec![false; w * h];
    let mut down = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let c = centre(x, y);
            if x + 1 < w {
                right[y * w + x] = !crosses(c, centre(x + 1, y));
            }
            if y + 1 < h {
                down[y * w + x] = !crosses(c, centre(x, y + 1));
            }
        }
    }
    let mut region = vec![u32::MAX; w * h];
    let mut count = 0u32;
    let mut queue = VecDeque::new();
    for start in 0..w * h {
        if region[start] != u32::MAX {
            continue;
        }
        region[start] = count;
        queue.push_back(start);
        while let Some(k) = queue.pop_front() {
            let (x, y) = (k % w, k / w);
            let steps = [
                (x + 1 < w && right[k]).then(|| k + 1),
                (x > 0 && right[k.wrapping_sub(1)]).then(|| k.wrapping_sub(1)),
                (y + 1 < h && down[k]).then(|| k + w),
                (y > 0 && down[k.wrapping_sub(w)]).then(|| k.wrapping_sub(w)),
            ];
            for n in steps.into_iter().flatten() {
                if region[n] == u32::MAX {
                    region[n] = count;
                    queue.push_back(n);
                }
            }
        }
        count += 1;
    }
    // What each region holds.
    let mut pixels = vec![0usize; count as usize];
    let mut open = vec![false; count as usize];
    let mut lo = vec![(usize::MAX, usize::MAX); count as usize];
    let mut hi = vec![(0usize, 0usize); count as usize];
    for (k, &r) in region.iter().enumerate() {
        let r = r as usize;
        let (x, y) = (k % w, k / w);
        pixels[r] += 1;
        open[r] |= x == 0 || y == 0 || x + 1 == w || y + 1 == h;
        lo[r] = (lo[r].0.min(x), lo[r].1.min(y));
        hi[r] = (hi[r].0.max(x + 1), hi[r].1.max(y + 1));
    }
    let room_of = |r: usize, name: String| Room {
        name,
        pixels: pixels[r],
        area: pixels[r] as f64 * step.x * step.y,
        lo: origin + DVec2::new(lo[r].0 as f64, lo[r].1 as f64) * step,
        hi: origin + DVec2::new(hi[r].0 as f64, hi[r].1 as f64) * step,
        open: open[r],
    };
    // Which region becomes which room.
    let mut room_index = vec![None; count as usize];
    let mut rooms = Vec::new();
    if named.is_empty() {
        let least = (LEAST_ROOM_SHARE * (w * h) as f64).max(1.0);
        let (mut inside, mut outside) = (0, 0);
        // Regions are numbered in reading order of their first pixel.
        for r in 0..count as usize {
            if (pixels[r] as f64) < least {
                continue;
            }
            let name = if open[r] {
                outside += 1;
                if outside == 1 {
                    "outside".to_string()
                } else {
                    format!("outside {outside}")
                }
            } else {
                inside += 1;
                format!("room {inside}")
            };
            room_index[r] = Some(rooms.len() as u32);
            rooms.push(room_of(r, name));
        }
    } else {
        for room in named {
            let p = (room.at - origin) / step;
            let (x, y) = (
                (p.x.max(0.0) as usize).min(w - 1),
                (p.y.max(0.0) as usize).min(h - 1),
            );
            let r = region[y * w + x];
            if let Some(j) = room_index[r as usize] {
                let first: &Room = &rooms[j as usize];
                return Err(RoomError::Same {
                    first: first.name.clone(),
                    second: room.name.clone(),
                });
            }
            room_index[r as usize] = Some(rooms.len() as u32);
            rooms.push(room_of(r as usize, room.name.clone()));
        }
    }
    let of_pixel = region
        .iter()
        .map(|&r| room_index.get(r as usize).copied().flatten())
        .collect();
    Ok(Rooms {
        size,
        rooms,
        of_pixel,
    })
}

/// The sine of the most a door's gap may turn off its walls' line.
const DOOR_LINE_SINE: f64 = 0.17;

/// Most ends of one cell that each end is paired with.
const ENDS_PER_CELL: usize = 64;

/// Most door lines per wall: a budget on the pairs of close ends.
const DOORS_PER_WALL: usize = 4;

/// The lines that bound rooms across doors: the scene's `doors`, and
/// those that close door gaps, between the ends of two different
/// walls closer than `door_width` (and apart), both walls along the gap, found on a grid of cells
/// of that size; at most [`DOORS_PER_WALL`] per wall.
fn door_lines(scene: &Scene, doors: &[Segment], door_width: f64) -> SegmentSet {
    let walls = scene.walls();
    let mut lines = doors.to_vec();
    if !(door_width > 0.0 && door_width.is_finite()) || walls.is_empty() {
        return SegmentSet::new(lines);
    }
    let ends: Vec<(usize, DVec2)> = walls
        .iter()
        .enumerate()
        .flat_map(|(i, w)| [(i, w.shape.a()), (i, w.shape.b())])
        .filter(|(_, p)| p.is_finite())
        .collect();
    let cell = |p: DVec2| {
        (
            (p.x / door_width).floor() as i64,
            (p.y / door_width).floor() as i64,
        )
    };
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for (k, &(_, p)) in ends.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(k);
    }
    let apart = 1e-9 * door_width;
    let budget = doors.len() + DOORS_PER_WALL * walls.len();
    for (k, &(i, p)) in ends.iter().enumerate() {
        let (cx, cy) = cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                // At most a few ends of each cell: walls that all meet at
                // one point must not cost their number squared.
                let near = grid.get(&(cx + dx, cy + dy)).into_iter().flatten();
                for &j in near.take(ENDS_PER_CELL) {
                    let (other, q) = ends[j];
                    let d = p.distance(q);
                    let along = |wall: usize| {
                        let chord = walls[wall].shape.chord();
                        let dir = (chord.b - chord.a).normalize_or_zero();
                        dir.perp_dot((q - p) / d).abs() < DOOR_LINE_SINE
                    };
                    if j > k
                        && other != i
                        && d > apart
                        && d < door_width
                        && along(i)
                        && along(other)
                        && lines.len() < budget
                    {
                        lines.push(Segment::new(p, q));
                    }
                }
            }
        }
    }
    SegmentSet::new(lines)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatray_tracer::{Canvas, Floor, Material, Rgb, Wall};

    /// A 40 x 20 canvas split by a wall at x = 20 with an opening of
    /// `gap` units from y = 8 upwards.
    fn two_rooms(gap: f64, turn: f64) -> Scene {
        let c = DVec2::new(20.0, 10.0);
        let (s, co) = turn.sin_cos();
        let at = |x: f64, y: f64| {
            let d = DVec2::new(x, y) - c;
            c + DVec2::new(co * d.x - s * d.y, s * d.x + co * d.y)
        };
        let wall = |a: DVec2, b: DVec2| Wall {
            shape: Segment::new(a, b).into(),
            material: Material::Diffuse { albedo: None },
        };
        Scene::new(
            Canvas {
                width: 40,
                height: 20,
                origin: DVec2::ZERO,
            },
            Floor::Color(Rgb::ONE),
            0.5,
            vec![
                wall(at(20.0, -5.0), at(20.0, 8.0)),
                wall(at(20.0, 8.0 + gap), at(20.0, 25.0)),
            ],
            Vec::new(),
        )
        .expect("a valid scene")
    }

    fn named() -> Vec<NamedRoom> {
        vec![
            NamedRoom {
                name: "west".into(),
                at: DVec2::new(5.0, 10.0),
            },
            NamedRoom {
                name: "east".into(),
                at: DVec2::new(35.0, 10.0),
            },
        ]
    }

    #[test]
    fn a_wall_parts_two_rooms_and_a_door_gap_keeps_them_apart() {
        for turn in [0.0, 0.3] {
            let shut = find(&two_rooms(0.0, turn), (40, 20), &named(), &[], 0.0).expect("rooms");
            assert_eq!(shut.rooms.len(), 2);
            let total: usize = shut.rooms.iter().map(|r| r.pixels).sum();
            assert_eq!(total, 800, "every pixel in one room");
            // About half each, give or take the tilted wall's pixels.
            assert!((shut.rooms[0].pixels as f64 - 400.0).abs() < 80.0);
            // A 3-unit opening is one region without a door width...
            let open = find(&two_rooms(3.0, turn), (40, 20), &named(), &[], 0.0);
            assert!(matches!(open, Err(RoomError::Same { .. })), "{open:?}");
            // ...and two rooms with a door width of 4.
            let door = find(&two_rooms(3.0, turn), (40, 20), &named(), &[], 4.0).expect("rooms");
            assert_eq!(door.rooms.len(), 2);
            assert!((door.rooms[0].pixels as f64 - 400.0).abs() < 80.0);
            // A 10-unit opening is wider than that door: one region.
            let wide = find(&two_rooms(10.0, turn), (40, 20), &named(), &[], 4.0);
            assert!(matches!(wide, Err(RoomError::Same { .. })), "{wide:?}");
        }
    }

    #[test]
    fn unnamed_regions_are_found_and_named_in_reading_order() {
        let rooms = find(&two_rooms(0.0, 0.0), (40, 20), &[], &[], 0.0).expect("rooms");
        let names: Vec<&str> = rooms.rooms.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["outside", "outside 2"]);
        assert_eq!(rooms.rooms[0].lo, DVec2::ZERO);
        assert_eq!(rooms.rooms[0].hi, DVec2::new(20.0, 20.0));
        assert!((rooms.rooms[0].area - 400.0).abs() < 1e-9);
    }
}
