//! Photons from a line or circle light aimed at the mirror and glass
//! edges, for the caustic pass: what reaches a receiver from such a light
//! after a run of mirror and glass events that no closed form takes
//! (light that enters a glass body and leaves it, or reflects inside it
//! first, and so on).
//!
//! A photon leaves a uniform point `y` of the light (of the rim, for a
//! circle) on a side it emits to, in a direction drawn from the parts of
//! that side's half-circle that meet the targets, cosine-weighted: with
//! `s` the sine of the angle from the normal, `cos(phi) d phi = d s`, so a
//! target seen from `y` is an interval of `s`, drawn uniformly. A line or
//! circle light emits `I cos(phi)` per radian per unit length (its power,
//! `2 I` per unit length and side, `LightShape::power`); so a photon that
//! stands for the whole light's power towards the targets carries
//! `I L M(y) / holding` over the number of photons, with `L` the light's
//! length, `M(y)` the sum of the targets' intervals of `s` at `y`, and
//! `holding` how many of them hold the direction drawn (targets can hide
//! one another).

use flatray_geometry::{DVec2, Segment};

use crate::sampling::Stream;
use crate::scene::{EMITTING_SIDE, LightShape};

/// Points along the light at which [`Aim::new`] averages the targets'
/// measure: only the shares of the lights' photons depend on it, never a
/// photon's expected power.
const MEASURE_POINTS: usize = 256;

/// The least mean measure a light takes its share of the photons by.
const MIN_MEAN: f64 = 1e-9;

/// A line or circle light's photons towards `targets`.
pub(crate) struct Aim {
    shape: LightShape,
    targets: Vec<Segment>,
    /// The light's length (the rim's, for a circle).
    length: f64,
    /// The mean over the light of the targets' measure `M(y)`.
    mean: f64,
}

/// A photon drawn by [`Aim::draw`]: where it leaves, its direction, and
/// `L M(y) / holding`, its power over the light's intensity and
/// the photons that the whole light's aimed power is split into.
pub(crate) struct Aimed {
    pub origin: DVec2,
    pub dir: DVec2,
    pub factor: f64,
}

impl Aim {
    /// `None` for a light that is not a line or a circle, or no target.
    pub(crate) fn new(shape: LightShape, targets: Vec<Segment>) -> Option<Aim> {
        let length = match shape {
            LightShape::Line { segment, .. } => segment.length(),
            LightShape::Circle { radius, .. } => std::f64::consts::TAU * radius,
            _ => return None,
        };
        let mut aim = Aim {
            shape,
            targets,
            length,
            mean: 0.0,
        };
        let mut intervals = Vec::new();
        let mut sum = 0.0;
        for k in 0..MEASURE_POINTS {
            let u = (k as f64 + 0.5) / MEASURE_POINTS as f64;
            for (y, normal) in aim.points(u) {
                intervals.clear();
                sum += aim.intervals(y, normal, &mut intervals);
            }
        }
        // A light that sees the targets only between the points looked at
        // still sends photons, rarely (each then carries the more): its
        // light after mirrors and glass is the photons' alone.
        aim.mean = (sum / MEASURE_POINTS as f64).max(MIN_MEAN);
        (aim.mean.is_finite() && length > 0.0 && length.is_finite() && !aim.targets.is_empty())
            .then_some(aim)
    }

    /// The light's power towards the targets, per unit intensity
    /// (estimated; it only shares the photons among the lights).
    pub(crate) fn measure(&self) -> f64 {
        self.length * self.mean
    }

    /// The point at `u` along the light and the normals of the sides it
    /// emits to there.
    fn points(&self, u: f64) -> impl Iterator<Item = (DVec2, DVec2)> + use<> {
        let mut out = [None, None];
        match self.shape {
            LightShape::Line {
                segment, one_sided, ..
            } => {
                let y = segment.point_at(u);
                out[0] = Some((y, segment.normal_on(EMITTING_SIDE)));
                if !one_sided {
                    out[1] = Some((y, segment.normal_on(EMITTING_SIDE.flip())));
                }
            }
            LightShape::Circle { at, radius } => {
                let (s, c) = (std::f64::consts::TAU * u).sin_cos();
                let normal = DVec2::new(c, s);
                out[0] = Some((at + normal * radius, normal));
            }
            _ => {}
        }
        out.into_iter().flatten()
    }

    /// The targets' intervals of `s` (the sine from `normal`, along
    /// `normal.perp()`) seen from `y` in front of it, into `out` (with the
    /// normal), and their measure.
    fn intervals(&self, y: DVec2, normal: DVec2, out: &mut Vec<(DVec2, f64, f64)>) -> f64 {
        let mut sum = 0.0;
        for target in &self.targets {
            let (a, b) = (target.a - y, target.b - y);
            let (ca, cb) = (a.dot(normal), b.dot(normal));
            // The part of the target in front of the light's side.
            let (a, b) = match (ca > 0.0, cb > 0.0) {
                (false, false) => continue,
                (true, true) => (a, b),
                (true, false) => (a, a + (b - a) * (ca / (ca - cb))),
                (false, true) => (b, a + (b - a) * (ca / (ca - cb))),
            };
            let sine = |v: DVec2| {
                let l = v.length();
                if l > 0.0 {
                    normal.perp().dot(v) / l
                } else {
                    0.0
                }
            };
            let (sa, sb) = (sine(a), sine(b));
            let (lo, hi) = (sa.min(sb).max(-1.0), sa.max(sb).min(1.0));
            if hi > lo {
                out.push((normal, lo, hi));
                sum += hi - lo;
            }
        }
        sum
    }

    /// A photon, from three numbers of `stream`; `None` where the point
    /// drawn sees no target (a photon of no power).
    pub(crate) fn draw(
        &self,
        stream: &mut Stream,
        scratch: &mut Vec<(DVec2, f64, f64)>,
    ) -> Option<Aimed> {
        let u = stream.uniform();
        scratch.clear();
        let mut y = DVec2::ZERO;
        let mut measure = 0.0;
        for (point, normal) in self.points(u) {
            y = point;
            measure += self.intervals(point, normal, scratch);
        }
        if measure <= 0.0 || measure.is_nan() {
            return None;
        }
        // An interval by its width, and `s` uniform in it.
        let mut pick = stream.uniform() * measure;
        let mut chosen = scratch.last().copied()?;
        for &interval in scratch.iter() {
            let width = interval.2 - interval.1;
            if pick < width {
                chosen = interval;
                break;
            }
            pick -= width;
        }
        let (normal, lo, hi) = chosen;
        let s = lo + (hi - lo) * stream.uniform();
        let dir = normal * (1.0 - s * s).max(0.0).sqrt() + normal.perp() * s;
        let holding = scratch
            .iter()
            .filter(|&&(n, a, b)| n == normal && a <= s && s <= b)
            .count()
            .max(1);
        Some(Aimed {
            origin: y,
            dir,
            factor: self.length * measure / holding as f64,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatray_geometry::Ray;

    /// The photons of a two-sided line light aimed at two targets, one
    /// partly behind the other, carry on average the light's power
    /// towards either (per unit intensity, `int dy int cos(phi) dphi`
    /// over the directions that meet one of them, by a fine grid of
    /// points and directions), to 4 standard errors; and every photon
    /// meets a target.
    #[test]
    fn aimed_photons_carry_the_power_towards_the_targets() {
        let shape = LightShape::Line {
            segment: Segment::new(DVec2::new(0.0, 0.0), DVec2::new(4.0, 1.0)),
            one_sided: false,
            wall: None,
        };
        let targets = vec![
            Segment::new(DVec2::new(1.0, 3.0), DVec2::new(5.0, 4.0)),
            Segment::new(DVec2::new(3.0, 5.0), DVec2::new(8.0, 5.5)),
            Segment::new(DVec2::new(-2.0, -3.0), DVec2::new(2.0, -2.0)),
        ];
        let aim = Aim::new(shape, targets.clone()).unwrap();
        let meets = |origin: DVec2, dir: DVec2| {
            targets.iter().any(|t| {
                flatray_geometry::intersect(&Ray::new(origin, dir), t)
                    .is_some_and(|h| h.u > 0.0 && h.u < 1.0)
            })
        };
        let mut stream = Stream::new(3, 4, 5);
        let mut scratch = Vec::new();
        let draws = 200_000;
        let (mut sum, mut squares) = (0.0, 0.0);
        for _ in 0..draws {
            let photon = aim.draw(&mut stream, &mut scratch).unwrap();
            assert!(meets(photon.origin, photon.dir));
            sum += photon.factor;
            squares += photon.factor * photon.factor;
        }
        let mean = sum / draws as f64;
        let error = ((squares / draws as f64 - mean * mean) / draws as f64).sqrt();
        // The same power on a grid.
        let LightShape::Line { segment, .. } = shape else {
            unreachable!()
        };
        let (points, angles) = (400, 4000);
        let mut expected = 0.0;
        for i in 0..points {
            let y = segment.point_at((i as f64 + 0.5) / points as f64);
            for k in 0..angles {
                let phi = std::f64::consts::TAU * (k as f64 + 0.5) / angles as f64;
                let dir = DVec2::new(phi.cos(), phi.sin());
                if meets(y, dir) {
                    let normal = segment.normal_on(flatray_geometry::Side::Positive);
                    expected += normal.dot(dir).abs();
                }
            }
        }
        expected *= segment.length() / points as f64 * std::f64::consts::TAU / angles as f64;
        assert!(
            (mean - expected).abs() < 4.0 * error + 2e-3 * expected,
            "{mean} +- {error} against {expected}"
        );
    }
}
