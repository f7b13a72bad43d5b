//! Direct light through one flat glass edge, in closed form: what a
//! receiver inside a smooth glass body sees of a line or circle light
//! outside it, refracted once at one of the body's edges.
//!
//! From a point `x` inside, at depth `d` below an edge's line, the ray
//! leaving `x` that meets the line at `tau` (the distance along it) leaves
//! the glass by Snell's law, `n sin(theta_in) = sin(theta_out)`, or is
//! totally reflected. The rays that leave form an ordered fan: two of them
//! never cross outside, and every point `y` in front of the line is on
//! exactly one of them, the root in `tau` of
//! `n (tau - tau_x) / |p - x| = (tau_y - tau) / |y - p|`, whose left side
//! grows with `tau` and whose right side shrinks (Fermat's principle in
//! the plane). So the rays that meet a convex light are one interval of
//! `tau`, whose ends are the roots for a line light's ends and the rays
//! tangent to a circle light; and the light seen from `x` can change only
//! at the roots for the ends of the walls around, where a wall crosses
//! the edge's line or the light, and at the edge's own ends. Each piece
//! between those cuts is tested at its middle (both legs, panes tinting)
//! and integrated in `tau` by 12-point Gauss-Legendre, split where the
//! falloff has a kink, and in the square root of the distance to an end
//! where the leaving ray grazes the edge: per radian at `x`,
//! `(1 - F) n I G(r) r`, with the
//! Fresnel transmittance `1 - F` of the edge, the radiance factor `n` of
//! leaving glass of index `n` (`L / n` is invariant along a ray in the
//! plane, `material::glass`), Beer-Lambert absorption over the inside
//! leg, and `r` the unfolded length of the path, as a path through the
//! edge counts it; `d theta / d tau = d / |p - x|^2`.
//!
//! Paths skip the emission they meet right after exactly that one
//! refraction out of the body their vertex is in (`path.rs`), so the two
//! estimators share the light with no overlap. Rough or dispersive glass,
//! and scenes with arcs, stay sampled (`ClosedForms::glass_lights`).

use flatray_geometry::{DVec2, Ray, Segment, Side, Skip, intersect};

use super::exact::{GAUSS_12, SCRATCH, SLIVER, find_walls, is_exact, kinks, legs};
use crate::decision::Decision;
use crate::estimators::Receiver;
use crate::lights::{circle, line};
use crate::optics::fresnel;
use crate::options::RenderOptions;
use crate::scene::{Falloff, LightShape, Material, Scene};
use crate::{Rgb, Stats};

/// Most pairs of a glass edge and a line or circle light that receivers
/// inside glass take in closed form (`ClosedForms::glass_lights`): each pair
/// costs every receiver inside the edge's body a look at the walls
/// around the edge and the light.
pub const MAX_GLASS_PAIRS: usize = 256;

/// Most steps of a root's search: each halves the bracket at least, so
/// this is past the bits of any `f64` bracket.
const MAX_STEPS: usize = 200;

/// The sine of the leaving ray's angle above which a piece's end counts
/// as grazing.
const GRAZING_SINE: f64 = 0.98;

/// The glass edge and line or circle light pairs of `scene`.
pub(crate) fn glass_pairs(scene: &Scene) -> usize {
    scene.glass_edges.len() * scene.lights.iter().filter(|l| is_exact(&l.shape)).count()
}

/// Whether receivers inside glass take line and circle lights seen
/// through one edge of their body in closed form ([`through_glass`]),
/// and why: where shadow rays are cast, light is refracted, the pairs fit
/// [`MAX_GLASS_PAIRS`], every body is smooth and not dispersive, and no
/// wall is an arc (the closed form takes the walls around an edge as
/// segments). Elsewhere path rays find that light.
pub(crate) fn decide(scene: &Scene, options: &RenderOptions, shadows: bool) -> Decision {
    let terms = super::Terms {
        pairs: glass_pairs(scene),
        most: MAX_GLASS_PAIRS,
        pair: "glass edge and light pair",
        none: "no glass and line or circle light in the scene",
        event: "refracted",
        otherwise: "path rays find them",
        runs: "every floor and wall point inside glass takes them exactly; path rays add them only after more than one mirror or glass event",
    };
    let rough_or_dispersive = scene
        .glass
        .iter()
        .any(|g| g.dispersion != 0.0 || g.roughness > 0.0);
    let held = if rough_or_dispersive {
        Some("rough or dispersive glass: path rays find them")
    } else if super::has_arcs(scene) {
        Some("the scene has arcs: path rays find them")
    } else if scene.lights.iter().any(|l| l.profile.is_some()) {
        // Its closed form integrates the angle outside the glass, which
        // a profile would weigh by the direction bent at the edge.
        Some("a light's radiance varies with its direction (a sky's profile): path rays find them")
    } else {
        None
    };
    super::decide(options, shadows, terms, held)
}

/// The light that every line and circle light brings `x` after exactly one
/// refraction out of the glass body `x` is in, if any: fluence on the
/// floor, irradiance on a wall side (`receiver.normal`), coloured by the
/// lights' colours.
pub(crate) fn through_glass(scene: &Scene, x: DVec2, receiver: Receiver, stats: &mut Stats) -> Rgb {
    let Some(body) = body_holding(scene, x) else {
        return Rgb::ZERO;
    };
    let mut sum = Rgb::ZERO;
    for index in 0..scene.lights.len() {
        sum += in_body(scene, body, index, x, receiver, stats);
    }
    sum
}

/// [`through_glass`] for light `index` alone.
pub(crate) fn through_glass_of(
    scene: &Scene,
    index: usize,
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    match body_holding(scene, x) {
        Some(body) => in_body(scene, body, index, x, receiver, stats),
        None => Rgb::ZERO,
    }
}

/// The glass body whose polygon holds `x` strictly (by the crossing
/// number of a ray along `+x`), if any. `Scene::glass_edges` lists each
/// body's edges together.
fn body_holding(scene: &Scene, x: DVec2) -> Option<u32> {
    let edges = &scene.glass_edges;
    let mut k = 0;
    while k < edges.len() {
        let body = body_of(scene, edges[k]);
        let mut inside = false;
        while k < edges.len() && body_of(scene, edges[k]) == body {
            if let Some(s) = scene.walls[edges[k] as usize].as_segment()
                && (s.a.y > x.y) != (s.b.y > x.y)
            {
                let at = s.a.x + (x.y - s.a.y) * (s.b.x - s.a.x) / (s.b.y - s.a.y);
                if x.x < at {
                    inside = !inside;
                }
            }
            k += 1;
        }
        if inside {
            return body;
        }
    }
    None
}

fn body_of(scene: &Scene, wall: u32) -> Option<u32> {
    scene.walls[wall as usize].material.glass().map(|(b, _)| b)
}

/// Light `index` through each edge of `body`, seen from `x` inside it.
fn in_body(
    scene: &Scene,
    body: u32,
    index: usize,
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    if !is_exact(&light.shape) {
        return Rgb::ZERO;
    }
    let glass = &scene.glass[body as usize];
    let mut sum = Rgb::ZERO;
    for &f in &scene.glass_edges {
        let wall = &scene.walls[f as usize];
        let Material::Glass { body: b, inside } = wall.material else {
            continue;
        };
        if b != body || receiver.wall == Some(f) {
            continue;
        }
        let Some(segment) = wall.as_segment() else {
            continue;
        };
        // A one-sided line whose dark side holds the whole edge (its ends,
        // or on its line) sends it nothing.
        if let LightShape::Line {
            segment: l,
            one_sided: true,
            ..
        } = light.shape
            && !line::lights(&l, true, segment.a)
            && !line::lights(&l, true, segment.b)
        {
            continue;
        }
        let Some(edge) = Edge::new(segment, inside, x, glass.ior) else {
            continue;
        };
        sum += through_edge(scene, &edge, f, index, receiver, glass.absorption, stats);
    }
    sum * light.color
}

/// One glass edge seen from a point `x` inside: the edge's line in the
/// coordinates `(tau, d)`, `tau` along it from its first end and `d`
/// out of the glass, and `x` at `(tau_x, -depth)`.
struct Edge {
    a: DVec2,
    along: DVec2,
    out: DVec2,
    length: f64,
    x: DVec2,
    tau_x: f64,
    depth: f64,
    /// The glass's index.
    n: f64,
}

impl Edge {
    /// `None` where `x` is not strictly on the edge's inside.
    fn new(segment: &Segment, inside: Side, x: DVec2, n: f64) -> Option<Edge> {
        let e = segment.b - segment.a;
        let length = e.length();
        if !(length > 0.0 && length.is_finite()) {
            return None;
        }
        let along = e / length;
        let out = -along.perp() * inside.sign();
        let depth = -(x - segment.a).dot(out);
        if !(depth > 0.0 && depth.is_finite()) {
            return None;
        }
        Some(Edge {
            a: segment.a,
            along,
            out,
            length,
            x,
            tau_x: (x - segment.a).dot(along),
            depth,
            n,
        })
    }

    fn point(&self, tau: f64) -> DVec2 {
        self.a + self.along * tau
    }

    /// `(tau, d)` of `y`.
    fn coords(&self, y: DVec2) -> (f64, f64) {
        let v = y - self.a;
        (v.dot(self.along), v.dot(self.out))
    }

    /// The direction of the ray that leaves the glass at `tau`, and the
    /// cosine of its angle of incidence inside; `None` where it is
    /// totally reflected.
    fn leaving(&self, tau: f64) -> Option<(DVec2, f64)> {
        let u = tau - self.tau_x;
        let l = (u * u + self.depth * self.depth).sqrt();
        let s = self.n * u / l;
        if s.abs() >= 1.0 || s.is_nan() {
            return None;
        }
        Some((
            self.along * s + self.out * (1.0 - s * s).sqrt(),
            self.depth / l,
        ))
    }

    /// [`Edge::root`] for a point `(tau_y, d_y)` strictly in front of the
    /// line, by Newton's method in `t`, the sine of the angle inside:
    /// the ray leaves at `tau_x + depth t / sqrt(1 - t^2)` with the sine
    /// `n t` outside, so it passes `y` where
    /// `F(t) = depth t / sqrt(1 - t^2) + d_y n t / sqrt(1 - n^2 t^2)`
    /// equals `|tau_y - tau_x|`. `F` is increasing and convex for `t >= 0`,
    /// so Newton's steps from a `t` where `F` is too large fall to the
    /// root without passing it; each of its two terms alone, and their
    /// slopes at 0, bound the root above and give that start. `None`
    /// where a value is not finite.
    fn root_in_front(&self, tau_y: f64, d_y: f64) -> Option<f64> {
        let (n, dx) = (self.n, self.depth);
        let offset = tau_y - self.tau_x;
        let target = offset.abs();
        if target == 0.0 {
            return Some(self.tau_x);
        }
        let (q, r) = (target / dx, target / d_y);
        let mut t = (target / (dx + n * d_y))
            .min(q / (1.0 + q * q).sqrt())
            .min(r / (1.0 + r * r).sqrt() / n);
        if !t.is_finite() {
            return None;
        }
        for _ in 0..MAX_STEPS {
            let (c1, c2) = ((1.0 - t * t).sqrt(), (1.0 - n * n * t * t).sqrt());
            let value = dx * t / c1 + d_y * n * t / c2 - target;
            let slope = dx / (c1 * c1 * c1) + d_y * n / (c2 * c2 * c2);
            let next = t - value / slope;
            // Falling while it gains: the root, to rounding.
            if !(next < t && next >= 0.0) {
                break;
            }
            t = next;
        }
        let tau = self.tau_x + offset.signum() * dx * t / (1.0 - t * t).sqrt();
        tau.is_finite().then_some(tau)
    }

    /// Whether the rays towards `ya` and `yb` (in front of the line, or
    /// on it) both leave before the edge's first end, or both after its
    /// last: the rays that leave the glass do not cross in front of its
    /// line, so the ray that leaves at an end splits the points in front
    /// into those reached before it and after it. A point within a
    /// rounding margin of that ray counts as reached through the edge, so
    /// that [`Edge::root`] decides it.
    fn beyond_ends(&self, ya: DVec2, yb: DVec2) -> bool {
        let (a, b) = (self.coords(ya), self.coords(yb));
        let scale = self.length + (a.0 - self.tau_x).abs() + (b.0 - self.tau_x).abs() + a.1 + b.1;
        let margin = 1e-9 * scale;
        // `s d - c (tau - end)`, with `(s, c)` the leaving ray's direction
        // in the edge's coordinates: above 0 before the ray, below after.
        let side = |end: f64, (tau, d): (f64, f64)| -> Option<f64> {
            let u = end - self.tau_x;
            let l = (u * u + self.depth * self.depth).sqrt();
            let s = self.n * u / l;
            if s.abs() >= 1.0 || s.is_nan() {
                // Totally reflected there: every leaving ray lies on one
                // side of this end, and it cuts nothing.
                return None;
            }
            let c = (1.0 - s * s).sqrt();
            Some(s * d - c * (tau - end))
        };
        let before = |y| side(0.0, y).is_some_and(|v| v > margin);
        let after = |y| side(self.length, y).is_some_and(|v| v < -margin);
        (before(a) && before(b)) || (after(a) && after(b))
    }

    /// The `tau` of the ray that leaves towards `y` (in front of the line,
    /// or on it): the root of Fermat's condition, by Newton's steps kept
    /// inside a shrinking bracket.
    fn root(&self, y: DVec2) -> f64 {
        let (tau_y, d_y) = self.coords(y);
        if d_y > 0.0
            && let Some(tau) = self.root_in_front(tau_y, d_y)
        {
            return tau;
        }
        let d_y = d_y.max(0.0);
        let (n, tx, dx) = (self.n, self.tau_x, self.depth);
        // Increasing in tau; its derivative, positive.
        let g = |tau: f64| {
            let (u, v) = (tau - tx, tau_y - tau);
            let (l1, l2) = ((u * u + dx * dx).sqrt(), (v * v + d_y * d_y).sqrt());
            let right = if l2 > 0.0 { v / l2 } else { 0.0 };
            let slope = n * dx * dx / (l1 * l1 * l1)
                + if l2 > 0.0 {
                    d_y * d_y / (l2 * l2 * l2)
                } else {
                    0.0
                };
            (n * u / l1 - right, slope)
        };
        let (mut lo, mut hi) = if tx <= tau_y {
            (tx, tau_y)
        } else {
            (tau_y, tx)
        };
        if lo == hi || !(lo.is_finite() && hi.is_finite()) {
            return lo;
        }
        // The straight line's crossing: near the root for a shallow x.
        let mut tau = tx + (tau_y - tx) * dx / (dx + d_y);
        for _ in 0..MAX_STEPS {
            let (value, slope) = g(tau);
            if value == 0.0 {
                return tau;
            }
            if value < 0.0 {
                lo = tau;
            } else {
                hi = tau;
            }
            let newton = tau - value / slope;
            let next = if newton > lo && newton < hi && newton.is_finite() {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if (next - tau).abs() <= 4.0 * f64::EPSILON * next.abs().max(dx) {
                return next;
            }
            tau = next;
        }
        tau
    }
}

/// Light `index` through edge `edge` (wall `f`), uncoloured.
fn through_edge(
    scene: &Scene,
    edge: &Edge,
    f: u32,
    index: usize,
    receiver: Receiver,
    absorption: Rgb,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    let Some(span) = light_span(edge, &light.shape) else {
        return Rgb::ZERO;
    };
    let whole = (span.0.max(0.0), span.1.min(edge.length));
    if whole.1 - whole.0 <= SLIVER * edge.length || whole.0.is_nan() || whole.1.is_nan() {
        return Rgb::ZERO;
    }
    let r0 = scene.small_radius;
    SCRATCH.with(|scratch| {
        let scratch = &mut *scratch.borrow_mut();
        let Some([h0, h1, h2, h3]) = light.shape.hull() else {
            return Rgb::ZERO;
        };
        let points = [
            edge.x,
            edge.point(0.0),
            edge.point(edge.length),
            h0,
            h1,
            h2,
            h3,
        ];
        // Every wall near the edge and the light: the receiver's own and
        // the light's are left out by `find_walls`.
        let around = Receiver {
            shadow_walls: None,
            ..receiver
        };
        find_walls(scene, index, around, &points, scratch, stats);
        let cuts = &mut scratch.cuts;
        cuts.clear();
        cuts.extend([whole.0, whole.1]);
        if let Some(normal) = receiver.normal {
            // Where the receiver's cosine turns: the ray along its wall.
            let dot = normal.dot(edge.along);
            if dot != 0.0 {
                cuts.push(-normal.dot(edge.a - edge.x) / dot);
            }
        }
        if let LightShape::Line { segment, .. } = light.shape {
            // Where the light's line (beyond the light too) meets the
            // edge's, the rays start to reach its other side.
            let e = segment.b - segment.a;
            let t = flatray_geometry::cross(segment.a - edge.a, e)
                / flatray_geometry::cross(edge.along, e);
            if t.is_finite() {
                cuts.push(t);
            }
        }
        for &w in &scratch.walls {
            if w == f {
                continue;
            }
            let Some(&s) = scene.walls[w as usize].as_segment() else {
                continue;
            };
            for q in [s.a, s.b] {
                cut_at(edge, q, cuts);
            }
            // Where the wall crosses the edge's line.
            if let Some(h) = flatray_geometry::line_crossing(&Ray::new(edge.a, edge.along), &s) {
                cuts.push(h.t);
            }
            // Where it crosses the light.
            match light.shape {
                LightShape::Line { segment, .. } => {
                    if let Some(h) =
                        flatray_geometry::line_crossing(&Ray::new(s.a, s.b - s.a), &segment)
                        && h.t > 0.0
                        && h.t < 1.0
                    {
                        cuts.push(edge.root(s.a + (s.b - s.a) * h.t));
                    }
                }
                LightShape::Circle { at, radius } => {
                    for t in circle_crossings(at, radius, s.a, s.b - s.a) {
                        if t > 0.0 && t < 1.0 {
                            cuts.push(edge.root(s.a + (s.b - s.a) * t));
                        }
                    }
                }
                _ => {}
            }
        }
        cuts.retain(|t| *t >= whole.0 && *t <= whole.1);
        cuts.sort_unstable_by(f64::total_cmp);
        cuts.dedup();
        let sliver = SLIVER * (whole.1 - whole.0);
        let light_wall = scene.light_wall[index].unwrap_or(u32::MAX);
        let inside_leg = Skip(receiver.wall.unwrap_or(u32::MAX), f);
        let outside_leg = Skip(f, light_wall);
        let mut sum = Rgb::ZERO;
        for k in 1..cuts.len() {
            let (a, b) = (cuts[k - 1], cuts[k]);
            if b - a <= sliver {
                continue;
            }
            let Some(at) = Leaving::at(edge, &light.shape, 0.5 * (a + b)) else {
                continue;
            };
            if receiver.normal.is_some_and(|n| n.dot(at.p - edge.x) <= 0.0) {
                continue;
            }
            let through = legs(scene, &scratch.walls, (edge.x, at.p), inside_leg)
                * legs(scene, &scratch.walls, (at.p, at.y), outside_leg);
            if through == Rgb::ZERO {
                continue;
            }
            sum += through * piece(edge, light, receiver.normal, absorption, (a, b), r0);
        }
        sum
    })
}

/// Adds the `tau` of the ray that passes wall end `q`: its root in front
/// of the edge's line, where the ray from `x` through it meets the line
/// behind.
fn cut_at(edge: &Edge, q: DVec2, cuts: &mut Vec<f64>) {
    let (tau_q, d_q) = edge.coords(q);
    if d_q == 0.0 {
        cuts.push(tau_q);
    } else if d_q > 0.0 {
        cuts.push(edge.root(q));
    } else if d_q > -edge.depth {
        cuts.push(edge.tau_x + (tau_q - edge.tau_x) * edge.depth / (edge.depth + d_q));
    }
}

/// A ray that leaves the glass at `p` towards the light, and where it
/// meets the light: at `y`, `t` from `p`, from `side` of a line light.
struct Leaving {
    p: DVec2,
    y: DVec2,
    t: f64,
    cos_in: f64,
    side: Option<Side>,
}

impl Leaving {
    fn at(edge: &Edge, shape: &LightShape, tau: f64) -> Option<Leaving> {
        let (dir, cos_in) = edge.leaving(tau)?;
        let p = edge.point(tau);
        let (t, side) = match *shape {
            LightShape::Line { segment, .. } => {
                let hit = intersect(&Ray::new(p, dir), &segment)?;
                (hit.t, segment.side_of(p))
            }
            LightShape::Circle { at, radius } => (
                circle::met_by(at, radius, &Ray::new(p, dir), f64::INFINITY)?,
                None,
            ),
            _ => return None,
        };
        Some(Leaving {
            p,
            y: p + dir * t,
            t,
            cos_in,
            side,
        })
    }
}

/// The light through the edge over `(a, b)` of `tau`, where every ray
/// meets the light and the walls let the same through: 12-point
/// Gauss-Legendre in `tau`, split where the falloff has a kink.
fn piece(
    edge: &Edge,
    light: &crate::scene::Light,
    normal: Option<DVec2>,
    absorption: Rgb,
    (a, b): (f64, f64),
    r0: f64,
) -> Rgb {
    let value = |tau: f64| -> (Rgb, f64) {
        let Some(at) = Leaving::at(edge, &light.shape, tau) else {
            return (Rgb::ZERO, f64::NAN);
        };
        let inside = at.p - edge.x;
        let l = inside.length();
        let r = l + at.t;
        let emitted = match light.shape {
            LightShape::Line { one_sided, .. } => match at.side {
                Some(side) => line::emitted(light, one_sided, side, r, r0),
                None => 0.0,
            },
            _ => light.intensity * light.falloff.per_radian(r, r0),
        };
        let cosine = normal.map_or(1.0, |n| n.dot(inside).max(0.0) / l);
        let scalar =
            (1.0 - fresnel(edge.n, 1.0, at.cos_in)) * edge.n * emitted * cosine * edge.depth
                / (l * l);
        let absorbed = if absorption == Rgb::ZERO {
            Rgb::ONE
        } else {
            Rgb::new(
                (-absorption.x * l).exp(),
                (-absorption.y * l).exp(),
                (-absorption.z * l).exp(),
            )
        };
        (absorbed * scalar, r)
    };
    let gauss = |a: f64, b: f64| {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        let mut sum = Rgb::ZERO;
        for (node, weight) in GAUSS_12 {
            sum += (value(mid - half * node).0 + value(mid + half * node).0) * weight;
        }
        sum * half
    };
    // Where a ray leaves the glass near grazing the integrand has a square
    // root's edge (the Fresnel transmittance falls as the leaving ray's
    // cosine, a square root in `tau`): a piece that ends there is split at
    // its middle, and the half at that end integrated in the square root
    // of the distance from it.
    let grazing = |tau: f64| {
        let u = tau - edge.tau_x;
        edge.n * u.abs() / (u * u + edge.depth * edge.depth).sqrt() > GRAZING_SINE
    };
    let gauss = |a: f64, b: f64| {
        let (at_a, at_b) = (grazing(a), grazing(b));
        if !at_a && !at_b {
            return gauss(a, b);
        }
        let mid = 0.5 * (a + b);
        let graded = |end: f64, other: f64, rough: bool| {
            if !rough {
                return gauss(end.min(other), end.max(other));
            }
            // tau = end + (other - end) w^2 over w in [0, 1]: a square
            // root's edge at `end` becomes smooth in `w`.
            let span = other - end;
            let mut sum = Rgb::ZERO;
            for (node, weight) in GAUSS_12 {
                for w in [0.5 - 0.5 * node, 0.5 + 0.5 * node] {
                    sum += value(end + span * w * w).0 * (2.0 * w * weight);
                }
            }
            sum * (0.5 * span.abs())
        };
        graded(a, mid, at_a) + graded(b, mid, at_b)
    };
    // The unfolded length is at least the depth of `x` plus how far in
    // front of the line the light begins: no kink below that is crossed.
    let nearest = edge.depth + light_front(edge, &light.shape);
    if light.falloff == Falloff::Flatland || kinks(light.falloff, r0).all(|rho| rho < nearest) {
        return gauss(a, b);
    }
    // Where the unfolded length crosses a kink of the falloff: found among
    // 16 steps, then by halving.
    const STEPS: usize = 16;
    let mut sum = Rgb::ZERO;
    let mut from = a;
    let mut prev = (a, value(a).1);
    for k in 1..=STEPS {
        let tau = a + (b - a) * k as f64 / STEPS as f64;
        let r = value(tau).1;
        for rho in kinks(light.falloff, r0) {
            if (prev.1 - rho) * (r - rho) < 0.0 {
                let (mut lo, mut hi) = (prev.0, tau);
                let below = prev.1 < rho;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if (value(mid).1 < rho) == below {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let cut = 0.5 * (lo + hi);
                if cut > from {
                    sum += gauss(from, cut);
                    from = cut;
                }
            }
        }
        prev = (tau, r);
    }
    sum + gauss(from, b)
}

/// How far in front of the edge's line the nearest point of the light
/// lies (0 where the light reaches the line).
fn light_front(edge: &Edge, shape: &LightShape) -> f64 {
    match *shape {
        LightShape::Line { segment, .. } => edge
            .coords(segment.a)
            .1
            .min(edge.coords(segment.b).1)
            .max(0.0),
        LightShape::Circle { at, radius } => (edge.coords(at).1 - radius).max(0.0),
        _ => 0.0,
    }
}

/// Where the line `p + t dir` meets the circle: 0 or 2 values of `t`.
fn circle_crossings(c: DVec2, radius: f64, p: DVec2, dir: DVec2) -> impl Iterator<Item = f64> {
    let o = p - c;
    let a = dir.length_squared();
    let b = o.dot(dir);
    let disc = b * b - a * (o.length_squared() - radius * radius);
    let roots = if disc >= 0.0 && a > 0.0 {
        let s = disc.sqrt();
        [(-b - s) / a, (-b + s) / a]
    } else {
        [f64::NAN; 2]
    };
    roots.into_iter().filter(|t| t.is_finite())
}

/// The `tau` interval of the rays that leave through the edge's line and
/// meet the light, before the edge's own ends cut it.
fn light_span(edge: &Edge, shape: &LightShape) -> Option<(f64, f64)> {
    match *shape {
        LightShape::Line { segment, .. } => {
            // The part in front of the edge's line.
            let (da, db) = (edge.coords(segment.a).1, edge.coords(segment.b).1);
            let (ya, yb) = match (da > 0.0, db > 0.0) {
                (false, false) => return None,
                (true, true) => (segment.a, segment.b),
                _ => {
                    let cut = segment.a + (segment.b - segment.a) * (da / (da - db));
                    if da > 0.0 {
                        (segment.a, cut)
                    } else {
                        (cut, segment.b)
                    }
                }
            };
            if edge.beyond_ends(ya, yb) {
                return None;
            }
            let (ta, tb) = (edge.root(ya), edge.root(yb));
            Some((ta.min(tb), ta.max(tb)))
        }
        LightShape::Circle { at, radius } => circle_span(edge, at, radius),
        _ => None,
    }
}

/// The `tau` interval of the rays that meet the disk at `c`: from the ray
/// through a point of the disk in front of the line, out to where the
/// rays stop meeting it on each side, by halving.
fn circle_span(edge: &Edge, c: DVec2, radius: f64) -> Option<(f64, f64)> {
    let d_c = edge.coords(c).1;
    if d_c + radius <= 0.0 || d_c.is_nan() {
        return None;
    }
    // A point of the disk in front of the line.
    let inner = if d_c > 0.0 {
        c
    } else {
        c + edge.out * (0.5 * (radius - d_c))
    };
    let start = edge.root(inner);
    // The rays that leave at all: `n |sin| < 1`.
    let reach = edge.depth / (edge.n * edge.n - 1.0).max(0.0).sqrt();
    let meets = |tau: f64| {
        edge.leaving(tau).is_some_and(|(dir, _)| {
            circle::met_by(c, radius, &Ray::new(edge.point(tau), dir), f64::INFINITY).is_some()
        })
    };
    if !meets(start) {
        return None;
    }
    // Where the rays stop meeting the disk, between `start` and `toward`.
    // With the disk wholly in front of the line, a ray meets it where its
    // line passes within `radius` of the centre: the signed miss distance
    // `|h| - radius` is continuous and changes sign once (the rays are
    // ordered), so regula falsi (Illinois) finds it in a few steps; the
    // ray at the end of the fan grazes the line, `d_c >= radius` off the
    // centre. Else the meeting test is halved.
    let wholly_in_front = d_c >= radius;
    let miss = |tau: f64| {
        let u = tau - edge.tau_x;
        let s = edge.n * u / (u * u + edge.depth * edge.depth).sqrt();
        let dir = if s.abs() < 1.0 {
            edge.along * s + edge.out * (1.0 - s * s).sqrt()
        } else {
            edge.along * s.signum()
        };
        flatray_geometry::cross(dir, c - edge.point(tau))
    };
    let end = |toward: f64| {
        if wholly_in_front {
            // The side the centre passes the rays on, out there: the
            // signed distance is smooth, and meets `radius` once.
            let sign = miss(toward).signum();
            let f = |tau: f64| sign * miss(tau) - radius;
            let (mut a, mut b) = (start, toward);
            let (mut fa, mut fb) = (f(a), f(b));
            if fb <= 0.0 {
                return b;
            }
            let mut side = 0;
            for _ in 0..MAX_STEPS {
                let c = (a * fb - b * fa) / (fb - fa);
                let c = if c > a.min(b) && c < a.max(b) {
                    c
                } else {
                    0.5 * (a + b)
                };
                if c == a || c == b {
                    break;
                }
                let fc = f(c);
                if fc <= 0.0 {
                    a = c;
                    fa = fc;
                    if side == -1 {
                        fb *= 0.5;
                    }
                    side = -1;
                } else {
                    b = c;
                    fb = fc;
                    if side == 1 {
                        fa *= 0.5;
                    }
                    side = 1;
                }
                if fc.abs() <= 1e-12 * radius
                    || (b - a).abs() <= 4.0 * f64::EPSILON * (a.abs() + b.abs() + edge.depth)
                {
                    break;
                }
            }
            return a;
        }
        let (mut inside, mut outside) = (start, toward);
        for _ in 0..MAX_STEPS {
            let mid = 0.5 * (inside + outside);
            if mid == inside || mid == outside {
                break;
            }
            if meets(mid) {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        inside
    };
    let (left, right) = if reach.is_finite() {
        (edge.tau_x - reach, edge.tau_x + reach)
    } else {
        // An index at most 1 refracts every ray out: the edge's ends bound
        // what matters.
        (
            start.min(0.0) - edge.length,
            start.max(edge.length) + edge.length,
        )
    };
    Some((end(left), end(right)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatray_geometry::cross;

    fn edge(n: f64) -> Edge {
        // The edge along +x from the origin, glass below (y < 0), x deep.
        let s = Segment::new(DVec2::new(-50.0, 0.0), DVec2::new(50.0, 0.0));
        let inside = s.side_of(DVec2::new(0.0, -1.0)).unwrap();
        Edge::new(&s, inside, DVec2::new(3.0, -7.0), n).unwrap()
    }

    /// A point 5 deep in glass of index 1.5 under a long edge, a line
    /// light 10 in front of it from -1e4 to 1e4, a wall across the way to
    /// it at 30, from 2 to 10 in front: the light through the edge, against the integral
    /// in the angle at the point of `(1 - F) n I` over the directions whose
    /// refracted ray meets the visible light, by a midpoint rule of 4
    /// million steps (with no Jacobian: the closed form's is in `tau`).
    /// Under `Flatland`, and with a wall receiver facing the edge.
    #[test]
    fn light_through_an_edge_matches_the_integral_over_angles() {
        use crate::estimators::exact::closed_forms::{OPAQUE, line, scene, wall};
        let n = 1.5;
        let face = Segment::new(DVec2::new(-1e5, 0.0), DVec2::new(1e5, 0.0));
        let inside = face.side_of(DVec2::new(0.0, -1.0)).unwrap();
        let x = DVec2::new(2.0, -5.0);
        let lamp = line(
            DVec2::new(-1e4, 10.0),
            DVec2::new(1e4, 10.0),
            Falloff::Flatland,
        );
        // A wall from the light's line at 30 down to 2 in front.
        let s = scene(
            vec![
                wall(face.a, face.b, OPAQUE),
                wall(DVec2::new(30.0, 2.0), DVec2::new(30.0, 10.0), OPAQUE),
            ],
            vec![lamp],
        );
        for normal in [None, Some(DVec2::new(0.6, 0.8))] {
            let edge = Edge::new(&face, inside, x, n).unwrap();
            let receiver = Receiver {
                normal,
                wall: None,
                shadow_walls: None,
            };
            let mut stats = Stats::default();
            let got = through_edge(&s, &edge, 0, 0, receiver, Rgb::ZERO, &mut stats).x;
            let steps = 4_000_000;
            let limit = (1.0 / n).asin();
            let mut expected = 0.0;
            for k in 0..steps {
                let theta = -limit + 2.0 * limit * (k as f64 + 0.5) / steps as f64;
                let out = (n * theta.sin()).asin();
                let p = x.x + 5.0 * theta.tan();
                let y = p + 10.0 * out.tan();
                // Where the ray crosses x = 30, if it does: hidden above 2.
                let hidden = (p < 30.0) != (y < 30.0) && 10.0 * (30.0 - p) / (y - p) > 2.0;
                if y.abs() < 1e4 && !hidden {
                    let cosine = normal.map_or(1.0, |m| {
                        m.dot(DVec2::new(theta.sin(), theta.cos())).max(0.0)
                    });
                    expected += (1.0 - fresnel(n, 1.0, theta.cos())) * n * cosine;
                }
            }
            expected *= 2.0 * limit / steps as f64;
            assert!(
                (got - expected).abs() < 1e-5 * expected,
                "{normal:?}: {got} against {expected}"
            );
        }
    }

    /// The root obeys Snell's law and its ray reaches the point.
    #[test]
    fn the_root_is_the_refracted_path() {
        let e = edge(1.5);
        for y in [
            DVec2::new(20.0, 30.0),
            DVec2::new(-40.0, 1e-3),
            DVec2::new(3.0, 5.0),
            DVec2::new(1e4, 2.0),
        ] {
            let tau = e.root(y);
            let p = e.point(tau);
            let (dir, _) = e.leaving(tau).unwrap();
            let to = (y - p).normalize();
            assert!(cross(dir, to).abs() < 1e-9, "{y}: {dir} {to}");
            assert!(dir.dot(to) > 0.0);
        }
        // Points all over the front, from near the line to far off it,
        // for indices above and below 1: the root is where Fermat's
        // condition `n sin(inside) = sin(outside)` changes sign, found
        // here by halving its bracket to the last bit.
        let mut stream = crate::sampling::Stream::new(3, 1, 4);
        for n in [1.5, 1.33, 2.4, 0.8] {
            let e = edge(n);
            for _ in 0..20_000 {
                let d = (stream.uniform() * 24.0 - 12.0).exp();
                let y = DVec2::new((stream.uniform() - 0.5) * 400.0, d);
                let (tau_y, d_y) = e.coords(y);
                let fermat = |tau: f64| {
                    let (u, v) = (tau - e.tau_x, tau_y - tau);
                    n * u / (u * u + e.depth * e.depth).sqrt() - v / (v * v + d_y * d_y).sqrt()
                };
                let (mut lo, mut hi) = (e.tau_x.min(tau_y), e.tau_x.max(tau_y));
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid == lo || mid == hi {
                        break;
                    }
                    if fermat(mid) < 0.0 {
                        lo = mid
                    } else {
                        hi = mid
                    }
                }
                let tau = e.root(y);
                let scale = (lo - e.tau_x).abs() + e.depth;
                assert!(
                    (tau - lo).abs() <= 1e-12 * scale,
                    "n {n}, {y}: root {tau}, halving {lo}"
                );
            }
        }
    }

    /// Points that `beyond_ends` puts before the first end or after the
    /// last are reached by rays that leave there, and a light it keeps
    /// has a point reached through the edge; on edges turned every way,
    /// from deep and shallow receivers, with indices above and below 1.
    #[test]
    fn beyond_ends_leaves_out_only_what_the_edge_shows_none_of() {
        let mut stream = crate::sampling::Stream::new(5, 7, 11);
        let (mut before, mut after, mut kept) = (0, 0, 0);
        for _ in 0..4000 {
            let angle = stream.uniform() * std::f64::consts::TAU;
            let along = DVec2::new(angle.cos(), angle.sin());
            let a = DVec2::new(
                stream.uniform() * 20.0 - 10.0,
                stream.uniform() * 20.0 - 10.0,
            );
            let length = 0.5 + stream.uniform() * 10.0;
            let segment = Segment::new(a, a + along * length);
            let inside = if stream.uniform() < 0.5 {
                Side::Positive
            } else {
                Side::Negative
            };
            let out = -along.perp() * inside.sign();
            let depth = 0.01 + stream.uniform() * 8.0;
            let x = a + along * (stream.uniform() * 30.0 - 10.0) - out * depth;
            let n = if stream.uniform() < 0.8 { 1.5 } else { 0.8 };
            let Some(edge) = Edge::new(&segment, inside, x, n) else {
                continue;
            };
            let front = |stream: &mut crate::sampling::Stream| {
                a + along * (stream.uniform() * 60.0 - 25.0) + out * (stream.uniform() * 15.0)
            };
            let (ya, yb) = (front(&mut stream), front(&mut stream));
            let (ta, tb) = (edge.root(ya), edge.root(yb));
            if edge.beyond_ends(ya, yb) {
                let low = ta < 0.0 && tb < 0.0;
                let high = ta > length && tb > length;
                assert!(low || high, "{ya} {yb}: roots {ta} {tb}, length {length}");
                before += low as u32;
                after += high as u32;
            } else {
                kept += 1;
            }
        }
        assert!(
            before > 100 && after > 100 && kept > 1000,
            "{before} {after} {kept}"
        );
    }
}
