//! Where a light's visibility cannot change across a pixel of the floor,
//! so that the floor memo's strata there share one shadow ray (or need
//! none).
//!
//! Which walls a shadow ray from floor point `x` to a point light crosses
//! changes only where `x` crosses a wall or a shadow edge: the ray from
//! the light through a wall's endpoint, beyond it. Inside an opaque wall's
//! shadow the floor is dark on both sides of any boundary, so for a point,
//! spot or sun three parts are left out: an edge past where it enters
//! such a shadow ([`umbra_entry`]), the edge of a wall end that such a
//! shadow holds ([`hidden_by`]), and the wall itself where one opaque wall
//! hides it end to end ([`hides_whole`]). On a floor plan that leaves a
//! light the walls and edges of the rooms it sees. For a line light, the
//! walls that cut the triangle from `x` to the light change only where `x`
//! crosses a wall, a ray from either end of the light through a wall's
//! endpoint, or the light's own line. Every such boundary is drawn into a
//! per-light mask of pixels: every pixel within an eighth of a pixel of
//! it is marked, so that a pixel left unmarked lies at least that far
//! from every boundary, far beyond any rounding. In an unmarked pixel:
//!
//! - a point, spot or directional light's transmittance is the same for
//!   every stratum: one shadow ray from the pixel's centre gives it, the
//!   very product of tints each stratum's own ray would give (same walls,
//!   same order), so the image is bit-identical;
//! - a line light is cut by no wall for any stratum: every transmittance
//!   is exactly 1 and no ray is cast; or every wall that cuts it stands
//!   between the whole pixel and the whole light (an umbra, or panes that
//!   every ray crosses): one shadow ray from the centre gives every
//!   stratum's transmittance, as for a point light; or else each stratum
//!   traces its own.
//!
//! Scenes with more wall-light pairs than [`MAX_PAIRS`] skip this (every
//! pixel traces), since drawing their boundaries would cost more than it
//! saves.

use flatray_geometry::{DVec2, Ray, Segment, Skip, clip_to_box, cross};
use rayon::prelude::*;

use crate::lights::Emitter;
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Above this many (wall, light) pairs every pixel traces its strata.
/// Drawing the boundaries costs about a line across the canvas per pair:
/// this bounds that cost.
pub const MAX_PAIRS: usize = 1 << 16;

/// Above this many (pixel, light) cells (a byte each) the masks are not
/// built: every pixel traces its strata.
pub const MAX_CELLS: u64 = 1 << 28;

/// What the strata of one pixel need for one light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Coherence {
    /// A boundary passes near: every stratum casts its own shadow ray.
    Varies,
    /// The same transmittance everywhere in the pixel: one shadow ray.
    Same,
    /// A line light that no wall cuts off anywhere in the pixel: a
    /// transmittance of exactly 1, and no ray.
    Clear,
}

/// The kinds of light whose boundaries [`FloorCoherence::build`] knows how
/// to draw: points, spots, suns and lines. For any other kind (circles,
/// beams, lasers) every pixel traces its strata, as without the masks.
pub(crate) fn draws(emitter: Emitter) -> bool {
    match emitter {
        Emitter::Point { .. } | Emitter::Direction(_) | Emitter::Segment { .. } => true,
        Emitter::Disk { .. } | Emitter::Arc(_) | Emitter::Parallel { .. } => false,
    }
}

/// Per pixel and light, a [`Coherence`].
pub(crate) struct FloorCoherence {
    width: usize,
    lights: usize,
    cells: Vec<Coherence>,
}

impl FloorCoherence {
    /// The masks for `scene` rendered at `size` pixels, or `None` when the
    /// scene is too large for them to pay (see [`MAX_PAIRS`]).
    pub fn build(scene: &Scene, size: (u32, u32)) -> Option<FloorCoherence> {
        let lights = scene.lights.len();
        let (width, height) = (size.0 as usize, size.1 as usize);
        if lights == 0
            || scene.walls.len() * lights > MAX_PAIRS
            || (width * height) as u64 * lights as u64 > MAX_CELLS
        {
            return None;
        }
        let step = scene.canvas.pixel_step(size);
        let mut cells = vec![Coherence::Varies; width * height * lights];
        // A few lights at a time, one per thread (each light's drawing is
        // serial), each holding its pixels' states until they are
        // written in.
        let batch = rayon::current_num_threads().max(1);
        for first in (0..lights).step_by(batch) {
            let group = first..(first + batch).min(lights);
            let states: Vec<Option<Vec<Coherence>>> = group
                .clone()
                .into_par_iter()
                .map(|index| light_states(scene, index, (width, height), step))
                .collect();
            cells
                .par_chunks_mut(width * lights)
                .enumerate()
                .for_each(|(y, row)| {
                    for (index, states) in group.clone().zip(&states) {
                        let Some(states) = states else { continue };
                        let of_row = &states[y * width..(y + 1) * width];
                        for (cell, &state) in row.iter_mut().skip(index).step_by(lights).zip(of_row)
                        {
                            *cell = state;
                        }
                    }
                });
        }
        Some(FloorCoherence {
            width,
            lights,
            cells,
        })
    }

    /// What pixel `(x, y)` needs for each light, in light order.
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> &[Coherence] {
        let first = (y as usize * self.width + x as usize) * self.lights;
        &self.cells[first..first + self.lights]
    }
}

/// Light `index`'s state at every pixel of an image of `width` x `height`
/// pixels of `step` world units, row by row; `None` where every pixel
/// traces its strata for it.
fn light_states(
    scene: &Scene,
    index: usize,
    (width, height): (usize, usize),
    step: DVec2,
) -> Option<Vec<Coherence>> {
    let light = &scene.lights[index];
    let emitter = light.shape.emitter();
    let to_pixels = |p: DVec2| (p - scene.canvas.origin) / step;
    if !draws(emitter) {
        // Every pixel traces its strata for this light.
        return None;
    }
    let mut mask = Mask::new(width, height);
    let own = scene.light_wall[index];
    let walls = || {
        scene
            .walls
            .iter()
            .enumerate()
            .filter(move |(i, _)| own != Some(*i as u32))
            // Straight walls only: the masks never run with arcs.
            .map(|(_, w)| w.shape.chord())
    };
    let mut complete = true;
    for wall in walls() {
        let (a, b) = (to_pixels(wall.a), to_pixels(wall.b));
        // The opaque wall that hides each end from a point, spot or sun.
        let hider = |end: DVec2| {
            let (way, t_max) = light.shape.source()?.way_from(end);
            hidden_by(scene, own, end, way, t_max, step)
        };
        let hiders = [hider(wall.a), hider(wall.b)];
        if !hides_whole(hiders[0], hiders[1]) {
            mask.mark(a, b - a, 0.0, 1.0);
        }
        for (end, hider) in [wall.a, wall.b].into_iter().zip(hiders) {
            let e = to_pixels(end);
            match emitter {
                Emitter::Point { at, .. } => {
                    // A wall that all but touches the light leaves
                    // its shadow rays' `t < 1` test to rounding.
                    complete &= !near(at, &wall);
                    if hider.is_none() {
                        let end_t = umbra_entry(scene, own, end, end - at, step);
                        mask.mark(e, e - to_pixels(at), 0.0, end_t);
                    }
                }
                Emitter::Direction(direction) => {
                    if hider.is_none() {
                        let end_t = umbra_entry(scene, own, end, direction, step);
                        mask.mark(e, direction / step, 0.0, end_t);
                    }
                }
                Emitter::Disk { .. } | Emitter::Arc(_) | Emitter::Parallel { .. } => {}
                Emitter::Segment { segment, .. } => {
                    // A wall that touches an end of the light cuts
                    // every triangle: the centre test below says
                    // so, and no boundary is needed.
                    for light_end in [segment.a, segment.b] {
                        let away = e - to_pixels(light_end);
                        if away != DVec2::ZERO {
                            mask.mark(e, away, 0.0, f64::INFINITY);
                        }
                    }
                }
            }
        }
    }
    if let Emitter::Segment { segment, .. } = emitter {
        let (a, b) = (to_pixels(segment.a), to_pixels(segment.b));
        mask.mark(a, b - a, f64::NEG_INFINITY, f64::INFINITY);
    }
    if let Emitter::Point { at, .. } = emitter {
        // The light's own pixel, where no direction is defined.
        let p = to_pixels(at);
        mask.mark(p, DVec2::ZERO, 0.0, 0.0);
    }
    if !complete || mask.overflow {
        return None;
    }
    // A wall that touches the light's ends (or the light, its
    // ends) leaves its rays' `t < 1` test to rounding: then every
    // pixel traces the line light.
    let far_walls: Option<Vec<Segment>> = match emitter {
        Emitter::Segment { segment, .. } => {
            let all: Vec<Segment> = walls().collect();
            (!all.iter().any(|w| near_light(w, &segment))).then_some(all)
        }
        Emitter::Point { .. }
        | Emitter::Direction(_)
        | Emitter::Disk { .. }
        | Emitter::Arc(_)
        | Emitter::Parallel { .. } => None,
    };
    // Rows in parallel: a line light tests every wall at every
    // unmarked pixel.
    let (marked, far_walls) = (&mask.marked, far_walls.as_deref());
    let states: Vec<Coherence> = (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..width).map(move |x| {
                if marked[y * width + x] {
                    return Coherence::Varies;
                }
                match (emitter, far_walls) {
                    (Emitter::Segment { segment, .. }, Some(walls)) => {
                        let centre =
                            scene.canvas.origin + (DVec2::new(x as f64, y as f64) + 0.5) * step;
                        line_coherence(walls, centre, &segment)
                    }
                    (Emitter::Segment { .. }, None) => Coherence::Varies,
                    (Emitter::Point { .. } | Emitter::Direction(_), _) => Coherence::Same,
                    (Emitter::Disk { .. } | Emitter::Arc(_) | Emitter::Parallel { .. }, _) => {
                        Coherence::Varies
                    }
                }
            })
        })
        .collect();
    Some(states)
}

/// How far, in pixels, a shadow edge's crossing must lie from the ends of
/// the opaque wall it enters, across the edge (its distance along the
/// wall times the sine of the angle between them), and how far behind
/// the wall's line the edge is still drawn.
const UMBRA_MARGIN: f64 = 3.0;

/// Where the shadow edge from wall end `from`, along `dir` away from a
/// point light (or along a sun's direction), lies inside an opaque wall's
/// shadow for good: past a crossing of an opaque wall at least
/// [`UMBRA_MARGIN`] pixels (across the edge) from that wall's ends, once
/// the edge lies that margin behind the wall's line. The least such ray
/// parameter over the walls it crosses; `INFINITY` where there is none.
///
/// Past it, every point within a pixel and a half of the edge lies behind
/// that wall's line, and its way to the light crosses the wall well
/// inside it: its transmittance is exactly 0 on both sides of the edge,
/// whatever other walls the edge separates. So the edge need not be drawn
/// there: a pixel that no drawn boundary touches is either wholly in the
/// shadow of opaque walls (the boundaries of that shadow are walls and
/// the drawn parts of edges) or crosses the same walls everywhere, as
/// before.
fn umbra_entry(scene: &Scene, own: Option<u32>, from: DVec2, dir: DVec2, step: DVec2) -> f64 {
    let dir_length = (dir / step).length();
    let mut end = f64::INFINITY;
    opaque_crossings(scene, own, (from, dir, f64::INFINITY), step, |c, t| {
        if t < end && c.along * c.sine >= UMBRA_MARGIN && t * dir_length >= UMBRA_MARGIN {
            end = end.min(t + UMBRA_MARGIN / (dir_length * c.sine));
        }
        true
    });
    if end.is_finite() { end } else { f64::INFINITY }
}

/// Calls `visit` with each opaque wall that the way from `from` along
/// `dir` (for `0 < t < t_max`) crosses, measured in pixels, and the
/// crossing's `t`, until `visit` returns `false`. The light's own wall
/// `own` is passed by, as its shadow rays pass it.
fn opaque_crossings(
    scene: &Scene,
    own: Option<u32>,
    (from, dir, t_max): (DVec2, DVec2, f64),
    step: DVec2,
    mut visit: impl FnMut(Hider, f64) -> bool,
) {
    let dir_pixels = dir / step;
    let dir_length = dir_pixels.length();
    let skip = Skip(own.unwrap_or(u32::MAX), u32::MAX);
    scene
        .segments
        .for_each_crossing(&Ray::new(from, dir), t_max, skip, |index, hit| {
            if !scene.stops_rays(index) {
                return true;
            }
            let edge = scene.walls[index as usize].shape.chord().edge() / step;
            let sine = (cross(edge, dir_pixels) / (edge.length() * dir_length)).abs();
            let crossing = Hider {
                wall: index,
                along: hit.u.min(1.0 - hit.u) * edge.length(),
                sine,
                behind: hit.t * dir_length * sine,
            };
            visit(crossing, hit.t)
        });
}

/// Where a way towards the light crosses an opaque wall, in pixels
/// ([`opaque_crossings`]): for a wall end, how that wall hides it
/// ([`hidden_by`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hider {
    /// The wall crossed.
    wall: u32,
    /// How far along it the way crosses it, from its nearer end.
    along: f64,
    /// The sine of the angle between the way and the wall.
    sine: f64,
    /// How far the way's start lies off the wall's line (behind it, seen
    /// from the light).
    behind: f64,
}

/// The first opaque wall found that hides wall end `end` from the light
/// with room to spare: the way from `end` to the light (`towards`, up to
/// `t_max`: the light at 1, or a sun at infinity) crosses it at least
/// [`UMBRA_MARGIN`] pixels (across that way) from its ends, and `end`
/// lies at least that far behind its line.
///
/// Then the shadow edge from `end` lies wholly inside that wall's shadow
/// and need not be drawn. A point within a pixel and a half of the edge
/// lies behind the wall's line too, and its way to the light crosses the
/// wall within a pixel and a half (across the way) of where the edge's
/// does, nearer for a point light, so well inside the wall: its
/// transmittance is exactly 0 on both sides of the edge. On a floor plan,
/// the light of one room sees few of the plan's wall ends; the others'
/// edges would otherwise fan out across every other room.
fn hidden_by(
    scene: &Scene,
    own: Option<u32>,
    end: DVec2,
    towards: DVec2,
    t_max: f64,
    step: DVec2,
) -> Option<Hider> {
    let dir_length = (towards / step).length();
    if !(dir_length.is_finite() && dir_length > 0.0) {
        return None;
    }
    let mut found = None;
    opaque_crossings(scene, own, (end, towards, t_max), step, |c, _| {
        if c.along * c.sine >= UMBRA_MARGIN && c.behind >= UMBRA_MARGIN {
            found = Some(c);
        }
        found.is_none()
    });
    found
}

/// Whether one opaque wall hides a whole wall, from ends hidden as
/// `first` and `second` say: the same wall hides both, with room to
/// spare for every point between them. The way to the light from a point
/// of the wall crosses the hiding wall between the ends' crossings, at an
/// angle between theirs, and the point lies behind its line at least as
/// far as the nearer end: so the floor within a pixel and a half of the
/// wall lies in its shadow, and crossing the wall changes no
/// transmittance there (each is exactly 0).
fn hides_whole(first: Option<Hider>, second: Option<Hider>) -> bool {
    let (Some(a), Some(b)) = (first, second) else {
        return false;
    };
    a.wall == b.wall
        && a.along.min(b.along) * a.sine.min(b.sine) >= UMBRA_MARGIN
        && a.behind.min(b.behind) >= UMBRA_MARGIN
}

/// The widest a mark reaches around a boundary's steps, in pixels: past
/// this (coordinates of trillions of pixels) the light's mask is not used.
const MAX_REACH: f64 = 4.0;

/// Pixels a boundary passes near.
struct Mask {
    width: usize,
    height: usize,
    marked: Vec<bool>,
    /// A boundary could not be drawn (not finite): trust no pixel.
    overflow: bool,
}

impl Mask {
    fn new(width: usize, height: usize) -> Mask {
        Mask {
            width,
            height,
            marked: vec![false; width * height],
            overflow: false,
        }
    }

    /// Marks every pixel that comes within an eighth of a pixel of
    /// `o + t d` for `t` in `[t0, t1]` (in pixel coordinates), clipped to
    /// the image; further where the coordinates are so large that
    /// rounding could move a point by a noticeable part of that.
    fn mark(&mut self, o: DVec2, d: DVec2, t0: f64, t1: f64) {
        if !(o.is_finite() && d.is_finite()) {
            self.overflow = true;
            return;
        }
        let lo = DVec2::splat(-2.0);
        let hi = DVec2::new(self.width as f64, self.height as f64) + 2.0;
        let Some((t0, t1)) = clip_to_box(o, d, t0, t1, lo, hi) else {
            return;
        };
        let length = d.length() * (t1 - t0);
        let magnitude = o.abs().max_element() + d.abs().max_element() * t0.abs().max(t1.abs());
        if !(length.is_finite() && magnitude.is_finite()) {
            self.overflow = true;
            return;
        }
        // Steps of at most a quarter of a pixel: every point of the
        // boundary lies within an eighth of a pixel of a step, so a pixel
        // within an eighth of a pixel of the boundary lies within a
        // quarter of one of the steps, and is marked; and a step's own
        // rounding (thousands of times less than 1e-12 of the coordinates'
        // magnitude) is added to the reach.
        let reach = 0.25 + 1e-12 * magnitude;
        if reach > MAX_REACH {
            // Coordinates so far out that rounding could move a point by
            // pixels: trust no pixel of this light.
            self.overflow = true;
            return;
        }
        let steps = (length * 4.0).ceil() as usize + 1;
        for k in 0..=steps {
            let t = t0 + (t1 - t0) * (k as f64 / steps as f64);
            let p = o + d * t;
            let (x0, x1) = ((p.x - reach).floor() as i64, (p.x + reach).floor() as i64);
            let (y0, y1) = ((p.y - reach).floor() as i64, (p.y + reach).floor() as i64);
            for y in y0.max(0)..=y1.min(self.height as i64 - 1) {
                for x in x0.max(0)..=x1.min(self.width as i64 - 1) {
                    self.marked[y as usize * self.width + x as usize] = true;
                }
            }
        }
    }
}

/// Whether `p` lies within rounding distance of `segment`: about 1e-9 of
/// the coordinates' magnitude, a million times what rounding can move a
/// computed point.
fn near(p: DVec2, segment: &Segment) -> bool {
    let scale = 1.0
        + p.abs()
            .max(segment.a.abs())
            .max(segment.b.abs())
            .max_element();
    let e = segment.b - segment.a;
    let t = ((p - segment.a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
    let d = (segment.a + e * t).distance(p);
    // A NaN distance (a degenerate segment) counts as near.
    d.is_nan() || d <= 1e-9 * scale
}

/// What the strata of an unmarked pixel of centre `centre` need for line
/// light `light`, given the `walls` its shadow rays can meet (none of
/// them near the light: see `near_light`): `Clear` when
/// none cuts the triangle of the centre and the light's ends; `Same` when
/// every wall that cuts it crosses both of its sides from the centre, so
/// that it stands between the whole pixel and the whole light (an umbra,
/// or a pane every ray goes through); `Varies` otherwise.
///
/// In an unmarked pixel no wall end crosses the lines from the pixel to
/// the light's ends, and no wall comes near the pixel or the light:
/// which sides each wall crosses is the same for
/// every point of the pixel, and a wall that crosses both separates the
/// point from every point of the light, far from the ends of the shadow
/// ray and from its own ends. So every stratum's shadow ray, wherever it
/// aims on the light, crosses exactly those walls, in index order, like
/// the one ray from the centre that `centre_transmittance` casts.
fn line_coherence(walls: &[Segment], centre: DVec2, light: &Segment) -> Coherence {
    let mut state = Coherence::Clear;
    for wall in walls {
        if !meets_triangle(wall, centre, light) {
            continue;
        }
        let separates = [light.a, light.b]
            .iter()
            .all(|&end| segments_meet(wall.a, wall.b, centre, end));
        if !separates {
            return Coherence::Varies;
        }
        state = Coherence::Same;
    }
    state
}

/// Whether `wall` meets the closed triangle of `x` and `light`'s ends.
fn meets_triangle(wall: &Segment, x: DVec2, light: &Segment) -> bool {
    let corners = [x, light.a, light.b];
    let inside = |p: DVec2| {
        let s: [f64; 3] = std::array::from_fn(|k| {
            flatray_geometry::cross(corners[(k + 1) % 3] - corners[k], p - corners[k])
        });
        s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
    };
    inside(wall.a)
        || inside(wall.b)
        || (0..3).any(|k| segments_meet(wall.a, wall.b, corners[k], corners[(k + 1) % 3]))
}

/// Whether an end of `wall` or of `light` lies within rounding distance
/// of the other.
fn near_light(wall: &Segment, light: &Segment) -> bool {
    near(light.a, wall) || near(light.b, wall) || near(wall.a, light) || near(wall.b, light)
}

/// Whether segments `p q` and `r s` meet (touching counts).
fn segments_meet(p: DVec2, q: DVec2, r: DVec2, s: DVec2) -> bool {
    flatray_geometry::segments_meet(&Segment::new(p, q), &Segment::new(r, s))
}

/// The transmittance from a pixel's `centre` to light `index`: what every
/// stratum of a `Same` pixel gets (aimed at the middle of a line light,
/// though any point of it would do: see `line_coherence`). `walls`, where
/// given, lists every wall between the pixel and the light.
pub(crate) fn centre_transmittance(
    scene: &Scene,
    index: usize,
    centre: DVec2,
    walls: Option<&[u32]>,
    stats: &mut Stats,
) -> Rgb {
    let skip = Skip(u32::MAX, scene.light_wall[index].unwrap_or(u32::MAX));
    let shape = &scene.lights[index].shape;
    if let Some(source) = shape.source() {
        let (way, t_max) = source.way_from(centre);
        return crate::estimators::transmittance(
            scene,
            &Ray::new(centre, way),
            t_max,
            skip,
            walls,
            stats,
        );
    }
    match shape.emitter() {
        Emitter::Segment { segment, .. } => crate::estimators::transmittance(
            scene,
            &Ray::new(centre, segment.point_at(0.5) - centre),
            1.0,
            skip,
            walls,
            stats,
        ),
        // Not drawn (`draws`): no pixel of it is `Same`.
        Emitter::Disk { at, .. } => crate::estimators::transmittance(
            scene,
            &Ray::new(centre, at - centre),
            1.0,
            skip,
            walls,
            stats,
        ),
        // Lights with a source were answered above; beams and lasers are
        // not drawn, and no pixel of theirs is `Same`.
        Emitter::Point { .. }
        | Emitter::Direction(_)
        | Emitter::Arc(_)
        | Emitter::Parallel { .. } => Rgb::ZERO,
    }
}

/// Where the masks pay: the floor memo casts shadow rays, and drawing the
/// shadow edges of every wall-light pair into every pixel-light cell fits
/// its budgets.
pub(crate) fn supports(facts: &crate::accel::Facts) -> crate::accel::Decision {
    use crate::accel::Decision;
    use crate::options::FastPath;
    if !facts.floor_memo {
        return Decision::skipped("no floor cache");
    }
    if !facts.shadows {
        return Decision::skipped("no shadow rays");
    }
    if facts.arcs > 0 {
        return Decision::skipped("curved walls: their shadow edges are not drawn");
    }
    if let Some(no) = Decision::allowed(facts.options, FastPath::Coherence, "coherence") {
        return no;
    }
    if facts.pairs > MAX_PAIRS {
        return Decision::skipped(format!(
            "{} wall-light pairs, over {MAX_PAIRS}: drawing the shadow edges would cost more than it saves",
            facts.pairs
        ));
    }
    if facts.mask_cells > MAX_CELLS {
        return Decision::skipped(format!(
            "{} pixel-light cells, over its budget of {MAX_CELLS}",
            facts.mask_cells
        ));
    }
    Decision::runs("one shadow ray per light where no shadow edge crosses the pixel")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The distance from segment `p q` to the closed unit square of pixel
    /// `(x, y)`: zero where they meet, else the least of the segment's
    /// ends to the square and the square's corners to the segment.
    fn distance_to_pixel(p: DVec2, q: DVec2, x: usize, y: usize) -> f64 {
        let (lo, hi) = (
            DVec2::new(x as f64, y as f64),
            DVec2::new(x as f64 + 1.0, y as f64 + 1.0),
        );
        if clip_to_box(p, q - p, 0.0, 1.0, lo, hi).is_some() {
            return 0.0;
        }
        let to_square = |v: DVec2| (v.clamp(lo, hi) - v).length();
        let to_segment = |v: DVec2| {
            let e = q - p;
            let t = ((v - p).dot(e) / e.length_squared()).clamp(0.0, 1.0);
            (p + e * t).distance(v)
        };
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        corners
            .iter()
            .map(|&c| to_segment(c))
            .chain([to_square(p), to_square(q)])
            .fold(f64::INFINITY, f64::min)
    }

    /// A boundary along the middle of a row of pixels marks that row, and
    /// neither row beside it.
    #[test]
    fn a_boundary_marks_only_the_pixels_it_passes_near() {
        let mut mask = Mask::new(30, 20);
        mask.mark(DVec2::new(2.5, 10.5), DVec2::new(18.0, 0.0), 0.0, 1.0);
        for y in 0..20 {
            for x in 0..30 {
                let expected = y == 10 && (2..=20).contains(&x);
                assert_eq!(mask.marked[y * 30 + x], expected, "pixel ({x}, {y})");
            }
        }
    }

    /// A boundary from billions of pixels away: a little wider, where
    /// rounding could move it, and past that the light's mask is given up
    /// (every pixel traces) rather than drawn pixels wide.
    #[test]
    fn a_boundary_from_far_away_widens_then_gives_up() {
        let mut near = Mask::new(400, 300);
        near.mark(DVec2::new(-2e9, 150.5), DVec2::new(1.0, 0.0), 0.0, 3e9);
        assert!(!near.overflow);
        let rows: Vec<usize> = (0..300).filter(|&y| near.marked[y * 400 + 200]).collect();
        assert!(rows.contains(&150) && rows.len() <= 7, "{rows:?}");
        // From ten trillion pixels away.
        let mut far = Mask::new(400, 300);
        far.mark(DVec2::new(-2e13, 150.5), DVec2::new(1.0, 0.0), 0.0, 3e13);
        assert!(far.overflow);
    }

    proptest! {
        /// Every pixel within an eighth of a pixel of a boundary is
        /// marked, in any direction, including a boundary of no length
        /// (a light's own pixel).
        #[test]
        fn every_pixel_near_a_boundary_is_marked(
            o in (-5.0..45.0f64, -5.0..35.0f64),
            d in (-30.0..30.0f64, -30.0..30.0f64),
            t1 in 0.0..1.5f64,
        ) {
            let (o, d) = (DVec2::new(o.0, o.1), DVec2::new(d.0, d.1));
            let mut mask = Mask::new(40, 30);
            mask.mark(o, d, 0.0, t1);
            prop_assert!(!mask.overflow);
            let (p, q) = (o, o + d * t1);
            for y in 0..30 {
                for x in 0..40 {
                    if distance_to_pixel(p, q, x, y) < 0.125 {
                        prop_assert!(mask.marked[y * 40 + x], "pixel ({}, {})", x, y);
                    }
                }
            }
        }
    }
}
