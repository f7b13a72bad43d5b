//! The serde types of the RON scene file. They mirror the file's text;
//! [`crate::load`] turns them into a `flatray_tracer::Scene`.
//!
//! Value checks that need no context live in the `TryFrom` conversions of
//! small newtypes (a finite number, a colour in range, a wall of non-zero
//! length), so that the RON parser reports them with the line and column
//! where the value stands.

use serde::Deserialize;

use flatray_tracer::scene::checks;
pub use flatray_tracer::scene::{
    MAX_CANVAS_PIXELS, MAX_CANVAS_SIDE, MAX_COORDINATE, MAX_INTENSITY, SMALL_RADIUS_RANGE,
};
/// Most samples per pixel a scene may ask for.
pub const MAX_SAMPLES: u32 = 1 << 20;
/// Most bounces a scene may ask for.
pub const MAX_BOUNCES: u32 = 1000;

/// A finite number.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Finite(pub f64);

impl TryFrom<f64> for Finite {
    type Error = String;
    fn try_from(v: f64) -> Result<Finite, String> {
        checks::finite(v).map(|()| Finite(v))
    }
}

/// A finite number `>= 0`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct NonNegative(pub f64);

impl TryFrom<f64> for NonNegative {
    type Error = String;
    fn try_from(v: f64) -> Result<NonNegative, String> {
        checks::non_negative(v).map(|()| NonNegative(v))
    }
}

/// A finite number `> 0`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Positive(pub f64);

impl TryFrom<f64> for Positive {
    type Error = String;
    fn try_from(v: f64) -> Result<Positive, String> {
        checks::positive(v).map(|()| Positive(v))
    }
}

/// A point `(x, y)` of finite numbers within [`MAX_COORDINATE`].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "(Finite, Finite)")]
pub struct Point(pub f64, pub f64);

impl TryFrom<(Finite, Finite)> for Point {
    type Error = String;
    fn try_from((x, y): (Finite, Finite)) -> Result<Point, String> {
        checks::point(x.0, y.0).map(|()| Point(x.0, y.0))
    }
}

/// A light's intensity: a number from 0 to [`MAX_INTENSITY`].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Intensity(pub f64);

impl TryFrom<f64> for Intensity {
    type Error = String;
    fn try_from(v: f64) -> Result<Intensity, String> {
        checks::intensity(v).map(|()| Intensity(v))
    }
}

/// An exposure: a number > 0 and at most [`MAX_INTENSITY`].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Exposure(pub f64);

impl TryFrom<f64> for Exposure {
    type Error = String;
    fn try_from(v: f64) -> Result<Exposure, String> {
        checks::exposure(v).map(|()| Exposure(v))
    }
}

/// The small radius of the falloff kernels, within [`SMALL_RADIUS_RANGE`].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct SmallRadius(pub f64);

impl TryFrom<f64> for SmallRadius {
    type Error = String;
    fn try_from(v: f64) -> Result<SmallRadius, String> {
        checks::small_radius(v).map(|()| SmallRadius(v))
    }
}

/// A non-zero direction `(x, y)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "(Finite, Finite)")]
pub struct Direction(pub f64, pub f64);

impl TryFrom<(Finite, Finite)> for Direction {
    type Error = String;
    fn try_from((x, y): (Finite, Finite)) -> Result<Direction, String> {
        let len = x.0.hypot(y.0);
        if len > 0.0 && len.is_finite() {
            Ok(Direction(x.0 / len, y.0 / len))
        } else {
            Err("expected a non-zero direction (x, y)".to_string())
        }
    }
}

/// A calendar date, written `"YYYY-MM-DD"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(try_from = "String")]
pub struct Date {
    pub year: i32,
    pub month: u32,
    pub day: u32,
}

impl TryFrom<String> for Date {
    type Error = String;
    fn try_from(text: String) -> Result<Date, String> {
        parse_date(&text)
    }
}

/// A time of day, written `"HH:MM"` or `"HH:MM:SS"`, from 00:00 to 23:59:59.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "String")]
pub struct TimeOfDay {
    pub hour: u32,
    pub minute: u32,
    pub second: u32,
}

impl TryFrom<String> for TimeOfDay {
    type Error = String;
    fn try_from(text: String) -> Result<TimeOfDay, String> {
        parse_time(&text)
    }
}

/// Reads `"YYYY-MM-DD"`: a year from 1 to 9999 and a day its month has.
fn parse_date(text: &str) -> Result<Date, String> {
    let bad = || {
        format!("expected a date as \"YYYY-MM-DD\" (for example \"2026-12-21\"), found {text:?}")
    };
    let mut parts = text.split('-');
    let (Some(y), Some(m), Some(d), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(bad());
    };
    let number = |s: &str, width: usize| {
        (s.len() == width && s.bytes().all(|b| b.is_ascii_digit()))
            .then(|| s.parse::<u32>().ok())
            .flatten()
    };
    let (Some(year), Some(month), Some(day)) = (number(y, 4), number(m, 2), number(d, 2)) else {
        return Err(bad());
    };
    if year == 0 || !(1..=12).contains(&month) {
        return Err(bad());
    }
    let leap = year % 4 == 0 && (year % 100 != 0 || year % 400 == 0);
    let days = match month {
        2 if leap => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    };
    if !(1..=days).contains(&day) {
        return Err(format!(
            "expected a day from 1 to {days} in month {month} of {year}, found {text:?}"
        ));
    }
    Ok(Date {
        year: year as i32,
        month,
        day,
    })
}

/// Reads `"HH:MM"` or `"HH:MM:SS"`, from 00:00 to 23:59:59.
fn parse_time(text: &str) -> Result<TimeOfDay, String> {
    let bad = || {
        format!(
            "expected a time of day as \"HH:MM\" or \"HH:MM:SS\" from 00:00 to 23:59:59, found {text:?}"
        )
    };
    let fields: Vec<&str> = text.splitn(4, ':').collect();
    if !(2..=3).contains(&fields.len()) {
        return Err(bad());
    }
    let mut values = [0u32; 3];
    for (value, field) in values.iter_mut().zip(&fields) {
        if field.len() != 2 || !field.bytes().all(|b| b.is_ascii_digit()) {
            return Err(bad());
        }
        *value = field.parse().map_err(|_| bad())?;
    }
    let [hour, minute, second] = values;
    if hour > 23 || minute > 59 || second > 59 {
        return Err(bad());
    }
    Ok(TimeOfDay {
        hour,
        minute,
        second,
    })
}

/// `v` when it lies in `[lo, hi]`; otherwise a message that expected `what`.
fn in_range(v: f64, lo: f64, hi: f64, what: &str) -> Result<f64, String> {
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(format!("expected {what}, found {v}"))
    }
}

/// A latitude in degrees, from -90 (south) to 90 (north).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Latitude(pub f64);

impl TryFrom<f64> for Latitude {
    type Error = String;
    fn try_from(v: f64) -> Result<Latitude, String> {
        in_range(v, -90.0, 90.0, "a latitude from -90 to 90 degrees").map(Latitude)
    }
}

/// A longitude in degrees, from -180 (west) to 180 (east).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Longitude(pub f64);

impl TryFrom<f64> for Longitude {
    type Error = String;
    fn try_from(v: f64) -> Result<Longitude, String> {
        in_range(v, -180.0, 180.0, "a longitude from -180 to 180 degrees").map(Longitude)
    }
}

/// A time zone as hours ahead of UTC, from -14 to 14 (1 is Paris in
/// winter, -5 New York in winter).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Zone(pub f64);

impl TryFrom<f64> for Zone {
    type Error = String;
    fn try_from(v: f64) -> Result<Zone, String> {
        in_range(
            v,
            -14.0,
            14.0,
            "a time zone from -14 to 14 hours ahead of UTC",
        )
        .map(Zone)
    }
}

/// An RGB colour, each component in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "(f64, f64, f64)")]
pub struct Color(pub f64, pub f64, pub f64);

impl Color {
    pub const WHITE: Color = Color(1.0, 1.0, 1.0);
}

impl TryFrom<(f64, f64, f64)> for Color {
    type Error = String;
    fn try_from((r, g, b): (f64, f64, f64)) -> Result<Color, String> {
        checks::color(flatray_tracer::Rgb::new(r, g, b)).map(|()| Color(r, g, b))
    }
}

fn white() -> Color {
    Color::WHITE
}
/// A rough mirror's roughness when not given: a slight blur.
pub const ROUGH_DEFAULT: f64 = 0.1;
fn rough_default() -> f64 {
    ROUGH_DEFAULT
}
fn one() -> Intensity {
    Intensity(1.0)
}

/// The canvas size in pixels, bounded so that a typo cannot allocate
/// gigabytes.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "(u32, u32)")]
pub struct CanvasSize(pub u32, pub u32);

impl TryFrom<(u32, u32)> for CanvasSize {
    type Error = String;
    fn try_from((w, h): (u32, u32)) -> Result<CanvasSize, String> {
        checks::canvas_size(w, h).map(|()| CanvasSize(w, h))
    }
}

/// The whole scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneFile {
    /// Canvas size in pixels; taken from the floor image when omitted.
    #[serde(default)]
    pub canvas: Option<CanvasSize>,
    /// World position of the canvas's top-left corner.
    #[serde(default)]
    pub origin: Option<Point>,
    pub floor: FloorSpec,
    #[serde(default)]
    pub falloff: FalloffSpec,
    /// Every kernel clamps the distance below at this radius.
    #[serde(default = "half")]
    pub small_radius: SmallRadius,
    #[serde(default)]
    pub walls: Vec<WallSpec>,
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    /// Closed polygons of glass.
    #[serde(default)]
    pub glass: Vec<GlassSpec>,
    #[serde(default)]
    pub render: RenderSpec,
    /// Doors: openings in walls, open or closed, and bounds between rooms.
    #[serde(default)]
    pub doors: Vec<DoorSpec>,
    /// Windows: panes in walls, each with a shutter over part of it.
    #[serde(default)]
    pub windows: Vec<WindowSpec>,
    /// Rooms named by a point inside each, for `flatray measure`.
    #[serde(default)]
    pub rooms: Vec<RoomSpec>,
    /// What one world unit measures, for `flatray measure`'s grid.
    #[serde(default)]
    pub units: Option<Units>,
}

/// A door from `a` to `b`: closed, a wall of the floor's albedo; open,
/// nothing that stops light. Either way a bound between rooms.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Door")]
pub struct DoorSpec {
    pub a: Point,
    pub b: Point,
    #[serde(default)]
    pub open: bool,
}

/// A window from `a` to `b`: a pane of `tint`, its first `shutter` share
/// (from `a`) shut by an opaque wall in its place.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Window")]
pub struct WindowSpec {
    pub a: Point,
    pub b: Point,
    #[serde(default = "window_tint")]
    pub tint: Color,
    #[serde(default = "no_shutter")]
    pub shutter: Fraction,
}

fn window_tint() -> Color {
    Color(0.9, 0.95, 1.0)
}
fn no_shutter() -> Fraction {
    Fraction(0.0)
}

/// A room: the region of the floor the walls enclose about `at`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Room")]
pub struct RoomSpec {
    pub name: String,
    pub at: Point,
}

/// What one world unit measures, and what the lights' intensities mean.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Units")]
pub struct Units {
    pub metres_per_unit: Positive,
    #[serde(default)]
    pub light: LightUnits,
}

/// What the lights' intensities mean.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub enum LightUnits {
    /// The renderer's own units.
    #[default]
    Relative,
    /// Photometric units under the 2.5D reading (`docs/model.md`): a
    /// lamp's (and an emitting wall's) intensity is its luminous flux in
    /// lumens, spread evenly over a storey `storey` metres high; a sun's
    /// or a directional light's, its illuminance in lux on a surface
    /// facing it; a sky's, the
    /// illuminance in lux of a floor open to it. The floor's fluence is
    /// then in lux.
    Lumens {
        #[serde(default = "default_storey")]
        storey: Positive,
    },
}

/// The storey height a lamp's lumens are spread over by default, in
/// metres.
pub const DEFAULT_STOREY_METRES: f64 = 2.5;

fn default_storey() -> Positive {
    Positive(DEFAULT_STOREY_METRES)
}

/// A glass body: a closed polygon (the last point joins the first).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Glass")]
pub struct GlassSpec {
    pub points: Vec<Point>,
    /// Per edge (from point `i` to the next), `Some(p)` where the edge is
    /// an arc through `p`; empty or all `None` for a polygon.
    #[serde(default)]
    pub through: Vec<Option<Point>>,
    /// Index of refraction at 0.55 micrometres.
    #[serde(default = "glass_ior")]
    pub ior: Ior,
    /// Beer-Lambert absorption per unit length, per channel.
    #[serde(default)]
    pub absorption: Option<(NonNegative, NonNegative, NonNegative)>,
    /// Cauchy's B coefficient in square micrometres (0.004 is flint-like);
    /// 0 for none.
    #[serde(default)]
    pub dispersion: NonNegative,
    /// The spread of a rough glass's lobe, from 0 (smooth) to 1.
    #[serde(default)]
    pub roughness: GlassRoughness,
}

/// A glass body's roughness, 0 to 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct GlassRoughness(pub f64);

impl TryFrom<f64> for GlassRoughness {
    type Error = String;
    fn try_from(v: f64) -> Result<GlassRoughness, String> {
        checks::glass_roughness(v).map(|()| GlassRoughness(v))
    }
}

fn glass_ior() -> Ior {
    Ior(1.5)
}

/// An index of refraction, 1 to 4.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Ior(pub f64);

impl TryFrom<f64> for Ior {
    type Error = String;
    fn try_from(v: f64) -> Result<Ior, String> {
        checks::ior(v).map(|()| Ior(v))
    }
}

fn half() -> SmallRadius {
    SmallRadius(0.5)
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Floor")]
pub enum FloorSpec {
    /// An image file, relative to the scene file's folder.
    Image(String),
    /// One albedo everywhere.
    Color(Color),
    /// A procedural tile pattern.
    Tiles {
        #[serde(default = "tile_size")]
        size: Positive,
        #[serde(default = "grout_width")]
        grout_width: NonNegative,
        #[serde(default = "tile_color")]
        tile: Color,
        #[serde(default = "grout_color")]
        grout: Color,
        #[serde(default = "tile_variation")]
        variation: Fraction,
    },
}

fn tile_size() -> Positive {
    Positive(25.0)
}
fn grout_width() -> NonNegative {
    NonNegative(2.0)
}
fn tile_color() -> Color {
    Color(0.75, 0.75, 0.72)
}
fn grout_color() -> Color {
    Color(0.35, 0.35, 0.35)
}
fn tile_variation() -> Fraction {
    Fraction(0.08)
}

/// A number in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "f64")]
pub struct Fraction(pub f64);

impl TryFrom<f64> for Fraction {
    type Error = String;
    fn try_from(v: f64) -> Result<Fraction, String> {
        checks::fraction(v).map(|()| Fraction(v))
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Falloff")]
pub enum FalloffSpec {
    #[default]
    Flatland,
    InverseSquare,
    Window {
        range: Positive,
    },
    Constant,
}

/// A wall with a material, optionally emitting light itself: a segment
/// of non-zero length from `a` to `b`, a circular arc from `a` through
/// `through` to `b`, or a full circle of `center` and `radius`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Wall", try_from = "RawWall")]
pub struct WallSpec {
    /// The first end (on a full circle, its point at angle 0).
    pub a: Point,
    /// The last end (on a full circle, `a`).
    pub b: Point,
    pub shape: WallShape,
    pub material: MaterialSpec,
    pub emit: Option<EmitSpec>,
}

/// The shape of a wall in the file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WallShape {
    Segment,
    /// An arc from `a` through this point to `b`.
    Through(Point),
    /// A full circle.
    Circle {
        center: Point,
        radius: f64,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Wall")]
pub struct RawWall {
    #[serde(default)]
    a: Option<Point>,
    #[serde(default)]
    b: Option<Point>,
    #[serde(default)]
    through: Option<Point>,
    #[serde(default)]
    center: Option<Point>,
    #[serde(default)]
    radius: Option<Positive>,
    #[serde(default)]
    material: MaterialSpec,
    #[serde(default)]
    emit: Option<EmitSpec>,
}

impl TryFrom<RawWall> for WallSpec {
    type Error = String;
    fn try_from(w: RawWall) -> Result<WallSpec, String> {
        let (a, b, shape) = match (w.a, w.b, w.through, w.center, w.radius) {
            (Some(a), Some(b), through, None, None) => {
                if a == b {
                    return Err(format!(
                        "a wall needs two different endpoints, found ({}, {}) twice",
                        a.0, a.1
                    ));
                }
                match through {
                    None => (a, b, WallShape::Segment),
                    Some(m) => {
                        let arc = flatray_geometry::Arc::through(
                            glam::DVec2::new(a.0, a.1),
                            glam::DVec2::new(m.0, m.1),
                            glam::DVec2::new(b.0, b.1),
                        );
                        if arc.is_err() {
                            return Err(format!(
                                "an arc's three points must not lie on one line, found a ({}, {}), through ({}, {}), b ({}, {})",
                                a.0, a.1, m.0, m.1, b.0, b.1
                            ));
                        }
                        (a, b, WallShape::Through(m))
                    }
                }
            }
            (None, None, None, Some(center), Some(radius)) => {
                let a = Point(center.0 + radius.0, center.1);
                checks::point(a.0, a.1)?;
                (
                    a,
                    a,
                    WallShape::Circle {
                        center,
                        radius: radius.0,
                    },
                )
            }
            _ => {
                return Err(
                    "expected a wall as `a` and `b` (a segment), `a`, `through` and `b` (an arc), or `center` and `radius` (a circle)"
                        .to_string(),
                );
            }
        };
        if shape != WallShape::Segment && w.emit.as_ref().is_some_and(|e| e.one_sided) {
            return Err(
                "an arc or a circle emits from both sides: `one_sided` is for straight walls"
                    .to_string(),
            );
        }
        Ok(WallSpec {
            a,
            b,
            shape,
            material: w.material,
            emit: w.emit,
        })
    }
}

impl WallSpec {
    /// The wall's shape in world units.
    pub fn geometry(&self) -> flatray_geometry::Shape {
        use flatray_geometry::{Arc, Segment, Shape};
        use glam::DVec2;
        let p = |q: Point| DVec2::new(q.0, q.1);
        match self.shape {
            WallShape::Segment => Shape::Segment(Segment::new(p(self.a), p(self.b))),
            WallShape::Through(m) => match Arc::through(p(self.a), p(m), p(self.b)) {
                Ok(arc) => Shape::Arc(arc),
                // Checked when read: never here.
                Err(_) => Shape::Segment(Segment::new(p(self.a), p(self.b))),
            },
            WallShape::Circle { center, radius } => Shape::Arc(Arc::circle(p(center), radius, 0.0)),
        }
    }
}

impl LightSpec {
    /// The light's spectrum, where it gives one.
    pub fn spectrum(&self) -> Option<&SpectrumSpec> {
        match self {
            LightSpec::Point { spectrum, .. }
            | LightSpec::Spot { spectrum, .. }
            | LightSpec::Line { spectrum, .. }
            | LightSpec::Directional { spectrum, .. }
            | LightSpec::Beam { spectrum, .. }
            | LightSpec::Laser { spectrum, .. }
            | LightSpec::Sun { spectrum, .. }
            | LightSpec::Sky { spectrum, .. }
            | LightSpec::Circle { spectrum, .. } => spectrum.as_ref(),
        }
    }

    /// The light's kind, as the scene format names it.
    pub fn kind(&self) -> &'static str {
        match self {
            LightSpec::Point { .. } => "Point",
            LightSpec::Spot { .. } => "Spot",
            LightSpec::Line { .. } => "Line",
            LightSpec::Directional { .. } => "Directional",
            LightSpec::Beam { .. } => "Beam",
            LightSpec::Laser { .. } => "Laser",
            LightSpec::Circle { .. } => "Circle",
            LightSpec::Sun { .. } => "Sun",
            LightSpec::Sky { .. } => "Sky",
        }
    }

    /// The light's colour.
    pub fn color(&self) -> Color {
        match *self {
            LightSpec::Point { color, .. }
            | LightSpec::Spot { color, .. }
            | LightSpec::Line { color, .. }
            | LightSpec::Directional { color, .. }
            | LightSpec::Beam { color, .. }
            | LightSpec::Laser { color, .. }
            | LightSpec::Sun { color, .. }
            | LightSpec::Sky { color, .. }
            | LightSpec::Circle { color, .. } => color,
        }
    }
}

/// A light's spectrum, in place of its colour.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Spectrum")]
pub enum SpectrumSpec {
    /// Planck's law at a temperature in kelvin.
    Blackbody(f64),
    /// A gas-discharge lamp's lines.
    Lamp(LampName),
    /// (wavelength in nm, value) pairs, linear between.
    Table(Vec<(f64, f64)>),
}

/// The gas-discharge lamps the format names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename = "Lamp")]
pub enum LampName {
    Sodium,
    Mercury,
    Neon,
    Hydrogen,
}

/// Light that a wall emits: it is then also a solid line light.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Emit")]
pub struct EmitSpec {
    #[serde(default = "white")]
    pub color: Color,
    /// Per unit length.
    #[serde(default = "one")]
    pub intensity: Intensity,
    /// What it emits wavelength by wavelength, in place of `color`.
    #[serde(default)]
    pub spectrum: Option<SpectrumSpec>,
    #[serde(default)]
    pub one_sided: bool,
    #[serde(default)]
    pub falloff: Option<FalloffSpec>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename = "Material")]
pub enum MaterialSpec {
    Diffuse {
        #[serde(default)]
        albedo: Option<Color>,
    },
    Mirror {
        #[serde(default = "white")]
        tint: Color,
    },
    /// A rough mirror: a glossy lobe about the mirror direction.
    Rough {
        #[serde(default = "rough_default")]
        roughness: f64,
        #[serde(default = "white")]
        tint: Color,
    },
    Transparent {
        #[serde(default = "white")]
        tint: Color,
    },
    /// Diffuse with the floor's albedo: what `material` means when omitted.
    #[default]
    #[serde(skip)]
    FloorDiffuse,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Light")]
pub enum LightSpec {
    Point {
        at: Point,
        #[serde(default = "white")]
        color: Color,
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
        #[serde(default)]
        falloff: Option<FalloffSpec>,
    },
    Spot {
        at: Point,
        direction: Direction,
        /// Half-angle of the cone, in degrees, where the light ends.
        cone: Positive,
        /// Width of the soft edge inside the cone, in degrees.
        #[serde(default)]
        softness: NonNegative,
        #[serde(default = "white")]
        color: Color,
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
        #[serde(default)]
        falloff: Option<FalloffSpec>,
    },
    Line {
        a: Point,
        b: Point,
        #[serde(default = "white")]
        color: Color,
        /// Per unit length.
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
        #[serde(default)]
        one_sided: bool,
        /// A solid line light also blocks light, as a black wall.
        #[serde(default)]
        solid: bool,
        #[serde(default)]
        falloff: Option<FalloffSpec>,
    },
    Directional {
        direction: Direction,
        #[serde(default = "white")]
        color: Color,
        /// Irradiance across the beam.
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
    },
    /// Parallel light leaving the segment from `a` to `b` in `direction`:
    /// a sun limited to a strip.
    Beam {
        a: Point,
        b: Point,
        direction: Direction,
        #[serde(default = "white")]
        color: Color,
        /// Irradiance across the beam.
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
    },
    /// One ray from `at` in `direction`: a beam of no width.
    Laser {
        at: Point,
        direction: Direction,
        #[serde(default = "white")]
        color: Color,
        /// The ray's power.
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
    },
    /// Sunlight from the sun's place in the sky at a date, a local time
    /// and a place on Earth: a `Directional` light along the sun's
    /// azimuth, its irradiance on the floor `intensity` times the sine of
    /// the sun's elevation; nothing at night.
    Sun {
        date: Date,
        /// Local time, in the time zone `zone`.
        time: TimeOfDay,
        /// Hours ahead of UTC of `time`.
        #[serde(default)]
        zone: Zone,
        latitude: Latitude,
        longitude: Longitude,
        /// The angle of north on the canvas, in degrees clockwise from up.
        #[serde(default)]
        north: Finite,
        #[serde(default = "white")]
        color: Color,
        /// Irradiance across the sun's rays (on a surface facing the sun).
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
    },
    /// Light arriving from beyond the scene in every direction that no
    /// wall blocks: of uniform radiance, or of a radiance that varies with
    /// the azimuth it arrives from (`profile`).
    Sky {
        #[serde(default = "white")]
        color: Color,
        /// The sky's radiance: an unobstructed point receives `2 pi`
        /// times it (with a profile, times the profile's integral over the
        /// circle).
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
        /// The radiance's factor by the azimuth the light arrives from:
        /// pairs of an azimuth (degrees clockwise from north) and a factor
        /// on `intensity`, linear between them around the circle. One pair
        /// is a uniform sky.
        #[serde(default)]
        profile: Option<Vec<(Finite, NonNegative)>>,
        /// The angle of north on the canvas, in degrees clockwise from up:
        /// where the profile's azimuths turn from.
        #[serde(default)]
        north: Finite,
    },
    /// A disk whose rim emits outward; not a wall.
    Circle {
        at: Point,
        radius: Positive,
        #[serde(default = "white")]
        color: Color,
        /// The rim's radiance.
        #[serde(default = "one")]
        intensity: Intensity,
        /// What it emits wavelength by wavelength, in place of `color`.
        #[serde(default)]
        spectrum: Option<SpectrumSpec>,
        #[serde(default)]
        falloff: Option<FalloffSpec>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Render")]
pub struct RenderSpec {
    #[serde(default = "default_samples")]
    pub samples: Samples,
    #[serde(default = "default_bounces")]
    pub bounces: Bounces,
    /// Most mirror and glass events in a row.
    #[serde(default = "default_specular")]
    pub specular: Specular,
    #[serde(default)]
    pub seed: u64,
    #[serde(default = "one_exposure")]
    pub exposure: Exposure,
    #[serde(default)]
    pub integrator: IntegratorSpec,
    #[serde(default)]
    pub tonemap: ToneMap,
    /// The cache of light on walls: `true` or `On`, `false` or `Off`, or
    /// `Direct` (direct light only), as `--cache` takes.
    #[serde(default)]
    pub cache: CacheSpec,
    /// The caustic pass, as `--caustics on/off` takes.
    #[serde(default = "yes")]
    pub caustics: bool,
    /// Which lights each point's shadow rays go to, as `--lights`.
    #[serde(default)]
    pub lights: LightsSpec,
    /// The memo's wall bin length, in pixels.
    #[serde(default = "one_positive")]
    pub cache_bin: Positive,
    /// The fewest stratified receiver points per pixel for the memoised
    /// floor light (a pixel takes at least as many as it has samples).
    #[serde(default = "default_floor_samples")]
    pub cache_floor_samples: Samples,
}

fn yes() -> bool {
    true
}
fn default_floor_samples() -> Samples {
    Samples(1)
}

impl Default for RenderSpec {
    fn default() -> RenderSpec {
        RenderSpec {
            samples: default_samples(),
            bounces: default_bounces(),
            specular: default_specular(),
            seed: 0,
            exposure: one_exposure(),
            integrator: IntegratorSpec::default(),
            tonemap: ToneMap::default(),
            cache: CacheSpec::default(),
            caustics: yes(),
            lights: LightsSpec::default(),
            cache_bin: one_positive(),
            cache_floor_samples: default_floor_samples(),
        }
    }
}

fn default_samples() -> Samples {
    Samples(16)
}
fn default_bounces() -> Bounces {
    Bounces(1)
}
fn default_specular() -> Specular {
    Specular(flatray_tracer::DEFAULT_SPECULAR)
}

/// Samples per pixel, 1 to [`MAX_SAMPLES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(try_from = "u32")]
pub struct Samples(pub u32);

impl TryFrom<u32> for Samples {
    type Error = String;
    fn try_from(v: u32) -> Result<Samples, String> {
        if (1..=MAX_SAMPLES).contains(&v) {
            Ok(Samples(v))
        } else {
            Err(format!("expected 1 to {MAX_SAMPLES} samples, found {v}"))
        }
    }
}

/// Mirror and glass events in a row, 0 to [`MAX_BOUNCES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(try_from = "u32")]
pub struct Specular(pub u32);

impl TryFrom<u32> for Specular {
    type Error = String;
    fn try_from(v: u32) -> Result<Specular, String> {
        if v <= MAX_BOUNCES {
            Ok(Specular(v))
        } else {
            Err(format!(
                "expected 0 to {MAX_BOUNCES} mirror and glass events in a row, found {v}"
            ))
        }
    }
}

/// Bounces, 0 to [`MAX_BOUNCES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(try_from = "u32")]
pub struct Bounces(pub u32);

impl TryFrom<u32> for Bounces {
    type Error = String;
    fn try_from(v: u32) -> Result<Bounces, String> {
        if v <= MAX_BOUNCES {
            Ok(Bounces(v))
        } else {
            Err(format!("expected 0 to {MAX_BOUNCES} bounces, found {v}"))
        }
    }
}
fn one_exposure() -> Exposure {
    Exposure(1.0)
}

fn one_positive() -> Positive {
    Positive(1.0)
}

/// The cache's setting: a switch, or how much is cached.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(untagged, expecting = "`On`, `Off`, `Direct`, `true` or `false`")]
pub enum CacheSpec {
    Switch(bool),
    Mode(CacheMode),
}

impl Default for CacheSpec {
    fn default() -> CacheSpec {
        CacheSpec::Mode(CacheMode::On)
    }
}

impl CacheSpec {
    /// `(enabled, onward)`: whether the memo runs, and whether it holds
    /// what light goes on from walls.
    pub fn memo(self) -> (bool, bool) {
        match self {
            CacheSpec::Switch(true) | CacheSpec::Mode(CacheMode::On) => (true, true),
            CacheSpec::Switch(false) | CacheSpec::Mode(CacheMode::Off) => (false, true),
            CacheSpec::Mode(CacheMode::Direct) => (true, false),
        }
    }
}

/// How much the cache holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename = "Cache")]
pub enum CacheMode {
    On,
    Off,
    Direct,
}

/// Which lights each point's shadow rays go to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename = "Lights")]
pub enum LightsSpec {
    #[default]
    Auto,
    Every,
    Table,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename = "Integrator")]
pub enum IntegratorSpec {
    #[default]
    Path,
    Original,
    Light,
}

/// How PNG output maps linear values to `[0, 1]` before sRGB encoding.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ToneMap {
    /// Values above 1 clip to white.
    Clamp,
    /// `x (1 + x / w^2) / (1 + x)`: highlights roll off and reach white at
    /// `white`.
    Reinhard {
        #[serde(default = "default_white")]
        white: Positive,
    },
}

impl Default for ToneMap {
    fn default() -> ToneMap {
        ToneMap::Reinhard {
            white: default_white(),
        }
    }
}

fn default_white() -> Positive {
    Positive(4.0)
}
