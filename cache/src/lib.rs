//! The direct-light memo of flatray (the original project's "dynamic
//! programming"): direct irradiance on walls, binned along each wall, per
//! side and per light, so that a path landing on a wall reads it instead
//! of casting shadow rays.
//!
//! What it is for: a compact table keyed by (wall, side, bin along the
//! wall, light), filled once before a render from a function of the key
//! alone, and read by linear interpolation between bin centres. Because
//! every stored value is a pure function of its key, the table is the same
//! whatever the number of threads that filled it.
//!
//! What it never does: decide physics. It does not know what irradiance
//! is; the tracer hands it a fill function and reads numbers back. It reads
//! no files and keeps no state that depends on scheduling.

use rayon::prelude::*;

/// An RGB triple as stored: three `f32`, enough for a cached irradiance.
pub type Value = [f32; 3];

/// The memo of direct irradiance on walls.
#[derive(Clone, Debug, Default)]
pub struct WallMemo {
    lights: usize,
    /// For each wall, its number of bins.
    bins: Vec<u32>,
    /// For each wall, the index of its first entry in `total`.
    offsets: Vec<usize>,
    /// Per (wall, side, bin, light), laid out wall by wall, then side,
    /// bin, light.
    per_light: Vec<Value>,
    /// Per (wall, side, bin): the sum over lights, what a lookup reads.
    total: Vec<Value>,
}

/// Where a lookup lands: a wall, a side (0 or 1) and a position `u` in
/// `[0, 1]` along the wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    pub wall: u32,
    pub side: usize,
    pub u: f64,
}

impl WallMemo {
    /// Builds the memo for walls of the given lengths, each cut into
    /// `ceil(length / bin_length)` bins (at least one), for `lights`
    /// lights. `fill(wall, side, u, light)` gives the value at the centre
    /// `u` of a bin; it is called once per entry, from several threads.
    pub fn build(
        lengths: &[f64],
        bin_length: f64,
        lights: usize,
        fill: impl Fn(u32, usize, f64, usize) -> Value + Sync,
    ) -> WallMemo {
        let bins: Vec<u32> = lengths
            .iter()
            .map(|&len| {
                let n = (len / bin_length).ceil();
                if n.is_finite() && n >= 1.0 {
                    n.min(u32::MAX as f64) as u32
                } else {
                    1
                }
            })
            .collect();
        let mut offsets = Vec::with_capacity(bins.len());
        let mut next = 0usize;
        for &n in &bins {
            offsets.push(next);
            next += 2 * n as usize;
        }
        let per_light: Vec<Value> = (0..bins.len())
            .into_par_iter()
            .flat_map_iter(|wall| {
                let n = bins[wall];
                let fill = &fill;
                (0..2usize).flat_map(move |side| {
                    (0..n).flat_map(move |bin| {
                        let u = (bin as f64 + 0.5) / n as f64;
                        (0..lights).map(move |light| fill(wall as u32, side, u, light))
                    })
                })
            })
            .collect();
        let total = per_light
            .chunks(lights.max(1))
            .map(|chunk| {
                chunk.iter().fold([0.0f32; 3], |acc, v| {
                    [acc[0] + v[0], acc[1] + v[1], acc[2] + v[2]]
                })
            })
            .collect();
        WallMemo {
            lights,
            bins,
            offsets,
            per_light: if lights == 0 { Vec::new() } else { per_light },
            total,
        }
    }

    /// The number of walls.
    pub fn walls(&self) -> usize {
        self.bins.len()
    }

    /// The number of bins of `wall`.
    pub fn bins(&self, wall: u32) -> u32 {
        self.bins[wall as usize]
    }

    /// Entries stored per light: (wall, side, bin, light) keys.
    pub fn entries(&self) -> usize {
        self.per_light.len()
    }

    /// Bytes held by the tables.
    pub fn memory_bytes(&self) -> usize {
        (self.per_light.len() + self.total.len()) * std::mem::size_of::<Value>()
            + self.bins.len() * (std::mem::size_of::<u32>() + std::mem::size_of::<usize>())
    }

    /// The value stored for one light at bin `bin`.
    pub fn entry(&self, wall: u32, side: usize, bin: u32, light: usize) -> Value {
        let base =
            self.offsets[wall as usize] + side * self.bins[wall as usize] as usize + bin as usize;
        self.per_light[base * self.lights + light]
    }

    /// The summed value over all lights at `key`, linearly interpolated
    /// between the centres of the two nearest bins (constant beyond the
    /// first and last centre).
    #[inline]
    pub fn lookup(&self, key: Key) -> Value {
        let n = self.bins[key.wall as usize] as usize;
        let base = self.offsets[key.wall as usize] + key.side * n;
        let x = (key.u * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let i = (x as usize).min(n - 1);
        let j = (i + 1).min(n - 1);
        let f = (x - i as f64) as f32;
        let (a, b) = (self.total[base + i], self.total[base + j]);
        [
            a[0] + (b[0] - a[0]) * f,
            a[1] + (b[1] - a[1]) * f,
            a[2] + (b[2] - a[2]) * f,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_are_about_one_length_unit_and_keyed_exactly() {
        let memo = WallMemo::build(&[10.0, 2.5, 0.1], 1.0, 2, |w, s, u, l| {
            [w as f32, s as f32 + u as f32, l as f32]
        });
        assert_eq!((memo.bins(0), memo.bins(1), memo.bins(2)), (10, 3, 1));
        assert_eq!(memo.entries(), (10 + 3 + 1) * 2 * 2);
        assert_eq!(memo.entry(1, 1, 2, 1), [1.0, 1.0 + (2.5 / 3.0) as f32, 1.0]);
        assert_eq!(memo.entry(0, 0, 0, 0), [0.0, 0.05, 0.0]);
    }

    #[test]
    fn lookups_interpolate_between_bin_centres_and_sum_lights() {
        // Value = u at the bin centre, for each of 3 lights.
        let memo = WallMemo::build(&[4.0], 1.0, 3, |_, _, u, _| [u as f32, 1.0, 0.0]);
        for u in [0.125, 0.3, 0.5, 0.61, 0.875] {
            let v = memo.lookup(Key {
                wall: 0,
                side: 0,
                u,
            });
            assert!((v[0] - 3.0 * u as f32).abs() < 1e-6, "u {u}: {v:?}");
            assert_eq!(v[1], 3.0);
        }
        // Beyond the outer centres the value is held constant.
        assert!(
            (memo.lookup(Key {
                wall: 0,
                side: 1,
                u: 0.0
            })[0]
                - 0.375)
                .abs()
                < 1e-6
        );
        assert!(
            (memo.lookup(Key {
                wall: 0,
                side: 1,
                u: 1.0
            })[0]
                - 2.625)
                .abs()
                < 1e-6
        );
    }

    #[test]
    fn the_table_does_not_depend_on_the_thread_count() {
        let lengths: Vec<f64> = (0..200).map(|k| 1.0 + k as f64 * 0.37).collect();
        let fill = |w: u32, s: usize, u: f64, l: usize| [(w as f64 * u) as f32, s as f32, l as f32];
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let four = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let a = one.install(|| WallMemo::build(&lengths, 0.5, 2, fill));
        let b = four.install(|| WallMemo::build(&lengths, 0.5, 2, fill));
        assert_eq!(a.per_light, b.per_light);
        assert_eq!(a.total, b.total);
    }

    #[test]
    fn memory_is_proportional_to_wall_length_times_lights() {
        let fill = |_: u32, _: usize, _: f64, _: usize| [0.0; 3];
        let small = WallMemo::build(&[100.0; 10], 1.0, 2, fill);
        let long = WallMemo::build(&[100.0; 20], 1.0, 2, fill);
        let lit = WallMemo::build(&[100.0; 10], 1.0, 4, fill);
        assert_eq!(small.entries() * 2, long.entries());
        assert_eq!(small.entries() * 2, lit.entries());
        let per_entry = small.memory_bytes() as f64 / small.entries() as f64;
        assert!(per_entry < 2.0 * std::mem::size_of::<Value>() as f64 + 1.0);
    }
}
