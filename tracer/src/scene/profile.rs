//! A radiance profile by direction: the factor by which a light's
//! radiance varies with the direction its light arrives from, as a table
//! of factors against angles, interpolated linearly and periodic over
//! the circle. A sky brighter to the south is a line light frame with
//! such a profile (`docs/model.md`, "Daylight").
//!
//! Angles are the world's: `atan2(d.y, d.x)` of the unit direction `d`
//! from a receiver towards where the light comes from. Besides the
//! factor in one direction, the profile gives the two integrals the
//! closed forms take over an interval of directions (the floor's `∫ p`,
//! a wall's `∫ p cos`), exactly: the factor is linear in the angle
//! between knots.

use std::f64::consts::TAU;

use flatray_geometry::{DVec2, cross};

/// Most knots a profile holds.
pub const MAX_KNOTS: usize = 3600;

/// Knots closer than this many radians stand at one direction.
const SAME_ANGLE: f64 = 1e-9;

/// A periodic, piecewise-linear factor over the circle of directions.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Knot angles in `[0, 2 pi)`, increasing.
    angles: Vec<f64>,
    /// The factor at each knot.
    values: Vec<f64>,
    /// `∫ p` from angle 0 to each knot.
    below: Vec<f64>,
    /// `∫ p` over the whole circle.
    total: f64,
    /// The largest factor.
    max: f64,
}

impl Profile {
    /// The profile through `knots` (world angle in radians, factor): any
    /// order, any angle (taken modulo `2 pi`), factors finite and at least
    /// 0, no two knots at one angle. One knot is a constant factor.
    pub fn new(knots: &[(f64, f64)]) -> Result<Profile, String> {
        if knots.is_empty() {
            return Err("a profile needs at least one knot".into());
        }
        if knots.len() > MAX_KNOTS {
            return Err(format!(
                "a profile holds at most {MAX_KNOTS} knots, found {}",
                knots.len()
            ));
        }
        let mut sorted = Vec::with_capacity(knots.len());
        for &(angle, value) in knots {
            if !angle.is_finite() {
                return Err(format!("a profile's angle must be finite, found {angle}"));
            }
            if !value.is_finite() || value < 0.0 {
                return Err(format!(
                    "a profile's factor must be finite and at least 0, found {value}"
                ));
            }
            sorted.push((angle.rem_euclid(TAU).min(TAU.next_down()), value));
        }
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Angles that differ by rounding (0 and 360 degrees) are one.
        let apart = |a: f64, b: f64| b - a > SAME_ANGLE;
        let wraps = sorted.len() > 1 && !apart(sorted[sorted.len() - 1].0, sorted[0].0 + TAU);
        if wraps || sorted.windows(2).any(|w| !apart(w[0].0, w[1].0)) {
            return Err("two knots of a profile stand at one direction".into());
        }
        let (angles, values): (Vec<f64>, Vec<f64>) = sorted.into_iter().unzip();
        let mut profile = Profile {
            below: vec![0.0; angles.len()],
            angles,
            values,
            total: 0.0,
            max: 0.0,
        };
        // From angle 0 to the first knot, the piece that wraps around.
        let mut sum = profile.piece_integral(profile.angles.len() - 1, 0.0, profile.angles[0]);
        for k in 0..profile.angles.len() {
            profile.below[k] = sum;
            let next = profile.angles.get(k + 1).copied().unwrap_or(TAU);
            sum += profile.piece_integral(k, profile.angles[k], next);
        }
        profile.total = sum;
        profile.max = profile.values.iter().copied().fold(0.0, f64::max);
        Ok(profile)
    }

    /// `∫ p` over the whole circle of directions: what an unobstructed
    /// receiver takes of a light of unit radiance with this profile.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The largest factor.
    pub fn max(&self) -> f64 {
        self.max
    }

    /// The factor towards direction `d` (any length but zero).
    #[inline]
    pub fn at(&self, d: DVec2) -> f64 {
        let angle = d.y.atan2(d.x).rem_euclid(TAU);
        let k = self.piece_of(angle);
        self.value_in(k, angle)
    }

    /// `∫ p` over the directions from `a` to `b`, the shorter way (at
    /// most `pi`).
    pub fn integral(&self, a: DVec2, b: DVec2) -> f64 {
        let mut sum = 0.0;
        self.pieces(a, b, |k, from, to| sum += self.piece_integral(k, from, to));
        sum
    }

    /// `∫ p cos` over the directions from `a` to `b`, the shorter way,
    /// with `cos` the cosine to unit normal `n`: what a wall of normal `n`
    /// takes.
    pub fn cosine_integral(&self, a: DVec2, b: DVec2, n: DVec2) -> f64 {
        let nu = n.y.atan2(n.x);
        let mut sum = 0.0;
        self.pieces(a, b, |k, from, to| {
            // `∫ (v + s t) cos(t + c) dt` over the piece, `t` from its knot.
            let (knot, v, s) = self.line_of(k, from);
            let c = knot - nu;
            let g = |t: f64| (v + s * t) * (t + c).sin() + s * (t + c).cos();
            sum += g(to - knot) - g(from - knot);
        });
        sum
    }

    /// Calls `each(piece, from, to)` for the parts of the arc from `a` to
    /// `b` (the shorter way) that lie between two knots, as angles in
    /// `[0, 2 pi]` with `from < to`.
    fn pieces(&self, a: DVec2, b: DVec2, mut each: impl FnMut(usize, f64, f64)) {
        let (a, b) = if cross(a, b) < 0.0 { (b, a) } else { (a, b) };
        let sweep = cross(a, b).atan2(a.dot(b));
        if sweep.is_nan() || sweep <= 0.0 {
            return;
        }
        // Unwrapped angles: the arc ends less than a turn and a half up.
        let mut from = a.y.atan2(a.x).rem_euclid(TAU);
        let end = from + sweep;
        // Each step reaches a knot, a turn's end or the arc's end.
        let mut steps = 2 * self.angles.len() + 2;
        while from < end && steps > 0 {
            steps -= 1;
            let turn = if from >= TAU { TAU } else { 0.0 };
            let local = from - turn;
            let k = self.piece_of(local);
            let next = if local < self.angles[0] {
                self.angles[0]
            } else {
                self.angles.get(k + 1).copied().unwrap_or(TAU)
            };
            let to = (turn + next).min(end);
            if to > from {
                each(k, local, to - turn);
            }
            from = to.max(from.next_up());
        }
    }

    /// The knot interval holding `angle` in `[0, 2 pi)`: the index of the
    /// last knot at or below it, or the last knot (whose piece wraps
    /// around) below the first.
    #[inline]
    fn piece_of(&self, angle: f64) -> usize {
        let n = self.angles.partition_point(|&a| a <= angle);
        if n == 0 { self.angles.len() - 1 } else { n - 1 }
    }

    /// The piece `k` as a line in the angle at `near` (a point of it, in
    /// `[0, 2 pi)`): its knot's angle (unwrapped next to `near`), value
    /// and slope.
    #[inline]
    fn line_of(&self, k: usize, near: f64) -> (f64, f64, f64) {
        let n = self.angles.len();
        let (a0, v0) = (self.angles[k], self.values[k]);
        let (mut a1, v1) = (self.angles[(k + 1) % n], self.values[(k + 1) % n]);
        if a1 <= a0 {
            a1 += TAU;
        }
        // The wrapping piece, read below its knot, starts a turn earlier.
        let a0 = if near < a0 { a0 - TAU } else { a0 };
        let a1 = if near < self.angles[k] { a1 - TAU } else { a1 };
        let slope = if a1 > a0 { (v1 - v0) / (a1 - a0) } else { 0.0 };
        (a0, v0, slope)
    }

    #[inline]
    fn value_in(&self, k: usize, angle: f64) -> f64 {
        let (knot, v, s) = self.line_of(k, angle);
        (v + s * (angle - knot)).max(0.0)
    }

    /// `∫ p` from `from` to `to`, both in piece `k` (in `[0, 2 pi]`).
    fn piece_integral(&self, k: usize, from: f64, to: f64) -> f64 {
        if to <= from {
            return 0.0;
        }
        let (knot, v, s) = self.line_of(k, from);
        let f = |t: f64| v * t + 0.5 * s * t * t;
        f(to - knot) - f(from - knot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn dir(angle: f64) -> DVec2 {
        DVec2::new(angle.cos(), angle.sin())
    }

    /// A midpoint sum of `f` over `[a, b]` in `n` steps.
    fn quadrature(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        (0..n).map(|i| f(a + (i as f64 + 0.5) * h)).sum::<f64>() * h
    }

    fn south() -> Profile {
        // Brighter towards +y, darker towards -y, knots out of order and
        // one past a turn.
        Profile::new(&[
            (0.5 * PI, 1.5),
            (-0.5 * PI, 0.5),
            (0.2, 1.0),
            (PI + 0.3, 0.8),
            (TAU + 2.0, 1.2),
        ])
        .unwrap()
    }

    #[test]
    fn the_factor_runs_through_the_knots_and_between_them_linearly() {
        let p = south();
        assert!((p.at(dir(0.5 * PI)) - 1.5).abs() < 1e-12);
        assert!((p.at(dir(-0.5 * PI)) - 0.5).abs() < 1e-12);
        assert!((p.at(dir(2.0)) - 1.2).abs() < 1e-12);
        // Half-way from 0.5 pi to 2.0.
        let mid = 0.5 * (0.5 * PI + 2.0);
        assert!((p.at(dir(mid)) - 0.5 * (1.5 + 1.2)).abs() < 1e-12);
        // Across the wrap: from 1.5 pi (0.5) to 0.2 (1.0).
        let (a, b) = (1.5 * PI, TAU + 0.2);
        let at = a + 0.25 * (b - a);
        assert!((p.at(dir(at)) - (0.5 + 0.25 * 0.5)).abs() < 1e-12);
        assert_eq!(p.max(), 1.5);
    }

    #[test]
    fn one_knot_is_a_constant() {
        let p = Profile::new(&[(1.0, 0.7)]).unwrap();
        for k in 0..16 {
            assert!((p.at(dir(k as f64 * 0.4)) - 0.7).abs() < 1e-15);
        }
        assert!((p.total() - 0.7 * TAU).abs() < 1e-12);
        let (a, b) = (dir(0.3), dir(2.9));
        assert!((p.integral(a, b) - 0.7 * 2.6).abs() < 1e-12);
        assert!((p.integral(b, a) - 0.7 * 2.6).abs() < 1e-12);
    }

    #[test]
    fn the_integrals_are_the_quadratures_of_the_factor() {
        let p = south();
        let total = quadrature(|t| p.at(dir(t)), 0.0, TAU, 200_000);
        assert!((p.total() - total).abs() < 1e-8, "{} {total}", p.total());
        for (from, sweep) in [
            (0.1, 0.5),
            (-2.0, 3.0),
            (1.4, PI - 1e-3),
            (5.9, 1.0),
            (3.0, 1e-7),
        ] {
            let (a, b) = (dir(from), dir(from + sweep));
            let want = quadrature(|t| p.at(dir(t)), from, from + sweep, 100_000);
            let got = p.integral(a, b);
            assert!(
                (got - want).abs() < 1e-8 * sweep.max(1e-3),
                "{from} {sweep}: {got} {want}"
            );
            assert!((p.integral(b, a) - got).abs() < 1e-13);
            for nu in [0.0, 1.0, -2.5] {
                let n = dir(nu);
                let want = quadrature(
                    |t| p.at(dir(t)) * (t - nu).cos(),
                    from,
                    from + sweep,
                    100_000,
                );
                let got = p.cosine_integral(a, b, n);
                assert!(
                    (got - want).abs() < 1e-8,
                    "{from} {sweep} {nu}: {got} {want}"
                );
            }
        }
        // No sweep, no light.
        assert_eq!(p.integral(dir(1.0), dir(1.0)), 0.0);
    }

    #[test]
    fn bad_tables_are_refused() {
        assert!(Profile::new(&[]).is_err());
        assert!(Profile::new(&[(0.0, -1.0)]).is_err());
        assert!(Profile::new(&[(0.0, f64::NAN)]).is_err());
        assert!(Profile::new(&[(f64::INFINITY, 1.0)]).is_err());
        assert!(Profile::new(&[(0.0, 1.0), (TAU, 2.0)]).is_err());
    }
}
