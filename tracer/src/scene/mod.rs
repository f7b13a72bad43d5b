//! The in-memory scene: data that the integrators read, checked when it
//! is built.
//!
//! `flatray-io` builds it from a scene file; embedders, tests and
//! benchmarks build it directly with [`Scene::new`] or
//! [`Scene::with_glass`], which check every value (`check.rs`) and derive
//! the tables the integrators use. Its fields are private, so the tables
//! cannot fall out of step with the walls and lights.

mod check;
mod profile;
pub use check::{
    IOR_RANGE, InvalidScene, Item, MAX_CANVAS_PIXELS, MAX_CANVAS_SIDE, MAX_COORDINATE,
    MAX_INTENSITY, SMALL_RADIUS_RANGE,
};
pub use profile::Profile;
/// The checks of single values, with the messages a scene file's errors
/// use.
pub mod checks {
    pub use super::check::{
        canvas_size, color, cone, exposure, finite, fraction, glass_roughness, intensity, ior,
        light_shape, non_negative, point, positive, roughness, small_radius, spectrum,
    };
}

use flatray_geometry::{DVec2, Ray, Segment, SegmentSet, Shape, Side, Skip};

use crate::Rgb;
use crate::spectrum::{Mixture, Sampled, Spectrum};

/// The rectangle of the world that the image covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Canvas {
    /// Size in world units (one unit is one pixel at scale 1).
    pub width: u32,
    pub height: u32,
    /// World position of the top-left corner.
    pub origin: DVec2,
}

impl Canvas {
    /// The size of one pixel, in world units along x and y, of an image
    /// of `width` x `height` pixels covering the canvas.
    #[inline]
    pub fn pixel_step(&self, (width, height): (u32, u32)) -> DVec2 {
        DVec2::new(
            self.width as f64 / width as f64,
            self.height as f64 / height as f64,
        )
    }

    /// Whether `p` lies in the canvas rectangle `[origin, origin + size)`.
    pub fn contains(&self, p: DVec2) -> bool {
        let q = p - self.origin;
        q.x >= 0.0 && q.y >= 0.0 && q.x < self.width as f64 && q.y < self.height as f64
    }
}

/// The floor's albedo, a function of the world point.
#[derive(Clone, Debug, PartialEq)]
pub enum Floor {
    /// One colour everywhere.
    Color(Rgb),
    /// Square tiles of side `size` with grout lines of width `grout_width`
    /// between them, anchored at the canvas origin. A tile's colour is
    /// `tile`, varied by `variation` (0 to 1) per tile, reproducibly.
    Tiles {
        size: f64,
        grout_width: f64,
        tile: Rgb,
        grout: Rgb,
        variation: f64,
    },
    /// A linear-albedo image stretched over the canvas, nearest texel.
    Image {
        width: u32,
        height: u32,
        texels: Vec<Rgb>,
    },
}

impl Floor {
    /// The albedo at world point `p` of a floor laid over `canvas`.
    pub fn albedo_at(&self, canvas: &Canvas, p: DVec2) -> Rgb {
        match self {
            Floor::Color(c) => *c,
            Floor::Tiles {
                size,
                grout_width,
                tile,
                grout,
                variation,
            } => {
                let q = (p - canvas.origin) / *size;
                let cell = DVec2::new(floor(q.x), floor(q.y));
                let within = (q - cell) * *size;
                let half = grout_width * 0.5;
                let in_grout = within.x < half
                    || within.y < half
                    || within.x >= size - half
                    || within.y >= size - half;
                if in_grout {
                    *grout
                } else {
                    *tile * tile_shade(cell.x as i64, cell.y as i64, *variation)
                }
            }
            Floor::Image {
                width,
                height,
                texels,
            } => {
                let q = p - canvas.origin;
                let sx = *width as f64 / canvas.width as f64;
                let sy = *height as f64 / canvas.height as f64;
                let ix = (floor(q.x * sx).max(0.0) as usize).min(*width as usize - 1);
                let iy = (floor(q.y * sy).max(0.0) as usize).min(*height as usize - 1);
                texels[iy * *width as usize + ix]
            }
        }
    }

    /// The exact mean albedo over the rectangle `[lo, hi]` of a floor laid
    /// over `canvas`: a pixel's square, whose value is its mean albedo
    /// times its mean fluence (`docs/model.md`). A rectangle over more than
    /// [`MEAN_CELLS`] tiles or texels takes the mean of a grid of
    /// [`MEAN_GRID`]² points instead (a pixel that wide shows no single
    /// grout line or texel).
    pub fn mean_albedo(&self, canvas: &Canvas, lo: DVec2, hi: DVec2) -> Rgb {
        let area = (hi.x - lo.x) * (hi.y - lo.y);
        if !(area > 0.0 && area.is_finite()) {
            return self.albedo_at(canvas, (lo + hi) * 0.5);
        }
        let sampled = || {
            let mut sum = Rgb::ZERO;
            for j in 0..MEAN_GRID {
                for i in 0..MEAN_GRID {
                    let f = (DVec2::new(i as f64, j as f64) + 0.5) / MEAN_GRID as f64;
                    sum += self.albedo_at(canvas, lo + (hi - lo) * f);
                }
            }
            sum / (MEAN_GRID * MEAN_GRID) as f64
        };
        // The length of `[a0, a1]` within `[b0, b1]`.
        let overlap = |a0: f64, a1: f64, b0: f64, b1: f64| (a1.min(b1) - a0.max(b0)).max(0.0);
        match self {
            Floor::Color(c) => *c,
            Floor::Tiles {
                size,
                grout_width,
                tile,
                grout,
                variation,
            } => {
                let (q0, q1) = ((lo - canvas.origin) / *size, (hi - canvas.origin) / *size);
                let (c0, c1) = (
                    DVec2::new(floor(q0.x), floor(q0.y)),
                    DVec2::new(floor(q1.x), floor(q1.y)),
                );
                let cells = (c1 - c0 + 1.0).x * (c1 - c0 + 1.0).y;
                if !cells.is_finite() || cells > MEAN_CELLS as f64 {
                    return sampled();
                }
                let half = grout_width * 0.5;
                let (lo, hi) = (lo - canvas.origin, hi - canvas.origin);
                let mut tiles = Rgb::ZERO;
                let mut tile_area = 0.0;
                for cy in c0.y as i64..=c1.y as i64 {
                    for cx in c0.x as i64..=c1.x as i64 {
                        let (x, y) = (cx as f64 * size, cy as f64 * size);
                        // A tile is its cell less the grout bands along
                        // its four sides: a rectangle.
                        let inside = overlap(lo.x, hi.x, x + half, x + size - half)
                            * overlap(lo.y, hi.y, y + half, y + size - half);
                        if inside > 0.0 {
                            tiles += *tile * tile_shade(cx, cy, *variation) * inside;
                            tile_area += inside;
                        }
                    }
                }
                (tiles + *grout * (area - tile_area).max(0.0)) / area
            }
            Floor::Image {
                width,
                height,
                texels,
            } => {
                let sx = *width as f64 / canvas.width as f64;
                let sy = *height as f64 / canvas.height as f64;
                let (lo, hi) = (lo - canvas.origin, hi - canvas.origin);
                // In texels, clamped to the image as `albedo_at` clamps.
                let (tx0, tx1) = (lo.x * sx, hi.x * sx);
                let (ty0, ty1) = (lo.y * sy, hi.y * sy);
                let last = |n: u32| (n - 1) as f64;
                let (i0, i1) = (
                    floor(tx0).clamp(0.0, last(*width)),
                    floor(tx1).clamp(0.0, last(*width)),
                );
                let (j0, j1) = (
                    floor(ty0).clamp(0.0, last(*height)),
                    floor(ty1).clamp(0.0, last(*height)),
                );
                if (i1 - i0 + 1.0) * (j1 - j0 + 1.0) > MEAN_CELLS as f64 {
                    return sampled();
                }
                let (i0, i1, j0, j1) = (i0 as usize, i1 as usize, j0 as usize, j1 as usize);
                // Texel `k` covers `[k, k + 1)`; the first and the last
                // reach on past the image, as `albedo_at` clamps.
                let reach = |k: usize, n: u32| {
                    let a = if k == 0 { f64::NEG_INFINITY } else { k as f64 };
                    let b = if k + 1 >= n as usize {
                        f64::INFINITY
                    } else {
                        (k + 1) as f64
                    };
                    (a, b)
                };
                let mut sum = Rgb::ZERO;
                let mut weights = 0.0;
                for j in j0..=j1 {
                    let (b0, b1) = reach(j, *height);
                    let wy = overlap(ty0, ty1, b0, b1);
                    for i in i0..=i1 {
                        let (a0, a1) = reach(i, *width);
                        let w = overlap(tx0, tx1, a0, a1) * wy;
                        if w > 0.0 {
                            sum += texels[j * *width as usize + i] * w;
                            weights += w;
                        }
                    }
                }
                if weights > 0.0 {
                    sum / weights
                } else {
                    self.albedo_at(canvas, (lo + hi) * 0.5 + canvas.origin)
                }
            }
        }
    }
}

/// Most tiles or texels that [`Floor::mean_albedo`] sums exactly.
pub const MEAN_CELLS: usize = 4096;
/// The side of the grid of points it averages beyond them.
pub const MEAN_GRID: usize = 64;

/// A convex part of the floor where the albedo is one colour, as
/// [`Floor::regions`] names them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Region {
    /// The whole floor (one colour).
    All,
    /// The inside of tile `(x, y)`.
    Tile(i64, i64),
    /// The grout line at tile column (or row) boundary `k`.
    Column(i64),
    Row(i64),
    /// Texel `(x, y)`, or the half-plane beyond an edge that clamps to it.
    Texel(i64, i64),
}

/// Where a coordinate `within` a tile of `size` falls across one axis,
/// at least `margin` from every border: inside the tile (`Some(true)`),
/// in a grout line (`Some(false)`, with the line's offset from this
/// tile's: 0 or 1), or too near a border to say (`None`).
fn tile_axis(within: f64, size: f64, half: f64, margin: f64) -> Option<(bool, i64)> {
    if within >= half + margin && within < size - half - margin {
        Some((true, 0))
    } else if within < half - margin {
        Some((false, 0))
    } else if within >= size - half + margin {
        Some((false, 1))
    } else {
        None
    }
}

impl Floor {
    /// The convex one-colour regions that hold every point within
    /// `margin` of `p` (at most two: a grout crossing is in a column and
    /// a row). Empty near a border between colours.
    fn regions(&self, canvas: &Canvas, p: DVec2, margin: f64) -> [Option<Region>; 2] {
        if !(p.is_finite() && margin.is_finite()) {
            return [None, None];
        }
        match self {
            Floor::Color(_) => [Some(Region::All), None],
            Floor::Tiles {
                size, grout_width, ..
            } => {
                let q = (p - canvas.origin) / *size;
                let cell = DVec2::new(floor(q.x), floor(q.y));
                let within = (q - cell) * *size;
                let half = grout_width * 0.5;
                let (cx, cy) = (cell.x as i64, cell.y as i64);
                let x = tile_axis(within.x, *size, half, margin);
                let y = tile_axis(within.y, *size, half, margin);
                match (x, y) {
                    (Some((true, _)), Some((true, _))) => [Some(Region::Tile(cx, cy)), None],
                    (x, y) => [
                        x.and_then(|(inside, k)| (!inside).then_some(Region::Column(cx + k))),
                        y.and_then(|(inside, k)| (!inside).then_some(Region::Row(cy + k))),
                    ],
                }
            }
            Floor::Image { width, height, .. } => {
                let q = p - canvas.origin;
                let t = DVec2::new(
                    q.x * *width as f64 / canvas.width as f64,
                    q.y * *height as f64 / canvas.height as f64,
                );
                // Texel units: the margin scaled like the coordinates.
                let m = margin
                    * (*width as f64 / canvas.width as f64)
                        .max(*height as f64 / canvas.height as f64);
                let axis = |t: f64, n: u32| -> Option<i64> {
                    let last = n as f64 - 1.0;
                    let i = floor(t).clamp(0.0, last);
                    let low_ok = i == 0.0 || t >= i + m;
                    let high_ok = i == last || t < i + 1.0 - m;
                    (low_ok && high_ok).then_some(i as i64)
                };
                match (axis(t.x, *width), axis(t.y, *height)) {
                    (Some(x), Some(y)) => [Some(Region::Texel(x, y)), None],
                    _ => [None, None],
                }
            }
        }
    }
}

/// The floor's albedo along the walls that take it: for each such wall,
/// equal cells of its parameter `u`, about a quarter of a unit long (short,
/// so that few cells straddle a border and read the floor), each holding
/// the albedo wherever it is one colour over the whole cell (a NaN marks a
/// cell that crosses a border: read the floor there). A hit reads its cell
/// instead of evaluating the floor: the same value, found in a table.
#[derive(Clone, Debug, Default)]
pub(crate) struct AlbedoAlong {
    /// Per wall: the cells (empty for a wall with its own albedo).
    cells: Vec<Vec<Rgb>>,
}

/// At most this many cells per wall.
const MAX_ALBEDO_CELLS: usize = 4096;

/// At most this many cells over all walls (24 bytes each: 96 MiB).
pub const ALBEDO_CELLS_BUDGET: usize = 1 << 22;

/// Cells per unit of a wall's length.
const CELLS_PER_UNIT: f64 = 4.0;

impl AlbedoAlong {
    fn new(canvas: &Canvas, floor: &Floor, walls: &[Wall]) -> AlbedoAlong {
        let taking = walls
            .iter()
            .filter(|w| w.material.takes_floor_albedo())
            .count();
        // The budget shared out: many long walls get coarser cells (a
        // cell that crosses a border reads the floor: the same values).
        let most = (ALBEDO_CELLS_BUDGET / taking.max(1)).clamp(1, MAX_ALBEDO_CELLS);
        let cells = walls
            .iter()
            .map(|wall| {
                // An arc's cells would not be straight: it reads the floor.
                if let (true, Some(segment)) =
                    (wall.material.takes_floor_albedo(), wall.as_segment())
                {
                    Self::cells(canvas, floor, segment, most)
                } else {
                    Vec::new()
                }
            })
            .collect();
        AlbedoAlong { cells }
    }

    fn cells(canvas: &Canvas, floor: &Floor, segment: &Segment, most: usize) -> Vec<Rgb> {
        let length = segment.length();
        let n = if length.is_finite() {
            ((length * CELLS_PER_UNIT).ceil().min(most as f64) as usize).max(1)
        } else {
            1
        };
        let scale = 1.0 + segment.a.abs().max(segment.b.abs()).max_element();
        let margin = 1e-9 * scale;
        // A cell reaches a little beyond its ends in u, for the rounding
        // of the index computed from a hit's u.
        let reach = 1e-9;
        (0..n)
            .map(|i| {
                let u0 = i as f64 / n as f64 - reach;
                let u1 = (i + 1) as f64 / n as f64 + reach;
                let ends = [segment.point_at(u0), segment.point_at(u1)];
                let [r0, r1] = ends.map(|p| floor.regions(canvas, p, margin));
                let shared = r0.iter().flatten().any(|r| r1.contains(&Some(*r)));
                if shared {
                    // Convex and one colour: any point of it tells the
                    // colour. Its centre is well inside.
                    floor.albedo_at(canvas, segment.point_at((i as f64 + 0.5) / n as f64))
                } else {
                    Rgb::splat(f64::NAN)
                }
            })
            .collect()
    }

    /// The floor's albedo at `x`, the point at `u` on wall `wall` (one
    /// that takes the floor's albedo).
    #[inline]
    pub(crate) fn at(&self, floor: &Floor, canvas: &Canvas, wall: u32, u: f64, x: DVec2) -> Rgb {
        let cells = &self.cells[wall as usize];
        let n = cells.len();
        if n > 0 {
            // u in [0, 1]; the casts saturate, and NaN gives 0. Through
            // i64: one instruction, where usize takes a dozen on x86-64.
            let cell = cells[((u * n as f64) as i64).clamp(0, n as i64 - 1) as usize];
            if !cell.x.is_nan() {
                return cell;
            }
        }
        floor.albedo_at(canvas, x)
    }
}

/// `x.floor()`, without the library call that baseline x86-64 (no
/// SSE4.1 rounding instruction) makes for it: the same value for every
/// `x` (but `+0` for `-0`).
#[inline]
fn floor(x: f64) -> f64 {
    if x.abs() < 4.0e18 {
        // Exact: |x| < 2^62 fits an i64, and truncation then rounds
        // towards zero.
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t }
    } else {
        // Integral already, infinite or NaN.
        x.floor()
    }
}

/// The shade of the tile in cell `(x, y)`: 1 less up to `variation`,
/// reproducibly per cell.
fn tile_shade(x: i64, y: i64, variation: f64) -> f64 {
    1.0 - variation * (hash2(x, y) as f64 / u64::MAX as f64)
}

fn hash2(x: i64, y: i64) -> u64 {
    let mut z = (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (y as u64).rotate_left(32);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Distance falloff `G(r)` of a light, with `r` clamped below at the
/// scene's small radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Falloff {
    /// `1 / r`: the physical law of flatland.
    Flatland,
    /// `1 / r^2`: the law the original project describes.
    InverseSquare,
    /// `max(0, 1 - r / range)^2`: what the original program computes.
    Window { range: f64 },
    /// No falloff.
    Constant,
}

impl Falloff {
    /// `G(max(r, r0))`.
    #[inline]
    pub fn g(self, r: f64, r0: f64) -> f64 {
        let r = r.max(r0);
        match self {
            Falloff::Flatland => 1.0 / r,
            Falloff::InverseSquare => 1.0 / (r * r),
            Falloff::Window { range } => {
                let w = (1.0 - r / range).max(0.0);
                w * w
            }
            Falloff::Constant => 1.0,
        }
    }

    /// What a line light delivers per radian of the angle it subtends,
    /// per unit intensity, at distance `r`: `G(r') r'` with
    /// `r' = max(r, r0)` (the cosine at the light cancels against the
    /// Jacobian from length to angle). The distance is clamped wherever it
    /// appears, so for `Flatland` this is exactly 1 at every distance: a
    /// Lambertian emitter of radiance `I`, with no bias next to the light.
    #[inline]
    pub fn per_radian(self, r: f64, r0: f64) -> f64 {
        let r = r.max(r0);
        match self {
            Falloff::Flatland => 1.0,
            _ => self.g(r, r0) * r,
        }
    }
}

/// How a wall treats light that reaches it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector; `None` takes the floor's albedo at the hit.
    Diffuse { albedo: Option<Rgb> },
    /// Perfect specular reflector.
    Mirror { tint: Rgb },
    /// A rough mirror: a glossy lobe about the mirror direction, of
    /// spread `roughness` (in `(0, 1]`: the standard deviation of the
    /// sine of the reflected angle; 0 is [`Material::Mirror`], which
    /// [`Material::rough`] gives; 1 a broad lobe), reflected light
    /// multiplied by `tint`.
    Rough { roughness: f64, tint: Rgb },
    /// Light passes straight through, multiplied by `tint`.
    Transparent { tint: Rgb },
    /// An edge of glass body `body` (an index into `Scene::glass`), whose
    /// inside is on side `inside`: Fresnel reflection or Snell refraction.
    Glass { body: u32, inside: Side },
}

/// What the rest of the tracer asks of a material, answered here beside
/// its definition so that no other module matches a material's kind. The
/// light a material sends on is its BSDF's (`crate::material`).
impl Material {
    /// A rough mirror of `roughness`, clamped to `[0, 1]`: roughness 0
    /// (or below) is the perfect mirror itself, the same bits.
    pub fn rough(roughness: f64, tint: Rgb) -> Material {
        if roughness > 0.0 {
            Material::Rough {
                roughness: roughness.min(1.0),
                tint,
            }
        } else {
            Material::Mirror { tint }
        }
    }

    /// A Lambertian reflector: the walls the memos bin and the caustic
    /// pass ends at.
    #[inline]
    pub fn is_diffuse(&self) -> bool {
        matches!(self, Material::Diffuse { .. })
    }

    /// A Lambertian reflector that takes the floor's albedo where it
    /// stands.
    #[inline]
    pub fn takes_floor_albedo(&self) -> bool {
        matches!(self, Material::Diffuse { albedo: None })
    }

    /// A Lambertian reflector's own albedo, `Some(None)` when it takes the
    /// floor's; `None` for every other material.
    #[inline]
    pub fn diffuse_albedo(&self) -> Option<Option<Rgb>> {
        match *self {
            Material::Diffuse { albedo } => Some(albedo),
            _ => None,
        }
    }

    /// The perfect mirror.
    #[inline]
    pub fn is_mirror(&self) -> bool {
        matches!(self, Material::Mirror { .. })
    }

    /// A rough mirror: a glossy, non-specular lobe.
    #[inline]
    pub fn is_glossy(&self) -> bool {
        matches!(self, Material::Rough { .. })
    }

    /// A transparent wall's tint; `None` for every other material.
    #[inline]
    pub fn pane_tint(&self) -> Option<Rgb> {
        match *self {
            Material::Transparent { tint } => Some(tint),
            _ => None,
        }
    }

    /// A transparent wall.
    #[inline]
    pub fn is_pane(&self) -> bool {
        self.pane_tint().is_some()
    }

    /// A glass edge's body and the side its inside is on.
    #[inline]
    pub fn glass(&self) -> Option<(u32, Side)> {
        match *self {
            Material::Glass { body, inside } => Some((body, inside)),
            _ => None,
        }
    }

    /// A glass edge.
    #[inline]
    pub fn is_glass(&self) -> bool {
        self.glass().is_some()
    }

    /// Whether the wall turns light by a delta event (a mirror or a glass
    /// edge): where light tracing must carry a lamp's light on, since no
    /// shadow ray finds it, and paths go on past their last bounce.
    #[inline]
    pub fn turns_specularly(&self) -> bool {
        matches!(self, Material::Mirror { .. } | Material::Glass { .. })
    }

    /// Whether the wall blocks light: all but a clear pane.
    #[inline]
    pub fn occludes(&self) -> bool {
        !matches!(self, Material::Transparent { tint } if *tint == Rgb::ONE)
    }

    /// Whether the wall sends light on (not black, not a pane), where a
    /// diffuse wall that takes the floor's albedo does so unless
    /// `floor_black`.
    pub fn reflects(&self, floor_black: bool) -> bool {
        match *self {
            Material::Diffuse { albedo: Some(a) } => a != Rgb::ZERO,
            Material::Diffuse { albedo: None } => !floor_black,
            Material::Mirror { tint } | Material::Rough { tint, .. } => tint != Rgb::ZERO,
            Material::Transparent { .. } => false,
            Material::Glass { .. } => true,
        }
    }

    /// Whether the wall turns light by a delta event and sends some on.
    pub fn reflects_specularly(&self) -> bool {
        match *self {
            Material::Mirror { tint } => tint != Rgb::ZERO,
            Material::Glass { .. } => true,
            _ => false,
        }
    }

    /// The material's name in the scene format's words.
    pub fn noun(&self) -> &'static str {
        match self {
            Material::Diffuse { .. } => "wall",
            Material::Mirror { .. } => "mirror",
            Material::Rough { .. } => "rough mirror",
            Material::Transparent { .. } => "pane",
            Material::Glass { .. } => "glass edge",
        }
    }
}

/// A closed polygon of glass; its edges are walls of `Material::Glass`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlassBody {
    /// Index of refraction at 0.55 micrometres.
    pub ior: f64,
    /// Cauchy's `B` coefficient (square micrometres); 0 for none.
    pub dispersion: f64,
    /// Beer-Lambert absorption per unit length inside, per channel.
    pub absorption: Rgb,
    /// The spread of its edges' lobe (`material::glass`), from 0 (smooth
    /// glass: Fresnel and Snell exactly) to 1.
    pub roughness: f64,
}

/// A two-sided wall: a segment or a circular arc, of any material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wall {
    pub shape: Shape,
    pub material: Material,
}

impl Wall {
    /// A straight wall from `a` to `b`.
    pub fn segment(a: DVec2, b: DVec2, material: Material) -> Wall {
        Wall {
            shape: Shape::Segment(Segment::new(a, b)),
            material,
        }
    }

    /// Its segment, if it is straight.
    #[inline]
    pub fn as_segment(&self) -> Option<&Segment> {
        self.shape.as_segment()
    }
}

/// The shape of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightShape {
    /// An isotropic point.
    Point { at: DVec2 },
    /// A point whose intensity is multiplied by a smooth window around
    /// `direction` (unit): 1 within `cone - softness` radians of it, 0
    /// beyond `cone`, smoothstep between.
    Spot {
        at: DVec2,
        direction: DVec2,
        cone: f64,
        softness: f64,
    },
    /// A segment emitting from both sides, or from its `Positive` side only
    /// when `one_sided`. `wall` is the index of the wall it also is, when
    /// the light is solid.
    Line {
        segment: Segment,
        one_sided: bool,
        wall: Option<u32>,
    },
    /// A circular arc (or a full circle) emitting from both sides, as a
    /// Lambertian emitter of radiance `intensity`: a curved wall that
    /// glows. `wall` is the index of the wall it also is.
    Arc {
        arc: flatray_geometry::Arc,
        wall: Option<u32>,
    },
    /// Parallel rays travelling in `direction` (unit) from outside the
    /// scene; `intensity` is the irradiance across the beam.
    Directional { direction: DVec2 },
    /// A disk whose rim emits outward as a Lambertian emitter of radiance
    /// `intensity`. Not a wall: it blocks no light.
    Circle { at: DVec2, radius: f64 },
    /// Parallel rays travelling in `direction` (unit) from every point of
    /// `segment`, which must not lie along it: a sun limited to a strip;
    /// `intensity` is the irradiance across the beam.
    Beam { segment: Segment, direction: DVec2 },
    /// One ray from `at` along `direction` (unit), of power `intensity`: a
    /// beam of no width, found only by light tracing and the caustic pass.
    Laser { at: DVec2, direction: DVec2 },
}

/// A light: its shape, colour, intensity and falloff, and optionally
/// its spectrum.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub shape: LightShape,
    /// Its colour in linear sRGB; for a light with a spectrum, the
    /// spectrum's colour ([`Scene::new`] sets it).
    pub color: Rgb,
    pub intensity: f64,
    pub falloff: Falloff,
    /// What it emits wavelength by wavelength: its colour where no glass
    /// disperses, each wavelength apart where glass does
    /// (`crate::spectrum`).
    pub spectrum: Option<Spectrum>,
    /// How its radiance varies with the direction its light arrives
    /// from: a factor on `intensity` ([`Profile`]). Only a line light
    /// that is no wall, under `Falloff::Flatland`, takes one (a sky's
    /// frame); `None` is a factor of 1 everywhere.
    pub profile: Option<std::sync::Arc<Profile>>,
}

impl Light {
    /// The factor of its profile on its radiance for light that arrives
    /// from direction `from` (from the receiver towards the light): 1 for
    /// a light without one.
    #[inline]
    pub fn profile_at(&self, from: DVec2) -> f64 {
        match &self.profile {
            Some(profile) => profile.at(from),
            None => 1.0,
        }
    }

    /// The spot window at a unit direction `to_receiver` from the light, or
    /// 1 for a light that is not a spot.
    #[inline]
    pub fn spot_window(&self, to_receiver: DVec2) -> f64 {
        match self.shape {
            LightShape::Spot {
                direction,
                cone,
                softness,
                ..
            } => {
                let angle = direction.dot(to_receiver).clamp(-1.0, 1.0).acos();
                smooth_window(angle, cone, softness)
            }
            _ => 1.0,
        }
    }
}

/// 1 for `angle <= cone - softness`, 0 for `angle >= cone`, smoothstep
/// between.
pub fn smooth_window(angle: f64, cone: f64, softness: f64) -> f64 {
    if angle >= cone {
        0.0
    } else if softness <= 0.0 || angle <= cone - softness {
        1.0
    } else {
        let x = (cone - angle) / softness;
        x * x * (3.0 - 2.0 * x)
    }
}

/// What a scene is built from: plain data, checked when it is built.
#[derive(Clone, Debug, PartialEq)]
pub struct Parts {
    pub canvas: Canvas,
    pub floor: Floor,
    pub small_radius: f64,
    pub walls: Vec<Wall>,
    pub lights: Vec<Light>,
    pub glass: Vec<GlassBody>,
}

impl Parts {
    /// The scene of these parts, checked ([`Scene::with_glass`]).
    pub fn build(self) -> Result<Scene, InvalidScene> {
        Scene::with_glass(
            self.canvas,
            self.floor,
            self.small_radius,
            self.walls,
            self.lights,
            self.glass,
        )
    }

    /// The scene of these parts, unchecked: for tests of the renderer's
    /// guards against values that no checked scene holds (a light of
    /// intensity 1e200). Never for user input.
    #[doc(hidden)]
    pub fn build_unchecked(self) -> Scene {
        Scene::derive(
            self.canvas,
            self.floor,
            self.small_radius,
            self.walls,
            self.lights,
            self.glass,
        )
    }
}

/// Per light, per flat mirror, intervals of the mirror's parameter
/// (`Scene::mirror_shadows`).
pub(crate) type MirrorShadows = Vec<Vec<Vec<(f64, f64)>>>;

/// A complete scene: its walls and lights, and the tables derived from
/// them. Built by [`Scene::new`] or [`Scene::with_glass`], which check
/// every value; read through its accessors; changed only by building a
/// new one from its [`Scene::parts`], so the tables always match.
///
/// ```compile_fail
/// // The walls are private: a wall pushed here would be missing from
/// // the tables that rays are traced against.
/// fn add(scene: &mut flatray_tracer::Scene, wall: flatray_tracer::Wall) {
///     scene.walls.push(wall);
/// }
/// ```
#[derive(Clone, Debug)]
pub struct Scene {
    pub(crate) canvas: Canvas,
    pub(crate) floor: Floor,
    /// Every kernel clamps `r` below at this radius (world units).
    pub(crate) small_radius: f64,
    pub(crate) walls: Vec<Wall>,
    pub(crate) lights: Vec<Light>,
    /// Glass bodies, referred to by `Material::Glass` walls.
    pub(crate) glass: Vec<GlassBody>,
    /// How many segments given to [`Scene::new`] lay along others and were
    /// merged with them (`docs/robustness.md`, rule 8).
    pub(crate) merged: usize,
    /// For each wall, the index of the line light it also is.
    pub(crate) wall_light: Vec<Option<u32>>,
    /// For each light, the wall it sits on, which its shadow rays ignore:
    /// a solid line light's own wall, or the first wall that a point or
    /// spot light lies on (to within rounding).
    pub(crate) light_wall: Vec<Option<u32>>,
    /// The walls that are flat, perfect mirrors (`Material::Mirror`) and
    /// reflect some light (a black mirror's tint sends none on), in
    /// index order: the closed forms through one mirror walk them and
    /// count them against their budgets.
    pub(crate) flat_mirrors: Vec<u32>,
    /// Per light, and for a point, spot, sun or beam per flat mirror (in
    /// the order of `flat_mirrors`), the parts of the mirror (intervals of
    /// its parameter) that opaque walls surely hide from the light: filled
    /// once, when the closed form of lights in mirrors first asks
    /// (`estimators::mirrored`).
    pub(crate) mirror_shadows: std::sync::OnceLock<MirrorShadows>,
    /// The glass edges that are segments, each body's together (by body,
    /// then index).
    pub(crate) glass_edges: Vec<u32>,
    /// The walls' segments, indexed like `walls`.
    pub(crate) segments: SegmentSet,
    /// The floor's albedo along the walls that take it.
    pub(crate) albedo_along: AlbedoAlong,
    /// The lights' spectra, held on the grid of wavelengths.
    pub(crate) spectra: Spectra,
}

/// The distinct spectra of a scene's lights on the grid of wavelengths,
/// which light each has, and how paths draw a wavelength at dispersive
/// glass.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Spectra {
    sampled: Vec<Sampled>,
    /// Per light, its spectrum's index in `sampled`.
    of_light: Vec<Option<u32>>,
    /// Whether some glass disperses: only then does a spectrum act
    /// wavelength by wavelength.
    dispersive: bool,
}

impl Spectra {
    /// The spectra of `lights`, each distinct one sampled once; their
    /// colours set from them.
    fn new(lights: &mut [Light], glass: &[GlassBody]) -> Spectra {
        let mut sampled = Vec::new();
        let mut index: std::collections::HashMap<Vec<u64>, u32> = Default::default();
        let of_light = lights
            .iter_mut()
            .map(|light| {
                let spectrum = light.spectrum?;
                let k = *index.entry(spectrum.key()).or_insert_with(|| {
                    sampled.push(spectrum.sampled());
                    sampled.len() as u32 - 1
                });
                light.color = sampled[k as usize].rgb();
                Some(k)
            })
            .collect();
        Spectra {
            sampled,
            of_light,
            dispersive: glass.iter().any(|g| g.dispersion != 0.0),
        }
    }

    /// A wavelength (micrometres) for a path at its first dispersive edge,
    /// and the colour weight it takes, from numbers in `[0, 1)` that
    /// `uniform` gives (one, or two where lamps have spectra).
    pub(crate) fn draw(&self, mut uniform: impl FnMut() -> f64) -> (f64, Rgb) {
        use crate::spectrum::{RANGE_NM, WIDTH_NM, wavelength_rgb};
        // Where a light has a spectrum, half its draws from the spectra.
        if self.sampled.is_empty() {
            let nm = RANGE_NM.0 + WIDTH_NM * uniform();
            (nm / 1000.0, wavelength_rgb(nm))
        } else {
            let (nm, pdf) = Mixture::new(&self.sampled).sample(uniform(), uniform());
            (nm / 1000.0, wavelength_rgb(nm) / (WIDTH_NM * pdf))
        }
    }

    /// For a photon of light `index`, where glass disperses and the light
    /// has a spectrum: a wavelength (micrometres) drawn from its spectrum
    /// at emission with a number `uniform` gives, and the photon's colour
    /// in place of the light's.
    pub(crate) fn photon(&self, index: usize, uniform: impl FnOnce() -> f64) -> Option<(f64, Rgb)> {
        if !self.dispersive {
            return None;
        }
        let k = self.of_light.get(index).copied().flatten()?;
        let s = &self.sampled[k as usize];
        let (nm, _) = s.sample(uniform());
        Some((nm / 1000.0, s.photon_rgb(nm)))
    }
}

impl Scene {
    /// Builds a scene of walls and lights and its derived tables, after
    /// checking every value ([`InvalidScene`] names the first that is
    /// out of bounds). Walls that lie along others are merged
    /// (`docs/robustness.md`, rule 8).
    ///
    /// ```
    /// use flatray_tracer::{Canvas, Falloff, Floor, Light, LightShape, Rgb, Scene};
    /// use glam::DVec2;
    ///
    /// let canvas = Canvas { width: 100, height: 100, origin: DVec2::ZERO };
    /// let lamp = Light {
    ///     shape: LightShape::Point { at: DVec2::new(50.0, 50.0) },
    ///     color: Rgb::ONE,
    ///     intensity: 1.0,
    ///     falloff: Falloff::Flatland,
    ///     spectrum: None,
    ///     profile: None,
    /// };
    /// let scene = Scene::new(canvas, Floor::Color(Rgb::splat(0.5)), 0.5, vec![], vec![lamp.clone()])?;
    /// assert_eq!(scene.lights().len(), 1);
    ///
    /// let far = Light { intensity: -1.0, ..lamp };
    /// let error = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, vec![], vec![far]).unwrap_err();
    /// assert_eq!(error.to_string(), "light 0: expected an intensity from 0 to 1e9, found -1");
    /// # Ok::<(), flatray_tracer::scene::InvalidScene>(())
    /// ```
    pub fn new(
        canvas: Canvas,
        floor: Floor,
        small_radius: f64,
        walls: Vec<Wall>,
        lights: Vec<Light>,
    ) -> Result<Scene, InvalidScene> {
        Scene::with_glass(canvas, floor, small_radius, walls, lights, Vec::new())
    }

    /// Builds a scene with glass bodies, which `Material::Glass` walls
    /// refer to by index, after checking every value.
    pub fn with_glass(
        canvas: Canvas,
        floor: Floor,
        small_radius: f64,
        walls: Vec<Wall>,
        lights: Vec<Light>,
        glass: Vec<GlassBody>,
    ) -> Result<Scene, InvalidScene> {
        check::scene(&canvas, &floor, small_radius, &walls, &lights, &glass)?;
        Ok(Scene::derive(
            canvas,
            floor,
            small_radius,
            walls,
            lights,
            glass,
        ))
    }

    /// What the scene is built from, to change and build again: the one
    /// way to edit a scene, so that its tables are derived anew.
    ///
    /// ```
    /// # use flatray_tracer::{Canvas, Falloff, Floor, Light, LightShape, Rgb, Scene};
    /// # use glam::DVec2;
    /// # let canvas = Canvas { width: 10, height: 10, origin: DVec2::ZERO };
    /// # let lamp = Light { shape: LightShape::Point { at: DVec2::new(5.0, 5.0) },
    /// #     color: Rgb::ONE, intensity: 1.0, falloff: Falloff::Flatland, spectrum: None,
    /// #     profile: None };
    /// # let scene = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, vec![], vec![lamp])?;
    /// let mut parts = scene.parts();
    /// parts.lights[0].intensity = 2.0;
    /// let brighter = parts.build()?;
    /// assert_eq!(brighter.lights()[0].intensity, 2.0);
    /// # Ok::<(), flatray_tracer::scene::InvalidScene>(())
    /// ```
    pub fn parts(&self) -> Parts {
        Parts {
            canvas: self.canvas,
            floor: self.floor.clone(),
            small_radius: self.small_radius,
            walls: self.walls.clone(),
            lights: self.lights.clone(),
            glass: self.glass.clone(),
        }
    }

    /// The derived tables of a scene whose values are checked.
    fn derive(
        canvas: Canvas,
        floor: Floor,
        small_radius: f64,
        mut walls: Vec<Wall>,
        mut lights: Vec<Light>,
        glass: Vec<GlassBody>,
    ) -> Scene {
        let spectra = Spectra::new(&mut lights, &glass);
        // A rough mirror of roughness 0 is the mirror, to the bit.
        for w in &mut walls {
            if let Material::Rough { roughness, tint } = w.material {
                w.material = Material::rough(roughness, tint);
            }
        }
        let (walls, merged) = resolve_overlaps(walls, &mut lights);
        let mut wall_light = vec![None; walls.len()];
        for (index, light) in lights.iter_mut().enumerate() {
            if let LightShape::Line { wall, .. } | LightShape::Arc { wall, .. } = &mut light.shape
                && let Some(w) = *wall
            {
                match wall_light.get_mut(w as usize) {
                    Some(slot) => *slot = Some(index as u32),
                    None => *wall = None,
                }
            }
        }
        let light_wall = lights
            .iter()
            .map(|light| match light.shape {
                LightShape::Line { wall, .. } | LightShape::Arc { wall, .. } => wall,
                LightShape::Point { at }
                | LightShape::Spot { at, .. }
                | LightShape::Laser { at, .. } => walls
                    .iter()
                    .position(|w| lies_on_shape(at, &w.shape))
                    .map(|i| i as u32),
                LightShape::Directional { .. }
                | LightShape::Circle { .. }
                | LightShape::Beam { .. } => None,
            })
            .collect();
        let segments = SegmentSet::of_shapes(walls.iter().map(|w| w.shape).collect());
        let albedo_along = AlbedoAlong::new(&canvas, &floor, &walls);
        let flat_mirrors = (0..walls.len() as u32)
            .filter(|&w| {
                let wall = &walls[w as usize];
                matches!(wall.material, Material::Mirror { .. })
                    && wall.material.reflects_specularly()
                    && wall.as_segment().is_some()
            })
            .collect();
        let mut glass_edges: Vec<u32> = (0..walls.len() as u32)
            .filter(|&w| {
                walls[w as usize].material.is_glass() && walls[w as usize].as_segment().is_some()
            })
            .collect();
        glass_edges.sort_by_key(|&w| (walls[w as usize].material.glass().map(|(b, _)| b), w));
        Scene {
            canvas,
            floor,
            small_radius,
            walls,
            lights,
            glass,
            merged,
            wall_light,
            light_wall,
            flat_mirrors,
            mirror_shadows: std::sync::OnceLock::new(),
            glass_edges,
            segments,
            albedo_along,
            spectra,
        }
    }

    /// The rectangle of the world the image covers.
    pub fn canvas(&self) -> &Canvas {
        &self.canvas
    }

    /// The floor's albedo.
    pub fn floor(&self) -> &Floor {
        &self.floor
    }

    /// The radius (world units) below which every kernel clamps `r`.
    pub fn small_radius(&self) -> f64 {
        self.small_radius
    }

    /// The walls, after walls that lay along others were merged: a
    /// glass body's edges among them, and a solid line light's wall.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The glass bodies, which `Material::Glass` walls refer to.
    pub fn glass(&self) -> &[GlassBody] {
        &self.glass
    }

    /// Each wall's length if it is diffuse, else 0: what the wall memo
    /// and the caustic pass bin.
    pub(crate) fn diffuse_lengths(&self) -> Vec<f64> {
        self.walls
            .iter()
            .map(|w| {
                if w.material.is_diffuse() {
                    w.shape.length()
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The segment set of the walls, for queries.
    pub fn segments(&self) -> &SegmentSet {
        &self.segments
    }

    /// How many cells the table of the floor's albedo along the walls
    /// holds, over all walls (at most `ALBEDO_CELLS_BUDGET`).
    pub fn albedo_cells(&self) -> usize {
        self.albedo_along.cells.iter().map(Vec::len).sum()
    }

    /// Whether a ray that meets wall `index` ends its straight line there
    /// (every wall but a transparent one: a path goes on through those
    /// without turning). An index that is no wall stops nothing.
    pub fn stops_rays(&self, index: u32) -> bool {
        self.walls
            .get(index as usize)
            .is_some_and(|w| !w.material.is_pane())
    }

    /// How many of the walls the scene was built from lay along other
    /// walls (on top of them, within rounding) and were merged with them
    /// by rule 8 of `docs/robustness.md`: the walls' count is that many
    /// fewer, or more where a wall was cut.
    pub fn merged_walls(&self) -> usize {
        self.merged
    }

    /// Where other walls meet or cross each diffuse wall, as positions
    /// along it: the wall memo's bins and the caustic pass's stop there.
    pub(crate) fn junctions(&self) -> Vec<Vec<f64>> {
        (0..self.walls.len() as u32)
            .map(|index| self.junctions_of(index))
            .collect()
    }

    /// Where other walls meet or cross wall `index`, if it is diffuse, as
    /// positions along it in `(0, 1)`; empty otherwise.
    pub(crate) fn junctions_of(&self, index: u32) -> Vec<f64> {
        let mut cuts = Vec::new();
        let Some(w) = self.walls.get(index as usize) else {
            return cuts;
        };
        if !w.material.is_diffuse() {
            return cuts;
        }
        match w.shape {
            Shape::Arc(arc) => {
                // Where segments cross the arc or end on it; arcs that
                // cross it are not cut at (a bin then straddles the
                // crossing, as a bin of a long wall can).
                for (other, o) in self.walls.iter().enumerate() {
                    let Some(seg) = o.as_segment() else { continue };
                    if other == index as usize {
                        continue;
                    }
                    let along = Ray::new(seg.a, seg.edge());
                    let (roots, n) = arc.line_crossings(&along, false, None);
                    for &t in &roots[..n] {
                        if (0.0..=1.0).contains(&t) {
                            let u = arc.position_of(along.at(t));
                            if u > 0.0 && u < 1.0 {
                                cuts.push(u);
                            }
                        }
                    }
                }
                cuts.sort_by(f64::total_cmp);
            }
            Shape::Segment(segment) => {
                let along = Ray::new(segment.a, segment.edge());
                self.segments
                    .for_each_crossing(&along, 1.0, Skip::one(index), |_, hit| {
                        if hit.t > 0.0 {
                            cuts.push(hit.t);
                        }
                        true
                    });
            }
        }
        cuts
    }

    /// What light `index` sends to a path that carries `wavelength`
    /// (micrometres), per unit of its intensity: its colour, or, for a
    /// light with a spectrum, its value at that wavelength.
    #[inline]
    pub(crate) fn light_colour(&self, index: usize, wavelength: Option<f64>) -> Rgb {
        let spectra = &self.spectra;
        match (wavelength, spectra.of_light.get(index).copied().flatten()) {
            (Some(um), Some(k)) => spectra.sampled[k as usize].at_wavelength(um * 1000.0),
            _ => self.lights[index].color,
        }
    }

    /// The wall a laser sits on, which its photons leave without meeting
    /// (a light on a wall shines past it, `docs/robustness.md` rule 4):
    /// `None` for any other light.
    pub(crate) fn laser_wall(&self, index: usize) -> Option<u32> {
        match self.lights.get(index)?.shape {
            LightShape::Laser { .. } => self.light_wall.get(index).copied().flatten(),
            _ => None,
        }
    }

    /// The line light that wall `index` also is, if any.
    pub fn light_of_wall(&self, index: u32) -> Option<u32> {
        self.wall_light.get(index as usize).copied().flatten()
    }
}

/// Walls that lie on top of each other, made into walls that do not
/// (`docs/robustness.md`, rule 8). Each group of walls that lie along one
/// line and overlap (`flatray_geometry::overlap`; glass edges and emitting
/// walls never move) has its line cut at every member's endpoint, and each
/// piece becomes one wall:
///
/// - where an emitting wall lies, that wall, whole and unchanged (two
///   emitting walls on one line are both kept);
/// - else, where an opaque wall lies, the one a path sees: a mirror before
///   a diffuse wall, and among those the darkest (its colour's components
///   in order; a wall that takes the floor's colour after any colour of
///   its own), then the least by coordinates;
/// - else, where panes alone lie, one pane whose tint is the product of
///   theirs: light crossing the line there passes all of them.
///
/// Consecutive pieces of one wall stay one segment, and a wall that keeps
/// its whole extent keeps its segment exactly. The pieces come after every
/// other wall, group by group in order of their coordinates and in order
/// along the line within a group, and share the members' own endpoints, so no gap opens between them or at the walls
/// that met the members' ends. The walls that come out do not depend on
/// the order of the walls that went in. Returns them and how many walls
/// were merged; the lights' wall indices are moved with their walls.
fn resolve_overlaps(walls: Vec<Wall>, lights: &mut [Light]) -> (Vec<Wall>, usize) {
    let emitting: Vec<bool> = {
        let mut emitting = vec![false; walls.len()];
        for light in lights.iter() {
            if let LightShape::Line { wall: Some(w), .. } | LightShape::Arc { wall: Some(w), .. } =
                light.shape
                && let Some(slot) = emitting.get_mut(w as usize)
            {
                *slot = true;
            }
        }
        emitting
    };
    // Arcs are not merged: only straight walls lie along a line.
    let segments: Vec<Segment> = walls.iter().map(|w| w.shape.chord()).collect();
    let groups = flatray_geometry::overlap::overlap_groups(&segments, |i| {
        !walls[i].material.is_glass() && walls[i].as_segment().is_some()
    });
    if groups.is_empty() {
        return (walls, 0);
    }
    // The walls that the groups' pieces replace, and the pieces, a list
    // per group.
    let mut removed = vec![false; walls.len()];
    let mut resolved: Vec<Vec<Wall>> = Vec::with_capacity(groups.len());
    let mut merged = 0;
    for group in &groups {
        merged += group.iter().filter(|&&i| !emitting[i]).count();
        let pieces = flatray_geometry::overlap::pieces(&segments, group);
        let out = resolve_group(&walls, &emitting, group, &pieces);
        for &i in group {
            removed[i] |= !emitting[i];
        }
        resolved.push(out);
    }
    // The groups' walls after every other, by their first piece's
    // coordinates: the same list wherever the members were listed.
    let first_point = |g: &Vec<Wall>| g.first().map_or([0.0; 4], coordinates);
    resolved.sort_by(|x, y| coordinate_order(first_point(x), first_point(y)));
    let mut new_index = vec![u32::MAX; walls.len()];
    let mut out = Vec::with_capacity(walls.len());
    for (i, wall) in walls.into_iter().enumerate() {
        if !removed[i] {
            new_index[i] = out.len() as u32;
            out.push(wall);
        }
    }
    out.extend(resolved.into_iter().flatten());
    for light in lights.iter_mut() {
        if let LightShape::Line { wall, .. } | LightShape::Arc { wall, .. } = &mut light.shape
            && let Some(w) = *wall
        {
            // An emitting wall is never replaced; an index out of range
            // stays out of range, and is treated as not solid.
            *wall = match new_index.get(w as usize) {
                Some(&n) if n != u32::MAX => Some(n),
                _ => Some(u32::MAX),
            };
        }
    }
    (out, merged)
}

/// What one piece of a line that several walls lie on becomes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Owner {
    /// An emitting wall lies there: it stays as it is, and no other wall.
    Emitting,
    /// One wall's material: that wall's (a position in the group).
    Wall(usize),
    /// Only panes, the same set of them as long as the number is the same:
    /// one pane of all their tints.
    Panes(usize),
    /// No wall (a sliver between two ends that are not the same point).
    Nobody,
}

/// The walls that one group's pieces become: a sweep along the line,
/// keeping the members that cover the current piece ordered by rule 8's
/// preference, so that time and memory stay about linear in the members.
fn resolve_group(
    walls: &[Wall],
    emitting: &[bool],
    group: &[usize],
    pieces: &flatray_geometry::overlap::Pieces,
) -> Vec<Wall> {
    use std::collections::BTreeSet;
    let pane = |g: usize| walls[group[g]].material.is_pane();
    // Each member's rank in its class (opaque walls by the wall a path
    // meets first, panes by tint then coordinates): an order of values,
    // not of the list.
    let mut by_preference: Vec<usize> = (0..group.len()).collect();
    by_preference.sort_by(|&x, &y| seen_order(&walls[group[x]], &walls[group[y]]));
    let mut rank = vec![0; group.len()];
    for (r, &g) in by_preference.iter().enumerate() {
        rank[g] = r;
    }
    let count = pieces.points.len().saturating_sub(1);
    let mut starting: Vec<Vec<usize>> = vec![Vec::new(); count + 1];
    let mut ending: Vec<Vec<usize>> = vec![Vec::new(); count + 1];
    for (g, span) in pieces.spans.iter().enumerate() {
        if span.start < span.end {
            starting[span.start].push(g);
            ending[span.end].push(g);
        }
    }
    let (mut emitters, mut opaque, mut panes) = (0usize, BTreeSet::new(), BTreeSet::new());
    let mut pane_sets = 0;
    // Per piece, where a run of several panes starts there, the product
    // of their tints in the order of their ranks.
    let mut tints: Vec<Rgb> = Vec::with_capacity(count);
    let mut owners = Vec::with_capacity(count);
    for k in 0..count {
        let mut panes_changed = false;
        for &g in ending[k].iter().chain(&starting[k]) {
            let entering = pieces.spans[g].start == k;
            if emitting[group[g]] {
                emitters = if entering { emitters + 1 } else { emitters - 1 };
            } else if pane(g) {
                panes_changed = true;
                if entering {
                    panes.insert((rank[g], g))
                } else {
                    panes.remove(&(rank[g], g))
                };
            } else if entering {
                opaque.insert((rank[g], g));
            } else {
                opaque.remove(&(rank[g], g));
            }
        }
        pane_sets += usize::from(panes_changed);
        owners.push(if emitters > 0 {
            Owner::Emitting
        } else if let Some(&(_, g)) = opaque.first() {
            Owner::Wall(g)
        } else {
            match panes.len() {
                0 => Owner::Nobody,
                1 => Owner::Wall(panes.first().map_or(0, |&(_, g)| g)),
                _ => Owner::Panes(pane_sets),
            }
        });
        // The tints of a piece's panes, where a run of them starts.
        let starts_run = k == 0 || owners[k - 1] != owners[k];
        tints.push(match owners[k] {
            Owner::Panes(_) if starts_run => panes.iter().fold(Rgb::ONE, |t, &(_, g)| {
                t * walls[group[g]].material.pane_tint().unwrap_or(Rgb::ONE)
            }),
            _ => Rgb::ONE,
        });
    }
    let mut out = Vec::new();
    let mut k = 0;
    while k < owners.len() {
        let mut end = k + 1;
        while end < owners.len() && owners[end] == owners[k] {
            end += 1;
        }
        let (p, q) = (pieces.points[k], pieces.points[end]);
        match owners[k] {
            Owner::Emitting | Owner::Nobody => {}
            Owner::Wall(g) => out.push(Wall {
                shape: Shape::Segment(if pieces.forward[g] {
                    Segment::new(p, q)
                } else {
                    Segment::new(q, p)
                }),
                material: walls[group[g]].material,
            }),
            Owner::Panes(_) => out.push(Wall {
                shape: Shape::Segment(Segment::new(p, q)),
                material: Material::Transparent { tint: tints[k] },
            }),
        }
        k = end;
    }
    out
}

/// Which of two opaque walls on one line a path sees: a mirror before a
/// rough mirror before a diffuse wall, the darker before the brighter, a wall of its own colour
/// before one of the floor's, then by coordinates.
fn seen_order(x: &Wall, y: &Wall) -> std::cmp::Ordering {
    let rank = |w: &Wall| match w.material {
        Material::Mirror { tint } => (0, tint),
        Material::Rough { tint, .. } => (1, tint),
        Material::Diffuse { albedo: Some(c) } => (2, c),
        Material::Diffuse { albedo: None } => (3, Rgb::ZERO),
        // Neither panes nor glass reach here.
        Material::Transparent { tint } => (4, tint),
        Material::Glass { .. } => (5, Rgb::ZERO),
    };
    let ((cx, tx), (cy, ty)) = (rank(x), rank(y));
    cx.cmp(&cy)
        .then(colour_order(tx, ty))
        .then_with(|| coordinate_order(coordinates(x), coordinates(y)))
}

fn coordinates(w: &Wall) -> [f64; 4] {
    let (a, b) = (w.shape.a(), w.shape.b());
    [a.x, a.y, b.x, b.y]
}

/// Two walls' coordinates in lexicographic order (a total order: NaN too).
fn coordinate_order(x: [f64; 4], y: [f64; 4]) -> std::cmp::Ordering {
    x.iter()
        .zip(y)
        .map(|(p, q)| p.total_cmp(&q))
        .find(|o| o.is_ne())
        .unwrap_or(std::cmp::Ordering::Equal)
}

fn colour_order(x: Rgb, y: Rgb) -> std::cmp::Ordering {
    x.x.total_cmp(&y.x)
        .then(x.y.total_cmp(&y.y))
        .then(x.z.total_cmp(&y.z))
}

/// Whether `p` lies on `segment` to within the rounding of the numbers
/// involved: its distance from the segment's line is below what computing
/// that distance can resolve, and it lies between the ends.
pub fn lies_on(p: DVec2, segment: &Segment) -> bool {
    let e = segment.edge();
    let tolerance = line_tolerance(p, segment);
    let along = (p - segment.a).dot(e);
    segment.side_value(p).abs() <= tolerance
        && along >= -tolerance
        && along <= e.length_squared() + tolerance
}

/// Whether `p` lies on `shape` to within rounding: [`lies_on`] for a
/// segment; for an arc, within rounding of its circle and on the arc's
/// side of its chord (or at an end).
pub fn lies_on_shape(p: DVec2, shape: &Shape) -> bool {
    match shape {
        Shape::Segment(segment) => lies_on(p, segment),
        Shape::Arc(arc) => {
            let f = p - arc.center;
            let scale = arc.center.abs().max(p.abs()).max_element().max(arc.radius);
            let tolerance = 16.0 * f64::EPSILON * scale;
            if (f.length() - arc.radius).abs() > tolerance {
                return false;
            }
            p == arc.a || p == arc.b || {
                let u = arc.position_of(p);
                (arc.point_at(u) - p).length() <= tolerance * 4.0
            }
        }
    }
}

/// Whether `p` lies on the infinite line through `segment`, to within the
/// rounding of the numbers involved (as [`lies_on`], without the ends).
pub fn lies_on_line(p: DVec2, segment: &Segment) -> bool {
    segment.side_value(p).abs() <= line_tolerance(p, segment)
}

/// What computing `segment.side_value(p)` can resolve.
fn line_tolerance(p: DVec2, segment: &Segment) -> f64 {
    let e = segment.edge();
    let magnitude = segment
        .a
        .abs()
        .max(segment.b.abs())
        .max(p.abs())
        .max_element();
    16.0 * f64::EPSILON * e.length() * magnitude.max(e.length())
}

/// The side of a one-sided line light that emits.
pub const EMITTING_SIDE: Side = Side::Positive;

#[cfg(test)]
mod tests {
    use super::*;

    /// An image floor's mean over a rectangle weighs each texel by its
    /// area in it; its edge texels reach on past the canvas, as a point
    /// read clamps; a rectangle over more texels than the budget takes
    /// the grid of points, within a pixel's share of one texel.
    #[test]
    fn an_image_floor_is_averaged_by_texel_area() {
        let canvas = Canvas {
            width: 4,
            height: 2,
            origin: DVec2::new(10.0, 20.0),
        };
        let texels = vec![
            Rgb::splat(0.0),
            Rgb::splat(1.0),
            Rgb::splat(2.0),
            Rgb::splat(3.0),
            Rgb::splat(4.0),
            Rgb::splat(5.0),
            Rgb::splat(6.0),
            Rgb::splat(7.0),
        ];
        // One texel per unit: a 4 x 2 image on a 4 x 2 canvas.
        let floor = Floor::Image {
            width: 4,
            height: 2,
            texels,
        };
        let at = |x0: f64, y0: f64, x1: f64, y1: f64| {
            floor
                .mean_albedo(
                    &canvas,
                    DVec2::new(10.0 + x0, 20.0 + y0),
                    DVec2::new(10.0 + x1, 20.0 + y1),
                )
                .x
        };
        assert_eq!(at(1.0, 0.0, 2.0, 1.0), 1.0);
        // A quarter of each of texels 0, 1, 4, 5.
        assert!((at(0.5, 0.5, 1.5, 1.5) - 2.5).abs() < 1e-12);
        // Three quarters of texel 2, one of texel 3.
        assert!((at(2.25, 0.0, 3.25, 1.0) - 2.25).abs() < 1e-12);
        // Past the canvas: the edge texel.
        assert!((at(-1.0, 0.0, 0.0, 1.0) - 0.0).abs() < 1e-12);
        assert!((at(3.5, 1.0, 4.5, 2.0) - 7.0).abs() < 1e-12);

        let big = Floor::Image {
            width: 256,
            height: 256,
            texels: (0..256 * 256)
                .map(|k| Rgb::splat((k % 256) as f64))
                .collect(),
        };
        let canvas = Canvas {
            width: 256,
            height: 256,
            origin: DVec2::ZERO,
        };
        // 128 x 128 texels: over the budget, the grid's mean.
        let mean = big.mean_albedo(&canvas, DVec2::ZERO, DVec2::splat(128.0)).x;
        assert!((mean - 63.5).abs() < 1.0, "{mean}");
    }

    #[test]
    fn the_fast_floor_is_the_floor() {
        let mut values = vec![
            0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            0.999_999_999_999,
            -0.999_999_999_999,
            1e-300,
            -1e-300,
            2.5e15,
            -2.5e15,
            4.5e15 + 0.5,
            -4.5e15 - 0.5,
            3.9e18,
            -3.9e18,
            4.0e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
        ];
        values.extend((0..2000).map(|k| (k as f64 - 1000.0) * 0.37));
        values.extend((-3..4).map(|k| k as f64 - f64::EPSILON * 4.0));
        for x in values {
            assert_eq!(super::floor(x), x.floor(), "{x}");
        }
        assert!(super::floor(f64::NAN).is_nan());
    }

    /// A tiny generator for test inputs: SplitMix64 over a counter.
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut z = seed;
        move || {
            z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut x = z;
            x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((x ^ (x >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn wall(a: (f64, f64), b: (f64, f64), material: Material) -> Wall {
        Wall {
            shape: Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1)).into(),
            material,
        }
    }

    /// Rule 8's outcomes, piece by piece: the opaque wall over a pane, a
    /// mirror over a diffuse wall, panes multiplied, an emitting wall kept
    /// whole, and the pieces after the other walls.
    #[test]
    fn walls_lying_on_walls_become_the_walls_rule_8_names() {
        let diffuse = Material::Diffuse { albedo: None };
        let mirror = Material::Mirror { tint: Rgb::ONE };
        let pane = |t: f64| Material::Transparent {
            tint: Rgb::splat(t),
        };
        let walls = vec![
            wall((0.0, 0.0), (10.0, 0.0), diffuse),
            wall((0.0, 5.0), (0.0, -5.0), diffuse),
            wall((6.0, 0.0), (2.0, 0.0), mirror),
            wall((8.0, 0.0), (14.0, 0.0), pane(0.5)),
            wall((12.0, 0.0), (16.0, 0.0), pane(0.25)),
        ];
        let (out, merged) = resolve_overlaps(walls.clone(), &mut []);
        assert_eq!(merged, 4);
        let expected = vec![
            walls[1],
            wall((0.0, 0.0), (2.0, 0.0), diffuse),
            wall((6.0, 0.0), (2.0, 0.0), mirror),
            wall((6.0, 0.0), (10.0, 0.0), diffuse),
            wall((10.0, 0.0), (12.0, 0.0), pane(0.5)),
            wall((12.0, 0.0), (14.0, 0.0), pane(0.125)),
            wall((14.0, 0.0), (16.0, 0.0), pane(0.25)),
        ];
        assert_eq!(out, expected);
        // An emitting wall stays whole; what lies on it goes.
        let mut lights = vec![Light {
            profile: None,
            shape: LightShape::Line {
                segment: walls[0].shape.chord(),
                one_sided: false,
                wall: Some(0),
            },
            color: Rgb::ONE,
            intensity: 1.0,
            falloff: Falloff::Flatland,
            spectrum: None,
        }];
        let (out, _) = resolve_overlaps(walls.clone(), &mut lights);
        assert_eq!(out[0], walls[0]);
        assert!(matches!(
            lights[0].shape,
            LightShape::Line { wall: Some(0), .. }
        ));
        assert_eq!(out.len(), 5, "{out:?}");
        // Many panes stacked on one wall, nested: resolved at once, to the
        // wall.
        let mut many = vec![wall((0.0, 0.0), (1e4, 0.0), diffuse)];
        many.extend((1..20_000).map(|k| {
            let k = k as f64 * 0.25;
            wall((k, 0.0), (1e4 - k, 0.0), pane(0.9))
        }));
        let (out, merged) = resolve_overlaps(many, &mut []);
        assert_eq!(merged, 20_000);
        assert_eq!(out, vec![wall((0.0, 0.0), (1e4, 0.0), diffuse)]);
    }

    #[test]
    fn the_albedo_along_a_wall_is_the_floors_albedo_at_every_hit() {
        let canvas = Canvas {
            width: 500,
            height: 400,
            origin: DVec2::new(-3.0, 7.5),
        };
        let tiles = |size: f64, grout_width: f64| Floor::Tiles {
            size,
            grout_width,
            tile: Rgb::new(0.78, 0.77, 0.72),
            grout: Rgb::splat(0.3),
            variation: 0.1,
        };
        let image = Floor::Image {
            width: 7,
            height: 5,
            texels: (0..35).map(|k| Rgb::splat(k as f64 / 35.0)).collect(),
        };
        let mut next = numbers(5);
        let mut walls = Vec::new();
        // Random walls, and walls along grout lines, tile edges and texel
        // borders, where cells must not claim one colour.
        for _ in 0..60 {
            let a = DVec2::new(next() * 600.0 - 50.0, next() * 500.0 - 50.0);
            let b = a + DVec2::new(next() * 200.0 - 100.0, next() * 200.0 - 100.0);
            walls.push(Segment::new(a, b));
        }
        for x in [
            -3.0 + 25.0,
            -3.0 + 26.0,
            -3.0 + 24.0,
            -3.0 + 1.0,
            -3.0 + 500.0 / 7.0 * 3.0,
        ] {
            walls.push(Segment::new(DVec2::new(x, 0.0), DVec2::new(x, 400.0)));
            walls.push(Segment::new(
                DVec2::new(x, 0.0),
                DVec2::new(x + 123.0, 400.0),
            ));
        }
        for y in [7.5 + 1.0, 7.5 + 49.0, 7.5 + 80.0] {
            walls.push(Segment::new(DVec2::new(-10.0, y), DVec2::new(480.0, y)));
        }
        let walls: Vec<Wall> = walls
            .into_iter()
            .map(|segment| Wall {
                shape: segment.into(),
                material: Material::Diffuse { albedo: None },
            })
            .collect();
        for floor in [
            tiles(25.0, 2.0),
            tiles(7.3, 0.9),
            image,
            Floor::Color(Rgb::splat(0.5)),
        ] {
            let along = AlbedoAlong::new(&canvas, &floor, &walls);
            let (mut known, mut all) = (0, 0);
            for (w, wall) in walls.iter().enumerate() {
                let cells = &along.cells[w];
                all += cells.len();
                known += cells.iter().filter(|c| !c.x.is_nan()).count();
                let n = cells.len() as f64;
                // Every cell border, a hair each side, and random points.
                let mut us: Vec<f64> = (0..=cells.len())
                    .flat_map(|i| {
                        let u = i as f64 / n;
                        [u, u - 1e-15, u + 1e-15, u - 1e-12, u + 1e-12]
                    })
                    .filter(|u| (0.0..=1.0).contains(u))
                    .collect();
                us.extend((0..400).map(|_| next()));
                for u in us {
                    let x = wall.shape.point_at(u);
                    assert_eq!(
                        along.at(&floor, &canvas, w as u32, u, x),
                        floor.albedo_at(&canvas, x),
                        "floor {floor:?}, wall {w}, u {u}"
                    );
                }
            }
            // The table answers most hits by itself (random diagonal walls
            // on 25-unit tiles: 72 %; the cells lost are those crossing a
            // grout border or a grout crossing).
            assert!(known * 10 > all * 6, "{known} of {all} cells known");
        }
    }
}
