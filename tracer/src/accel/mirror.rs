//! Culling the rays that leave walls: each mirror is cut into short
//! pieces, and for each piece and arc of directions the walls its
//! reflected rays can meet are listed once per render
//! (`flatray_geometry::ArcCandidates` of the piece's bounding box). A ray
//! off a mirror then tests only its list, with the same answer as a test
//! of every wall. Where the onward memo gathers paths from the diffuse
//! walls (two bounces or more), their first rays take lists too, per
//! longer piece.

use flatray_geometry::{ArcCandidates, DVec2};
use rayon::prelude::*;

use crate::options::LONG_LIST;
use crate::sampling::ARCS;
use crate::scene::{Material, Scene};

/// The lists of every mirror's pieces (and diffuse wall's), by wall.
#[derive(Debug, Default)]
pub(crate) struct MirrorArcs {
    /// Per wall: its pieces' lists (empty for a wall that takes none).
    walls: Vec<Vec<ArcCandidates>>,
}

/// The length of a piece, in pixels of the rendered image.
pub(crate) const MIRROR_PIECE: u32 = 4;
/// At most this many pieces per mirror.
const MAX_PIECES: usize = 256;
/// The length of a diffuse wall's piece, in pixels, for the onward memo's
/// gathers: they leave the walls' bins once per render pass, not once
/// per pixel sample, so longer pieces serve them.
pub(crate) const GATHER_PIECE: u32 = 16;
/// At most this many pieces of diffuse walls in all: their pieces grow
/// on a large canvas.
const MAX_GATHER_PIECES: f64 = 8192.0;
/// A piece's box holds the points a little beyond its ends in `u`, for
/// the rounding of the piece found from a hit's `u`.
const REACH: f64 = 1e-9;

impl MirrorArcs {
    /// The lists for `scene` rendered at `scale` pixels per unit: for its
    /// mirrors, and with `gathers` for its diffuse walls; `None` where no
    /// wall takes any.
    pub(crate) fn build(scene: &Scene, scale: f64, gathers: bool) -> Option<MirrorArcs> {
        let mirror = |m: &Material| m.is_mirror();
        let diffuse = |m: &Material| gathers && m.is_diffuse();
        if !scene
            .walls
            .iter()
            .any(|w| mirror(&w.material) || diffuse(&w.material))
        {
            return None;
        }
        let mirror_piece = MIRROR_PIECE as f64 / scale;
        let diffuse_length: f64 = scene
            .walls
            .iter()
            .filter(|w| diffuse(&w.material))
            .map(|w| w.shape.length())
            .sum();
        let gather_piece = (GATHER_PIECE as f64 / scale).max(diffuse_length / MAX_GATHER_PIECES);
        let walls = scene
            .walls
            .par_iter()
            .map(|wall| {
                let (piece, most) = if mirror(&wall.material) {
                    (mirror_piece, MAX_PIECES)
                } else if diffuse(&wall.material) {
                    (gather_piece, MAX_GATHER_PIECES as usize)
                } else {
                    return Vec::new();
                };
                // An arc's pieces are not straight: its rays take the
                // whole set.
                let Some(&s) = wall.as_segment() else {
                    return Vec::new();
                };
                let pieces = (s.length() / piece).ceil();
                let n = if pieces.is_finite() {
                    (pieces as usize).clamp(1, most)
                } else {
                    1
                };
                (0..n)
                    .map(|i| {
                        let u0 = (i as f64 / n as f64 - REACH).max(0.0);
                        let u1 = ((i + 1) as f64 / n as f64 + REACH).min(1.0);
                        let (p, q) = (s.point_at(u0), s.point_at(u1));
                        fill(scene, p.min(q), p.max(q))
                    })
                    .collect()
            })
            .collect();
        Some(MirrorArcs { walls })
    }

    /// The walls that a ray leaving wall `wall` from its point at `u`, in
    /// direction `dir`, can meet; `None` for a wall that takes no lists,
    /// and where the list is long (the whole set costs less).
    #[inline(always)]
    fn lists(&self, wall: u32, u: f64, dir: DVec2) -> Option<&[u32]> {
        let pieces = self.walls.get(wall as usize)?;
        let n = pieces.len();
        // u in [0, 1]: the cast saturates (NaN gives 0).
        let piece = pieces.get(((u * n as f64) as usize).min(n.checked_sub(1)?))?;
        Some(piece.arc(arc_of(dir))).filter(|list| list.len() <= LONG_LIST)
    }
}

/// The lists of a mirror piece's box: the walls its rays can meet, less
/// those that walls opaque to them hide.
fn fill(scene: &Scene, lo: DVec2, hi: DVec2) -> ArcCandidates {
    let mut arcs = ArcCandidates::default();
    arcs.fill(&scene.segments, lo, hi, ARCS, None);
    arcs.drop_blocked(&scene.segments, lo, hi, |i| scene.stops_rays(i));
    arcs
}

/// The arc of [`ARCS`] that holds direction `dir` (arc `k` spans the
/// angles `2 pi k / ARCS` to `2 pi (k + 1) / ARCS`), with no division: the
/// quadrant from the signs, the arc within it from how many of the arc
/// edges' tangents `|y| / |x|` reaches. Wrong only within 1e-15 radians of
/// an edge, where either arc's list holds the walls (they reach 1e-9
/// radians beyond the arc).
#[inline(always)]
fn arc_of(dir: DVec2) -> usize {
    let (ax, ay) = (dir.x.abs(), dir.y.abs());
    let mut j = 0;
    for t in EDGE_TANGENTS {
        j += (ay >= t * ax) as usize;
    }
    // j in 0..16: the arc of the first quadrant that (|x|, |y|) lies in.
    let arc = match (dir.x < 0.0, dir.y < 0.0) {
        (false, false) => j,
        (true, false) => 31 - j,
        (true, true) => 32 + j,
        (false, true) => 63 - j,
    };
    arc & (ARCS - 1)
}

/// `tan(k pi / 32)` for `k` in `1..16`: the arcs' edges in the first
/// quadrant.
const EDGE_TANGENTS: [f64; 15] = [
    0.09849140335716425,
    0.198912367379658,
    0.3033466836073424,
    0.41421356237309503,
    0.5345111359507916,
    0.6681786379192989,
    0.8206787908286602,
    0.9999999999999999,
    1.2185035255879764,
    1.496605762665489,
    1.8708684117893888,
    2.414213562373095,
    3.296558208938321,
    5.027339492125846,
    10.153170387608842,
];

impl crate::path::MirrorWalls for MirrorArcs {
    #[inline]
    fn walls(&self, wall: u32, u: f64, dir: DVec2) -> Option<&[u32]> {
        self.lists(wall, u, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_direction_falls_in_the_arc_that_spans_its_angle() {
        assert_eq!(ARCS, 64, "the edge tangents are for 64 arcs");
        for k in 0..ARCS {
            for f in [1e-9, 1e-6, 0.25, 0.5, 0.75, 1.0 - 1e-6, 1.0 - 1e-9] {
                let a = (k as f64 + f) * std::f64::consts::TAU / ARCS as f64;
                let dir = DVec2::new(a.cos(), a.sin()) * 3.0;
                assert_eq!(arc_of(dir), k, "arc {k}, fraction {f}");
            }
        }
        assert!(arc_of(DVec2::new(1.0, -1e-300)) < ARCS);
        assert!(arc_of(DVec2::new(f64::NAN, 1.0)) < ARCS);
    }
}
