//! Direct light from a point, a spot or the sun, averaged over a pixel's
//! square of the floor in closed form.
//!
//! A point light at `p` gives the floor at `x` the value
//! `I G(|x - p|)`, times a spot's window at the direction from `p` to
//! `x`, times the transmittance of the segment between them; the sun
//! gives `I` times the transmittance along its direction. Each wall in
//! front of the light casts a shadow that is convex: the points beyond
//! the wall's line and within the rays through its ends (a strip, for
//! the sun), three half-planes. Taking each shadow out of the square, or
//! tinting its part by a pane's tint, leaves the lit part as convex
//! pieces, each with what gets through to it.
//!
//! A piece's integral of the kernel is a sum over its edges in polar
//! coordinates about the light: the edge from `a` to `b` adds, with the
//! sign of `a x b`, the integral over its angle of `F(R) w`, where `R` is
//! the distance to the edge's line in that direction, `F(R)` the
//! integral of `G(r) r` from 0 to `R` (`PhotonKernel::integral`) and `w`
//! the spot's window. Along the edge (at distance `s` from the foot of the
//! perpendicular of length `h`) that is the integral of
//! `F(sqrt(h^2 + s^2)) h / (h^2 + s^2)`, smooth between the places where
//! `R` passes the kernel's radii or the window its edges, and analytic
//! but for branch points at `s = +-ih`. Gauss-Legendre rules, split at
//! those places and wherever the branch points come near, integrate it
//! to rounding. The sun's kernel is 1: a piece brings its area.
//!
//! The result does not depend on a random number: the floor memo adds it
//! to every point of its pixel, in place of the light's shadow rays.
//! `docs/model.md` ("Direct light in closed form") states where it runs.

use std::cell::RefCell;

use flatray_geometry::{Arc, DVec2, MAX_HULL_POINTS, Ray, Shape, arc_crossings, convex_hull};

use crate::estimators::Receiver;
use crate::lights::{PhotonKernel, sun_line};
use crate::scene::{Falloff, LightShape, Scene, smooth_window};
use crate::{Rgb, Stats};

/// Pieces of a square (and parts of it a shadow covers) of no more than
/// this share of its area count for nothing: a gap that rounding leaves
/// between the shadows of two walls that share a corner lets no light
/// through, and a shadow that grazes the square changes nothing (the
/// same rule as the line light's, `exact::SLIVER`).
const SLIVER: f64 = 1e-9;

/// Most convex pieces a square may be cut into; beyond, the light is left
/// to the floor's points there.
pub(crate) const MOST_PIECES: usize = 64;

/// Whether a light's direct light on the floor can be averaged over a
/// pixel's square here: a point, a spot or the sun.
pub(crate) fn takes_square(shape: &LightShape) -> bool {
    matches!(
        shape,
        LightShape::Point { .. } | LightShape::Spot { .. } | LightShape::Directional { .. }
    )
}

/// Pixels no further than this many of their diagonals from a point or
/// spot light: there its kernel varies steeply across a pixel.
const STEEP_WITHIN: f64 = 8.0;

/// Whether a point or spot light's kernel varies steeply across the
/// square from `corner` across `step`: the light lies within
/// `STEEP_WITHIN` diagonals of it.
pub(crate) fn steep_kernel(shape: &LightShape, (corner, step): (DVec2, DVec2)) -> bool {
    let at = match *shape {
        LightShape::Point { at } | LightShape::Spot { at, .. } => at,
        _ => return false,
    };
    let (lo, hi) = (corner.min(corner + step), corner.max(corner + step));
    (at.clamp(lo, hi) - at).length() <= STEEP_WITHIN * step.length()
}

/// Where the light comes from: a point, or a direction of travel.
#[derive(Clone, Copy, Debug)]
enum Source {
    Point(DVec2),
    Sun(DVec2),
}

/// A spot's window: its direction, cone and softness.
#[derive(Clone, Copy, Debug)]
struct Window {
    direction: DVec2,
    cone: f64,
    softness: f64,
}

/// What a point light's kernel is, for the edge integrals.
#[derive(Clone, Copy, Debug)]
struct Kernel {
    falloff: Falloff,
    r0: f64,
    window: Option<Window>,
}

/// The points left of the line through `q` along `e`, the line included.
#[derive(Clone, Copy, Debug)]
struct Half {
    q: DVec2,
    e: DVec2,
}

impl Half {
    #[inline]
    fn side(self, x: DVec2) -> f64 {
        self.e.perp_dot(x - self.q)
    }
}

/// A convex piece of the square: `len` vertices from `start` in the
/// vertex buffer, and what gets through to it.
#[derive(Clone, Copy, Debug)]
struct Piece {
    start: usize,
    len: usize,
    through: Rgb,
}

/// Reused buffers, one set per thread. They grow with the walls in front
/// of one square and its light (the list, or the query's), and with the
/// pieces, within `MOST_PIECES`.
#[derive(Default)]
struct Scratch {
    walls: Vec<u32>,
    query: Vec<u32>,
    points: Vec<DVec2>,
    pieces: Vec<Piece>,
    next_points: Vec<DVec2>,
    next_pieces: Vec<Piece>,
    inside: Vec<DVec2>,
    outside: Vec<DVec2>,
    rest: Vec<DVec2>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// What a light gives a pixel's square of the floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Square {
    /// No wall's shadow covers any of the square, and the light's kernel
    /// varies gently across it: the light reaches every point whole, and
    /// the pixel's points take it (their transmittance is 1).
    Uniform,
    /// The light's mean over the square, coloured.
    Mean(Rgb),
}

/// What light `index` (a point, a spot or the sun) gives the floor over
/// the pixel square from `corner` across `step`. With `known`, every
/// point of the square has that transmittance (the plan casts no shadow
/// rays, or the coherence masks proved it); else the walls of
/// `receiver`'s list towards the light (or a query of the walls, without
/// one) shade it. `None` where the light is of another kind, an arc may
/// shade the square, or the walls cut it into more than `MOST_PIECES`:
/// the floor's points take the light there.
///
/// Which of these it is depends on the scene alone, not on the list: a
/// wall whose shadow covers none of the square changes nothing.
pub(crate) fn square_light(
    scene: &Scene,
    index: usize,
    (corner, step): (DVec2, DVec2),
    receiver: Receiver,
    known: Option<Rgb>,
    stats: &mut Stats,
) -> Option<Square> {
    let light = scene.lights.get(index)?;
    let (source, kernel) = match light.shape {
        LightShape::Point { at } => (Source::Point(at), None),
        LightShape::Spot {
            at,
            direction,
            cone,
            softness,
        } => (
            Source::Point(at),
            Some(Window {
                direction,
                cone,
                softness,
            }),
        ),
        LightShape::Directional { direction } => (Source::Sun(direction), None),
        _ => return None,
    };
    let kernel = Kernel {
        falloff: light.falloff,
        r0: scene.small_radius,
        window: kernel,
    };
    let area = step.x * step.y;
    if area == 0.0 || !area.is_finite() {
        return None;
    }
    let steep = steep_kernel(&light.shape, (corner, step));
    if known == Some(Rgb::ONE) && !steep {
        return Some(Square::Uniform);
    }
    if known == Some(Rgb::ZERO) {
        return Some(Square::Mean(Rgb::ZERO));
    }
    let square = [
        corner,
        corner + DVec2::new(step.x, 0.0),
        corner + step,
        corner + DVec2::new(0.0, step.y),
    ];
    let integral = SCRATCH.with(|scratch| {
        let scratch = &mut *scratch.borrow_mut();
        scratch.points.clear();
        scratch.pieces.clear();
        scratch.points.extend_from_slice(&square);
        scratch.pieces.push(Piece {
            start: 0,
            len: 4,
            through: known.unwrap_or(Rgb::ONE),
        });
        if known.is_none() {
            stats.work.floor_square_lights += 1;
            let least = SLIVER * area.abs();
            let mut hull = [DVec2::ZERO; 2 * MAX_HULL_POINTS + 1];
            find_walls(scene, index, source, &square, receiver, scratch);
            let mut touched = false;
            for k in 0..scratch.walls.len() {
                let w = scratch.walls[k];
                let wall = &scene.walls[w as usize];
                let segment = match wall.shape {
                    Shape::Segment(segment) => segment,
                    // An arc's shadow is not convex: where the arc meets
                    // the region between the square and the light, the
                    // points take the light.
                    Shape::Arc(arc) => match reach(source, &square, scene, &mut hull) {
                        Some(region) if !arc_meets(&arc, region) => continue,
                        _ => return None,
                    },
                };
                let Some(shadow) = shadow(source, segment.a, segment.b) else {
                    continue;
                };
                if shadow
                    .iter()
                    .any(|h| square.iter().all(|&x| h.side(x) < 0.0))
                {
                    continue;
                }
                touched |= cut(scratch, shadow, wall.material.pane_tint(), least)?;
            }
            if !touched && !steep {
                return Some(None);
            }
        }
        // Each piece's share of the mean, signed as the square is, so
        // the ratio is positive but for rounding (where the kernel is
        // constant over the piece, its edges' terms cancel).
        let mut sum = Rgb::ZERO;
        for piece in &scratch.pieces {
            let polygon = &scratch.points[piece.start..piece.start + piece.len];
            let value = match source {
                Source::Sun(_) => signed_area(polygon, corner),
                Source::Point(p) => point_integral(polygon, p, kernel),
            };
            sum += piece.through * (value / area).max(0.0);
        }
        Some(Some(sum))
    })?;
    let Some(integral) = integral else {
        return Some(Square::Uniform);
    };
    let mean = integral * light.intensity * light.color;
    mean.is_finite().then_some(Square::Mean(mean))
}

/// Whether a shadow covers more than `least` of a convex polygon's area:
/// its part inside the shadow (left in `rest`), with the polygon's
/// orientation.
fn inside_part(
    polygon: &[DVec2],
    shadow: [Half; 3],
    (inside, outside, rest): (&mut Vec<DVec2>, &mut Vec<DVec2>, &mut Vec<DVec2>),
    least: f64,
) -> bool {
    rest.clear();
    rest.extend_from_slice(polygon);
    for half in shadow {
        split(rest, half, inside, outside);
        std::mem::swap(rest, inside);
        if rest.len() < 3 {
            return false;
        }
    }
    let origin = polygon[0];
    signed_area(rest, origin) * signed_area(polygon, origin).signum() > least
}

/// The region light crosses to reach the square: the convex hull of the
/// square and the light (for the sun, the square and its beam back
/// across the scene), counter-clockwise, in `hull`. `None` where a point
/// of it is not finite.
fn reach<'a>(
    source: Source,
    square: &[DVec2; 4],
    scene: &Scene,
    hull: &'a mut [DVec2; 2 * MAX_HULL_POINTS + 1],
) -> Option<&'a [DVec2]> {
    let mut points = [DVec2::ZERO; MAX_HULL_POINTS];
    points[..4].copy_from_slice(square);
    let count = match source {
        Source::Point(p) => {
            points[4] = p;
            5
        }
        Source::Sun(direction) => {
            let back = direction * sun_line(scene, direction).2;
            for k in 0..4 {
                points[4 + k] = square[k] - back;
            }
            8
        }
    };
    convex_hull(&points[..count], hull)
}

/// Whether an arc meets a convex polygon (counter-clockwise): an end of
/// it inside, or it crosses an edge.
fn arc_meets(arc: &Arc, polygon: &[DVec2]) -> bool {
    let n = polygon.len();
    let inside = |x: DVec2| {
        (0..n).all(|k| (polygon[(k + 1) % n] - polygon[k]).perp_dot(x - polygon[k]) >= 0.0)
    };
    if n < 3 || inside(arc.a) || inside(arc.b) || inside(arc.point_at(0.5)) {
        return true;
    }
    (0..n).any(|k| {
        let ray = Ray::new(polygon[k], polygon[(k + 1) % n] - polygon[k]);
        arc_crossings(&ray, arc, 1.0, false, false).1 > 0
    })
}

/// The walls that can shade the square from the light, but for those
/// that let everything through and the light's own wall: the receiver's
/// list towards the light where it has one, else a query of the walls in
/// the box around the square and the light (for the sun, the square and
/// its beam back across the scene).
fn find_walls(
    scene: &Scene,
    index: usize,
    source: Source,
    square: &[DVec2; 4],
    receiver: Receiver,
    scratch: &mut Scratch,
) {
    let skip = receiver.skip(scene.light_wall.get(index).copied().flatten());
    let Scratch { walls, query, .. } = scratch;
    walls.clear();
    let keep = |w: u32| {
        !skip.contains(w)
            && scene
                .walls
                .get(w as usize)
                .is_some_and(|wall| wall.material.pane_tint() != Some(Rgb::ONE))
    };
    match receiver.walls_towards(index) {
        Some(list) => walls.extend(list.iter().copied().filter(|&w| keep(w))),
        None => {
            let (mut lo, mut hi) = (square[0], square[0]);
            let mut take = |x: DVec2| {
                lo = lo.min(x);
                hi = hi.max(x);
            };
            for &x in square {
                take(x);
            }
            match source {
                Source::Point(p) => take(p),
                Source::Sun(direction) => {
                    let reach = sun_line(scene, direction).2;
                    for &x in square {
                        take(x - direction * reach);
                    }
                }
            }
            let pad = DVec2::splat(1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element()));
            scene
                .segments
                .for_each_in_box(lo - pad, hi + pad, query, |w| {
                    if keep(w) {
                        walls.push(w);
                    }
                });
        }
    }
}

/// The shadow of the wall from `a` to `b`: three half-planes whose common
/// part holds the points beyond the wall's line that the light reaches
/// only across it. `None` where the light lies along the wall's line (the
/// wall hides nothing of the floor but its own line).
fn shadow(source: Source, a: DVec2, b: DVec2) -> Option<[Half; 3]> {
    let edge = b - a;
    match source {
        Source::Point(p) => {
            let s = edge.perp_dot(p - a);
            let scale = edge.length() * ((p - a).length() + (p - b).length());
            if s.is_nan() || s.abs() <= 16.0 * f64::EPSILON * scale {
                return None;
            }
            // The light left of the wall from `a` to `b`.
            let (a, b) = if s > 0.0 { (a, b) } else { (b, a) };
            Some([
                Half { q: b, e: a - b },
                Half { q: p, e: a - p },
                Half { q: p, e: p - b },
            ])
        }
        Source::Sun(direction) => {
            let s = edge.perp_dot(-direction);
            if s.is_nan() || s.abs() <= 16.0 * f64::EPSILON * edge.length() {
                return None;
            }
            // Upstream left of the wall from `a` to `b`.
            let (a, b) = if s > 0.0 { (a, b) } else { (b, a) };
            Some([
                Half { q: b, e: a - b },
                Half { q: a, e: direction },
                Half {
                    q: b,
                    e: -direction,
                },
            ])
        }
    }
}

/// Takes one shadow out of every piece it covers part of: the parts of
/// a piece outside it stay as they were; the part inside takes the
/// pane's `tint`, or is dropped behind an opaque wall. A piece the shadow
/// covers no area of stays as it is, to the bit, so that walls whose
/// shadows miss the square change nothing (whichever list they come
/// from). Whether any piece was covered; `None` past `MOST_PIECES`.
fn cut(scratch: &mut Scratch, shadow: [Half; 3], tint: Option<Rgb>, least: f64) -> Option<bool> {
    let Scratch {
        points,
        pieces,
        next_points,
        next_pieces,
        inside,
        outside,
        rest,
        ..
    } = scratch;
    next_points.clear();
    next_pieces.clear();
    let mut push = |polygon: &[DVec2], through: Rgb| {
        if polygon.len() >= 3
            && through != Rgb::ZERO
            && signed_area(polygon, polygon[0]).abs() > least
        {
            next_pieces.push(Piece {
                start: next_points.len(),
                len: polygon.len(),
                through,
            });
            next_points.extend_from_slice(polygon);
        }
    };
    let mut touched = false;
    for piece in pieces.iter() {
        let polygon = &points[piece.start..piece.start + piece.len];
        if !inside_part(polygon, shadow, (inside, outside, rest), least) {
            push(polygon, piece.through);
            continue;
        }
        touched = true;
        rest.clear();
        rest.extend_from_slice(polygon);
        for half in shadow {
            split(rest, half, inside, outside);
            push(outside, piece.through);
            std::mem::swap(rest, inside);
            if rest.len() < 3 {
                break;
            }
        }
        if rest.len() >= 3
            && let Some(tint) = tint
        {
            push(rest, piece.through * tint);
        }
    }
    std::mem::swap(points, next_points);
    std::mem::swap(pieces, next_pieces);
    (pieces.len() <= MOST_PIECES).then_some(touched)
}

/// Splits a convex polygon by a half-plane into the part inside it and
/// the part outside (either may be empty).
fn split(polygon: &[DVec2], half: Half, inside: &mut Vec<DVec2>, outside: &mut Vec<DVec2>) {
    inside.clear();
    outside.clear();
    let n = polygon.len();
    for i in 0..n {
        let (u, v) = (polygon[i], polygon[(i + 1) % n]);
        let (su, sv) = (half.side(u), half.side(v));
        if su >= 0.0 {
            inside.push(u);
        }
        if su <= 0.0 {
            outside.push(u);
        }
        if (su > 0.0 && sv < 0.0) || (su < 0.0 && sv > 0.0) {
            let x = u + (v - u) * (su / (su - sv));
            inside.push(x);
            outside.push(x);
        }
    }
}

/// The signed area of a polygon (positive counter-clockwise), about
/// `origin` for precision.
fn signed_area(polygon: &[DVec2], origin: DVec2) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| (polygon[i] - origin).perp_dot(polygon[(i + 1) % n] - origin))
        .sum::<f64>()
        * 0.5
}

/// The integral of a point light's kernel over a polygon, signed by its
/// orientation: the sum over its edges of the light's triangle on each.
fn point_integral(polygon: &[DVec2], p: DVec2, kernel: Kernel) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| edge_integral(polygon[i] - p, polygon[(i + 1) % n] - p, kernel))
        .sum()
}

/// Gauss-Legendre nodes and weights on `[-1, 1]`, the positive half.
const GAUSS_2: [(f64, f64); 1] = [(0.577_350_269_189_625_8, 1.0)];
const GAUSS_4: [(f64, f64); 2] = [
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];
const GAUSS_8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Pieces of one edge no more than this: past it, the rest of the edge
/// is taken by one rule (it lies within a rounding of the light's
/// line, where the edge's triangle has no area to speak of).
const MOST_EDGE_PIECES: usize = 96;

/// The kernel's integral over the triangle from the light (the origin)
/// to the edge from `a` to `b`, signed by `a x b`.
fn edge_integral(a: DVec2, b: DVec2, kernel: Kernel) -> f64 {
    let edge = b - a;
    let length = edge.length();
    if length.is_nan() || length <= 0.0 {
        return 0.0;
    }
    let t = edge / length;
    let cross = a.perp_dot(t);
    let h = cross.abs();
    if h.is_nan() || h <= 0.0 {
        return 0.0;
    }
    // The foot of the perpendicular, and the unit normal towards it.
    let n = (a - t * a.dot(t)) / h;
    let (s_a, s_b) = (a.dot(t), a.dot(t) + length);
    // Where the integrand has a kink: the kernel's radii, the window's
    // edges.
    let mut cuts = [0.0f64; 12];
    let mut count = 0;
    let mut cut = |s: f64| {
        if s > s_a && s < s_b && count < cuts.len() {
            cuts[count] = s;
            count += 1;
        }
    };
    let mut radius = |r: f64| {
        if r > h {
            let s = ((r - h) * (r + h)).sqrt();
            cut(-s);
            cut(s);
        }
    };
    radius(kernel.r0);
    if let Falloff::Window { range } = kernel.falloff {
        radius(range);
    }
    if let Some(window) = kernel.window {
        // The direction at `s` makes the angle `atan2(s, h)` with the
        // normal; the window's edges lie at fixed angles from its
        // direction.
        let centre = window.direction.dot(t).atan2(window.direction.dot(n));
        for angle in [
            0.0,
            window.cone - window.softness,
            window.cone,
            std::f64::consts::PI,
        ] {
            for phi in [centre - angle, centre + angle] {
                let phi = (phi + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                if phi.abs() < std::f64::consts::FRAC_PI_2 {
                    cut(h * phi.tan());
                }
            }
        }
    }
    let cuts = &mut cuts[..count];
    cuts.sort_by(f64::total_cmp);
    let f = |s: f64| {
        let r2 = h * h + s * s;
        let r = r2.sqrt();
        let mut value = PhotonKernel::Point(kernel.falloff).integral(0.0, r, kernel.r0) * h / r2;
        if let Some(window) = kernel.window {
            let u = (n * h + t * s) / r;
            let angle = window
                .direction
                .perp_dot(u)
                .abs()
                .atan2(window.direction.dot(u));
            value *= smooth_window(angle, window.cone, window.softness);
        }
        value
    };
    let mut sum = 0.0;
    let mut from = s_a;
    for &to in cuts.iter().chain(std::iter::once(&s_b)) {
        sum += graded(from, to, h, &f);
        from = to;
    }
    sum * cross.signum()
}

/// The integral of `f` over `[from, to]` by Gauss-Legendre rules, on
/// pieces small enough against their distance to the branch points
/// `+-ih` that the rule is exact to rounding: a piece is split until the
/// Bernstein ellipse through them has `rho >= 8`, then taken by 8 points
/// (error about `rho^-16`), 4 where `rho >= 80` or 2 where
/// `rho >= 6000`.
fn graded(from: f64, to: f64, h: f64, f: &impl Fn(f64) -> f64) -> f64 {
    let rho = |l: f64, r: f64| {
        let (c, w) = (0.5 * (l + r), 0.5 * (r - l));
        // The branch point in the piece's own coordinates, where the
        // piece is [-1, 1].
        let (x, y) = (-c / w, h / w);
        let y2 = y * y;
        let a = 0.5 * (((x - 1.0) * (x - 1.0) + y2).sqrt() + ((x + 1.0) * (x + 1.0) + y2).sqrt());
        a + (a * a - 1.0).max(0.0).sqrt()
    };
    let rule = |l: f64, r: f64, nodes: &[(f64, f64)]| {
        let (c, w) = (0.5 * (l + r), 0.5 * (r - l));
        nodes
            .iter()
            .map(|&(x, weight)| weight * (f(c - w * x) + f(c + w * x)))
            .sum::<f64>()
            * w
    };
    let mut sum = 0.0;
    // A stack of pieces, taken left to right.
    let mut stack = [(0.0f64, 0.0f64); 64];
    let mut top = 1;
    stack[0] = (from, to);
    let mut pieces = 0;
    while top > 0 {
        top -= 1;
        let (l, r) = stack[top];
        if l.is_nan() || r.is_nan() || r <= l {
            continue;
        }
        let q = rho(l, r);
        pieces += 1;
        if q < 8.0 && pieces < MOST_EDGE_PIECES && top + 2 <= stack.len() {
            // The half nearer the branch points is split the more; the
            // foot of the perpendicular splits them evenly.
            let m = if l < 0.0 && r > 0.0 {
                0.0
            } else {
                0.5 * (l + r)
            };
            stack[top] = (m, r);
            stack[top + 1] = (l, m);
            top += 2;
            continue;
        }
        let nodes: &[(f64, f64)] = if q >= 6000.0 {
            &GAUSS_2
        } else if q >= 80.0 {
            &GAUSS_4
        } else {
            &GAUSS_8
        };
        sum += rule(l, r, nodes);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::exact::closed_forms::{OPAQUE, scene, wall};
    use crate::estimators::{Visibility, light_contribution};
    use crate::scene::{Light, Material};

    fn light(shape: LightShape, falloff: Falloff) -> Light {
        Light {
            profile: None,
            shape,
            color: Rgb::ONE,
            intensity: 1.0,
            falloff,
            spectrum: None,
        }
    }

    fn point(at: DVec2, falloff: Falloff) -> Light {
        light(LightShape::Point { at }, falloff)
    }

    /// The mean of light 0 over the square, with the transmittance
    /// `known` or the walls'.
    fn mean_with(scene: &Scene, square: (DVec2, DVec2), known: Option<Rgb>) -> Rgb {
        let got = square_light(
            scene,
            0,
            square,
            Receiver::FLOOR,
            known,
            &mut Stats::default(),
        );
        match got {
            Some(Square::Mean(mean)) => mean,
            _ => panic!("{got:?}: the square takes no mean"),
        }
    }

    /// The square's mean where walls shade it.
    fn mean(scene: &Scene, square: (DVec2, DVec2)) -> Rgb {
        mean_with(scene, square, None)
    }

    /// The kernel's mean over a square that nothing shades: asked with a
    /// known transmittance of one half (halving and doubling are exact).
    fn kernel_mean(scene: &Scene, square: (DVec2, DVec2)) -> Rgb {
        mean_with(scene, square, Some(Rgb::splat(0.5))) * 2.0
    }

    /// The mean of the sampled estimator (one shadow ray per point) over
    /// an `n` x `n` grid of the square's midpoints.
    fn grid_mean(scene: &Scene, (corner, step): (DVec2, DVec2), n: usize) -> Rgb {
        let mut sum = Rgb::ZERO;
        let mut stats = Stats::default();
        for i in 0..n {
            for j in 0..n {
                let x = corner
                    + step * DVec2::new((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                sum += light_contribution(
                    scene,
                    0,
                    x,
                    Receiver::FLOOR,
                    0.5,
                    Visibility::Trace,
                    &mut stats,
                );
            }
        }
        sum / (n * n) as f64
    }

    fn turn(x: DVec2, angle: f64) -> DVec2 {
        DVec2::from_angle(angle).rotate(x)
    }

    /// A point light at the origin, a wall at `x = 2` from `y = 1` to
    /// `y = 5`: its shadow's lower edge, `y = x / 2`, crosses the square
    /// `[5, 6] x [2, 3]`, leaving lit the part below it, of area
    /// `int_5^6 (x / 2 - 2) dx = 0.75`. Under the constant kernel the mean
    /// is that area; behind a pane of tint `t`, `0.75 + 0.25 t`. The same
    /// turned by 0.7 radians, and with the square's corners in the other
    /// order.
    #[test]
    fn a_shadow_edge_leaves_lit_the_area_by_hand() {
        let tint = Rgb::new(0.5, 0.25, 1.0);
        for angle in [0.0, 0.7, -2.3] {
            for (material, expected) in [
                (OPAQUE, Rgb::splat(0.75)),
                (
                    Material::Transparent { tint },
                    Rgb::splat(0.75) + tint * 0.25,
                ),
            ] {
                let s = scene(
                    vec![wall(
                        turn(DVec2::new(2.0, 1.0), angle),
                        turn(DVec2::new(2.0, 5.0), angle),
                        material,
                    )],
                    vec![point(DVec2::ZERO, Falloff::Constant)],
                );
                if angle == 0.0 {
                    for square in [
                        (DVec2::new(5.0, 2.0), DVec2::new(1.0, 1.0)),
                        (DVec2::new(6.0, 3.0), DVec2::new(-1.0, -1.0)),
                        (DVec2::new(5.0, 3.0), DVec2::new(1.0, -1.0)),
                    ] {
                        let got = mean(&s, square);
                        assert!((got - expected).abs().max_element() < 1e-14, "{got:?}");
                    }
                } else {
                    // A turned square is not a pixel: compare the wall's
                    // shadow on the axis-aligned square against the grid.
                    let square = (turn(DVec2::new(5.0, 2.0), angle), DVec2::new(0.7, 0.9));
                    let got = mean(&s, square);
                    let grid = grid_mean(&s, square, 800);
                    assert!((got - grid).abs().max_element() < 2e-3, "{got:?} {grid:?}");
                }
            }
        }
    }

    /// The square's mean, however it is found.
    fn value(scene: &Scene, square: (DVec2, DVec2)) -> Rgb {
        let mut stats = Stats::default();
        match square_light(scene, 0, square, Receiver::FLOOR, None, &mut stats) {
            Some(Square::Mean(mean)) => mean,
            Some(Square::Uniform) => kernel_mean(scene, square),
            None => panic!("the points take the light"),
        }
    }

    /// Points, spots and the sun, with walls and panes crossing the
    /// square at odd angles, a wall ending inside it, a light on a wall's
    /// line and at a wall's end, against the mean of the sampled
    /// estimator over a 1000 x 1000 grid (whose error at an edge is about
    /// a thousandth of the square's side).
    #[test]
    fn squares_agree_with_the_sampled_estimator() {
        let pane = Material::Transparent {
            tint: Rgb::new(0.3, 0.6, 0.9),
        };
        let walls = vec![
            wall(DVec2::new(2.0, 1.1), DVec2::new(2.3, 4.0), OPAQUE),
            wall(DVec2::new(2.6, 0.2), DVec2::new(3.2, 1.9), pane),
            wall(DVec2::new(3.9, 2.4), DVec2::new(4.35, 2.6), OPAQUE),
            wall(DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0), OPAQUE),
        ];
        let spot = LightShape::Spot {
            at: DVec2::new(0.2, 0.9),
            direction: DVec2::new(1.0, 0.3).normalize(),
            cone: 0.5,
            softness: 0.2,
        };
        let lights = [
            light(
                LightShape::Point {
                    at: DVec2::new(0.1, 0.8),
                },
                Falloff::Flatland,
            ),
            light(
                LightShape::Point {
                    at: DVec2::new(0.0, 0.0),
                },
                Falloff::InverseSquare,
            ),
            light(
                LightShape::Point {
                    at: DVec2::new(1.0, 0.0),
                },
                Falloff::Window { range: 9.0 },
            ),
            light(spot, Falloff::Flatland),
            light(
                LightShape::Directional {
                    direction: DVec2::new(1.0, 0.45).normalize(),
                },
                Falloff::Flatland,
            ),
        ];
        let square = (DVec2::new(3.7, 1.6), DVec2::new(0.9, 1.3));
        for l in lights {
            let s = scene(walls.clone(), vec![l.clone()]);
            let got = value(&s, square);
            let grid = grid_mean(&s, square, 1000);
            let scale = grid.max_element().max(1e-3);
            assert!(
                (got - grid).abs().max_element() < 3e-3 * scale,
                "{:?}: {got:?} against {grid:?}",
                l.shape
            );
        }
    }

    /// A wall whose shadow misses the square changes nothing, to the bit,
    /// whether or not it is in the list: the walls a block's list holds
    /// beyond those that matter leave the image as it is.
    #[test]
    fn walls_whose_shadows_miss_the_square_change_nothing() {
        // Its shadow's edge, `y = 2.5 + x / 40`, crosses the square.
        let near = wall(DVec2::new(2.0, 2.55), DVec2::new(2.2, 4.0), OPAQUE);
        let far = [
            // Behind the light.
            wall(DVec2::new(-3.0, 5.0), DVec2::new(-2.0, 7.0), OPAQUE),
            // Beyond the square, facing it.
            wall(DVec2::new(6.0, 0.0), DVec2::new(6.0, 5.0), OPAQUE),
            // Its shadow's edge, `y = 2.5`, along the square's side.
            wall(DVec2::new(1.0, 1.0), DVec2::new(1.0, 2.5), OPAQUE),
        ];
        let lamp = point(DVec2::new(0.0, 2.5), Falloff::Flatland);
        // Small enough that the lamp's kernel is not steep across it.
        let square = (DVec2::new(3.0, 2.5), DVec2::new(0.1, 0.1));
        let alone = scene(vec![near], vec![lamp.clone()]);
        let mut all = vec![near];
        all.extend(far);
        let crowded = scene(all, vec![lamp.clone()]);
        let at = |s: &Scene, list: Option<Vec<u32>>| {
            let lists = [list];
            let receiver = Receiver {
                shadow_walls: Some(&lists[..]),
                ..Receiver::FLOOR
            };
            square_light(s, 0, square, receiver, None, &mut Stats::default())
        };
        let reference = at(&alone, None);
        assert!(matches!(reference, Some(Square::Mean(_))), "{reference:?}");
        assert_eq!(at(&crowded, None), reference);
        assert_eq!(at(&crowded, Some(vec![0, 1, 2, 3])), reference);
        assert_eq!(at(&crowded, Some(vec![0])), reference);
        // Alone, the far walls leave the square whole.
        let far_only = scene(far.to_vec(), vec![lamp]);
        let got = square_light(
            &far_only,
            0,
            square,
            Receiver::FLOOR,
            None,
            &mut Stats::default(),
        );
        assert_eq!(got, Some(Square::Uniform));
    }

    /// Far from the origin (a million units) and at a hundredth of a unit,
    /// a shadow edge's square keeps its lit fraction.
    #[test]
    fn huge_and_tiny_coordinates_keep_the_lit_area() {
        for (offset, size) in [(1e6, 1.0), (0.0, 0.01), (-3e5, 0.1)] {
            let o = DVec2::splat(offset);
            let s = scene(
                vec![wall(
                    o + DVec2::new(2.0, 1.0) * size,
                    o + DVec2::new(2.0, 5.0) * size,
                    OPAQUE,
                )],
                vec![point(o, Falloff::Constant)],
            );
            let got = mean(&s, (o + DVec2::new(5.0, 2.0) * size, DVec2::splat(size)));
            assert!(
                (got - Rgb::splat(0.75)).abs().max_element() < 1e-7,
                "at {offset}, {size}: {got:?}"
            );
        }
    }

    /// Without walls, the square's mean is the kernel's mean over it:
    /// against a fine midpoint rule, for every falloff, with the light far
    /// away, beside the square, on its edge and inside it (within the
    /// small radius).
    #[test]
    fn a_clear_square_takes_the_kernels_mean() {
        let falloffs = [
            Falloff::Flatland,
            Falloff::InverseSquare,
            Falloff::Constant,
            Falloff::Window { range: 3.0 },
        ];
        let square = (DVec2::new(1.0, -0.5), DVec2::new(1.25, 0.75));
        for falloff in falloffs {
            for at in [
                DVec2::new(-20.0, 7.0),
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(1.6, -0.1),
                DVec2::new(3.1, 0.25),
            ] {
                let s = scene(vec![], vec![point(at, falloff)]);
                let got = kernel_mean(&s, square).x;
                let n = 2000;
                let mut sum = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        let x = square.0
                            + square.1
                                * DVec2::new(
                                    (i as f64 + 0.5) / n as f64,
                                    (j as f64 + 0.5) / n as f64,
                                );
                        sum += falloff.g((x - at).length(), s.small_radius);
                    }
                }
                let grid = sum / (n * n) as f64;
                assert!(
                    (got - grid).abs() <= 2e-6 * grid,
                    "{falloff:?} at {at}: {got} against {grid}"
                );
            }
        }
    }
}
