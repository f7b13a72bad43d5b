//! How far a path goes: diffuse reflections are counted against
//! `RenderOptions::bounces`, specular events (mirrors, glass) in a row
//! against `RenderOptions::specular`, with Russian roulette on long runs.
//! The path tracer, the light tracer and the caustic pass count alike, so
//! they estimate the same truncated model (`docs/model.md`).
//!
//! It never decides what a material does: it only counts the events the
//! integrators report.

use flatray_geometry::{Segment, Shape, Side};

use crate::sampling::Stream;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Specular events in a row up to which a path always goes on; past
/// them, Russian roulette decides.
pub const ROULETTE_FROM: u32 = 8;

/// How far paths go: most diffuse reflections, most specular events in a
/// row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Limits {
    pub bounces: u32,
    pub specular: u32,
}

impl Limits {
    /// How far the paths of a render with `options` go.
    pub(crate) fn of(options: &crate::options::RenderOptions) -> Limits {
        Limits {
            bounces: options.bounces,
            specular: options.specular,
        }
    }
}

/// The specular events since a path (or photon) left the floor, a light
/// or its last diffuse wall, and its throughput then.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Run {
    events: u32,
    start: f64,
}

/// What a specular event leaves of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Onward {
    /// The path goes on, its throughput multiplied by this (1 before the
    /// roulette, `1 / q` for a survivor of it).
    Go(f64),
    /// The run is longer than the limit.
    Limit,
    /// Russian roulette ended it.
    Roulette,
}

impl Run {
    /// A run starting at `throughput`.
    #[inline]
    pub fn new(throughput: Rgb) -> Run {
        Run {
            events: 0,
            start: throughput.max_element(),
        }
    }

    /// One more specular event, after which the path's throughput is
    /// `throughput`: the factor its throughput takes if it goes on, or
    /// `None` where it stops (counted in `stats`: the limit, or the
    /// roulette).
    #[inline]
    pub fn next(
        &mut self,
        limit: u32,
        throughput: Rgb,
        stream: &mut Stream,
        stats: &mut Stats,
    ) -> Option<f64> {
        match self.event(limit, throughput, stream) {
            Onward::Go(weight) => Some(weight),
            Onward::Limit => {
                stats.physics.paths_bounce_limit += 1;
                None
            }
            Onward::Roulette => {
                stats.physics.paths_roulette += 1;
                None
            }
        }
    }

    /// One more specular event, after which the path's throughput is
    /// `throughput`: whether it goes on, at most `limit` events in a row.
    /// Past [`ROULETTE_FROM`] events it survives with probability
    /// `q = min(1, max(throughput) / max(throughput at the run's start))`
    /// and is then weighted by `1 / q`: the expectation is unchanged. A
    /// draw is taken from `stream` only where `q < 1`.
    #[inline]
    fn event(&mut self, limit: u32, throughput: Rgb, stream: &mut Stream) -> Onward {
        self.events += 1;
        if self.events > limit {
            return Onward::Limit;
        }
        if self.events <= ROULETTE_FROM {
            return Onward::Go(1.0);
        }
        let q = throughput.max_element() / self.start;
        // Not below 1 (or not a number, from a start of zero): go on.
        if q.partial_cmp(&1.0) != Some(std::cmp::Ordering::Less) {
            return Onward::Go(1.0);
        }
        if q > 0.0 && stream.uniform() < q {
            // A survivor's throughput, times this, peaks at its run's
            // start again.
            Onward::Go(1.0 / q)
        } else {
            Onward::Roulette
        }
    }
}

/// Most (diffuse wall, specular wall) pairs [`last_leg_sides`] tests:
/// past them every side takes its last leg.
const LAST_LEG_PAIRS: usize = 1 << 22;

/// Per wall and side (`2 * wall + side`), whether a path's last leg from
/// there (past its last diffuse bounce) can meet a light: whether a ray
/// leaving that side can reach a mirror or glass edge from which light of
/// a line or circle light can come back. A leg from a side this says
/// `false` of adds exactly nothing, so the path ends there instead; the
/// answer is conservative (a `true` may find nothing). Tolerances of
/// `1e-9` of the coordinates' magnitude keep lines grazing a wall's line
/// on the side of `true`.
///
/// A ray leaving side `s` of wall `W` travels in `W`'s half-plane on `s`,
/// so it meets a specular wall `M` only if `M` reaches into it, and
/// arrives on a side of `M` whose half-plane holds a point of `W`. After a
/// mirror it travels in that side's half-plane: it can meet a light, or
/// go on by another specular wall, only if one reaches into it. Glass
/// bends rays, so a glass edge passes light on whenever a light is in the
/// scene.
pub(crate) fn last_leg_sides(scene: &Scene) -> Vec<bool> {
    let walls = &scene.walls;
    let specular: Vec<usize> = (0..walls.len())
        .filter(|&i| walls[i].material.turns_specularly())
        .collect();
    let diffuse = walls.len() - specular.len();
    let areas = scene.lights.iter().any(|l| l.shape.has_area());
    if !areas || specular.is_empty() {
        return vec![false; 2 * walls.len()];
    }
    if diffuse.saturating_mul(specular.len()) > LAST_LEG_PAIRS
        || specular
            .len()
            .saturating_mul(specular.len() + scene.lights.len())
            > LAST_LEG_PAIRS
    {
        return vec![true; 2 * walls.len()];
    }
    let tolerance = |s: &Segment| 1e-9 * s.a.abs().max(s.b.abs()).max_element().max(1.0);
    // Whether wall `t` reaches into the half-plane of side `side` of
    // wall `s`; always, where either is an arc (which curves to both).
    let in_front = |s: &Shape, side: Side, t: &Shape| {
        let (Shape::Segment(s), Shape::Segment(t)) = (s, t) else {
            return true;
        };
        let n = s.normal_on(side);
        let tol = tolerance(s).max(tolerance(t));
        (t.a - s.a).dot(n).max((t.b - s.a).dot(n)) > -tol
    };
    // Per specular wall and side: whether light can come back from it.
    let lit: Vec<[bool; 2]> = specular
        .iter()
        .map(|&m| {
            let (true, Some(ms)) = (!walls[m].material.is_glass(), walls[m].as_segment()) else {
                return [true; 2];
            };
            [Side::Positive, Side::Negative].map(|side| {
                let n = ms.normal_on(side);
                scene
                    .lights
                    .iter()
                    .any(|l| l.shape.reaches_in_front(ms.a, n, tolerance(ms)))
                    || specular
                        .iter()
                        .any(|&o| o != m && in_front(&walls[m].shape, side, &walls[o].shape))
            })
        })
        .collect();
    let mut sides = vec![false; 2 * walls.len()];
    for (w, wall) in walls.iter().enumerate() {
        if !wall.material.is_diffuse() {
            continue;
        }
        let ws = &wall.shape;
        for side in [Side::Positive, Side::Negative] {
            sides[2 * w + side.index()] = specular.iter().zip(&lit).any(|(&m, lit)| {
                let ms = &walls[m].shape;
                in_front(ws, side, ms)
                    && [Side::Positive, Side::Negative]
                        .iter()
                        .any(|&ms_side| lit[ms_side.index()] && in_front(ms, ms_side, ws))
            });
        }
    }
    sides
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Canvas, Falloff, Floor, Light, LightShape, Material, Wall};
    use flatray_geometry::DVec2;

    /// A mirror along x = 10 with a line light on its right: walls on the
    /// right that face it take last legs; walls on its left (whose rays
    /// meet its unlit side) and a wall facing away take none; with a
    /// second mirror on the left, light can come round, and they do.
    #[test]
    fn last_legs_only_where_a_mirror_can_send_a_light_back() {
        let wall = |a: (f64, f64), b: (f64, f64), material| Wall {
            shape: Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1)).into(),
            material,
        };
        let diffuse = Material::Diffuse { albedo: None };
        let mirror = Material::Mirror { tint: Rgb::ONE };
        let light = Light {
            profile: None,
            shape: LightShape::Line {
                segment: Segment::new(DVec2::new(14.0, 1.0), DVec2::new(16.0, 1.0)),
                one_sided: false,
                wall: None,
            },
            color: Rgb::ONE,
            intensity: 1.0,
            falloff: Falloff::Flatland,
            spectrum: None,
        };
        let canvas = Canvas {
            width: 30,
            height: 20,
            origin: DVec2::ZERO,
        };
        let mut walls = vec![
            wall((10.0, 5.0), (10.0, 15.0), mirror),
            // Right of the mirror, vertical: faces it from its Negative
            // side (normal (-1, 0) for a wall from (20, 15) to (20, 5)).
            wall((20.0, 15.0), (20.0, 5.0), diffuse),
            // Left of the mirror.
            wall((2.0, 5.0), (2.0, 15.0), diffuse),
        ];
        let scene = Scene::new(
            canvas,
            Floor::Color(Rgb::ONE),
            0.5,
            walls.clone(),
            vec![light.clone()],
        )
        .expect("a valid scene");
        let sides = last_leg_sides(&scene);
        let facing = |w: usize, towards: DVec2| {
            let s = &scene.walls[w].shape.chord();
            let side = if s.normal().dot(towards) > 0.0 {
                Side::Positive
            } else {
                Side::Negative
            };
            sides[2 * w + side.index()]
        };
        let (left, right) = (DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0));
        // The right wall's side towards the mirror: yes; away from it: no.
        assert!(facing(1, left));
        assert!(!facing(1, right));
        // The left wall sees only the mirror's unlit side.
        assert!(!facing(2, right));
        assert!(!facing(2, left));
        // A mirror on the far left lights the first mirror's left side.
        walls.push(wall((0.5, 0.0), (0.5, 20.0), mirror));
        let scene = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, vec![light])
            .expect("a valid scene");
        let sides = last_leg_sides(&scene);
        let s = &scene.walls[2].shape.chord();
        let towards_mirror = if s.normal().dot(right) > 0.0 {
            Side::Positive
        } else {
            Side::Negative
        };
        assert!(sides[2 * 2 + towards_mirror.index()]);
    }

    /// Short runs go on untouched and long ones stop at the limit; past
    /// the roulette's start, the expected weight of a survivor is the
    /// throughput's loss undone: E[survives / q] = 1, within 5 standard
    /// errors over 100,000 fixed-seed trials.
    #[test]
    fn runs_stop_at_the_limit_and_the_roulette_keeps_the_mean() {
        let mut stream = Stream::new(7, 0, 0);
        let mut run = Run::new(Rgb::ONE);
        for _ in 0..ROULETTE_FROM {
            assert_eq!(
                run.event(10, Rgb::splat(0.01), &mut stream),
                Onward::Go(1.0)
            );
        }
        let mut full = Run::new(Rgb::ONE);
        for _ in 0..3 {
            assert_eq!(full.event(3, Rgb::ONE, &mut stream), Onward::Go(1.0));
        }
        assert_eq!(full.event(3, Rgb::ONE, &mut stream), Onward::Limit);

        let q = 0.3;
        let trials = 100_000;
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        for k in 0..trials {
            let mut stream = Stream::new(11, k, 0);
            let mut run = Run::new(Rgb::ONE);
            for _ in 0..ROULETTE_FROM {
                run.event(100, Rgb::ONE, &mut stream);
            }
            let w = match run.event(100, Rgb::new(0.1, q, 0.2), &mut stream) {
                Onward::Go(w) => w,
                _ => 0.0,
            };
            sum += w;
            sum2 += w * w;
        }
        let n = trials as f64;
        let mean = sum / n;
        let se = ((sum2 / n - mean * mean) / n).sqrt();
        assert!((mean - 1.0).abs() < 5.0 * se, "{mean} ± {se}");
        assert!(se > 0.0 && se < 0.01);
    }
}
