//! The falloff kernel a light's photons carry on their first flight.

use crate::scene::Falloff;

/// How the first flight of a photon reproduces its light's kernel: the
/// photon density of a point light in the plane already falls as `1 / r`
/// (`Flatland`), so a flight at distance `r` is weighted by `G(r') r`
/// (`r' = max(r, r0)`) for a point and `G(r') r'` for a line light, the
/// per-radian term of `Falloff::per_radian`. Both are 1 for `Flatland`
/// beyond `r0`.
#[derive(Clone, Copy, Debug)]
pub(crate) enum PhotonKernel {
    None,
    Point(Falloff),
    Line(Falloff),
}

impl PhotonKernel {
    #[inline]
    pub(crate) fn factor(self, r: f64, r0: f64) -> f64 {
        match self {
            PhotonKernel::None => 1.0,
            PhotonKernel::Point(falloff) => falloff.g(r, r0) * r,
            PhotonKernel::Line(falloff) => falloff.per_radian(r, r0),
        }
    }

    /// Whether the factor is 1 everywhere beyond `r0`, so a flight needs no
    /// per-pixel evaluation there.
    pub(crate) fn is_flat_beyond_r0(self) -> bool {
        match self {
            PhotonKernel::None => true,
            PhotonKernel::Point(f) | PhotonKernel::Line(f) => f == Falloff::Flatland,
        }
    }

    /// The factor's integral over distances `s0..s1` from the light
    /// (`0 <= s0 <= s1`), in closed form: what a pixel crossing between
    /// those distances adds per unit of scaled power, so the track-length
    /// estimate of a pixel's mean fluence has the kernel's exact mean
    /// along the crossing, not its value at one point.
    ///
    /// Below `r0` the distance is clamped: a point's factor is `G(r0) s`,
    /// a line's `G(r0) r0`. Beyond it both are `G(s) s`: 1, `1 / s`,
    /// `(1 - s / R)^2 s` up to the window's range `R`, or `s`.
    pub(crate) fn integral(self, s0: f64, s1: f64, r0: f64) -> f64 {
        let falloff = match self {
            PhotonKernel::None => return s1 - s0,
            PhotonKernel::Point(f) | PhotonKernel::Line(f) => f,
        };
        let mut sum = 0.0;
        let (a, b) = (s0, s1.min(r0));
        if b > a {
            sum += match self {
                PhotonKernel::Point(_) => falloff.g(r0, r0) * (b - a) * (0.5 * (a + b)),
                _ => falloff.per_radian(r0, r0) * (b - a),
            };
        }
        let (a, b) = (s0.max(r0), s1);
        if b > a {
            sum += match falloff {
                Falloff::Flatland => b - a,
                Falloff::InverseSquare if a > 0.0 => ((b - a) / a).ln_1p(),
                Falloff::InverseSquare => f64::INFINITY,
                Falloff::Window { range } => {
                    let b = b.min(range);
                    if b > a {
                        // A cubic: Simpson's rule is exact.
                        let f = |s: f64| {
                            let w = 1.0 - s / range;
                            w * w * s
                        };
                        (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))
                    } else {
                        0.0
                    }
                }
                Falloff::Constant => (b - a) * (0.5 * (a + b)),
            };
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form integral of every kernel's factor matches a fine
    /// midpoint rule over the factor itself, across `r0` and the window's
    /// range, and from the light out to far away.
    #[test]
    fn a_kernel_integral_is_the_integral_of_its_factor() {
        let r0 = 0.5;
        let falloffs = [
            Falloff::Flatland,
            Falloff::InverseSquare,
            Falloff::Window { range: 3.7 },
            Falloff::Constant,
        ];
        let spans = [
            (0.0, 0.3),
            (0.0, 0.5),
            (0.2, 0.9),
            (0.5, 2.0),
            (3.0, 4.5),
            (5.0, 5.001),
            (1e6, 1e6 + 0.7),
        ];
        for falloff in falloffs {
            for kernel in [
                PhotonKernel::Point(falloff),
                PhotonKernel::Line(falloff),
                PhotonKernel::None,
            ] {
                for (s0, s1) in spans {
                    let n = 200_000;
                    let h = (s1 - s0) / n as f64;
                    let numeric: f64 = (0..n)
                        .map(|k| kernel.factor(s0 + (k as f64 + 0.5) * h, r0) * h)
                        .sum();
                    let exact = kernel.integral(s0, s1, r0);
                    assert!(
                        (exact - numeric).abs() <= 1e-7 * numeric.abs().max(1e-12),
                        "{kernel:?} over {s0}..{s1}: {exact} against {numeric}"
                    );
                }
            }
        }
    }
}
