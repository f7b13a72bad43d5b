//! Random streams and the samplers the integrators draw from.
//!
//! Every sample's numbers come from its own stream, a pure function of
//! (seed, pixel or path index, sample index), never of the thread that runs
//! it: an image is bit-identical for any number of threads, and one pixel
//! and sample can be re-rendered alone.
//!
//! A stream is SplitMix64 (Steele, Lea and Flood, 2014): a 64-bit counter
//! advanced by the golden-ratio increment, each number the counter's value
//! through a bijective mix. A pixel's key, a hash of (seed, pixel), starts
//! one SplitMix64 sequence; sample `s`'s stream is that sequence from its
//! number `s * 2^20` on. Starting a stream costs no mix, and two samples'
//! streams share no counter unless one of them draws 2^20 numbers. A
//! sample's first numbers are its receiver point's two coordinates, 32 bits
//! each from one mix: two mixes draw a floor ray's point and direction,
//! where a generator with a larger state (xoshiro, seeded by four mixes)
//! cost seven.

use std::f64::consts::PI;

use flatray_geometry::{DVec2, Ray, Segment, cross, line_crossing};

/// The random stream of one sample.
#[derive(Clone, Debug)]
pub struct Stream(u64);

impl Stream {
    /// The stream keyed by `(seed, index, sample)`, where `index` is the
    /// pixel (or light path) index.
    pub fn new(seed: u64, index: u64, sample: u64) -> Stream {
        StreamKey::new(seed, index).stream(sample)
    }

    /// A uniform number in `[0, 1)`.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        // The top 53 bits, as a multiple of 2^-53.
        (self.bits() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform numbers in `[0, 1)`, multiples of 2^-32, from the two
    /// halves of one draw's 64 bits: for the coordinates of a point inside
    /// a pixel, where 32 bits are finer than any image needs.
    #[inline]
    pub fn uniform_pair(&mut self) -> (f64, f64) {
        let bits = self.bits();
        let scale = 1.0 / (1u64 << 32) as f64;
        ((bits >> 32) as f64 * scale, (bits as u32) as f64 * scale)
    }

    /// The next 64 random bits.
    #[inline]
    pub fn bits(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        finalise(self.0)
    }

    /// Where the stream stands, without drawing: a number keyed as its
    /// draws are, for decisions that several callers holding the stream
    /// at one point must make alike (the wall memo's checks).
    #[inline]
    pub fn key(&self) -> u64 {
        self.0
    }
}

/// The part of a stream's key shared by all samples of one pixel (or light
/// path): computed once per pixel, it leaves no mix to start a sample's.
#[derive(Clone, Copy, Debug)]
pub struct StreamKey(u64);

impl StreamKey {
    #[inline]
    pub fn new(seed: u64, index: u64) -> StreamKey {
        StreamKey(mix(mix(seed) ^ index))
    }

    /// The stream of sample `sample`: the same as `Stream::new(seed,
    /// index, sample)`.
    #[inline]
    pub fn stream(self, sample: u64) -> Stream {
        Stream(self.0.wrapping_add(sample.wrapping_mul(STREAM_SPACING)))
    }
}

/// A seed for a part of a render apart from every other: `seed` mixed
/// with `index`, as a pixel's stream key is.
pub fn derive_seed(seed: u64, index: u64) -> u64 {
    StreamKey::new(seed, index).0
}

/// SplitMix64's increment: 2^64 over the golden ratio, odd.
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// How far apart two consecutive samples' streams start: 2^20 increments.
/// Stream indices below 2^44 start apart (the floor's and the arc offset's
/// are near 2^40).
const STREAM_SPACING: u64 = GOLDEN << 20;

/// One SplitMix64 step from state `z`: a bijective mix of 64 bits.
#[inline]
fn mix(z: u64) -> u64 {
    finalise(z.wrapping_add(GOLDEN))
}

/// The SplitMix64 finaliser (Stafford's variant 13).
#[inline]
fn finalise(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Point `k` of a pixel's sequence of points in the unit square: the
/// Sobol sequence's first two dimensions, Owen-scrambled by `seeds` (a
/// pixel's own pair) with Burley's hash ("Practical hash-based Owen
/// scrambling", 2020). Every prefix of the sequence is spread evenly, and
/// any `2^m` points from a multiple of `2^m` on have one point in each of
/// the `2^m` boxes of any shape `2^-a x 2^-(m-a)` (a (0, m, 2)-net): the
/// first `4^L` points form a jittered grid of `2^L x 2^L` cells. The
/// scrambling makes each point uniform over the square, so a render can
/// draw more points later, and draw them alone, without moving the ones it
/// has.
#[inline]
pub fn sobol_point(k: u32, seeds: [u32; 2]) -> DVec2 {
    // The first dimension is the index with its bits reversed (van der
    // Corput): scrambled, reversed, it is the index itself.
    let x = laine_karras(k, seeds[0]).reverse_bits();
    // The second, bit-reversed: the columns of its generator matrix for
    // each set bit of the index.
    let reversed = sobol_second_reversed(k);
    let y = laine_karras(reversed, seeds[1]).reverse_bits();
    let scale = 1.0 / (1u64 << 32) as f64;
    DVec2::new(x as f64 * scale, y as f64 * scale)
}

/// [`SOBOL_SECOND_REVERSED`] summed (by exclusive or) over the set bits
/// of each 10-bit number, for bits 0 to 9 and 10 to 19 of an index.
const SOBOL_SECOND_TABLES: [[u32; 1024]; 2] = {
    let mut tables = [[0u32; 1024]; 2];
    let mut t = 0;
    while t < 2 {
        let mut i = 0;
        while i < 1024 {
            let mut sum = 0;
            let mut bit = 0;
            while bit < 10 {
                if i >> bit & 1 == 1 {
                    sum ^= SOBOL_SECOND_REVERSED[10 * t + bit];
                }
                bit += 1;
            }
            tables[t][i] = sum;
            i += 1;
        }
        t += 1;
    }
    tables
};

/// Points `first ..` of a pixel's sequence ([`sobol_point`]), as many as
/// `points` holds, each scaled by `step` from `corner`: the same points,
/// eight at a time in vector instructions (of the caller's target
/// features: inlined always).
#[inline(always)]
pub fn sobol_points(
    first: u32,
    seeds: [u32; 2],
    (corner, step): (DVec2, DVec2),
    points: &mut [DVec2],
) {
    let scale = 1.0 / (1u64 << 32) as f64;
    let mut k = first;
    let mut rest = &mut points[..];
    // One by one up to a multiple of eight, then eight at a time.
    while !rest.is_empty() && (!k.is_multiple_of(8) || rest.len() < 8) {
        rest[0] = corner + sobol_point(k, seeds) * step;
        rest = &mut rest[1..];
        k = k.wrapping_add(1);
    }
    while rest.len() >= 8 {
        // The second dimension is linear in the index's bits: the eight
        // share the high bits' columns and differ by the low three's.
        let high = sobol_second_reversed(k);
        let (mut xs, mut ys) = ([0u32; 8], [0u32; 8]);
        for j in 0..8 {
            xs[j] = laine_karras(k + j as u32, seeds[0]).reverse_bits();
            ys[j] = laine_karras(high ^ SOBOL_SECOND_TABLES[0][j], seeds[1]).reverse_bits();
        }
        for j in 0..8 {
            let p = DVec2::new(xs[j] as f64 * scale, ys[j] as f64 * scale);
            rest[j] = corner + p * step;
        }
        rest = &mut rest[8..];
        k = k.wrapping_add(8);
        while !rest.is_empty() && rest.len() < 8 {
            rest[0] = corner + sobol_point(k, seeds) * step;
            rest = &mut rest[1..];
            k = k.wrapping_add(1);
        }
    }
}

/// The Sobol sequence's second dimension at index `k`, bit-reversed and
/// not scrambled.
#[inline(always)]
fn sobol_second_reversed(k: u32) -> u32 {
    let mut reversed = SOBOL_SECOND_TABLES[0][(k & 1023) as usize]
        ^ SOBOL_SECOND_TABLES[1][((k >> 10) & 1023) as usize];
    let (mut rest, mut column) = (k >> 20, 20u32);
    while rest != 0 {
        let skip = rest.trailing_zeros();
        column += skip;
        reversed ^= SOBOL_SECOND_REVERSED[column as usize];
        rest = rest.checked_shr(skip + 1).unwrap_or(0);
        column += 1;
    }
    reversed
}

/// The Laine-Karras permutation with Burley's constants: a hash of `x`
/// that flips each bit by the bits below it (the nested scramble, in the
/// bit-reversed order).
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// The Sobol sequence's second dimension's generator columns (direction
/// numbers `v_0 = 2^31`, `v_j = v_(j-1) xor v_(j-1) >> 1`), each with its
/// bits reversed.
const SOBOL_SECOND_REVERSED: [u32; 32] = {
    let mut columns = [0u32; 32];
    let mut v = 1u32 << 31;
    let mut j = 0;
    while j < 32 {
        columns[j] = v.reverse_bits();
        v ^= v >> 1;
        j += 1;
    }
    columns
};

/// A uniform direction on the circle (pdf `1 / 2pi` per radian): one
/// number, turned into an angle by [`circle_point`].
#[inline]
pub fn uniform_circle(stream: &mut Stream) -> DVec2 {
    circle_point(stream.uniform())
}

/// The arc of [`ARCS`] that sample `sample` of a pixel whose arcs are
/// turned by `offset` takes its floor direction from: the samples' arcs
/// are stratified. Each run of `ARCS` samples takes every arc once, and
/// the first samples of a run are spread round the circle (the sample's
/// index with its bits reversed: 0, 32, 16, 48, 8, ...), so that a pixel
/// of few samples still looks every way. With `offset` uniform in
/// `0..ARCS`, every sample's arc is uniform: its direction from
/// [`circle_in_arc`] is uniform on the circle, as if drawn alone.
#[inline]
pub fn sample_arc(offset: usize, sample: u32) -> usize {
    (reverse_arc_bits(sample as usize) + offset) & (ARCS - 1)
}

/// The first sample of each run of `ARCS` that [`sample_arc`] gives arc
/// `arc`: the samples of that arc are `first_sample_of_arc(..) + ARCS j`.
#[inline]
pub fn first_sample_of_arc(offset: usize, arc: usize) -> u32 {
    reverse_arc_bits(arc.wrapping_sub(offset)) as u32
}

/// The low `log2(ARCS)` bits of `k`, reversed: its own inverse. From a
/// table: x86 has no instruction to reverse bits.
#[inline]
fn reverse_arc_bits(k: usize) -> usize {
    REVERSED_ARC_BITS[k & (ARCS - 1)] as usize
}

/// `run`'s bits reversed behind the binary point, in `[0, 1)`: the van
/// der Corput sequence, whose first `2^k` values fall one in each `2^-k`
/// of the unit interval.
#[inline(always)]
pub fn radical_inverse(run: u32) -> f64 {
    run.reverse_bits() as f64 * (1.0 / 4_294_967_296.0)
}

/// [`reverse_arc_bits`] of each arc.
const REVERSED_ARC_BITS: [u8; ARCS] = {
    let mut table = [0; ARCS];
    let mut k = 0;
    while k < ARCS {
        table[k] = (k.reverse_bits() >> (usize::BITS - ARCS.trailing_zeros())) as u8;
        k += 1;
    }
    table
};

/// A uniform direction inside arc `arc` of [`ARCS`] (arc `k` spans the
/// angles `2 pi k / ARCS` to `2 pi (k + 1) / ARCS`, as
/// `flatray_geometry::ArcCandidates` numbers them): one number.
#[inline]
pub fn circle_in_arc(arc: usize, stream: &mut Stream) -> DVec2 {
    arc_point(arc, stream.uniform())
}

/// `(cos 2 pi u, sin 2 pi u)` for `u` in `[0, 1)`, to within 1e-15, with
/// no branch and no library call: `64u`'s integer part picks one of 64
/// equal arcs, whose centre's cosine and sine come from a table; the
/// offset `a` from the centre (`|a| <= pi/64`) turns that by Taylor
/// polynomials whose first omitted terms are below 5e-18. It replaced
/// rejection sampling from the square, whose 21 % of rejected draws were
/// mispredicted branches.
#[inline]
pub fn circle_point(u: f64) -> DVec2 {
    // Exact: a product by a power of two, then a difference on its grid.
    let x = u * ARCS as f64;
    let arc = x as i64;
    arc_point(arc as usize, x - arc as f64)
}

/// The point of the circle `fraction` (in `[0, 1)`) of the way through arc
/// `arc`.
#[inline]
pub fn arc_point(arc: usize, fraction: f64) -> DVec2 {
    let (x, y) = arc_turn(ARC_CENTRES[arc & (ARCS - 1)], fraction);
    DVec2::new(x, y)
}

/// [`circle_in_arc`] for `N` samples of one arc at once, each lane's
/// fraction of the way through it given: the same directions, computed in
/// vector instructions (of the caller's target features: inlined always).
#[inline(always)]
pub fn arc_points<const N: usize>(arc: usize, fractions: &[f64; N]) -> ([f64; N], [f64; N]) {
    // `& (ARCS - 1)` keeps the index in bounds without a check.
    let centre = ARC_CENTRES[arc & (ARCS - 1)];
    let (mut xs, mut ys) = ([0.0; N], [0.0; N]);
    for k in 0..N {
        (xs[k], ys[k]) = arc_turn(centre, fractions[k]);
    }
    (xs, ys)
}

/// The point `fraction` of the way through the arc whose centre is at
/// `(cc, sc)`: the centre turned by Taylor polynomials.
#[inline(always)]
fn arc_turn((cc, sc): (f64, f64), fraction: f64) -> (f64, f64) {
    let a = (fraction - 0.5) * (std::f64::consts::TAU / ARCS as f64);
    let a2 = a * a;
    let s = a * (1.0 + a2 * (-1.0 / 6.0 + a2 * (1.0 / 120.0 + a2 * (-1.0 / 5040.0))));
    let c = 1.0 + a2 * (-0.5 + a2 * (1.0 / 24.0 + a2 * (-1.0 / 720.0 + a2 * (1.0 / 40_320.0))));
    (cc * c - sc * s, sc * c + cc * s)
}

/// The arcs of [`circle_point`]'s table. A pixel's floor directions are
/// stratified over the same arcs ([`sample_arc`]), and the floor's rays
/// culled by them. (128 or 256 arcs, each a part of a table arc, were no
/// faster: more lists to fill per block, fewer samples per list.)
pub const ARCS: usize = 64;

/// `(cos, sin)` of the centre of arc `k`, `2 pi (k + 1/2) / 64`,
/// correctly rounded (computed to 50 digits).
#[rustfmt::skip]
const ARC_CENTRES: [(f64, f64); ARCS] = [
    (0.9987954562051724, 0.049067674327418015),
    (0.989176509964781, 0.14673047445536175),
    (0.970031253194544, 0.2429801799032639),
    (0.9415440651830208, 0.33688985339222005),
    (0.9039892931234433, 0.4275550934302821),
    (0.8577286100002721, 0.5141027441932218),
    (0.8032075314806449, 0.5956993044924334),
    (0.7409511253549591, 0.6715589548470184),
    (0.6715589548470184, 0.7409511253549591),
    (0.5956993044924334, 0.8032075314806449),
    (0.5141027441932218, 0.8577286100002721),
    (0.4275550934302821, 0.9039892931234433),
    (0.33688985339222005, 0.9415440651830208),
    (0.2429801799032639, 0.970031253194544),
    (0.14673047445536175, 0.989176509964781),
    (0.049067674327418015, 0.9987954562051724),
    (-0.049067674327418015, 0.9987954562051724),
    (-0.14673047445536175, 0.989176509964781),
    (-0.2429801799032639, 0.970031253194544),
    (-0.33688985339222005, 0.9415440651830208),
    (-0.4275550934302821, 0.9039892931234433),
    (-0.5141027441932218, 0.8577286100002721),
    (-0.5956993044924334, 0.8032075314806449),
    (-0.6715589548470184, 0.7409511253549591),
    (-0.7409511253549591, 0.6715589548470184),
    (-0.8032075314806449, 0.5956993044924334),
    (-0.8577286100002721, 0.5141027441932218),
    (-0.9039892931234433, 0.4275550934302821),
    (-0.9415440651830208, 0.33688985339222005),
    (-0.970031253194544, 0.2429801799032639),
    (-0.989176509964781, 0.14673047445536175),
    (-0.9987954562051724, 0.049067674327418015),
    (-0.9987954562051724, -0.049067674327418015),
    (-0.989176509964781, -0.14673047445536175),
    (-0.970031253194544, -0.2429801799032639),
    (-0.9415440651830208, -0.33688985339222005),
    (-0.9039892931234433, -0.4275550934302821),
    (-0.8577286100002721, -0.5141027441932218),
    (-0.8032075314806449, -0.5956993044924334),
    (-0.7409511253549591, -0.6715589548470184),
    (-0.6715589548470184, -0.7409511253549591),
    (-0.5956993044924334, -0.8032075314806449),
    (-0.5141027441932218, -0.8577286100002721),
    (-0.4275550934302821, -0.9039892931234433),
    (-0.33688985339222005, -0.9415440651830208),
    (-0.2429801799032639, -0.970031253194544),
    (-0.14673047445536175, -0.989176509964781),
    (-0.049067674327418015, -0.9987954562051724),
    (0.049067674327418015, -0.9987954562051724),
    (0.14673047445536175, -0.989176509964781),
    (0.2429801799032639, -0.970031253194544),
    (0.33688985339222005, -0.9415440651830208),
    (0.4275550934302821, -0.9039892931234433),
    (0.5141027441932218, -0.8577286100002721),
    (0.5956993044924334, -0.8032075314806449),
    (0.6715589548470184, -0.7409511253549591),
    (0.7409511253549591, -0.6715589548470184),
    (0.8032075314806449, -0.5956993044924334),
    (0.8577286100002721, -0.5141027441932218),
    (0.9039892931234433, -0.4275550934302821),
    (0.9415440651830208, -0.33688985339222005),
    (0.970031253194544, -0.2429801799032639),
    (0.989176509964781, -0.14673047445536175),
    (0.9987954562051724, -0.049067674327418015),
];

/// The leaving rule: a direction sampled on a wall's half circle stays at
/// least `1e-6` radians away from the wall. A point computed on a wall is
/// off its line by rounding (about 1e-16 of its coordinates), and a ray
/// leaving closer to the wall than that could pass outside the wall's far
/// end and out of a closed room. The directions cut away carry about 1e-12
/// of the reflected light.
pub const GRAZING_SIN: f64 = 1.0 - 5e-13;
/// `GRAZING_SIN` as an angle from the normal: `pi / 2 - 1e-6`.
pub const GRAZING_ANGLE: f64 = std::f64::consts::FRAC_PI_2 - 1e-6;

/// A cosine-weighted direction on the half circle around unit normal `n`:
/// the angle `theta` from `n` has pdf `cos(theta) / 2`. Sampled by drawing
/// `sin(theta)` uniformly in `[-1, 1]`.
#[inline]
pub fn cosine_half_circle(n: DVec2, u: f64) -> DVec2 {
    // The leaving rule: never closer than GRAZING to the wall itself.
    let s = (2.0 * u - 1.0).clamp(-GRAZING_SIN, GRAZING_SIN);
    let c = (1.0 - s * s).max(0.0).sqrt();
    n * c + n.perp() * s
}

/// A uniform direction on the half circle around unit normal `n` (pdf
/// `1 / pi`), with the cosine of its angle to `n`.
#[inline]
pub fn uniform_half_circle(n: DVec2, u: f64) -> (DVec2, f64) {
    let theta = (PI * (u - 0.5)).clamp(-GRAZING_ANGLE, GRAZING_ANGLE);
    let (s, c) = theta.sin_cos();
    (n * c + n.perp() * s, c)
}

/// `(cos theta, sin theta)` for `theta` in `[0, 2 pi)`, by
/// [`circle_point`] (no library call; within 1e-15).
#[inline(always)]
fn turn(theta: f64) -> DVec2 {
    circle_point(theta * (1.0 / std::f64::consts::TAU))
}

/// `atan2(y, x)` for `y >= 0` (an angle in `[0, pi]`), to within a
/// relative 1e-15, with no library call: the ratio of the smaller to the
/// larger of `|x|` and `y` is `t` in `[0, 1]`; `atan t` is the table's value at the
/// nearest `k / 32` plus `atan` of the small remainder
/// `(t - k/32) / (1 + t k/32)` (at most 1/64), a series whose first
/// omitted term is below 1e-21. Not finite, or `(0, 0)`: not an angle.
#[inline(always)]
fn atan2_upper(y: f64, x: f64) -> f64 {
    let (ax, steep) = (x.abs(), y > x.abs());
    let t = if steep { ax / y } else { y / ax };
    let k = (t * 32.0 + 0.5) as i64;
    let tk = k as f64 * (1.0 / 32.0);
    let d = (t - tk) / (1.0 + t * tk);
    let d2 = d * d;
    let small =
        d * (1.0 + d2 * (-1.0 / 3.0 + d2 * (1.0 / 5.0 + d2 * (-1.0 / 7.0 + d2 * (1.0 / 9.0)))));
    // `& 63` keeps the index in bounds (k is 0 to 32 for t in [0, 1]).
    let a = ATAN_32NDS[(k as usize & 63).min(32)] + small;
    // atan(y/|x|) from atan of the ratio, then the side of x.
    let a = if steep {
        std::f64::consts::FRAC_PI_2 - a
    } else {
        a
    };
    if x < 0.0 { PI - a } else { a }
}

/// `atan(k / 32)` for `k` in `0..=32`, correctly rounded (computed to 60
/// digits).
#[rustfmt::skip]
const ATAN_32NDS: [f64; 33] = [
    0.0,
    0.031239833430268277,
    0.06241880999595735,
    0.09347678115858947,
    0.12435499454676144,
    0.15499674192394097,
    0.18534794999569476,
    0.21535769969773805,
    0.24497866312686414,
    0.2741674511196588,
    0.3028848683749714,
    0.3310960767041321,
    0.35877067027057225,
    0.38588266939807375,
    0.4124104415973873,
    0.43833655985795783,
    0.4636476090008061,
    0.48833395105640554,
    0.5123894603107377,
    0.5358112379604637,
    0.5585993153435624,
    0.5807563535676704,
    0.6022873461349642,
    0.6231993299340659,
    0.6435011087932844,
    0.6632029927060933,
    0.6823165548747481,
    0.7008544078844502,
    0.7188299996216245,
    0.7362574289814281,
    0.7531512809621944,
    0.7695264804056583,
    std::f64::consts::FRAC_PI_4,
];

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
    let subtended = atan2_upper(c.abs(), va.dot(vb));
    angle_sample(p, light, c, subtended, turn(subtended * u))
}

/// The end of [`sample_subtended_angle`], given the cross product `c` of
/// the light's ends seen from `p`, the angle it subtends, and the
/// rotation `(cos, sin)` of the drawn share of that angle.
#[inline(always)]
fn angle_sample(
    p: DVec2,
    light: &Segment,
    c: f64,
    subtended: f64,
    rotation: DVec2,
) -> Option<AngleSample> {
    let da = (light.a - p).normalize();
    // Rotate da towards b by the drawn angle: the rotation's sign follows c.
    let perp = if c > 0.0 { da.perp() } else { -da.perp() };
    let dir = da * rotation.x + perp * rotation.y;
    let hit = line_crossing(&Ray::new(p, dir), light)?;
    if hit.t.is_nan() || hit.t <= 0.0 {
        return None;
    }
    Some(AngleSample {
        point: light.point_at(hit.u),
        dir,
        distance: hit.t,
        subtended,
    })
}

/// [`sample_subtended_angle`] at `N` points at once, point `k` at
/// `(px[k], py[k])` with the number `us[k]`: for each point the same
/// operations as one call, so the same samples, but with no branch (both
/// ways computed and one chosen), so that the compiler turns the lanes
/// into vector instructions (of the caller's target features: inlined
/// always) and the long chain of one point's arithmetic (an `atan2`, a
/// rotation, a division) overlaps the others'.
#[inline(always)]
pub fn angle_sample_lanes<const N: usize>(
    px: &[f64; N],
    py: &[f64; N],
    us: &[f64; N],
    light: &Segment,
) -> AngleLanes<N> {
    let (a, b) = (light.a, light.b);
    let e = b - a;
    let mut lanes = AngleLanes {
        x: [0.0; N],
        y: [0.0; N],
        distance: [0.0; N],
        subtended: [0.0; N],
        valid: [false; N],
    };
    for k in 0..N {
        // `sample_subtended_angle`, term by term.
        let (vax, vay) = (a.x - px[k], a.y - py[k]);
        let (vbx, vby) = (b.x - px[k], b.y - py[k]);
        let c = vax * vby - vay * vbx;
        let subtended = atan2_upper(c.abs(), vax * vbx + vay * vby);
        let DVec2 { x: rx, y: ry } = turn(subtended * us[k]);
        // `angle_sample`: `da` normalised as glam does it.
        let recip = 1.0 / (vax * vax + vay * vay).sqrt();
        let (dax, day) = (vax * recip, vay * recip);
        let (perpx, perpy) = if c > 0.0 { (-day, dax) } else { (day, -dax) };
        let (dx, dy) = (dax * rx + perpx * ry, day * rx + perpy * ry);
        // `line_crossing` from `p` along the direction.
        let sa = dx * vay - dy * vax;
        let sb = dx * vby - dy * vbx;
        let apart = (sa > 0.0 && sb > 0.0) | (sa < 0.0 && sb < 0.0) | (sa == 0.0 && sb == 0.0);
        let t = (vax * e.y - vay * e.x) / (sb - sa);
        let u = sa / (sa - sb);
        // `t > 0` is false for NaN, as `!(t.is_nan() || t <= 0)` is.
        lanes.valid[k] = (c != 0.0) & !apart & (t > 0.0);
        lanes.x[k] = a.x + u * e.x;
        lanes.y[k] = a.y + u * e.y;
        lanes.distance[k] = t;
        lanes.subtended[k] = subtended;
    }
    lanes
}

/// What [`angle_sample_lanes`] gives, lane by lane: each lane's
/// [`AngleSample`] where `valid`, without its direction.
#[derive(Clone, Copy, Debug)]
pub struct AngleLanes<const N: usize> {
    /// The sampled point on the light.
    pub x: [f64; N],
    pub y: [f64; N],
    pub distance: [f64; N],
    pub subtended: [f64; N],
    /// Whether the lane has a sample (`sample_subtended_angle` is `Some`).
    pub valid: [bool; N],
}

/// The angle that segment `light` subtends at `p` (0 on its line).
pub fn subtended_angle(p: DVec2, light: &Segment) -> f64 {
    let va = light.a - p;
    let vb = light.b - p;
    cross(va, vb).abs().atan2(va.dot(vb))
}

#[cfg(test)]
mod tests {
    //! The samplers draw from the densities they claim: chi-square tests
    //! with fixed seeds, so each run is the same.

    use super::*;
    use std::f64::consts::TAU;

    /// The 0.1 % critical value of the chi-square distribution with 19
    /// degrees of freedom: a correct sampler exceeds it once in 1000 seeds.
    const CHI2_19_999: f64 = 43.82;
    const BINS: usize = 20;
    const DRAWS: usize = 200_000;

    /// Chi-square statistic of `counts` against bin probabilities `expected`.
    fn chi_square(counts: &[usize], expected: &[f64]) -> f64 {
        let total: usize = counts.iter().sum();
        counts
            .iter()
            .zip(expected)
            .map(|(&c, &p)| {
                let e = p * total as f64;
                (c as f64 - e).powi(2) / e
            })
            .sum()
    }

    /// P(bin) = (sin(hi) - sin(lo)) / 2, the integral of cos / 2 over each
    /// of `BINS` equal bins of the half circle.
    fn cosine_bins() -> Vec<f64> {
        (0..BINS)
            .map(|k| {
                let lo = -PI / 2.0 + PI * k as f64 / BINS as f64;
                let hi = lo + PI / BINS as f64;
                (hi.sin() - lo.sin()) / 2.0
            })
            .collect()
    }

    /// A pixel's scrambling seeds, from `seed`.
    fn seeds(seed: u64) -> [u32; 2] {
        let bits = Stream::new(seed, 0, 0).bits();
        [(bits >> 32) as u32, bits as u32]
    }

    /// The sequence's first `count` points for the seeds of `seed`.
    fn sobol(seed: u64, count: u32) -> Vec<DVec2> {
        (0..count).map(|k| sobol_point(k, seeds(seed))).collect()
    }

    /// Every `2^m` points from a multiple of `2^m` on, for `m` up to 10,
    /// have one point in each box of every shape `2^-a x 2^-(m - a)`.
    #[test]
    fn sobol_points_form_nets() {
        for seed in 0..8 {
            let points = sobol(seed, 4096);
            for m in 0..=10u32 {
                let n = 1usize << m;
                for block in points.chunks(n).take(3) {
                    for a in 0..=m {
                        let mut counts = vec![0u8; n];
                        for p in block {
                            assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                            let i = (p.x * (1u64 << a) as f64) as usize;
                            let j = (p.y * (1u64 << (m - a)) as f64) as usize;
                            counts[(i << (m - a)) | j] += 1;
                        }
                        assert!(counts.iter().all(|&c| c == 1), "seed {seed} m {m} a {a}");
                    }
                }
            }
        }
    }

    /// The tables give the generator matrix's columns summed bit by bit,
    /// for indices of any size.
    #[test]
    fn sobol_tables_match_the_columns() {
        let seeds = [0, 0];
        let mut stream = Stream::new(3, 0, 0);
        for k in (0..5000).chain((0..5000).map(|_| stream.bits() as u32)) {
            let mut reversed = 0u32;
            for (bit, column) in SOBOL_SECOND_REVERSED.iter().enumerate() {
                if k >> bit & 1 == 1 {
                    reversed ^= column;
                }
            }
            let y = laine_karras(reversed, seeds[1]).reverse_bits();
            let expected = y as f64 / (1u64 << 32) as f64;
            assert_eq!(sobol_point(k, seeds).y, expected, "index {k}");
        }
    }

    /// Eight at a time, the same points.
    #[test]
    fn sobol_points_in_lanes_are_the_same() {
        let seeds = [12345, 678910];
        let (corner, step) = (DVec2::new(-3.0, 7.5), DVec2::new(0.25, 0.5));
        for (first, count) in [(0, 64), (3, 29), (16, 16), (1000, 7), ((1 << 20) - 5, 40)] {
            let mut points = vec![DVec2::ZERO; count];
            sobol_points(first, seeds, (corner, step), &mut points);
            for (j, p) in points.iter().enumerate() {
                let expected = corner + sobol_point(first + j as u32, seeds) * step;
                assert_eq!(*p, expected, "point {}", first + j as u32);
            }
        }
    }

    /// Each point, whatever its index, is uniform over the square across
    /// pixels (seeds).
    #[test]
    fn sobol_points_are_each_uniform() {
        for k in [0, 1, 3, 6, 17, 45, 1000] {
            let mut counts = [0usize; BINS];
            for seed in 0..40_000u64 {
                let p = sobol_point(k, seeds(seed));
                // Bins mix both coordinates, so each is tested.
                let bin = ((p.x * 5.0) as usize) * 4 + (p.y * 4.0) as usize;
                counts[bin] += 1;
            }
            let chi2 = chi_square(&counts, &[1.0 / BINS as f64; BINS]);
            assert!(chi2 < CHI2_19_999, "point {k}: chi2 {chi2}");
        }
    }

    #[test]
    fn cosine_sampler_draws_cos_over_two() {
        let n = DVec2::new(0.6, -0.8);
        let mut stream = Stream::new(1, 2, 3);
        let mut counts = [0usize; BINS];
        for _ in 0..DRAWS {
            let d = cosine_half_circle(n, stream.uniform());
            assert!((d.length() - 1.0).abs() < 1e-12);
            // Angle from n in (-pi/2, pi/2), positive towards perp(n).
            let theta = d.dot(n.perp()).atan2(d.dot(n));
            let bin = ((theta + PI / 2.0) / PI * BINS as f64) as usize;
            counts[bin.min(BINS - 1)] += 1;
        }
        let chi2 = chi_square(&counts, &cosine_bins());
        assert!(chi2 < CHI2_19_999, "chi-square {chi2}: {counts:?}");
    }

    #[test]
    fn a_wrong_density_fails_the_cosine_test() {
        // The test must be able to fail: uniform half-circle directions
        // are not cosine-distributed.
        let n = DVec2::new(1.0, 0.0);
        let mut stream = Stream::new(1, 2, 3);
        let mut counts = [0usize; BINS];
        for _ in 0..DRAWS {
            let (d, _) = uniform_half_circle(n, stream.uniform());
            let theta = d.dot(n.perp()).atan2(d.dot(n));
            let bin = ((theta + PI / 2.0) / PI * BINS as f64) as usize;
            counts[bin.min(BINS - 1)] += 1;
        }
        assert!(chi_square(&counts, &cosine_bins()) > 10.0 * CHI2_19_999);
    }

    #[test]
    fn uniform_circle_is_uniform() {
        let mut stream = Stream::new(4, 5, 6);
        let mut counts = [0usize; BINS];
        for _ in 0..DRAWS {
            let d = uniform_circle(&mut stream);
            let a = d.y.atan2(d.x).rem_euclid(TAU);
            counts[((a / TAU * BINS as f64) as usize).min(BINS - 1)] += 1;
        }
        let chi2 = chi_square(&counts, &[1.0 / BINS as f64; BINS]);
        assert!(chi2 < CHI2_19_999, "chi-square {chi2}: {counts:?}");
    }

    #[test]
    fn circle_point_is_cos_and_sin_of_two_pi_u() {
        // Every quarter turn and its edges, and a fine sweep.
        let edges = [0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875];
        let sweep = (0..100_000).map(|k| k as f64 / 100_000.0 + 3.7e-6);
        let below_one = 1.0 - f64::EPSILON / 2.0;
        for u in edges.into_iter().chain(sweep).chain([below_one]) {
            let d = circle_point(u);
            let (s, c) = (TAU * u).sin_cos();
            assert!(
                (d.x - c).abs() < 1e-15 && (d.y - s).abs() < 1e-15,
                "u {u}: {d:?} against ({c}, {s})"
            );
            assert!(
                (d.length() - 1.0).abs() < 1e-15,
                "u {u}: length {}",
                d.length()
            );
        }
    }

    #[test]
    fn each_run_of_samples_takes_every_arc_once_spread_from_its_first() {
        for offset in 0..ARCS {
            for run in 0..3u32 {
                let arcs: Vec<usize> = (0..ARCS as u32)
                    .map(|k| sample_arc(offset, run * ARCS as u32 + k))
                    .collect();
                let mut sorted = arcs.clone();
                sorted.sort();
                assert_eq!(sorted, (0..ARCS).collect::<Vec<_>>(), "offset {offset}");
                // The first 2^m samples of a run are 2^(6-m) arcs apart.
                for m in 0..=ARCS.trailing_zeros() {
                    let mut first: Vec<usize> = arcs[..1 << m].to_vec();
                    first.sort();
                    let gap = ARCS >> m;
                    assert!(
                        first
                            .iter()
                            .all(|&a| (a + ARCS - offset).is_multiple_of(gap))
                    );
                }
                for (k, &arc) in arcs.iter().enumerate() {
                    assert_eq!(first_sample_of_arc(offset, arc), k as u32);
                }
            }
        }
    }

    #[test]
    fn a_stratified_sample_direction_is_uniform_on_the_circle() {
        // One sample index, many pixels: the offset drawn per pixel makes
        // each sample's direction uniform, as the estimator needs. For
        // samples 0 and 5 of 40,000 pixels, the angle's histogram.
        for sample in [0, 5] {
            let mut counts = [0usize; BINS];
            for pixel in 0..DRAWS as u64 / 10 {
                let key = StreamKey::new(9, pixel);
                let offset = (key.stream(u64::MAX).uniform() * ARCS as f64) as usize;
                let d = circle_in_arc(sample_arc(offset, sample), &mut key.stream(sample as u64));
                let a = d.y.atan2(d.x).rem_euclid(TAU);
                counts[((a / TAU * BINS as f64) as usize).min(BINS - 1)] += 1;
            }
            let chi2 = chi_square(&counts, &[1.0 / BINS as f64; BINS]);
            assert!(
                chi2 < CHI2_19_999,
                "sample {sample}: chi-square {chi2}: {counts:?}"
            );
        }
    }

    #[test]
    fn stream_numbers_are_uniform_in_the_unit_interval() {
        // Across streams (the first number of each) and along one stream.
        let key = StreamKey::new(11, 12);
        let across = (0..DRAWS as u64).map(|k| key.stream(k).uniform());
        let mut one = Stream::new(13, 14, 15);
        let along: Vec<f64> = (0..DRAWS).map(|_| one.uniform()).collect();
        for numbers in [across.collect::<Vec<f64>>(), along] {
            let mut counts = [0usize; BINS];
            for u in numbers {
                assert!((0.0..1.0).contains(&u));
                counts[(u * BINS as f64) as usize] += 1;
            }
            let chi2 = chi_square(&counts, &[1.0 / BINS as f64; BINS]);
            assert!(chi2 < CHI2_19_999, "chi-square {chi2}: {counts:?}");
        }
    }

    #[test]
    fn neighbouring_streams_draw_independent_numbers() {
        // Pairs of numbers that one sample, or two of a pixel, draw: their
        // joint histogram on a 10 x 10 grid over 40,000 pixels against
        // the uniform square (chi-square, 99 degrees of freedom, 0.1 %).
        const CHI2_99_999: f64 = 148.2;
        let mut grids = [[0usize; 100]; 5];
        let cell = |u: f64, v: f64| (u * 10.0) as usize * 10 + (v * 10.0) as usize;
        for pixel in 0..DRAWS as u64 / 5 {
            let key = StreamKey::new(3, pixel);
            // A sample's receiver point and direction, the next sample's,
            // the same arc's next sample's, and two floor strata's points.
            let draw = |sample: u64| {
                let mut stream = key.stream(sample);
                let (x, y) = stream.uniform_pair();
                (x, y, stream.uniform())
            };
            let (x0, y0, d0) = draw(5);
            let (x1, _, _) = draw(6);
            let (_, _, d64) = draw(5 + ARCS as u64);
            let (f0, _, _) = draw(1 << 40);
            let (f1, _, _) = draw((1 << 40) + 1);
            for (grid, (u, v)) in
                grids
                    .iter_mut()
                    .zip([(x0, y0), (x0, x1), (d0, d64), (d0, x1), (f0, f1)])
            {
                grid[cell(u, v)] += 1;
            }
        }
        for (k, grid) in grids.iter().enumerate() {
            let chi2 = chi_square(grid, &[0.01; 100]);
            assert!(chi2 < CHI2_99_999, "pair {k}: chi-square {chi2}");
        }
    }

    #[test]
    fn a_pair_is_the_two_halves_of_one_draw() {
        let (mut one, mut two) = (Stream::new(1, 2, 3), Stream::new(1, 2, 3));
        let (x, y) = one.uniform_pair();
        let bits = two.bits();
        assert_eq!(x, (bits >> 32) as f64 / 4294967296.0);
        assert_eq!(y, (bits & 0xffff_ffff) as f64 / 4294967296.0);
        // The next number is the stream's next draw.
        assert_eq!(one.uniform(), two.uniform());
    }

    #[test]
    fn line_light_sampler_is_uniform_in_subtended_angle() {
        let p = DVec2::new(1.0, 2.0);
        for light in [
            Segment::new(DVec2::new(5.0, -3.0), DVec2::new(6.0, 9.0)),
            Segment::new(DVec2::new(6.0, 9.0), DVec2::new(5.0, -3.0)),
            Segment::new(DVec2::new(-4.0, 2.5), DVec2::new(8.0, 2.7)),
        ] {
            let mut stream = Stream::new(7, 8, 9);
            let mut counts = [0usize; BINS];
            let da = (light.a - p).normalize();
            for _ in 0..DRAWS {
                let s = sample_subtended_angle(p, &light, stream.uniform()).unwrap();
                assert!((s.subtended - subtended_angle(p, &light)).abs() < 1e-12);
                // The point lies on the segment and in the sampled direction.
                assert!(light.side_value(s.point).abs() < 1e-9 * light.length());
                assert!(((s.point - p).normalize() - s.dir).length() < 1e-9);
                let offset = cross(da, s.dir).abs().atan2(da.dot(s.dir));
                let bin = (offset / s.subtended * BINS as f64) as usize;
                counts[bin.min(BINS - 1)] += 1;
            }
            let chi2 = chi_square(&counts, &[1.0 / BINS as f64; BINS]);
            assert!(chi2 < CHI2_19_999, "chi-square {chi2}: {counts:?}");
        }
    }

    #[test]
    fn the_tabled_atan2_is_atan2() {
        let mut stream = Stream::new(2, 3, 4);
        let mut cases: Vec<(f64, f64)> = (0..200_000)
            .map(|_| {
                let angle = stream.uniform() * PI;
                let r = (stream.uniform() * 40.0 - 20.0).exp();
                (r * angle.sin(), r * angle.cos())
            })
            .collect();
        // The octant borders, the axes and the table's points.
        for k in 0..=32 {
            let t = k as f64 / 32.0;
            cases.extend([(t, 1.0), (1.0, t), (t, -1.0), (1.0, -t), (t, 1.0 + 1e-16)]);
        }
        cases.extend([
            (1.0, 0.0),
            (1e-300, 1.0),
            (1e-300, -1.0),
            (1.0, 1e-300),
            (0.0, 1.0),
            (0.0, -1.0),
        ]);
        for (y, x) in cases {
            let (ours, libm) = (atan2_upper(y, x), y.atan2(x));
            assert!(
                (ours - libm).abs() <= 1e-15 * libm.max(1e-300),
                "atan2({y}, {x}): {ours} against {libm}"
            );
        }
    }

    #[test]
    fn angle_samples_in_lanes_are_the_single_samples() {
        let light = Segment::new(DVec2::new(5.0, -3.0), DVec2::new(6.0, 9.0));
        let mut stream = Stream::new(1, 1, 1);
        let mut points: Vec<DVec2> = (0..1998)
            .map(|_| DVec2::new(stream.uniform() * 20.0 - 5.0, stream.uniform() * 20.0 - 5.0))
            .collect();
        // On the light's line, on its ends, on the light itself, and where
        // the drawn direction grazes an end (u = 0 and just below 1).
        points.extend([light.a, light.b, light.point_at(0.5), light.point_at(2.0)]);
        points.extend([DVec2::new(-3.0, 1.0), DVec2::new(11.0, 2.0)]);
        let mut us: Vec<f64> = points.iter().map(|_| stream.uniform()).collect();
        let n = us.len();
        assert_eq!(n % 4, 0);
        us[n - 2] = 0.0;
        us[n - 1] = 1.0 - f64::EPSILON / 2.0;
        for (chunk, numbers) in points.chunks_exact(4).zip(us.chunks_exact(4)) {
            let px = std::array::from_fn(|k| chunk[k].x);
            let py = std::array::from_fn(|k| chunk[k].y);
            let lanes = angle_sample_lanes::<4>(&px, &py, numbers.try_into().unwrap(), &light);
            for k in 0..4 {
                let one = sample_subtended_angle(chunk[k], &light, numbers[k]);
                let lane = lanes.valid[k].then(|| {
                    (
                        DVec2::new(lanes.x[k], lanes.y[k]),
                        lanes.distance[k],
                        lanes.subtended[k],
                    )
                });
                assert_eq!(
                    format!("{lane:?}"),
                    format!("{:?}", one.map(|s| (s.point, s.distance, s.subtended))),
                    "point {}",
                    chunk[k]
                );
            }
        }
    }

    #[test]
    fn streams_differ_by_key_and_repeat_for_the_same_key() {
        let first = |seed, index, sample| Stream::new(seed, index, sample).uniform();
        assert_eq!(first(1, 2, 3), first(1, 2, 3));
        assert_ne!(first(1, 2, 3), first(1, 2, 4));
        assert_ne!(first(1, 2, 3), first(1, 3, 3));
        assert_ne!(first(1, 2, 3), first(2, 2, 3));
        // Swapping pixel and sample must not give the same stream.
        assert_ne!(first(0, 5, 9), first(0, 9, 5));
    }
}
