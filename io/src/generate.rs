//! Floor plans made up to order: apartments of rooms with doors, windows,
//! furniture, coloured walls, mirrors and lamps, written as scene text.
//! For benchmarks and tests beyond the example rooms, and for trying
//! flatray on a plan of any size.
//!
//! Every plan is a pure function of its [`Apartment`] settings (a fixed
//! generator, no crate's random numbers), so a seed names one plan for
//! good.

use std::fmt::Write as _;

/// What to make.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Apartment {
    /// Rooms, laid out on a grid about as wide as it is tall (at least 1,
    /// at most 10,000).
    pub rooms: u32,
    /// Lamps per room (at most 64): points, and the fourth, eighth and so
    /// on of each room's lamps a spot (1 to 3 a room make points only).
    pub lamps_per_room: u32,
    /// The share of rooms with a mirror on a wall (0 to 1).
    pub mirrors: f64,
    /// Whether sunlight comes in through the windows.
    pub sun: bool,
    pub seed: u64,
}

impl Default for Apartment {
    fn default() -> Apartment {
        Apartment {
            rooms: 16,
            lamps_per_room: 1,
            mirrors: 0.3,
            sun: true,
            seed: 1,
        }
    }
}

/// SplitMix64: the same numbers on every machine and version.
struct Numbers(u64);

impl Numbers {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn between(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// The `n + 1` lines of a grid of `n` rooms, the inner ones moved by
    /// up to `jitter` either way.
    fn grid_lines(&mut self, n: usize, jitter: f64) -> Vec<f64> {
        (0..=n)
            .map(|i| {
                let moved = if i == 0 || i == n {
                    0.0
                } else {
                    self.between(-jitter, jitter)
                };
                MARGIN + i as f64 * ROOM + moved
            })
            .collect()
    }
}

/// Room size in world units (a pixel each at scale 1).
const ROOM: f64 = 120.0;
const MARGIN: f64 = 20.0;
const DOOR: f64 = 24.0;
const WINDOW: f64 = 30.0;

/// The wall colours a room may take (its own walls and furniture).
const COLOURS: [(f64, f64, f64); 6] = [
    (0.8, 0.78, 0.72),
    (0.75, 0.45, 0.35),
    (0.45, 0.6, 0.75),
    (0.55, 0.7, 0.5),
    (0.85, 0.8, 0.55),
    (0.6, 0.55, 0.65),
];

impl Apartment {
    /// The plan as scene text, with a comment saying how it was made.
    pub fn to_ron(&self) -> String {
        let rooms = self.rooms.clamp(1, 10_000) as usize;
        let lamps = self.lamps_per_room.min(64);
        let cols = (rooms as f64).sqrt().ceil() as usize;
        let rows = rooms.div_ceil(cols);
        let mut rng = Numbers(self.seed ^ 0x5eed_f1a7_a9a7_7e47);
        // Jittered grid lines, shared by neighbouring rooms so corners
        // meet exactly.
        let xs = rng.grid_lines(cols, 15.0);
        let ys = rng.grid_lines(rows, 12.0);
        let width = (2.0 * MARGIN + cols as f64 * ROOM).ceil() as u32;
        let height = (2.0 * MARGIN + rows as f64 * ROOM).ceil() as u32;
        let exists = |c: usize, r: usize| r * cols + c < rooms;
        let colour: Vec<usize> = (0..rows * cols)
            .map(|_| (rng.uniform() * COLOURS.len() as f64) as usize % COLOURS.len())
            .collect();

        let mut walls = Walls::default();
        let mut lights = String::new();
        let (mut lights_made, mut mirrors_made) = (0usize, 0usize);
        walls.comment("Walls between rooms, each with a door.");
        for r in 0..rows {
            for c in 0..cols {
                if !exists(c, r) {
                    continue;
                }
                let (x0, x1, y0, y1) = (xs[c], xs[c + 1], ys[r], ys[r + 1]);
                // Right side: to the next room, or outside (a window).
                let right_inside = c + 1 < cols && exists(c + 1, r);
                let at = rng.between(0.3, 0.7);
                walls.split((x1, y0), (x1, y1), at, !right_inside);
                // Bottom side likewise.
                let below_inside = r + 1 < rows && exists(c, r + 1);
                let at = rng.between(0.3, 0.7);
                walls.split((x0, y1), (x1, y1), at, !below_inside);
                // Left and top only on the outside (inside, the
                // neighbour drew them).
                if c == 0 || !exists(c - 1, r) {
                    let at = rng.between(0.3, 0.7);
                    walls.split((x0, y0), (x0, y1), at, true);
                }
                if r == 0 || !exists(c, r - 1) {
                    let at = rng.between(0.3, 0.7);
                    walls.split((x0, y0), (x1, y0), at, true);
                }
            }
        }
        walls.comment("Furniture and mirrors.");
        for r in 0..rows {
            for c in 0..cols {
                if !exists(c, r) {
                    continue;
                }
                let (x0, x1, y0, y1) = (xs[c], xs[c + 1], ys[r], ys[r + 1]);
                let (cr, cg, cb) = COLOURS[colour[r * cols + c]];
                let coloured =
                    format!(", material: Diffuse(albedo: Some(({cr:.2}, {cg:.2}, {cb:.2})))");
                // Two to three stubs: a table, a cupboard, a bed's edge.
                let stubs = 2 + (rng.uniform() * 2.0) as usize;
                for _ in 0..stubs {
                    let (px, py) = (
                        rng.between(x0 + 20.0, x1 - 20.0),
                        rng.between(y0 + 20.0, y1 - 20.0),
                    );
                    let angle = rng.between(0.0, std::f64::consts::PI);
                    let length = rng.between(8.0, 22.0);
                    let (dx, dy) = (angle.cos() * length / 2.0, angle.sin() * length / 2.0);
                    walls.wall((px - dx, py - dy), (px + dx, py + dy), &coloured);
                }
                if rng.uniform() < self.mirrors {
                    // A mirror hung a unit off the room's top wall.
                    let (a, b) = (
                        rng.between(x0 + 10.0, x0 + 40.0),
                        rng.between(x1 - 40.0, x1 - 10.0),
                    );
                    walls.wall(
                        (a, y0 + 1.0),
                        (b, y0 + 1.0),
                        ", material: Mirror(tint: (0.92, 0.93, 0.95))",
                    );
                    mirrors_made += 1;
                }
                for k in 0..lamps {
                    let (px, py) = (
                        rng.between(x0 + 15.0, x1 - 15.0),
                        rng.between(y0 + 15.0, y1 - 15.0),
                    );
                    let warm = rng.between(0.75, 0.95);
                    if k % 4 == 3 {
                        let angle = rng.between(0.0, std::f64::consts::TAU);
                        let _ = writeln!(
                            lights,
                            "        Spot(at: ({px:.2}, {py:.2}), direction: ({:.3}, {:.3}), cone: 50, softness: 15, color: (1.0, {warm:.2}, {:.2}), intensity: 30.0),",
                            angle.cos(),
                            angle.sin(),
                            warm * 0.85
                        );
                    } else {
                        let _ = writeln!(
                            lights,
                            "        Point(at: ({px:.2}, {py:.2}), color: (1.0, {warm:.2}, {:.2}), intensity: 20.0),",
                            warm * 0.85
                        );
                    }
                    lights_made += 1;
                }
            }
        }
        if self.sun {
            let _ = writeln!(
                lights,
                "        Directional(direction: (0.8, 0.6), color: (1.0, 0.97, 0.9), intensity: 0.6),"
            );
            lights_made += 1;
        }
        let mut text = String::new();
        let _ = writeln!(
            text,
            "// An apartment of {rooms} rooms made by `flatray generate --rooms {rooms} --lamps {lamps} --mirrors {} --seed {}{}`:\n// {} walls (doors between rooms, windows as clear panes, furniture), {} mirrors, {} lights.",
            self.mirrors,
            self.seed,
            if self.sun { "" } else { " --no-sun" },
            walls.count,
            mirrors_made,
            lights_made
        );
        let _ = writeln!(
            text,
            "Scene(\n    canvas: ({width}, {height}),\n    floor: Tiles(size: 20.0, grout_width: 1.0, tile: (0.76, 0.7, 0.62), grout: (0.4, 0.38, 0.35), variation: 0.15),\n    walls: [\n{}    ],\n    doors: [\n{}    ],\n    lights: [\n{lights}    ],\n    render: (samples: 16, bounces: 3),\n)",
            walls.text, walls.doors
        );
        text
    }
}

/// Wall lines of scene text, counted, and the doors' lines.
#[derive(Default)]
struct Walls {
    text: String,
    count: usize,
    doors: String,
}

impl Walls {
    fn comment(&mut self, text: &str) {
        let _ = writeln!(self.text, "        // {text}");
    }

    fn wall(&mut self, a: (f64, f64), b: (f64, f64), material: &str) {
        let _ = writeln!(
            self.text,
            "        Wall(a: ({:.2}, {:.2}), b: ({:.2}, {:.2}){material}),",
            a.0, a.1, b.0, b.1
        );
        self.count += 1;
    }

    /// A wall from `a` to `b` with an opening centred at fraction `at` of
    /// it: a window (a clear pane) or an open door (no wall, but a bound
    /// between the rooms).
    fn split(&mut self, a: (f64, f64), b: (f64, f64), at: f64, window: bool) {
        let width = if window { WINDOW } else { DOOR };
        let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let (t0, t1) = (at - width / length / 2.0, at + width / length / 2.0);
        let p = |t: f64| (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        self.wall(a, p(t0), "");
        if window {
            self.wall(
                p(t0),
                p(t1),
                ", material: Transparent(tint: (0.9, 0.95, 1.0))",
            );
        } else {
            let (d0, d1) = (p(t0), p(t1));
            let _ = writeln!(
                self.doors,
                "        Door(a: ({:.2}, {:.2}), b: ({:.2}, {:.2}), open: true),",
                d0.0, d0.1, d1.0, d1.1
            );
        }
        self.wall(p(t1), b, "");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_plan_loads_and_its_size_follows_the_settings() {
        for rooms in [1, 2, 5, 16, 40] {
            for seed in [1, 2, 3] {
                let plan = Apartment {
                    rooms,
                    seed,
                    ..Apartment::default()
                };
                let text = plan.to_ron();
                let loaded = crate::parse(
                    &text,
                    std::path::Path::new("apartment.ron"),
                    std::path::Path::new("."),
                )
                .unwrap_or_else(|e| panic!("{e}\n{text}"));
                let walls = loaded.scene.walls().len();
                // At least the rooms' sides and two stubs each.
                assert!(walls >= 4 * rooms as usize, "{rooms} rooms: {walls} walls");
                assert_eq!(loaded.scene.lights().len(), rooms as usize + 1);
                // The same settings, the same text.
                assert_eq!(text, plan.to_ron());
            }
        }
    }
}
