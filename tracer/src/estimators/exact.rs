//! Direct light from a line or circle light in closed form.
//!
//! What a receiver point `x` sees of a light with an area is a set of
//! directions: the angle the light subtends, less the parts that walls in
//! front of it cover (and tinted where panes cover it). The light brings
//! `I G(r) r` per radian of that set (`Falloff::per_radian`), times the
//! receiver's cosine at a wall. Both the set and the integral are
//! computed here, not sampled:
//!
//! - a line light is cut at the positions `s` along it where a wall's
//!   shadow begins or ends (each wall's shadow on the light's segment is
//!   one interval, found by clipping `[0, 1]` against three half-planes,
//!   linear in `s`), and each visible piece is integrated by its
//!   antiderivative in the distance `u` along the light's line, for every
//!   falloff and both receivers;
//! - a circle light is cut along the near rim it shows `x` at every angle
//!   where a wall's shadow can begin or end, each piece is tested at its
//!   middle, and integrated exactly under `Flatland` (the angle, or the
//!   sine of the cosine's antiderivative) and by 12-point Gauss-Legendre in
//!   the rim's angle, split where the falloff has a kink, for the others.
//!
//! An arc in front of a light is handled the same way: the places where
//! its shadow can begin or end (the rays through its ends and tangent to
//! its circle, and where it crosses the light) cut the light, and each
//! piece is tested at its middle by the exact ray-arc crossing.
//!
//! The answer does not depend on a random number: next-event estimation
//! with it has no variance from the light's sampling, only from where the
//! receiver point is. `docs/model.md` ("Direct light in closed form")
//! states where it is used and where the light stays sampled.

use std::cell::RefCell;

use flatray_geometry::{Arc, DVec2, Ray, Segment, Shape, Skip, cross, intersect};

use crate::decision::Decision;
use crate::estimators::{Receiver, Visibility};
use crate::options::RenderOptions;
use crate::scene::{EMITTING_SIDE, Falloff, LightShape, Material, Profile, Scene};
use crate::{Rgb, Stats};

/// A span of the light (positions along a line light, `[0, 1]`; angles
/// of a circle light's rim about the direction to `x`) and what of the
/// light gets through there.
#[derive(Clone, Copy, Debug)]
struct Span {
    from: f64,
    to: f64,
    through: Rgb,
}

/// A wall in front of the light, as the sweep over the light's spans
/// takes it.
#[derive(Clone, Copy, Debug)]
struct Cover {
    from: f64,
    to: f64,
    /// `None`: opaque; else a pane's tint.
    tint: Option<Rgb>,
    wall: u32,
}

/// Reused buffers, one set per thread: the walls near the light, the
/// covers they cast and the visible spans. They grow with the walls in
/// front of one light, never with the render.
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) walls: Vec<u32>,
    query: Vec<u32>,
    covers: Vec<Cover>,
    spans: Vec<Span>,
    pub(super) cuts: Vec<f64>,
}

thread_local! {
    pub(super) static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Pieces of a light (and shadows on it) no wider than this share of the
/// light's whole span count for nothing: a shadow that grazes the
/// light's end, or a gap that rounding leaves between two walls that
/// share a corner, or between a wall and the horizon of a receiver on its
/// neighbour, changes neither the image nor, when nothing else is in the
/// way, the bits of the whole light's integral.
pub(super) const SLIVER: f64 = 1e-9;

/// Whether light `shape` is given in closed form: lines and circles.
#[inline]
pub(crate) fn is_exact(shape: &LightShape) -> bool {
    matches!(shape, LightShape::Line { .. } | LightShape::Circle { .. })
}

/// The light that line or circle light `index` brings `x`, uncoloured by
/// the light's colour but tinted by the panes it crosses: fluence on the
/// floor, irradiance on a wall side (`receiver.normal`). With
/// `Visibility::Trace` the walls in front of the light are found and
/// taken out (those in `receiver.walls_towards(index)` where known, else
/// the walls whose boxes meet the box around `x` and the light); with
/// `Visibility::Known(t)`, the whole light times `t`. `None` for a light
/// that is not a line or a circle.
pub(crate) fn exact_light(
    scene: &Scene,
    index: usize,
    x: DVec2,
    receiver: Receiver,
    vis: Visibility,
    stats: &mut Stats,
) -> Option<Rgb> {
    let light = &scene.lights[index];
    let r0 = scene.small_radius;
    let value = match light.shape {
        LightShape::Line {
            segment, one_sided, ..
        } => {
            if one_sided && segment.side_of(x) != Some(EMITTING_SIDE) {
                return Some(Rgb::ZERO);
            }
            let line = LineView::new(x, &segment)?;
            let Some(whole) = line.receiving(receiver.normal) else {
                return Some(Rgb::ZERO);
            };
            SCRATCH.with(|scratch| {
                let scratch = &mut *scratch.borrow_mut();
                scratch.spans.clear();
                match vis {
                    Visibility::Known(t) => scratch.spans.push(Span {
                        from: whole.0,
                        to: whole.1,
                        through: t,
                    }),
                    Visibility::Trace => {
                        let hull = [x, segment.a, segment.b];
                        find_walls(scene, index, receiver, &hull, scratch, stats);
                        scratch.covers.clear();
                        let skip = receiver.skip(scene.light_wall[index]);
                        for &w in &scratch.walls {
                            match &scene.walls[w as usize].shape {
                                Shape::Segment(segment) => {
                                    line.cover(scene, w, segment, whole, &mut scratch.covers);
                                }
                                Shape::Arc(arc) => line.arc_cover(
                                    scene,
                                    (w, arc, skip),
                                    whole,
                                    &mut scratch.cuts,
                                    &mut scratch.covers,
                                ),
                            }
                        }
                        sweep(whole, scratch);
                    }
                }
                let profile = light.profile.as_deref();
                line.spans_integral(
                    &scratch.spans,
                    receiver.normal,
                    (light.falloff, profile),
                    r0,
                )
            })
        }
        LightShape::Circle { at, radius } => {
            let disk = DiskView::new(x, at, radius)?;
            SCRATCH.with(|scratch| {
                let scratch = &mut *scratch.borrow_mut();
                let whole = (-disk.half, disk.half);
                scratch.covers.clear();
                let trace = vis == Visibility::Trace;
                if trace {
                    let (lo, hi) = (at - DVec2::splat(radius), at + DVec2::splat(radius));
                    let hull = [x, lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
                    find_walls(scene, index, receiver, &hull, scratch, stats);
                }
                // Every angle where what the rim shows `x` can change:
                // where a wall's shadow begins or ends, where the
                // receiver's cosine turns, where the falloff has a kink.
                let mut kink_cuts = [f64::NAN; 4];
                if light.falloff != Falloff::Flatland {
                    for (k, rho) in kinks(light.falloff, r0).enumerate().take(2) {
                        if let Some(t) = disk.at_distance(rho) {
                            kink_cuts[2 * k] = -t;
                            kink_cuts[2 * k + 1] = t;
                        }
                    }
                    kink_cuts.sort_unstable_by(f64::total_cmp);
                }
                let cuts = &mut scratch.cuts;
                cuts.clear();
                cuts.extend([whole.0, whole.1]);
                if let Some(n) = receiver.normal {
                    disk.cuts_by_line(x, n.perp(), cuts);
                }
                if trace {
                    for &w in &scratch.walls {
                        match &scene.walls[w as usize].shape {
                            Shape::Segment(s) => {
                                disk.cuts_by_line(s.a, s.b - s.a, cuts);
                                disk.cuts_by_ray(x, s.a - x, cuts);
                                disk.cuts_by_ray(x, s.b - x, cuts);
                            }
                            Shape::Arc(arc) => {
                                for p in arc_turning_points(arc, x) {
                                    disk.cuts_by_ray(x, p - x, cuts);
                                }
                                for p in circles_meet(arc.center, arc.radius, at, radius)
                                    .into_iter()
                                    .flatten()
                                {
                                    disk.cuts_by_ray(x, p - x, cuts);
                                }
                            }
                        }
                    }
                }
                cuts.retain(|t| *t >= whole.0 && *t <= whole.1);
                cuts.sort_unstable_by(f64::total_cmp);
                cuts.dedup();
                // Each piece is seen as its middle is; neighbours seen
                // alike are one span, so that walls that hide nothing
                // leave the integral's bits as they are.
                let sliver = SLIVER * (whole.1 - whole.0);
                scratch.spans.clear();
                for k in 1..scratch.cuts.len() {
                    let (a, b) = (scratch.cuts[k - 1], scratch.cuts[k]);
                    if b - a <= sliver {
                        continue;
                    }
                    let mid = disk.rim(0.5 * (a + b));
                    let seen = receiver.normal.is_none_or(|n| n.dot(mid - x) > 0.0);
                    let through = match vis {
                        _ if !seen => Rgb::ZERO,
                        Visibility::Known(t) => t,
                        Visibility::Trace => {
                            through_walls(scene, &scratch.walls, x, mid, receiver, index)
                        }
                    };
                    if through == Rgb::ZERO {
                        continue;
                    }
                    extend_spans(&mut scratch.spans, (a, b), through);
                }
                let mut sum = Rgb::ZERO;
                for span in &scratch.spans {
                    // Integrated between the kinks, where it is smooth.
                    let (mut a, b) = (span.from, span.to);
                    for &cut in kink_cuts.iter() {
                        if cut > a && cut < b {
                            sum += span.through
                                * disk.integral(a, cut, receiver.normal, light.falloff, r0);
                            a = cut;
                        }
                    }
                    sum += span.through * disk.integral(a, b, receiver.normal, light.falloff, r0);
                }
                sum
            })
        }
        _ => return None,
    };
    Some(value * light.intensity)
}

/// Most pairs of a flat mirror and a line or circle light that receivers
/// take in closed form through the mirror (`ClosedForms::mirror_lights`):
/// each pair costs every receiver point a look at the walls around the
/// mirror and the light.
pub const MAX_MIRROR_PAIRS: usize = 64;

/// The flat mirror and line or circle light pairs of `scene`.
pub(crate) fn mirror_pairs(scene: &Scene) -> usize {
    scene.flat_mirrors.len() * scene.lights.iter().filter(|l| is_exact(&l.shape)).count()
}

/// Whether receivers take line and circle lights seen in one flat mirror
/// in closed form ([`through_mirrors`]), and why: where shadow rays are
/// cast, light is reflected, the pairs fit [`MAX_MIRROR_PAIRS`] and no
/// wall is an arc (the closed form takes the walls around a mirror as
/// segments). Elsewhere path rays find that light.
pub(crate) fn decide(scene: &Scene, options: &RenderOptions, shadows: bool) -> Decision {
    let terms = super::Terms {
        pairs: mirror_pairs(scene),
        most: MAX_MIRROR_PAIRS,
        pair: "flat mirror and light pair",
        none: "no flat mirror and line or circle light in the scene",
        event: "reflected",
        otherwise: "path rays find them",
        runs: "every floor and wall point takes them exactly; path rays add them only after more than one mirror or glass event",
    };
    let held = super::has_arcs(scene).then_some("the scene has arcs: path rays find them");
    super::decide(options, shadows, terms, held)
}

/// The light that every line and circle light brings `x` after exactly
/// one reflection off one of `mirrors` (flat mirrors; their tints), in
/// closed form: the light seen from `x` reflected in the mirror's line,
/// through the mirror's segment as a window, with the walls before the
/// mirror (reflected) and after it in the way. Tinted by the light's
/// colour. `docs/model.md`, "Lines and circles in a mirror".
pub(crate) fn through_mirrors(
    scene: &Scene,
    mirrors: &[u32],
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    for index in 0..scene.lights.len() {
        if is_exact(&scene.lights[index].shape) {
            sum += through_mirrors_of(scene, mirrors, index, x, receiver, stats);
        }
    }
    sum
}

/// [`through_mirrors`] for light `index` alone (nothing for a light that
/// is not a line or a circle).
pub(crate) fn through_mirrors_of(
    scene: &Scene,
    mirrors: &[u32],
    index: usize,
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    if !is_exact(&light.shape) {
        return Rgb::ZERO;
    }
    let mut sum = Rgb::ZERO;
    for &m in mirrors {
        let wall = &scene.walls[m as usize];
        let Material::Mirror { tint } = wall.material else {
            continue;
        };
        if receiver.wall == Some(m) {
            continue;
        }
        // The plan takes lights in mirrors in closed form only in scenes
        // without arcs; flat mirrors are segments.
        let Some(segment) = wall.as_segment() else {
            continue;
        };
        let v = in_mirror(scene, index, m, segment, x, receiver, stats);
        sum += v * tint;
    }
    sum * light.color
}

/// What a line or circle light as seen from one side of a mirror: the
/// light's points from a viewpoint, the cuts where what is seen can
/// change, and the integral over a piece.
enum View {
    Line(LineView),
    Disk(DiskView),
}

impl View {
    fn point(&self, t: f64) -> DVec2 {
        match self {
            View::Line(l) => l.point(t),
            View::Disk(d) => d.rim(t),
        }
    }

    /// Adds the cut where the ray from the viewpoint through `p` meets
    /// the light.
    fn cut_toward(&self, p: DVec2, cuts: &mut Vec<f64>) {
        match self {
            View::Line(l) => {
                let d = p - l.x;
                let s = cross(d, l.a - l.x) / cross(l.edge, d);
                if s.is_finite() {
                    cuts.push(s);
                }
            }
            View::Disk(disk) => disk.cuts_by_ray(disk.x, p - disk.x, cuts),
        }
    }

    /// Adds the cuts where the line through `p` along `dir` meets the
    /// light.
    fn cut_line(&self, p: DVec2, dir: DVec2, cuts: &mut Vec<f64>) {
        match self {
            View::Line(l) => {
                let s = cross(p - l.a, dir) / cross(l.edge, dir);
                if s.is_finite() {
                    cuts.push(s);
                }
            }
            View::Disk(disk) => disk.cuts_by_line(p, dir, cuts),
        }
    }
}

/// Reflects `p` across the line of `mirror`.
#[inline]
fn reflect_point(mirror: &Segment, p: DVec2) -> DVec2 {
    let e = mirror.b - mirror.a;
    let foot = mirror.a + e * ((p - mirror.a).dot(e) / e.length_squared());
    2.0 * foot - p
}

/// The light `index` brings `x` off mirror `m` (its segment `mirror`),
/// uncoloured and untinted by the mirror, times the light's intensity.
fn in_mirror(
    scene: &Scene,
    index: usize,
    m: u32,
    mirror: &Segment,
    x: DVec2,
    receiver: Receiver,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    let r0 = scene.small_radius;
    // Seen from the image, the directions towards the light are those its
    // light leaves in, reversed: what its profile takes.
    let emitter = (light.falloff, light.profile.as_deref());
    // A point on the mirror's line sees it edge-on.
    let side = mirror.side_value(x);
    if side == 0.0 || !side.is_finite() {
        return Rgb::ZERO;
    }
    let image = reflect_point(mirror, x);
    let e = mirror.b - mirror.a;
    // The receiver's normal reflected in the mirror's line, as the image sees it.
    let normal = receiver
        .normal
        .map(|n| 2.0 * e * (n.dot(e) / e.length_squared()) - n);
    let (view, whole, hull) = match light.shape {
        LightShape::Line {
            segment, one_sided, ..
        } => {
            // A light wholly behind the mirror's line sends nothing to
            // this side by it.
            let (sa, sb) = (mirror.side_value(segment.a), mirror.side_value(segment.b));
            if sa * side <= 0.0 && sb * side <= 0.0 {
                return Rgb::ZERO;
            }
            if one_sided && segment.side_of(image) != Some(EMITTING_SIDE) {
                return Rgb::ZERO;
            }
            let Some(line) = LineView::new(image, &segment) else {
                return Rgb::ZERO;
            };
            let Some(whole) = line.receiving(normal) else {
                return Rgb::ZERO;
            };
            (
                View::Line(line),
                whole,
                [segment.a, segment.b, segment.a, segment.b],
            )
        }
        LightShape::Circle { at, radius } => {
            if mirror.side_value(at) * side <= 0.0 {
                return Rgb::ZERO;
            }
            let Some(disk) = DiskView::new(image, at, radius) else {
                return Rgb::ZERO;
            };
            let whole = (-disk.half, disk.half);
            let r = DVec2::splat(radius);
            (View::Disk(disk), whole, [at - r, at + r, at - r, at + r])
        }
        _ => return Rgb::ZERO,
    };
    // The part of the light seen through the mirror's segment: for a
    // line, the mirror's own shadow on it seen from the image.
    let whole = match &view {
        View::Line(line) => match line.shadow_of(mirror, whole) {
            Some(window) if window.1 - window.0 > SLIVER => window,
            _ => return Rgb::ZERO,
        },
        View::Disk(_) => whole,
    };
    SCRATCH.with(|scratch| {
        let scratch = &mut *scratch.borrow_mut();
        let points = [x, mirror.a, mirror.b, hull[0], hull[1]];
        find_walls(scene, index, Receiver::FLOOR, &points, scratch, stats);
        if let View::Line(line) = &view {
            // Each wall's part on this side of the mirror's line hides
            // one interval of the light twice over: itself, after the
            // mirror, and its image, before it (but the receiver's own
            // wall, which the first leg leaves from).
            scratch.covers.clear();
            for &w in &scratch.walls {
                if w == m {
                    continue;
                }
                let wall = &scene.walls[w as usize];
                let Some(front) = wall.as_segment().and_then(|s| front_part(mirror, side, s))
                else {
                    continue;
                };
                let image_of = Segment::new(
                    reflect_point(mirror, front.a),
                    reflect_point(mirror, front.b),
                );
                let legs = [(front, false), (image_of, true)];
                for (segment, first_leg) in legs {
                    if first_leg && receiver.wall == Some(w) {
                        continue;
                    }
                    line.cover(scene, w, &segment, whole, &mut scratch.covers);
                }
            }
            sweep(whole, scratch);
            return line.spans_integral(&scratch.spans, normal, emitter, r0) * light.intensity;
        }
        let cuts = &mut scratch.cuts;
        cuts.clear();
        cuts.extend([whole.0, whole.1]);
        view.cut_toward(mirror.a, cuts);
        view.cut_toward(mirror.b, cuts);
        if let Some(n) = normal {
            view.cut_line(image, n.perp(), cuts);
        }
        for &w in &scratch.walls {
            if w == m {
                continue;
            }
            let Some(&s) = scene.walls[w as usize].as_segment() else {
                continue;
            };
            let (a, b) = (reflect_point(mirror, s.a), reflect_point(mirror, s.b));
            for p in [s.a, s.b, a, b] {
                view.cut_toward(p, cuts);
            }
            view.cut_line(s.a, s.b - s.a, cuts);
            view.cut_line(a, b - a, cuts);
            // Where the wall crosses the mirror's line, it passes from
            // one leg to the other.
            if let Some(h) = flatray_geometry::line_crossing(&Ray::new(s.a, s.b - s.a), mirror) {
                view.cut_toward(s.a + (s.b - s.a) * h.t, cuts);
            }
        }
        let mut kink_cuts = [f64::NAN; 4];
        if let View::Disk(disk) = &view
            && light.falloff != Falloff::Flatland
        {
            for (k, rho) in kinks(light.falloff, r0).enumerate().take(2) {
                if let Some(t) = disk.at_distance(rho) {
                    kink_cuts[2 * k] = -t;
                    kink_cuts[2 * k + 1] = t;
                }
            }
            kink_cuts.sort_unstable_by(f64::total_cmp);
        }
        cuts.retain(|t| *t >= whole.0 && *t <= whole.1);
        cuts.sort_unstable_by(f64::total_cmp);
        cuts.dedup();
        let sliver = SLIVER * (whole.1 - whole.0);
        scratch.spans.clear();
        let skip_leg_one = Skip(receiver.wall.unwrap_or(u32::MAX), m);
        let skip_leg_two = Skip(m, scene.light_wall[index].unwrap_or(u32::MAX));
        for k in 1..scratch.cuts.len() {
            let (a, b) = (scratch.cuts[k - 1], scratch.cuts[k]);
            if b - a <= sliver {
                continue;
            }
            let p = view.point(0.5 * (a + b));
            if normal.is_some_and(|n| n.dot(p - image) <= 0.0) {
                continue;
            }
            // Where the unfolded ray from the image meets the mirror.
            let Some(h) = intersect(&Ray::new(image, p - image), mirror) else {
                continue;
            };
            if !(h.t > 0.0 && h.t < 1.0) {
                continue;
            }
            let at = image + (p - image) * h.t;
            let through = legs(scene, &scratch.walls, (x, at), skip_leg_one)
                * legs(scene, &scratch.walls, (at, p), skip_leg_two);
            if through == Rgb::ZERO {
                continue;
            }
            extend_spans(&mut scratch.spans, (a, b), through);
        }
        let mut sum = Rgb::ZERO;
        for span in &scratch.spans {
            sum += span.through
                * match &view {
                    View::Line(line) => line.integral(span.from, span.to, normal, emitter, r0),
                    View::Disk(disk) => {
                        let (mut a, b) = (span.from, span.to);
                        let mut v = 0.0;
                        for &cut in kink_cuts.iter() {
                            if cut > a && cut < b {
                                v += disk.integral(a, cut, normal, light.falloff, r0);
                                a = cut;
                            }
                        }
                        v + disk.integral(a, b, normal, light.falloff, r0)
                    }
                };
        }
        sum * light.intensity
    })
}

/// The part of `segment` on the side of `mirror`'s line whose side value
/// has the sign of `side`, if any.
fn front_part(mirror: &Segment, side: f64, segment: &Segment) -> Option<Segment> {
    let (sa, sb) = (
        mirror.side_value(segment.a) * side.signum(),
        mirror.side_value(segment.b) * side.signum(),
    );
    match (sa > 0.0, sb > 0.0) {
        (true, true) => Some(*segment),
        (false, false) => None,
        _ => {
            let cut = segment.a + (segment.b - segment.a) * (sa / (sa - sb));
            Some(if sa > 0.0 {
                Segment::new(segment.a, cut)
            } else {
                Segment::new(cut, segment.b)
            })
        }
    }
}

/// The product of the tints of `walls` (but those `skip` names) that the
/// segment from `from` to `to` crosses, zero at the first opaque one.
pub(super) fn legs(scene: &Scene, walls: &[u32], (from, to): (DVec2, DVec2), skip: Skip) -> Rgb {
    let ray = Ray::new(from, to - from);
    let mut through = Rgb::ONE;
    for &w in walls {
        let wall = &scene.walls[w as usize];
        let crossings = match &wall.shape {
            Shape::Segment(_) if skip.contains(w) => 0,
            Shape::Segment(segment) => intersect(&ray, segment)
                .is_some_and(|hit| hit.t > 0.0 && hit.t < 1.0)
                .into(),
            // A leg that leaves or reaches an arc can still cross it.
            Shape::Arc(arc) => crossings_within(arc, &ray, skip, w),
        };
        for _ in 0..crossings {
            match wall.material.pane_tint() {
                Some(tint) => through *= tint,
                None => return Rgb::ZERO,
            }
        }
    }
    through
}

/// The candidate walls in front of light `index` seen from the receiver:
/// its list where known, else those whose boxes meet the box around
/// `hull` (padded by a relative `1e-9`), without the receiver's wall and
/// the light's own. Counts one shadow query.
pub(super) fn find_walls(
    scene: &Scene,
    index: usize,
    receiver: Receiver,
    hull: &[DVec2],
    scratch: &mut Scratch,
    stats: &mut Stats,
) {
    stats.work.shadow_rays += 1;
    let skip = receiver.skip(scene.light_wall[index]);
    scratch.walls.clear();
    match receiver.walls_towards(index) {
        Some(list) => {
            stats.work.listed_shadow_rays += 1;
            scratch.walls.extend(
                list.iter()
                    .copied()
                    .filter(|&w| !skip.contains(w) || scene.segments.arc(w).is_some()),
            );
        }
        None => {
            let (mut lo, mut hi) = (hull[0], hull[0]);
            for &p in hull {
                lo = lo.min(p);
                hi = hi.max(p);
            }
            let pad = DVec2::splat(1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element()));
            let Scratch { walls, query, .. } = scratch;
            scene
                .segments
                .for_each_in_box(lo - pad, hi + pad, query, |w| {
                    // An arc can hide light from a point on itself.
                    if !skip.contains(w) || scene.segments.arc(w).is_some() {
                        walls.push(w);
                    }
                });
        }
    }
    // Walls that let everything through need no shadow of their own.
    scratch
        .walls
        .retain(|&w| scene.walls[w as usize].material.pane_tint() != Some(Rgb::ONE));
}

/// The product of the tints of `walls` that the segment from `x` to `p`
/// crosses (in the walls' order), zero at the first opaque one.
fn through_walls(
    scene: &Scene,
    walls: &[u32],
    x: DVec2,
    p: DVec2,
    receiver: Receiver,
    index: usize,
) -> Rgb {
    legs(scene, walls, (x, p), receiver.skip(scene.light_wall[index]))
}

/// Adds the piece from `a` to `b` that lets `through` through to
/// `spans`: the last span grown where it ends at `a` and lets the same
/// through, so that walls that hide nothing leave the integral's bits as
/// they are.
#[inline]
fn extend_spans(spans: &mut Vec<Span>, (a, b): (f64, f64), through: Rgb) {
    match spans.last_mut() {
        Some(last) if last.to == a && last.through == through => last.to = b,
        _ => spans.push(Span {
            from: a,
            to: b,
            through,
        }),
    }
}

/// Turns the covers of `scratch` into the visible spans of `whole`: where
/// no opaque cover lies, with the product of the panes' tints over each
/// span (in the order of their walls' indices).
fn sweep(whole: (f64, f64), scratch: &mut Scratch) {
    let Scratch {
        covers,
        spans,
        cuts,
        ..
    } = scratch;
    spans.clear();
    if covers.is_empty() {
        spans.push(Span {
            from: whole.0,
            to: whole.1,
            through: Rgb::ONE,
        });
        return;
    }
    covers.sort_unstable_by_key(|c| c.wall);
    cuts.clear();
    cuts.extend([whole.0, whole.1]);
    for c in covers.iter() {
        cuts.extend([c.from, c.to]);
    }
    cuts.sort_unstable_by(f64::total_cmp);
    cuts.dedup();
    let sliver = SLIVER * (whole.1 - whole.0);
    for pair in cuts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if b <= a || a < whole.0 || b > whole.1 {
            continue;
        }
        let mut through = Rgb::ONE;
        for c in covers.iter() {
            if c.from <= a && c.to >= b {
                match c.tint {
                    Some(tint) => through *= tint,
                    None => {
                        through = Rgb::ZERO;
                        break;
                    }
                }
            }
        }
        if through == Rgb::ZERO || b - a <= sliver {
            continue;
        }
        // Neighbours that let the same through are one span: a light
        // with no wall in front of it is one span, whatever cuts it.
        extend_spans(spans, (a, b), through);
    }
}

/// The distances at which `falloff.per_radian` has a kink: the small
/// radius (inside it, the distance is clamped), and a window's range
/// (beyond it, nothing).
pub(super) fn kinks(falloff: Falloff, r0: f64) -> impl Iterator<Item = f64> {
    let range = match falloff {
        Falloff::Window { range } => Some(range),
        _ => None,
    };
    std::iter::once(r0)
        .chain(range)
        .filter(|r| r.is_finite() && *r > 0.0)
}

/// A line light seen from `x`: its points `A + s (B - A)`, and the
/// coordinates that its integrals take: `u`, the signed distance along
/// its line from the foot of the perpendicular from `x`, and `h`, that
/// perpendicular's length.
struct LineView {
    x: DVec2,
    a: DVec2,
    edge: DVec2,
    /// Unit, along the light.
    along: DVec2,
    length: f64,
    /// `u` at `s = 0`.
    u0: f64,
    h: f64,
    /// From `x` to the foot of the perpendicular.
    foot: DVec2,
}

impl LineView {
    /// `None` where the light's segment has no length; a point on the
    /// light's line sees none of it (every direction grazes), which the
    /// caller gets as `h == 0` and an empty integral.
    fn new(x: DVec2, segment: &Segment) -> Option<LineView> {
        let edge = segment.b - segment.a;
        let length = edge.length();
        if length.is_nan() || length <= 0.0 {
            return None;
        }
        let along = edge / length;
        let va = segment.a - x;
        let u0 = va.dot(along);
        let foot = va - along * u0;
        let h = cross(along, va).abs();
        Some(LineView {
            x,
            a: segment.a,
            edge,
            along,
            length,
            u0,
            h,
            foot,
        })
    }

    #[inline]
    fn point(&self, s: f64) -> DVec2 {
        self.a + self.edge * s
    }

    /// The part of `[0, 1]` that a receiver of unit normal `normal` can
    /// receive from: where the light lies on the normal's side of the
    /// receiver (all of it for the floor). `None` where nothing is left,
    /// or `x` lies on the light's line.
    fn receiving(&self, normal: Option<DVec2>) -> Option<(f64, f64)> {
        if self.h.is_nan() || self.h <= 0.0 {
            return None;
        }
        let whole = (0.0, 1.0);
        match normal {
            None => Some(whole),
            Some(n) => {
                let at = |p: DVec2| n.dot(p - self.x);
                clip(whole, at(self.point(0.0)), at(self.point(1.0)), false)
            }
        }
    }

    /// The positions `s` in `within` where `wall` lies strictly between
    /// `x` and the light: inside the angle the wall subtends at `x`, and
    /// beyond the wall's line from `x`. One interval, since both are
    /// convex; `None` where the wall covers none of the light.
    fn shadow_of(&self, wall: &Segment, within: (f64, f64)) -> Option<(f64, f64)> {
        let (p, q) = (wall.a - self.x, wall.b - self.x);
        let turn = cross(p, q);
        if turn == 0.0 {
            // `x` lies on the wall's line: the wall is seen edge-on.
            return None;
        }
        let sign = turn.signum();
        let (la, lb) = (self.point(0.0) - self.x, self.point(1.0) - self.x);
        // Inside the angle from `p` to `q`.
        let span = clip(within, sign * cross(p, la), sign * cross(p, lb), false)?;
        let span = clip(span, sign * cross(la, q), sign * cross(lb, q), false)?;
        // Strictly beyond the wall's line: on the other side from `x`
        // (whose side is `sign`). A light point on that line is not
        // hidden: a shadow ray to it ends there.
        let e = q - p;
        clip(
            span,
            -sign * cross(e, la - p),
            -sign * cross(e, lb - p),
            true,
        )
    }

    /// Adds to `covers` the shadow that `segment` (wall `w`'s, or a part
    /// or image of it) casts on `within`, if it is wider than a sliver.
    fn cover(
        &self,
        scene: &Scene,
        w: u32,
        segment: &Segment,
        within: (f64, f64),
        covers: &mut Vec<Cover>,
    ) {
        if let Some((from, to)) = self.shadow_of(segment, within)
            && to - from > SLIVER
        {
            covers.push(Cover {
                from,
                to,
                tint: scene.walls[w as usize].material.pane_tint(),
                wall: w,
            });
        }
    }

    /// Adds to `covers` the shadow that arc `w` casts on `within`: the
    /// light cut where the arc's shadow can begin or end (the rays from
    /// `x` through its ends and its tangent points, and where the arc
    /// crosses the light), each piece tested at its middle by the exact
    /// crossing, with `skip` (the receiver's and the light's walls) as
    /// shadow rays take it. `cuts` is scratch.
    fn arc_cover(
        &self,
        scene: &Scene,
        (w, arc, skip): (u32, &Arc, Skip),
        within: (f64, f64),
        cuts: &mut Vec<f64>,
        covers: &mut Vec<Cover>,
    ) {
        // An arc whose circle stays clear of the triangle from `x` to the
        // light hides none of it (`x` on the arc lies on the circle: the
        // test then passes).
        let (pa, pb) = (self.point(within.0), self.point(within.1));
        if !circle_meets_triangle(arc.center, arc.radius, [self.x, pa, pb]) {
            return;
        }
        cuts.clear();
        cuts.extend([within.0, within.1]);
        let la = self.a - self.x;
        for p in arc_turning_points(arc, self.x) {
            // Where the line from `x` through `p` meets the light's line.
            let e = p - self.x;
            let s = -cross(e, la) / cross(e, self.edge);
            if s.is_finite() {
                cuts.push(s);
            }
        }
        let along = Ray::new(self.a, self.edge);
        let (roots, n) = arc.line_crossings(&along, false, None);
        cuts.extend(roots[..n].iter().copied());
        cuts.retain(|s| *s >= within.0 && *s <= within.1);
        cuts.sort_unstable_by(f64::total_cmp);
        cuts.dedup();
        let tint = scene.walls[w as usize].material.pane_tint();
        for k in 1..cuts.len() {
            let (from, to) = (cuts[k - 1], cuts[k]);
            if to <= from {
                continue;
            }
            let mid = self.point(0.5 * (from + to));
            let ray = Ray::new(self.x, mid - self.x);
            let crossed = crossings_within(arc, &ray, skip, w);
            // A pane arc crossed twice tints twice: two covers.
            for _ in 0..crossed {
                match covers.last_mut() {
                    Some(last) if last.wall == w && last.to == from && crossed == 1 => {
                        last.to = to;
                    }
                    _ => covers.push(Cover {
                        from,
                        to,
                        tint,
                        wall: w,
                    }),
                }
            }
        }
    }

    /// The sum over `spans` of what gets through each times its integral.
    fn spans_integral(
        &self,
        spans: &[Span],
        normal: Option<DVec2>,
        emitter: (Falloff, Option<&Profile>),
        r0: f64,
    ) -> Rgb {
        let mut sum = Rgb::ZERO;
        for span in spans {
            let v = self.integral(span.from, span.to, normal, emitter, r0);
            sum += span.through * v;
        }
        sum
    }

    /// `∫ per_radian(r) cos dphi` over the light's positions `s` from
    /// `from` to `to`: the angle (or, on a wall of unit normal `normal`,
    /// the receiver's cosine) weighed by what the falloff brings per
    /// radian, by antiderivatives in `u`, split where the falloff has a
    /// kink. `emitter` is the light's falloff and its profile, which only
    /// `Flatland` takes (`Light::profile`): then the profile's own
    /// integrals over the directions from `x`.
    fn integral(
        &self,
        from: f64,
        to: f64,
        normal: Option<DVec2>,
        (falloff, profile): (Falloff, Option<&Profile>),
        r0: f64,
    ) -> f64 {
        if to.is_nan() || to <= from || self.h.is_nan() || self.h <= 0.0 {
            return 0.0;
        }
        let (ua, ub) = (self.u0 + from * self.length, self.u0 + to * self.length);
        // The receiver's cosine is `(alpha + beta u) / r` on a wall.
        let cosine = normal.map(|n| (n.dot(self.foot), n.dot(self.along)));
        // The integrands are positive: integrate from the lower `u` up.
        let (lo, hi) = if ua <= ub { (ua, ub) } else { (ub, ua) };
        if falloff == Falloff::Flatland {
            // One per radian at every distance, the clamp included.
            let (a, b) = (self.point(from) - self.x, self.point(to) - self.x);
            return match (profile, normal.zip(cosine)) {
                (None, None) => angle_between(a, b),
                (None, Some((_, c))) => flat_wall(self.h, c, lo, hi),
                (Some(p), None) => p.integral(a, b),
                (Some(p), Some((n, _))) => p.cosine_integral(a, b, n),
            };
        }
        // Cuts where `r` crosses a kink's distance: `u = +-sqrt(rho^2 - h^2)`.
        let mut cuts = [lo, hi, lo, lo, lo, lo];
        let mut n = 2;
        for rho in kinks(falloff, r0) {
            if rho > self.h {
                let w = (rho * rho - self.h * self.h).sqrt();
                for u in [-w, w] {
                    if u > lo && u < hi {
                        cuts[n] = u;
                        n += 1;
                    }
                }
            }
        }
        let cuts = &mut cuts[..n];
        cuts.sort_unstable_by(f64::total_cmp);
        let mut sum = 0.0;
        for pair in cuts.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            if b <= a {
                continue;
            }
            let mid = 0.5 * (a + b);
            let r_mid = (self.h * self.h + mid * mid).sqrt();
            sum += if r_mid < r0 {
                // Clamped: a constant per radian.
                let c0 = falloff.per_radian(r0, r0);
                c0 * match cosine {
                    None => flat_floor(self.h, a, b),
                    Some(c) => flat_wall(self.h, c, a, b),
                }
            } else {
                match falloff {
                    Falloff::Window { range } if r_mid >= range => 0.0,
                    _ => {
                        let f = |u: f64| antiderivative(falloff, self.h, cosine, u);
                        f(b) - f(a)
                    }
                }
            };
        }
        sum
    }
}

/// `∫ dphi` from `u = a` to `b` along a line at distance `h`.
#[inline]
fn flat_floor(h: f64, a: f64, b: f64) -> f64 {
    (b / h).atan() - (a / h).atan()
}

/// `∫ cos dphi` on a wall, the cosine `(alpha + beta u) / r`: with
/// `dphi = h du / r^2`, `alpha u / (h r) - beta h / r`.
#[inline]
fn flat_wall(h: f64, (alpha, beta): (f64, f64), a: f64, b: f64) -> f64 {
    let f = |u: f64| {
        let r = (h * h + u * u).sqrt();
        alpha * u / (h * r) - beta * h / r
    };
    f(b) - f(a)
}

/// An antiderivative in `u` of `G(r) r * cos * h / r^2` for a falloff
/// other than `Flatland`, outside the small radius and inside a window's
/// range: `cos` is 1 on the floor, `(alpha + beta u) / r` on a wall.
fn antiderivative(falloff: Falloff, h: f64, cosine: Option<(f64, f64)>, u: f64) -> f64 {
    let r2 = h * h + u * u;
    let r = r2.sqrt();
    match (falloff, cosine) {
        // G r = 1 / r.
        (Falloff::InverseSquare, None) => u / (h * r),
        (Falloff::InverseSquare, Some((alpha, beta))) => {
            let atan = (u / h).atan();
            h * (alpha * (u / (2.0 * h * h * r2) + atan / (2.0 * h * h * h)) - beta / (2.0 * r2))
        }
        // G r = r.
        (Falloff::Constant, None) => h * asinh(h, u, r),
        (Falloff::Constant, Some((alpha, beta))) => alpha * (u / h).atan() + beta * h * r.ln(),
        // G r = (1 - r / R)^2 r = r - 2 r^2 / R + r^3 / R^2.
        (Falloff::Window { range }, None) => {
            let asinh = asinh(h, u, r);
            h * (asinh - 2.0 * u / range + (u * r + h * h * asinh) / (2.0 * range * range))
        }
        (Falloff::Window { range }, Some((alpha, beta))) => {
            let (asinh, atan) = (asinh(h, u, r), (u / h).atan());
            h * (alpha * (atan / h - 2.0 * asinh / range + u / (range * range))
                + beta * (r.ln() - 2.0 * r / range + u * u / (2.0 * range * range)))
        }
        (Falloff::Flatland, None) => (u / h).atan(),
        (Falloff::Flatland, Some((alpha, beta))) => alpha * u / (h * r) - beta * h / r,
    }
}

/// `asinh(u / h)` given `r = sqrt(h^2 + u^2)`: `ln((u + r) / h)`, with
/// `u + r` written `h^2 / (r - u)` for negative `u`, where the sum would
/// cancel.
#[inline]
fn asinh(h: f64, u: f64, r: f64) -> f64 {
    if u >= 0.0 {
        ((u + r) / h).ln()
    } else {
        (h / (r - u)).ln()
    }
}

/// The angle between two directions, in `[0, pi]`.
#[inline]
fn angle_between(a: DVec2, b: DVec2) -> f64 {
    cross(a, b).abs().atan2(a.dot(b))
}

/// Clips `span` (of a parameter `s`) to where a value linear in `s`, `g0`
/// at `s = 0` and `g1` at `s = 1`, is at least 0 (greater, when
/// `strict`). `None` where nothing is left.
fn clip(span: (f64, f64), g0: f64, g1: f64, strict: bool) -> Option<(f64, f64)> {
    let keeps = |g: f64| if strict { g > 0.0 } else { g >= 0.0 };
    let (mut from, mut to) = span;
    match (keeps(g0), keeps(g1)) {
        (true, true) => {}
        (false, false) => return None,
        (true, false) => to = to.min(g0 / (g0 - g1)),
        (false, true) => from = from.max(g0 / (g0 - g1)),
    }
    (to > from).then_some((from, to))
}

/// A circle light seen from `x` outside it: the near rim's points
/// `c + R (cos, sin)(psi0 + t)` for `t` in `(-half, half)`, `psi0` the
/// direction from the centre to `x`, `half = acos(R / d)`.
struct DiskView {
    x: DVec2,
    c: DVec2,
    radius: f64,
    /// Unit, from the centre towards `x`.
    out: DVec2,
    d: f64,
    half: f64,
}

/// Nodes and weights of 12-point Gauss-Legendre quadrature on `[-1, 1]`
/// (the positive half; the rule is symmetric).
pub(super) const GAUSS_12: [(f64, f64); 6] = [
    (0.125_233_408_511_468_9, 0.249_147_045_813_402_8),
    (0.367_831_498_998_180_2, 0.233_492_536_538_354_8),
    (0.587_317_954_286_617_4, 0.203_167_426_723_065_9),
    (0.769_902_674_194_304_7, 0.160_078_328_543_346_2),
    (0.904_117_256_370_474_9, 0.106_939_325_995_318_4),
    (0.981_560_634_246_719_3, 0.047_175_336_386_511_8),
];

impl DiskView {
    /// `None` on or inside the rim: the rim emits outward only.
    fn new(x: DVec2, c: DVec2, radius: f64) -> Option<DiskView> {
        let v = x - c;
        let d = v.length();
        if d.is_nan() || d <= radius {
            return None;
        }
        Some(DiskView {
            x,
            c,
            radius,
            out: v / d,
            d,
            half: (radius / d).clamp(-1.0, 1.0).acos(),
        })
    }

    /// The rim's point at `t`.
    #[inline]
    fn rim(&self, t: f64) -> DVec2 {
        let (s, c) = t.sin_cos();
        self.c + (self.out * c + self.out.perp() * s) * self.radius
    }

    /// The `t` of a point `p` of the rim.
    #[inline]
    fn t_of(&self, p: DVec2) -> f64 {
        let v = p - self.c;
        cross(self.out, v).atan2(self.out.dot(v))
    }

    /// Adds the `t` of the points where the line through `p` along `dir`
    /// meets the rim.
    fn cuts_by_line(&self, p: DVec2, dir: DVec2, cuts: &mut Vec<f64>) {
        for lambda in self.line_roots(p, dir).into_iter().flatten() {
            cuts.push(self.t_of(p + dir * lambda));
        }
    }

    /// Adds the `t` of the near point where the ray from `x` along `dir`
    /// meets the rim, if it does.
    fn cuts_by_ray(&self, x: DVec2, dir: DVec2, cuts: &mut Vec<f64>) {
        let roots = self.line_roots(x, dir).unwrap_or([-1.0; 2]);
        let near = roots
            .into_iter()
            .filter(|l| *l > 0.0)
            .fold(f64::INFINITY, f64::min);
        if near.is_finite() {
            cuts.push(self.t_of(x + dir * near));
        }
    }

    /// The `lambda` where `p + lambda dir` lies on the rim (none, or two
    /// that may be equal).
    fn line_roots(&self, p: DVec2, dir: DVec2) -> Option<[f64; 2]> {
        let o = p - self.c;
        let a = dir.length_squared();
        let b = o.dot(dir);
        let c = o.length_squared() - self.radius * self.radius;
        let disc = b * b - a * c;
        if a.is_nan() || a <= 0.0 || disc.is_nan() || disc < 0.0 {
            return None;
        }
        // The stable pair: the root of larger magnitude first.
        let q = -(b + if b < 0.0 { -1.0 } else { 1.0 } * disc.sqrt());
        if q == 0.0 {
            return Some([0.0, 0.0]);
        }
        Some([q / a, c / q])
    }

    /// The `t >= 0` where the rim is `rho` from `x` (at `-t` too).
    fn at_distance(&self, rho: f64) -> Option<f64> {
        let cos = (self.radius * self.radius + self.d * self.d - rho * rho)
            / (2.0 * self.radius * self.d);
        (cos.abs() <= 1.0).then(|| cos.acos())
    }

    /// `∫ per_radian(r) cos dphi` over the rim from `t = a` to `b` (the
    /// receiver's cosine on a wall of unit normal `normal`, 1 on the
    /// floor), where it is positive and the falloff smooth: exactly under
    /// `Flatland`, else by Gauss-Legendre in `t`, where the angle seen
    /// from `x` grows by `cos_e R dt / r`.
    fn integral(&self, a: f64, b: f64, normal: Option<DVec2>, falloff: Falloff, r0: f64) -> f64 {
        let (pa, pb) = (self.rim(a) - self.x, self.rim(b) - self.x);
        if falloff == Falloff::Flatland {
            return match normal {
                None => angle_between(pa, pb),
                Some(n) => {
                    // The antiderivative of cos(phi - phi_n) is
                    // sin(phi - phi_n): `n . perp(d)` with a sign for the
                    // direction of the turn from `pa` to `pb`.
                    let (da, db) = (pa.normalize(), pb.normalize());
                    let turn = cross(da, db).signum();
                    turn * n.dot(da.perp() - db.perp())
                }
            };
        }
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        let f = |t: f64| {
            let p = self.rim(t);
            let v = p - self.x;
            let r = v.length();
            let normal_rim = (p - self.c) / self.radius;
            let cos_e = -normal_rim.dot(v) / r;
            let cos_r = normal.map_or(1.0, |n| (n.dot(v) / r).max(0.0));
            falloff.per_radian(r, r0) * cos_r * cos_e.max(0.0) * self.radius / r
        };
        let mut sum = 0.0;
        for (node, weight) in GAUSS_12 {
            sum += weight * (f(mid - half * node) + f(mid + half * node));
        }
        sum * half
    }
}

/// How many times the segment `ray` (`t` from 0 to 1) crosses arc `w`,
/// leaving or reaching it as `skip` says: the roots alone, no position.
#[inline]
fn crossings_within(arc: &Arc, ray: &Ray, skip: Skip, w: u32) -> usize {
    let (roots, n) = arc.line_crossings(ray, skip.0 == w, (skip.1 == w).then_some(1.0));
    roots[..n].iter().filter(|&&t| t > 0.0 && t < 1.0).count()
}

/// Whether the circle of `centre` and `radius` comes within a relative
/// `1e-9` of the triangle (inside it, or near an edge).
fn circle_meets_triangle(centre: DVec2, radius: f64, t: [DVec2; 3]) -> bool {
    let scale = centre.abs().max_element().max(radius);
    let reach = radius + 1e-9 * scale;
    let side = |a: DVec2, b: DVec2| cross(b - a, centre - a);
    let (s0, s1, s2) = (side(t[0], t[1]), side(t[1], t[2]), side(t[2], t[0]));
    let inside = (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0);
    inside
        || (0..3).any(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let e = b - a;
            let u = ((centre - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
            let u = if u.is_nan() { 0.0 } else { u };
            centre.distance(a + e * u) <= reach
        })
}

/// The points of `arc` where the view from `x` can turn: its ends, and
/// its circle's tangent points from `x` that lie on it.
fn arc_turning_points(arc: &Arc, x: DVec2) -> impl Iterator<Item = DVec2> {
    let mut points = [None; 4];
    if !arc.is_full() {
        points[0] = Some(arc.a);
        points[1] = Some(arc.b);
    }
    let f = x - arc.center;
    let d2 = f.length_squared();
    let r2 = arc.radius * arc.radius;
    if d2 > r2 {
        // The tangent points: at angle acos(r / d) either side of `f`.
        let cos = arc.radius / d2.sqrt();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let u = f / d2.sqrt();
        for (k, s) in [sin, -sin].into_iter().enumerate() {
            let dir = DVec2::new(u.x * cos - u.y * s, u.x * s + u.y * cos);
            let p = arc.center + dir * arc.radius;
            // On the arc's side of its chord (a tangent point a hair off
            // it adds a cut that changes nothing).
            let on = arc.is_full() || arc.bulge * cross(arc.b - arc.a, p - arc.a) >= 0.0;
            if on {
                points[2 + k] = Some(p);
            }
        }
    }
    points.into_iter().flatten()
}

/// Where the circles `(c1, r1)` and `(c2, r2)` meet: none, or two points
/// (which may be one).
fn circles_meet(c1: DVec2, r1: f64, c2: DVec2, r2: f64) -> Option<[DVec2; 2]> {
    let v = c2 - c1;
    let d = v.length();
    if d.is_nan() || d <= 0.0 || d > r1 + r2 || d < (r1 - r2).abs() {
        return None;
    }
    let along = (d * d + r1 * r1 - r2 * r2) / (2.0 * d);
    let h = (r1 * r1 - along * along).max(0.0).sqrt();
    let u = v / d;
    let foot = c1 + u * along;
    Some([foot + u.perp() * h, foot - u.perp() * h])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Simpson's rule with many steps: the reference for the
    /// antiderivatives.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
        let n = 20_000;
        let h = (b - a) / n as f64;
        let mut sum = f(a) + f(b);
        for k in 1..n {
            let w = if k % 2 == 1 { 4.0 } else { 2.0 };
            sum += w * f(a + h * k as f64);
        }
        sum * h / 3.0
    }

    /// Every falloff's integral over a line light, floor and wall, against
    /// Simpson's rule in the angle; the kinks (small radius, window)
    /// inside the light.
    #[test]
    fn line_integrals_match_quadrature_for_every_falloff() {
        let falloffs = [
            Falloff::Flatland,
            Falloff::InverseSquare,
            Falloff::Constant,
            Falloff::Window { range: 6.0 },
        ];
        let segment = Segment::new(DVec2::new(-3.0, 2.0), DVec2::new(5.0, 3.5));
        for x in [
            DVec2::new(0.3, 0.1),
            DVec2::new(1.0, 2.5),
            DVec2::new(-4.0, -1.0),
        ] {
            let line = LineView::new(x, &segment).expect("a line");
            for normal in [
                None,
                Some(DVec2::new(0.6, 0.8)),
                Some(DVec2::new(-0.8, 0.6)),
            ] {
                for falloff in falloffs {
                    for r0 in [0.5, 1.5] {
                        let (from, to) = (0.1, 0.85);
                        // The integral takes the part the receiver faces.
                        let exact = match line.receiving(normal) {
                            Some((a, b)) if b.min(to) > a.max(from) => {
                                line.integral(a.max(from), b.min(to), normal, (falloff, None), r0)
                            }
                            _ => 0.0,
                        };
                        // In the angle: direction from x to the light point.
                        let (pa, pb) = (line.point(from) - x, line.point(to) - x);
                        let fa = pa.y.atan2(pa.x);
                        let fb = fa + cross(pa, pb).atan2(pa.dot(pb));
                        let reference = simpson(
                            |phi| {
                                let d = DVec2::new(phi.cos(), phi.sin());
                                let t = cross(segment.a - x, segment.b - segment.a)
                                    / cross(d, segment.b - segment.a);
                                let cos = normal.map_or(1.0, |n| n.dot(d).max(0.0));
                                falloff.per_radian(t, r0) * cos
                            },
                            fa.min(fb),
                            fa.max(fb),
                        );
                        let got = exact.abs();
                        assert!(
                            (got - reference).abs() <= 1e-7 * (1.0 + reference.abs()),
                            "{falloff:?}, r0 {r0}, {normal:?} at {x}: {got} against {reference}"
                        );
                    }
                }
            }
        }
    }

    /// The circle's integral against Simpson's rule in the angle seen from
    /// `x`, with the near rim's distance.
    #[test]
    fn circle_integrals_match_quadrature_for_every_falloff() {
        let c = DVec2::new(1.0, 2.0);
        let radius = 1.2;
        for x in [DVec2::new(4.0, 0.5), DVec2::new(1.3, 3.6)] {
            let disk = DiskView::new(x, c, radius).expect("outside");
            for normal in [None, Some((c - x).normalize()), Some(DVec2::new(0.0, 1.0))] {
                for falloff in [
                    Falloff::Flatland,
                    Falloff::InverseSquare,
                    Falloff::Constant,
                    Falloff::Window { range: 3.5 },
                ] {
                    let r0 = 0.5;
                    let mut cuts = vec![-disk.half, disk.half];
                    if let Some(n) = normal {
                        disk.cuts_by_line(x, n.perp(), &mut cuts);
                    }
                    for rho in kinks(falloff, r0) {
                        if let Some(t) = disk.at_distance(rho) {
                            cuts.extend([-t, t]);
                        }
                    }
                    cuts.retain(|t| t.abs() <= disk.half);
                    cuts.sort_by(f64::total_cmp);
                    let mut exact = 0.0;
                    for w in cuts.windows(2) {
                        let mid = disk.rim(0.5 * (w[0] + w[1]));
                        if normal.is_some_and(|n| n.dot(mid - x) <= 0.0) {
                            continue;
                        }
                        exact += disk.integral(w[0], w[1], normal, falloff, r0);
                    }
                    let to_c = c - x;
                    let centre = to_c.y.atan2(to_c.x);
                    let half = (radius / to_c.length()).asin();
                    let reference = simpson(
                        |phi| {
                            let d = DVec2::new(phi.cos(), phi.sin());
                            let b = to_c.dot(d);
                            let t = b
                                - (b * b - to_c.length_squared() + radius * radius)
                                    .max(0.0)
                                    .sqrt();
                            let cos = normal.map_or(1.0, |n| n.dot(d).max(0.0));
                            falloff.per_radian(t, r0) * cos
                        },
                        centre - half,
                        centre + half,
                    );
                    assert!(
                        (exact - reference).abs() <= 1e-5 * (1.0 + reference.abs()),
                        "{falloff:?}, {normal:?} at {x}: {exact} against {reference}"
                    );
                }
            }
        }
    }

    /// A wall across the middle of a line light, seen from below: its
    /// shadow on the light is where the lines from `x` through its ends
    /// meet the light, by hand.
    #[test]
    fn a_walls_shadow_on_a_line_light_is_where_its_ends_project() {
        let x = DVec2::new(0.0, 0.0);
        let light = Segment::new(DVec2::new(-4.0, 4.0), DVec2::new(4.0, 4.0));
        let line = LineView::new(x, &light).expect("a line");
        // A wall from (-1, 2) to (1, 2): its ends project to x = -2 and 2
        // on the light, s = 0.25 and 0.75.
        let wall = Segment::new(DVec2::new(-1.0, 2.0), DVec2::new(1.0, 2.0));
        let (from, to) = line.shadow_of(&wall, (0.0, 1.0)).expect("a shadow");
        assert!((from - 0.25).abs() < 1e-15 && (to - 0.75).abs() < 1e-15);
        // Behind the light: no shadow.
        let behind = Segment::new(DVec2::new(-1.0, 5.0), DVec2::new(1.0, 5.0));
        assert!(line.shadow_of(&behind, (0.0, 1.0)).is_none());
        // Crossing the light: only the part in front of it hides it.
        let across = Segment::new(DVec2::new(0.0, 3.0), DVec2::new(2.0, 5.0));
        let (from, to) = line.shadow_of(&across, (0.0, 1.0)).expect("a shadow");
        // The wall meets the light at (1, 4), s = 5/8; its near end (0, 3)
        // projects to (0, 4), s = 1/2.
        assert!(
            (from - 0.5).abs() < 1e-15 && (to - 0.625).abs() < 1e-15,
            "{from} {to}"
        );
        // Seen edge-on: nothing.
        let edge_on = Segment::new(DVec2::new(0.0, 1.0), DVec2::new(0.0, 3.0));
        assert!(line.shadow_of(&edge_on, (0.0, 1.0)).is_none());
    }
}

/// The closed form through a scene: walls found, shadows swept, tints
/// multiplied; each case worked out by hand.
#[cfg(test)]
pub(crate) mod closed_forms {
    use super::*;
    use crate::scene::{Canvas, Floor, Light, Material, Wall};

    /// A scene on a canvas of 100 x 100 units about the origin.
    pub(crate) fn scene(walls: Vec<Wall>, lights: Vec<Light>) -> Scene {
        let canvas = Canvas {
            width: 100,
            height: 100,
            origin: DVec2::new(-50.0, -50.0),
        };
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, lights).expect("a valid scene")
    }

    pub(crate) fn line(a: DVec2, b: DVec2, falloff: Falloff) -> Light {
        Light {
            profile: None,
            shape: LightShape::Line {
                segment: Segment::new(a, b),
                one_sided: false,
                wall: None,
            },
            color: Rgb::ONE,
            intensity: 1.0,
            falloff,
            spectrum: None,
        }
    }

    /// A straight wall from `a` to `b`.
    pub(crate) fn wall(a: DVec2, b: DVec2, material: Material) -> Wall {
        Wall {
            shape: Segment::new(a, b).into(),
            material,
        }
    }

    pub(crate) const OPAQUE: Material = Material::Diffuse { albedo: None };

    fn at(scene: &Scene, x: DVec2, normal: Option<DVec2>, wall: Option<u32>) -> Rgb {
        let receiver = Receiver {
            normal,
            wall,
            shadow_walls: None,
        };
        let mut stats = Stats::default();
        exact_light(scene, 0, x, receiver, Visibility::Trace, &mut stats).expect("an area light")
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + b.abs())
    }

    /// A round column of radius 2 at (1, 6) between the origin and a
    /// line light from (-6, 10) to (8, 10): it hides the directions within
    /// `asin(2 / |c|)` of the column's centre, a cone whose edges are the
    /// tangents, so under `Flatland` the fluence is the light's angle less
    /// the cone's. The same with a circle light of radius 1.5 at
    /// (6, 12), whose rim the cone cuts, and with a pane column, which
    /// tints the hidden directions twice (the ray crosses it twice).
    #[test]
    fn a_round_column_hides_the_cone_of_its_tangents() {
        use flatray_geometry::Arc;
        let o = DVec2::ZERO;
        let c = DVec2::new(1.0, 6.0);
        let column = |material| Wall {
            shape: Arc::circle(c, 2.0, 0.3).into(),
            material,
        };
        let half = (2.0 / c.length()).asin();
        let axis = c.y.atan2(c.x);
        let (cone_lo, cone_hi) = (axis - half, axis + half);
        // The line light's angle, and its part inside the cone.
        let (left, right) = (DVec2::new(-6.0, 10.0), DVec2::new(8.0, 10.0));
        let angle = |p: DVec2| p.y.atan2(p.x);
        let (from, to) = (angle(right), angle(left));
        let hidden = (to.min(cone_hi) - from.max(cone_lo)).max(0.0);
        let line = |falloff| vec![line(left, right, falloff)];
        let opaque = scene(vec![column(OPAQUE)], line(Falloff::Flatland));
        let v = at(&opaque, o, None, None).x;
        assert!(
            close(v, to - from - hidden),
            "{v} against {}",
            to - from - hidden
        );
        let tint = 0.5;
        let pane = scene(
            vec![column(Material::Transparent {
                tint: Rgb::splat(tint),
            })],
            line(Falloff::Flatland),
        );
        let v = at(&pane, o, None, None).x;
        let expected = to - from - hidden + hidden * tint * tint;
        assert!(close(v, expected), "{v} against {expected}");
        // The circle light: its near rim seen from the origin spans the
        // cone of its own tangents; the column's cone cuts it.
        let (lc, lr) = (DVec2::new(6.0, 12.0), 1.5);
        let light_half = (lr / lc.length()).asin();
        let light_axis = angle(lc);
        let (l_lo, l_hi) = (light_axis - light_half, light_axis + light_half);
        let hidden = (l_hi.min(cone_hi) - l_lo.max(cone_lo)).max(0.0);
        let circle = Light {
            profile: None,
            shape: LightShape::Circle { at: lc, radius: lr },
            color: Rgb::ONE,
            intensity: 1.0,
            falloff: Falloff::Flatland,
            spectrum: None,
        };
        let s = scene(vec![column(OPAQUE)], vec![circle]);
        let v = at(&s, o, None, None).x;
        let expected = l_hi - l_lo - hidden;
        assert!(
            hidden > 0.0 && hidden < l_hi - l_lo,
            "the cone cuts the light"
        );
        assert!(close(v, expected), "{v} against {expected}");
    }

    /// A line light from (-4, 10) to (4, 10) seen from the origin, and a
    /// wall from (0, 5) to (10, 5) hiding its right half: under
    /// `Flatland` the fluence is the angle from the light's left end to
    /// the wall's end, `atan(4 / 10)`, and on a wall facing up, the sine
    /// of it.
    #[test]
    fn a_line_light_half_hidden_by_a_wall_gives_its_visible_angle() {
        let o = DVec2::ZERO;
        let s = scene(
            vec![wall(DVec2::new(0.0, 5.0), DVec2::new(10.0, 5.0), OPAQUE)],
            vec![line(
                DVec2::new(-4.0, 10.0),
                DVec2::new(4.0, 10.0),
                Falloff::Flatland,
            )],
        );
        let visible = (0.4f64).atan();
        assert!(close(at(&s, o, None, None).x, visible));
        // Facing up, cos(phi) over the angle from the vertical to the
        // left end: sin(atan(0.4)).
        let up = Some(DVec2::new(0.0, 1.0));
        assert!(close(at(&s, o, up, None).x, visible.sin()));
        // Facing right, only the part right of the vertical counts, and
        // the wall hides all of it.
        let right = Some(DVec2::new(1.0, 0.0));
        assert_eq!(at(&s, o, right, None), Rgb::ZERO);
    }

    /// The same light under every other falloff: the integral of
    /// `G(r) r` over the visible angle, against Simpson's rule over that
    /// angle by hand.
    #[test]
    fn every_falloff_integrates_over_the_visible_angle_only() {
        for falloff in [
            Falloff::InverseSquare,
            Falloff::Constant,
            Falloff::Window { range: 10.5 },
        ] {
            let s = scene(
                vec![wall(DVec2::new(0.0, 5.0), DVec2::new(10.0, 5.0), OPAQUE)],
                vec![line(DVec2::new(-4.0, 10.0), DVec2::new(4.0, 10.0), falloff)],
            );
            let got = at(&s, DVec2::ZERO, None, None).x;
            // From the left end (angle atan(4/10) left of vertical) to the
            // vertical; the distance to the light is 10 / cos.
            let n = 20_000;
            let top = (0.4f64).atan();
            let h = top / n as f64;
            let f = |phi: f64| falloff.per_radian(10.0 / phi.cos(), 0.5);
            let mut sum = f(0.0) + f(top);
            for k in 1..n {
                sum += if k % 2 == 1 { 4.0 } else { 2.0 } * f(h * k as f64);
            }
            let reference = sum * h / 3.0;
            assert!(
                (got - reference).abs() <= 1e-9 * reference,
                "{falloff:?}: {got} against {reference}"
            );
        }
    }

    /// A pane of tint (0.5, 0.25, 1) across the light's left half, and an
    /// opaque wall across the right quarter: `t a1 + a2` with `a1` the
    /// angle behind the pane and `a2` the open one.
    #[test]
    fn a_tinted_pane_tints_the_part_of_the_light_it_covers() {
        let tint = Rgb::new(0.5, 0.25, 1.0);
        let s = scene(
            vec![
                wall(
                    DVec2::new(-10.0, 5.0),
                    DVec2::new(0.0, 5.0),
                    Material::Transparent { tint },
                ),
                wall(DVec2::new(1.0, 5.0), DVec2::new(10.0, 5.0), OPAQUE),
            ],
            vec![line(
                DVec2::new(-4.0, 10.0),
                DVec2::new(4.0, 10.0),
                Falloff::Flatland,
            )],
        );
        let got = at(&s, DVec2::ZERO, None, None);
        let behind_pane = (0.4f64).atan();
        // Open from the vertical to the opaque wall's end at (1, 5),
        // which projects to (2, 10).
        let open = (0.2f64).atan();
        for (c, t) in [(got.x, 0.5), (got.y, 0.25), (got.z, 1.0)] {
            assert!(close(c, t * behind_pane + open), "{got:?}");
        }
    }

    /// A circle light of radius 2 at (0, 10) seen from the origin, a wall
    /// ending at (0, 5) hiding its right half: the visible angle is half
    /// the disk's, `asin(2 / 10)`; a wall ending at (-0.25, 5) leaves
    /// the angle from the disk's left tangent to its end.
    #[test]
    fn a_circle_light_behind_a_walls_end_gives_its_visible_angle() {
        let disk = Light {
            shape: LightShape::Circle {
                at: DVec2::new(0.0, 10.0),
                radius: 2.0,
            },
            ..line(DVec2::ZERO, DVec2::X, Falloff::Flatland)
        };
        for (end, visible) in [
            (0.0, (0.2f64).asin()),
            (-0.25, (0.2f64).asin() - (0.05f64).atan()),
        ] {
            let s = scene(
                vec![wall(DVec2::new(end, 5.0), DVec2::new(10.0, 5.0), OPAQUE)],
                vec![disk.clone()],
            );
            let got = at(&s, DVec2::ZERO, None, None).x;
            assert!(close(got, visible), "end {end}: {got} against {visible}");
        }
    }

    /// A line light from (-2, 5) to (2, 5) and a mirror along y = 0 of
    /// tint 0.8: from (0, 3) the light's image, seen from the point's
    /// image (0, -3), subtends `2 atan(2 / 8)` through the mirror. A wall
    /// from (0, 1) to (5, 1) between the point and the mirror hides the
    /// half whose first leg runs right of the vertical; on a wall facing
    /// down, the cosine's integral is `2 sin(atan(1 / 4))`.
    #[test]
    fn a_line_light_in_a_mirror_gives_its_images_visible_angle() {
        let tint = Rgb::splat(0.8);
        let mirror = wall(
            DVec2::new(-10.0, 0.0),
            DVec2::new(10.0, 0.0),
            Material::Mirror { tint },
        );
        let light = line(
            DVec2::new(-2.0, 5.0),
            DVec2::new(2.0, 5.0),
            Falloff::Flatland,
        );
        let x = DVec2::new(0.0, 3.0);
        let mut stats = Stats::default();
        let s = scene(vec![mirror], vec![light.clone()]);
        let mut through = |s: &Scene, normal: Option<DVec2>| {
            let receiver = Receiver {
                normal,
                wall: None,
                shadow_walls: None,
            };
            through_mirrors(s, &s.flat_mirrors, x, receiver, &mut stats).x
        };
        let angle = 2.0 * (0.25f64).atan();
        assert!(close(through(&s, None), 0.8 * angle));
        let down = Some(DVec2::new(0.0, -1.0));
        assert!(close(through(&s, down), 0.8 * 2.0 * (0.25f64).atan().sin()));
        // Facing up: the mirror is behind the receiver.
        assert_eq!(through(&s, Some(DVec2::new(0.0, 1.0))), 0.0);
        let half = scene(
            vec![
                mirror,
                wall(DVec2::new(0.0, 1.0), DVec2::new(5.0, 1.0), OPAQUE),
            ],
            vec![light.clone()],
        );
        assert!(close(through(&half, None), 0.8 * angle / 2.0));
        // The same wall above the light hides nothing.
        let above = scene(
            vec![
                mirror,
                wall(DVec2::new(0.0, 6.0), DVec2::new(5.0, 6.0), OPAQUE),
            ],
            vec![light],
        );
        assert!(close(through(&above, None), 0.8 * angle));
    }

    /// A closed square room turned by an odd angle, its corners shared
    /// endpoints at coordinates no float holds exactly, a line light and
    /// a circle light outside: nothing reaches any point inside, exactly.
    #[test]
    fn nothing_leaks_into_a_closed_room_through_its_corners() {
        for degrees in [0.0f64, 17.0, 45.0, 73.3] {
            let (sin, cos) = degrees.to_radians().sin_cos();
            let turn = |x: f64, y: f64| DVec2::new(cos * x - sin * y, sin * x + cos * y);
            let corners = [
                turn(-10.1, -10.7),
                turn(10.3, -10.7),
                turn(10.3, 10.9),
                turn(-10.1, 10.9),
            ];
            let walls = (0..4)
                .map(|k| wall(corners[k], corners[(k + 1) % 4], OPAQUE))
                .collect();
            let lights = vec![
                line(turn(-30.0, 20.0), turn(30.0, 25.0), Falloff::Flatland),
                Light {
                    shape: LightShape::Circle {
                        at: turn(0.0, -25.0),
                        radius: 3.0,
                    },
                    ..line(DVec2::ZERO, DVec2::X, Falloff::Flatland)
                },
            ];
            let s = scene(walls, lights);
            let mut stats = Stats::default();
            for i in 0..41 {
                for j in 0..41 {
                    let x = turn(-10.0 + 0.5 * i as f64, -10.6 + 0.5 * j as f64);
                    for index in 0..2 {
                        let got = exact_light(
                            &s,
                            index,
                            x,
                            Receiver::FLOOR,
                            Visibility::Trace,
                            &mut stats,
                        );
                        assert_eq!(
                            got,
                            Some(Rgb::ZERO),
                            "light {index} at {x}, {degrees} degrees"
                        );
                    }
                }
            }
        }
    }
}
