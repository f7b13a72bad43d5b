//! Points, spots, suns and beams seen in one flat mirror, in closed form.
//!
//! Counts one class of light paths (`Ledger::aimed_mirrors`): light from
//! a light of one direction per point, reflected once off a flat mirror,
//! arriving at the floor or at a diffuse wall. Such a light reaches a
//! receiver `x` by the mirror along exactly one path: the one the light
//! sends the receiver's image `x'` (`x` reflected in the mirror's line),
//! folded at the point `h` where it crosses the mirror. The light's own
//! sample at `x'` gives what arrives (its falloff over the path's whole
//! length, a spot's window in the direction it leaves, a beam's strip),
//! the receiver's normal reflected gives the cosine, and two shadow rays,
//! `x` to `h` and `h` to the light, the walls in the way. No sample is
//! drawn: at a floor point or a wall point the value is exact, and the
//! caustic pass, which would otherwise count these paths by photons,
//! leaves them alone.
//!
//! What it never does: take a light with an area (`exact.rs` does, through
//! mirrors), a curved mirror, or more than one reflection.

use flatray_geometry::{DVec2, Ray, Segment, Skip, cross};

use crate::decision::Decision;
use crate::estimators::{Receiver, transmittance};
use crate::lights::arriving;
use crate::options::RenderOptions;
use crate::scene::{LightShape, Material, MirrorShadows, Scene};
use crate::{Rgb, Stats};

/// Most pairs of a flat mirror and a point, spot, sun or beam that
/// receivers take in closed form: each pair costs every receiver point a
/// reflection and, where the mirror is in view, two shadow rays.
pub const MAX_AIMED_MIRROR_PAIRS: usize = 64;

/// Whether a light is one this closed form takes: one direction per
/// point, found by a shadow ray (not a laser, which no receiver finds).
#[inline]
pub(crate) fn is_aimed(shape: &LightShape) -> bool {
    matches!(
        shape,
        LightShape::Point { .. }
            | LightShape::Spot { .. }
            | LightShape::Directional { .. }
            | LightShape::Beam { .. }
    )
}

/// Pairs of a flat mirror and a point, spot, sun or beam.
pub(crate) fn pairs(scene: &Scene) -> usize {
    let aimed = scene.lights.iter().filter(|l| is_aimed(&l.shape)).count();
    scene.flat_mirrors.len() * aimed
}

/// Whether every run of specular events a light path can take in `scene`
/// is one reflection off one flat mirror: every wall that reflects
/// specularly is a flat mirror, and all of them lie on one line, so that
/// light one of them reflects never reaches another (two-sided mirrors
/// off one line could face each other). Where so, and the closed form
/// runs, it counts all the light of points, spots, suns and beams after
/// mirrors: none is left to photons.
pub(crate) fn takes_every_run(scene: &Scene) -> bool {
    let mut line: Option<Segment> = None;
    for wall in scene
        .walls
        .iter()
        .filter(|w| w.material.reflects_specularly())
    {
        let (Material::Mirror { .. }, Some(&segment)) = (wall.material, wall.as_segment()) else {
            return false;
        };
        let Some(first) = line else {
            line = Some(segment);
            continue;
        };
        let along = first.b - first.a;
        let length = along.length();
        // Off the line by more than rounding in the points' size: light
        // off one mirror could reach the other.
        let on_line = |p: DVec2| {
            let off = cross(along, p - first.a).abs();
            let size = first
                .a
                .abs()
                .max(first.b.abs())
                .max(p.abs())
                .max_element()
                .max(length);
            length > 0.0 && off <= 1e-12 * length * size.max(1.0)
        };
        if !(on_line(segment.a) && on_line(segment.b)) {
            return false;
        }
    }
    true
}

/// Where receivers take points, spots, suns and beams seen in one flat
/// mirror in closed form, and why: wherever shadow rays are cast and
/// mirrors reflect, within [`MAX_AIMED_MIRROR_PAIRS`].
pub(crate) fn decide(scene: &Scene, options: &RenderOptions, shadows: bool) -> Decision {
    let terms = super::Terms {
        pairs: pairs(scene),
        most: MAX_AIMED_MIRROR_PAIRS,
        pair: "flat mirror and light pair",
        none: "no flat mirror and point, spot, directional light or beam in the scene",
        event: "reflected",
        otherwise: "the caustic pass takes them",
        runs: "every floor and wall point takes them exactly, by the path to its image; the caustic pass leaves them alone",
    };
    super::decide(options, shadows, terms, None)
}

/// The light that every point, spot, sun and beam (or light `light`
/// alone) brings `x` after exactly one reflection off one of the scene's
/// flat mirrors, tinted by the mirror and coloured by the light.
pub(crate) fn aimed_in_mirrors(
    scene: &Scene,
    light: Option<usize>,
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    let lights = match light {
        Some(index) => index..index.saturating_add(1).min(scene.lights.len()),
        None => 0..scene.lights.len(),
    };
    let shadows = scene.mirror_shadows.get_or_init(|| mirror_shadows(scene));
    let mut sum = Rgb::ZERO;
    for index in lights {
        let shape = &scene.lights[index].shape;
        if !is_aimed(shape) {
            continue;
        }
        let mut of_light = Rgb::ZERO;
        for (k, &m) in scene.flat_mirrors.iter().enumerate() {
            let hidden = shadows
                .get(index)
                .and_then(|of_light| of_light.get(k))
                .map_or(&[][..], |h| &h[..]);
            let wall = &scene.walls[m as usize];
            let Material::Mirror { tint } = wall.material else {
                continue;
            };
            // A receiver on the mirror, or a light on it, meets no
            // reflection there.
            if tint == Rgb::ZERO
                || receiver.wall == Some(m)
                || scene.light_wall[index] == Some(m)
                || wholly_hidden(hidden)
            {
                continue;
            }
            let Some(mirror) = wall.as_segment() else {
                continue;
            };
            of_light += tint * in_mirror(scene, index, (m, mirror, hidden), x, receiver, stats);
        }
        sum += of_light * scene.lights[index].color;
    }
    sum
}

/// What light `index` brings `x` off mirror `m` (its segment `mirror`),
/// uncoloured and untinted by the mirror (tinted by the panes it
/// crosses), times the light's intensity.
fn in_mirror(
    scene: &Scene,
    index: usize,
    (m, mirror, hidden): (u32, &Segment, &[(f64, f64)]),
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    // A point on the mirror's line sees it edge-on.
    let side = mirror.side_value(x);
    if side == 0.0 || !side.is_finite() {
        return Rgb::ZERO;
    }
    let e = mirror.b - mirror.a;
    let image = reflect_point(mirror, x);
    // The light's number: points, spots, suns and beams draw none.
    let Some(s) = light.shape.incident(light, image, 0.5, scene.small_radius) else {
        return Rgb::ZERO;
    };
    if s.at_the_light() {
        return Rgb::ZERO;
    }
    // Where the ray from the image towards the light crosses the mirror's
    // line (`image + t to = a + u e`): within the segment, before the
    // light. A light on the image's side of the line is never crossed to.
    let denom = cross(s.to, e);
    let rel = mirror.a - image;
    let t = cross(rel, e) / denom;
    let u = cross(rel, s.to) / denom;
    if !(t > 0.0 && t < s.t_max && u > 0.0 && u < 1.0) {
        return Rgb::ZERO;
    }
    // Where walls surely hide that point of the mirror from the light,
    // nothing arrives, and no ray need say so.
    if hidden.iter().any(|&(lo, hi)| lo < u && u < hi) {
        return Rgb::ZERO;
    }
    // The receiver's normal reflected in the mirror's line, as the image
    // sees it: the cosine of the light arriving at `x`.
    let cosine = match receiver.normal {
        None => 1.0,
        Some(n) => {
            let reflected = 2.0 * e * (n.dot(e) / e.length_squared()) - n;
            reflected.dot(s.dir()).max(0.0)
        }
    };
    let v = arriving(light.intensity, s.value, cosine, s.pdf);
    if !(v > 0.0 && v.is_finite()) {
        return Rgb::ZERO;
    }
    let h = mirror.a + u * e;
    let skip_x = Skip(receiver.wall.unwrap_or(u32::MAX), m);
    stats.work.mirrored_shadow_rays += 1;
    let first = transmittance(scene, &Ray::new(x, h - x), 1.0, skip_x, None, stats);
    if first == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let skip_h = Skip(m, scene.light_wall[index].unwrap_or(u32::MAX));
    stats.work.mirrored_shadow_rays += 1;
    let second = transmittance(scene, &Ray::new(h, s.to), s.t_max - t, skip_h, None, stats);
    first * second * v
}

/// For every light and flat mirror of `scene`, the intervals of the
/// mirror's parameter that an opaque wall surely hides from the light:
/// for a point or spot at `p`, each opaque segment wholly between `p` and
/// the mirror's line (both ends strictly closer to the line, on `p`'s
/// side) hides the interval between its ends' projections from `p`; for
/// a sun, each one wholly upstream of the line hides the interval between
/// its ends' projections along the sunlight. Shrunk by a margin, so that
/// a point inside one is hidden whatever the rounding of its ray. Beams,
/// arcs and panes hide nothing here (their rays decide). Empty lists
/// beyond the closed form's budget, which never asks.
fn mirror_shadows(scene: &Scene) -> MirrorShadows {
    if pairs(scene) > MAX_AIMED_MIRROR_PAIRS {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(scene.lights.len());
    for (index, light) in scene.lights.iter().enumerate() {
        let mut of_light = Vec::new();
        if !is_aimed(&light.shape) {
            out.push(of_light);
            continue;
        }
        for &m in &scene.flat_mirrors {
            let mut hidden = Vec::new();
            if let Some(mirror) = scene.walls[m as usize].as_segment() {
                for (w, wall) in scene.walls.iter().enumerate() {
                    let w = w as u32;
                    if w == m || scene.light_wall[index] == Some(w) {
                        continue;
                    }
                    if wall.material.pane_tint().is_some() {
                        continue;
                    }
                    let Some(segment) = wall.as_segment() else {
                        continue;
                    };
                    let interval = match light.shape {
                        LightShape::Point { at } | LightShape::Spot { at, .. } => {
                            shadow_from(segment, |q| central(mirror, at, q))
                        }
                        LightShape::Directional { direction } => {
                            shadow_from(segment, |q| parallel(mirror, direction, q))
                        }
                        _ => None,
                    };
                    hidden.extend(interval);
                }
            }
            of_light.push(merged(hidden));
        }
        out.push(of_light);
    }
    out
}

/// The union of open intervals, as disjoint ones in order: a mirror
/// wholly hidden is then one interval that holds `[0, 1]`.
fn merged(mut intervals: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    intervals.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(intervals.len());
    for (lo, hi) in intervals {
        match out.last_mut() {
            // Open intervals that overlap join; ones that only touch
            // leave their common end uncovered.
            Some(last) if lo < last.1 => last.1 = last.1.max(hi),
            _ => out.push((lo, hi)),
        }
    }
    out
}

/// Whether walls surely hide the whole mirror from the light: its one
/// merged interval holds the mirror's parameter from 0 to 1.
#[inline]
fn wholly_hidden(hidden: &[(f64, f64)]) -> bool {
    hidden
        .first()
        .is_some_and(|&(lo, hi)| lo <= 0.0 && hi >= 1.0)
}

/// The interval a segment hides of the mirror's parameter, given where
/// each end projects (`None` where an end is not wholly in front).
fn shadow_from(segment: &Segment, project: impl Fn(DVec2) -> Option<f64>) -> Option<(f64, f64)> {
    let (ua, ub) = (project(segment.a)?, project(segment.b)?);
    let (lo, hi) = (ua.min(ub), ua.max(ub));
    // A margin of a millionth of the mirror and of the parameter's
    // rounding, so that only points surely inside count.
    let margin = 1e-6 + 1e-9 * (lo.abs() + hi.abs());
    let (lo, hi) = (lo + margin, hi - margin);
    (lo < hi && hi > 0.0 && lo < 1.0).then_some((lo, hi))
}

/// Where the ray from `p` through `q` meets the mirror's line, as the
/// mirror's parameter, if `q` lies strictly between `p` and that line.
fn central(mirror: &Segment, p: DVec2, q: DVec2) -> Option<f64> {
    let (sp, sq) = (mirror.side_value(p), mirror.side_value(q));
    let ratio = sq / sp;
    if !(ratio > 1e-9 && ratio < 1.0 - 1e-9) {
        return None;
    }
    let d = q - p;
    let e = mirror.b - mirror.a;
    let denom = cross(d, e);
    let u = cross(mirror.a - p, d) / denom;
    u.is_finite().then_some(u)
}

/// Where sunlight through `q`, travelling along `direction`, meets the
/// mirror's line, as the mirror's parameter, if `q` lies strictly
/// upstream of it.
fn parallel(mirror: &Segment, direction: DVec2, q: DVec2) -> Option<f64> {
    let e = mirror.b - mirror.a;
    let denom = cross(direction, e);
    // q + s direction = a + u e: s > 0 upstream.
    let rel = mirror.a - q;
    let s = cross(rel, e) / denom;
    let u = cross(rel, direction) / denom;
    (s.is_finite() && u.is_finite() && s > 1e-9 * e.length()).then_some(u)
}

/// Reflects `p` across the line of `mirror`.
#[inline]
fn reflect_point(mirror: &Segment, p: DVec2) -> DVec2 {
    let e = mirror.b - mirror.a;
    let foot = mirror.a + e * ((p - mirror.a).dot(e) / e.length_squared());
    2.0 * foot - p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_intervals_merge_where_they_overlap_and_not_where_they_touch() {
        let m = merged(vec![
            (0.5, 0.9),
            (-0.2, 0.3),
            (0.2, 0.6),
            (1.0, 1.4),
            (0.9, 1.1),
        ]);
        assert_eq!(m, vec![(-0.2, 0.9), (0.9, 1.4)]);
        // Two walls that meet leave the point between them open: the
        // mirror is not wholly hidden.
        assert!(!wholly_hidden(&m));
        assert!(wholly_hidden(&merged(vec![(0.4, 1.2), (-0.1, 0.5)])));
        assert!(!wholly_hidden(&merged(vec![(0.0001, 1.2)])));
        assert!(!wholly_hidden(&[]));
    }

    /// A black mirror sends no light on: the closed form neither walks it
    /// nor counts it against its budget, nor does it stop the closed form
    /// from taking every run.
    #[test]
    fn black_mirrors_are_left_out_of_the_pairs() {
        use crate::scene::{Canvas, Falloff, Floor, Light, Wall};
        let wall = |a: (f64, f64), b: (f64, f64), tint: Rgb| {
            Wall::segment(
                DVec2::new(a.0, a.1),
                DVec2::new(b.0, b.1),
                Material::Mirror { tint },
            )
        };
        let walls = vec![
            wall((10.0, 10.0), (50.0, 10.0), Rgb::splat(0.9)),
            // Facing the first mirror, and black.
            wall((10.0, 30.0), (50.0, 30.0), Rgb::ZERO),
        ];
        let lights = vec![Light {
            profile: None,
            shape: LightShape::Point {
                at: DVec2::new(30.0, 20.0),
            },
            color: Rgb::ONE,
            intensity: 1.0,
            falloff: Falloff::Flatland,
            spectrum: None,
        }];
        let canvas = Canvas {
            width: 60,
            height: 40,
            origin: DVec2::ZERO,
        };
        let scene =
            Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, lights).expect("a valid scene");
        assert_eq!(scene.flat_mirrors, vec![0]);
        assert_eq!(pairs(&scene), 1);
        assert!(takes_every_run(&scene));
    }
}
