//! The rough mirror's lobe: a Gaussian about the mirror direction in the
//! sine of the angle from the normal, folded back at grazing incidence.
//!
//! Write a direction `w` leaving a wall side of unit normal `n` as its
//! sine `s = t . w` along the tangent `t = n.perp()`, in `(-1, 1)`, with
//! `ds = cos(theta) dtheta`. The mirror sends `s_o` to `-s_o`. The lobe
//! draws `s_i = -s_o + sigma z` (`z` standard normal) and folds it back
//! into `(-1, 1)` at each end, as a reflecting boundary does: its density
//! `q(s_i | s_o)` is the heat kernel on `(-1, 1)` with reflecting ends,
//! the sum of the Gaussian's images.
//!
//! That kernel is symmetric and integrates to 1 over `s_i` for every
//! `s_o`, so the BSDF `f(wo, wi) = tint q(s_i | s_o)` is reciprocal
//! (`f(wo, wi) = f(wi, wo)`) and reflects exactly `tint` of the light
//! from every direction (`∫ f cos dtheta = tint ∫ q ds = tint`). Sampling
//! draws exactly `f cos`: the weight `f cos / pdf` is `tint`. As `sigma`
//! goes to 0 the lobe becomes the mirror; as it grows it flattens towards
//! `q = 1/2`, the Lambertian `f = rho / 2` (at the format's widest,
//! `sigma = 1`, `q` still runs from 0.22 to 0.8).

use std::f64::consts::TAU;

use flatray_geometry::DVec2;

/// Beyond this many standard deviations a Gaussian image adds less than
/// `1e-16` of the peak: left out.
const REACH: f64 = 8.6;

/// The lobe's density per unit of `s_i`, the sine of the outgoing
/// direction, for light arriving at sine `s_o`, of spread `sigma > 0`.
#[inline]
pub(super) fn density(sigma: f64, s_o: f64, s_i: f64) -> f64 {
    let centre = -s_o;
    let reach = REACH * sigma;
    let norm = 1.0 / (sigma * (TAU).sqrt());
    let gauss = |d: f64| {
        if d.abs() > reach {
            0.0
        } else {
            let x = d / sigma;
            (-0.5 * x * x).exp()
        }
    };
    // The images of the centre under reflection at 1 and -1: centre + 4k
    // and 2 - centre + 4k, for every k whose image lies within reach.
    let most = ((reach + 4.0) / 4.0).ceil() as i32;
    let mut sum = 0.0;
    for k in -most..=most {
        let shift = 4.0 * k as f64;
        sum += gauss(s_i - centre - shift) + gauss(s_i - (2.0 - centre) - shift);
    }
    sum * norm
}

/// A sine `s_i` drawn from [`density`] with two uniform numbers in
/// `[0, 1)`.
#[inline]
pub(super) fn sample(sigma: f64, s_o: f64, (u1, u2): (f64, f64)) -> f64 {
    // Box-Muller: one standard normal number.
    let z = (-2.0 * (1.0 - u1).ln()).sqrt() * (TAU * u2).cos();
    let s = -s_o + sigma * z;
    // Folded into (-1, 1): the period is 4, and the second half runs back.
    let m = (s + 1.0).rem_euclid(4.0);
    let m = if m > 2.0 { 4.0 - m } else { m };
    (m - 1.0).clamp(-1.0, 1.0)
}

/// The sine of unit direction `w` (pointing away from the wall) along
/// the tangent of unit normal `n`, and its cosine to `n`.
#[inline]
pub(super) fn sine_cosine(n: DVec2, w: DVec2) -> (f64, f64) {
    (n.perp().dot(w), n.dot(w))
}

/// The unit direction away from the wall of sine `s` along the tangent of
/// unit normal `n`.
#[inline]
pub(super) fn direction(n: DVec2, s: f64) -> DVec2 {
    n * (1.0 - s * s).max(0.0).sqrt() + n.perp() * s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The density integrates to 1 over the sines and is symmetric, for
    /// narrow and wide lobes and arrivals near grazing.
    #[test]
    fn the_lobe_is_a_symmetric_density() {
        for sigma in [0.02, 0.1, 0.3, 1.0] {
            for s_o in [-0.99, -0.5, 0.0, 0.3, 0.95] {
                let m = 200_000;
                let sum: f64 = (0..m)
                    .map(|k| {
                        let s = -1.0 + 2.0 * (k as f64 + 0.5) / m as f64;
                        density(sigma, s_o, s) * 2.0 / m as f64
                    })
                    .sum();
                assert!((sum - 1.0).abs() < 1e-6, "sigma {sigma}, s_o {s_o}: {sum}");
                for s_i in [-0.9, -0.2, 0.4, 0.99] {
                    let (a, b) = (density(sigma, s_o, s_i), density(sigma, s_i, s_o));
                    assert!((a - b).abs() <= 1e-12 * a.max(1.0), "{a} {b}");
                }
            }
        }
        // Widest, the lobe is still brightest about the mirror direction,
        // and much flatter than a narrow one; far wider, it is Lambertian
        // (q = 1/2).
        assert!(density(1.0, 0.3, -0.3) > density(1.0, 0.3, 0.6));
        assert!(density(1.0, 0.3, -0.3) < 0.7);
        assert!((density(3.0, 0.3, 0.9) - 0.5).abs() < 1e-4);
    }

    /// Samples fall inside `[-1, 1]`, and their histogram matches the
    /// density within 4 standard errors per bin (a chi-square in spirit:
    /// each bin tested alone).
    #[test]
    fn samples_follow_the_density() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for (sigma, s_o) in [(0.05, 0.2), (0.3, -0.8), (0.8, 0.6)] {
            let bins = 40;
            let n = 400_000;
            let mut counts = vec![0u32; bins];
            for _ in 0..n {
                let s = sample(sigma, s_o, (uniform(), uniform()));
                assert!((-1.0..=1.0).contains(&s));
                let b = (((s + 1.0) / 2.0 * bins as f64) as usize).min(bins - 1);
                counts[b] += 1;
            }
            for (b, &count) in counts.iter().enumerate() {
                let (lo, hi) = (
                    -1.0 + 2.0 * b as f64 / bins as f64,
                    -1.0 + 2.0 * (b + 1) as f64 / bins as f64,
                );
                let steps = 400;
                let p: f64 = (0..steps)
                    .map(|k| {
                        let s = lo + (hi - lo) * (k as f64 + 0.5) / steps as f64;
                        density(sigma, s_o, s) * (hi - lo) / steps as f64
                    })
                    .sum();
                let expected = p * n as f64;
                let se = (expected * (1.0 - p)).sqrt().max(1.0);
                assert!(
                    (count as f64 - expected).abs() < 4.0 * se + 2.0,
                    "sigma {sigma}, bin {b}: {count} against {expected:.1}"
                );
            }
        }
    }
}
