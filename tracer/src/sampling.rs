//! Random streams and the samplers the integrators draw from.
//!
//! Every sample's numbers come from its own stream, a pure function of
//! (seed, pixel or path index, sample index), never of the thread that runs
//! it: an image is bit-identical for any number of threads, and one pixel
//! and sample can be re-rendered alone.

use std::f64::consts::{PI, TAU};

use flatray_geometry::{DVec2, Ray, Segment, cross, line_crossing};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// The random stream of one sample.
pub struct Stream(Xoshiro256PlusPlus);

impl Stream {
    /// The stream keyed by `(seed, index, sample)`, where `index` is the
    /// pixel (or light path) index.
    pub fn new(seed: u64, index: u64, sample: u64) -> Stream {
        let key = mix(mix(mix(seed) ^ index) ^ sample.rotate_left(29));
        Stream(Xoshiro256PlusPlus::seed_from_u64(key))
    }

    /// A uniform number in `[0, 1)`.
    #[inline]
    pub fn next(&mut self) -> f64 {
        self.0.random::<f64>()
    }
}

/// The SplitMix64 finaliser: a bijective mix of 64 bits.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform direction on the circle (pdf `1 / 2pi` per radian).
#[inline]
pub fn uniform_circle(u: f64) -> DVec2 {
    let (s, c) = (TAU * u).sin_cos();
    DVec2::new(c, s)
}

/// A cosine-weighted direction on the half circle around unit normal `n`:
/// the angle `theta` from `n` has pdf `cos(theta) / 2`. Sampled by drawing
/// `sin(theta)` uniformly in `[-1, 1]`.
#[inline]
pub fn cosine_half_circle(n: DVec2, u: f64) -> DVec2 {
    let s = 2.0 * u - 1.0;
    let c = (1.0 - s * s).max(0.0).sqrt();
    n * c + n.perp() * s
}

/// A uniform direction on the half circle around unit normal `n` (pdf
/// `1 / pi`), with the cosine of its angle to `n`.
#[inline]
pub fn uniform_half_circle(n: DVec2, u: f64) -> (DVec2, f64) {
    let theta = PI * (u - 0.5);
    let (s, c) = theta.sin_cos();
    (n * c + n.perp() * s, c)
}

/// A point on segment `light` seen from `p`, drawn uniformly in the angle
/// that the segment subtends at `p`.
#[derive(Clone, Copy, Debug)]
pub struct AngleSample {
    /// The sampled point on the segment.
    pub point: DVec2,
    /// Unit direction from `p` to `point`.
    pub dir: DVec2,
    /// Distance from `p` to `point`.
    pub distance: f64,
    /// The angle the whole segment subtends at `p` (the inverse pdf).
    pub subtended: f64,
}

/// Samples the angle subtended by `light` at `p`. `None` when `p` lies on
/// the segment's line (the segment subtends no angle, or `p` is on it).
pub fn sample_subtended_angle(p: DVec2, light: &Segment, u: f64) -> Option<AngleSample> {
    let va = light.a - p;
    let vb = light.b - p;
    let c = cross(va, vb);
    if c == 0.0 {
        return None;
    }
    let subtended = c.abs().atan2(va.dot(vb));
    let da = va.normalize();
    // Rotate da towards vb by theta: the rotation's sign follows c.
    let theta = subtended * u;
    let (s, co) = theta.sin_cos();
    let perp = if c > 0.0 { da.perp() } else { -da.perp() };
    let dir = da * co + perp * s;
    let hit = line_crossing(&Ray::new(p, dir), light)?;
    if !(hit.t > 0.0) {
        return None;
    }
    Some(AngleSample {
        point: light.point_at(hit.u),
        dir,
        distance: hit.t,
        subtended,
    })
}

/// The angle that segment `light` subtends at `p` (0 on its line).
pub fn subtended_angle(p: DVec2, light: &Segment) -> f64 {
    let va = light.a - p;
    let vb = light.b - p;
    cross(va, vb).abs().atan2(va.dot(vb))
}
