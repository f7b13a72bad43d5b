//! Fixed-seed inputs for flatray's criterion benchmarks: the room's walls,
//! procedural mazes of any size, and rays.
//!
//! What it is for: giving every benchmark the same work on every run. What
//! it never does: time anything itself (criterion does).

use flatray_geometry::{DVec2, Ray, Segment};

/// A tiny deterministic generator (SplitMix64), so inputs never depend on
/// a crate's version.
pub struct Inputs(u64);

impl Inputs {
    pub fn new(seed: u64) -> Inputs {
        Inputs(seed)
    }

    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// `count` rays from uniform points in `[0, size)^2` in uniform
    /// directions.
    pub fn rays(&mut self, count: usize, size: f64) -> Vec<Ray> {
        (0..count)
            .map(|_| {
                let o = DVec2::new(self.uniform() * size, self.uniform() * size);
                let a = self.uniform() * std::f64::consts::TAU;
                Ray::new(o, DVec2::new(a.cos(), a.sin()))
            })
            .collect()
    }
}

/// The original room's 13 walls.
pub fn room_walls() -> Vec<Segment> {
    let w = [
        (155, 101, 155, 215),
        (155, 102, 210, 102),
        (210, 103, 210, 0),
        (290, 103, 290, 0),
        (65, 288, 162, 288),
        (153, 287, 153, 400),
        (343, 101, 343, 295),
        (290, 102, 345, 102),
        (235, 380, 235, 499),
        (370, 128, 370, 263),
        (256, 373, 266, 363),
        (283, 346, 293, 336),
        (309, 320, 319, 310),
    ];
    w.iter()
        .map(|&(ax, ay, bx, by)| {
            Segment::new(
                DVec2::new(ax as f64, ay as f64),
                DVec2::new(bx as f64, by as f64),
            )
        })
        .collect()
}

/// A maze of about `walls` walls on a `size` x `size` canvas: a grid of
/// cells whose every edge is a wall with probability one half, fixed by
/// `seed`. Walls share endpoints at grid corners.
pub fn maze(walls: usize, size: f64, seed: u64) -> Vec<Segment> {
    let mut inputs = Inputs::new(seed);
    // A grid of n x n cells has about 2 n^2 edges; keep half of them.
    let n = ((walls as f64).sqrt().ceil() as usize).max(1);
    let cell = size / n as f64;
    let mut out = Vec::with_capacity(walls + 4 * n);
    for j in 0..=n {
        for i in 0..=n {
            let p = DVec2::new(i as f64 * cell, j as f64 * cell);
            let border_x = j == 0 || j == n;
            let border_y = i == 0 || i == n;
            if i < n && (border_x || inputs.uniform() < 0.5) {
                out.push(Segment::new(p, p + DVec2::new(cell, 0.0)));
            }
            if j < n && (border_y || inputs.uniform() < 0.5) {
                out.push(Segment::new(p, p + DVec2::new(0.0, cell)));
            }
        }
    }
    out
}
