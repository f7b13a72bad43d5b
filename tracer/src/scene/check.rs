//! What a scene must be for the integrators to be sound: finite numbers
//! within the bounds below, colours that reflect at most what they
//! receive, unit directions, and indices that point at something.
//! [`Scene::new`](super::Scene::new) checks all of it, so that a scene
//! built in code is held to what a scene file is; `flatray-io` checks the
//! same bounds as it reads a file, with the same messages and the line
//! and column they belong to.

use flatray_geometry::{DVec2, Shape};

use super::{Canvas, Falloff, Floor, GlassBody, Light, LightShape, Material, Wall};
use crate::Rgb;
use crate::spectrum::Spectrum;

/// Largest canvas side, in pixels.
pub const MAX_CANVAS_SIDE: u32 = 32_768;
/// Largest canvas area, in pixels (about 2 GB of f32 RGB at most).
pub const MAX_CANVAS_PIXELS: u64 = 1 << 27;
/// Largest coordinate magnitude, in world units: far beyond any floor
/// plan, and small enough that products of coordinates stay finite.
pub const MAX_COORDINATE: f64 = 1e15;
/// Largest light intensity and exposure: their product with the largest
/// falloff (`1 / small_radius^2`) stays finite in a 32-bit image.
pub const MAX_INTENSITY: f64 = 1e9;
/// Smallest and largest `small_radius`.
pub const SMALL_RADIUS_RANGE: (f64, f64) = (1e-6, 1e6);
/// Smallest and largest index of refraction.
pub const IOR_RANGE: (f64, f64) = (1.0, 4.0);

/// The part of a scene a check failed on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Item {
    Canvas,
    Floor,
    SmallRadius,
    /// A wall, by its index in the list given to the constructor.
    Wall(usize),
    /// A light, by its index in the list given to the constructor.
    Light(usize),
    /// A glass body, by its index.
    Glass(usize),
}

impl std::fmt::Display for Item {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Item::Canvas => write!(f, "canvas"),
            Item::Floor => write!(f, "floor"),
            Item::SmallRadius => write!(f, "small_radius"),
            Item::Wall(k) => write!(f, "wall {k}"),
            Item::Light(k) => write!(f, "light {k}"),
            Item::Glass(k) => write!(f, "glass {k}"),
        }
    }
}

/// Why a scene could not be built: the item and what was expected of it.
#[derive(Clone, Debug, PartialEq)]
pub struct InvalidScene {
    pub item: Item,
    /// What was expected and what was found, in the words of a scene
    /// file's messages.
    pub message: String,
}

impl std::fmt::Display for InvalidScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.item, self.message)
    }
}

impl std::error::Error for InvalidScene {}

type Checked = Result<(), String>;

/// A finite number.
pub fn finite(v: f64) -> Checked {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("expected a finite number, found {v}"))
    }
}

/// A finite number `>= 0`.
pub fn non_negative(v: f64) -> Checked {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("expected a finite number >= 0, found {v}"))
    }
}

/// A finite number `> 0`.
pub fn positive(v: f64) -> Checked {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("expected a finite number > 0, found {v}"))
    }
}

/// A number in `[0, 1]`.
pub fn fraction(v: f64) -> Checked {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!("expected a number in [0, 1], found {v}"))
    }
}

/// A point of finite coordinates within [`MAX_COORDINATE`].
pub fn point(x: f64, y: f64) -> Checked {
    finite(x)?;
    finite(y)?;
    if x.abs() <= MAX_COORDINATE && y.abs() <= MAX_COORDINATE {
        Ok(())
    } else {
        Err(format!(
            "expected coordinates within ±{MAX_COORDINATE:e}, found ({x}, {y})"
        ))
    }
}

/// A light's intensity, from 0 to [`MAX_INTENSITY`].
pub fn intensity(v: f64) -> Checked {
    if (0.0..=MAX_INTENSITY).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "expected an intensity from 0 to {MAX_INTENSITY:e}, found {v}"
        ))
    }
}

/// An exposure, `> 0` and at most [`MAX_INTENSITY`].
pub fn exposure(v: f64) -> Checked {
    if v > 0.0 && v <= MAX_INTENSITY {
        Ok(())
    } else {
        Err(format!(
            "expected an exposure > 0 and at most {MAX_INTENSITY:e}, found {v}"
        ))
    }
}

/// The falloff kernels' small radius, within [`SMALL_RADIUS_RANGE`].
pub fn small_radius(v: f64) -> Checked {
    let (low, high) = SMALL_RADIUS_RANGE;
    if (low..=high).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "expected a small radius from {low:e} to {high:e}, found {v}"
        ))
    }
}

/// An index of refraction, within [`IOR_RANGE`].
pub fn ior(v: f64) -> Checked {
    let (low, high) = IOR_RANGE;
    if (low..=high).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "expected an index of refraction from {low} to {high}, found {v}"
        ))
    }
}

/// A colour or an albedo: each component in `[0, 1]`.
pub fn color(c: Rgb) -> Checked {
    for v in c.to_array() {
        if !(0.0..=1.0).contains(&v) {
            return Err(format!(
                "expected a colour (r, g, b) with each component in [0, 1], found {v}"
            ));
        }
    }
    Ok(())
}

/// A canvas of 1 to [`MAX_CANVAS_SIDE`] pixels each way and at most
/// [`MAX_CANVAS_PIXELS`] in all.
pub fn canvas_size(w: u32, h: u32) -> Checked {
    if w == 0 || h == 0 || w > MAX_CANVAS_SIDE || h > MAX_CANVAS_SIDE {
        return Err(format!(
            "expected a canvas of 1 to {MAX_CANVAS_SIDE} pixels each way, found {w} x {h}"
        ));
    }
    if w as u64 * h as u64 > MAX_CANVAS_PIXELS {
        return Err(format!(
            "expected a canvas of at most {MAX_CANVAS_PIXELS} pixels, found {w} x {h}"
        ));
    }
    Ok(())
}

/// A rough mirror's roughness, from 0 to 1.
pub fn roughness(v: f64) -> Checked {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "a rough mirror's `roughness` is from 0 (a mirror) to 1 (a broad lobe), not {v}"
        ))
    }
}

/// A glass body's roughness, from 0 (smooth glass) to 1.
pub fn glass_roughness(v: f64) -> Checked {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "a glass body's `roughness` is from 0 (smooth glass) to 1 (a broad lobe), not {v}"
        ))
    }
}

/// A spot's cone and softness (radians): `0 < cone <= pi`, `0 <= softness
/// <= cone`. Said in degrees, as a scene file gives them.
pub fn cone(cone: f64, softness: f64) -> Checked {
    // 180 degrees in radians may round a little above pi.
    let ok = cone > 0.0
        && cone <= std::f64::consts::PI * (1.0 + 1e-12)
        && (0.0..=cone).contains(&softness);
    if ok {
        Ok(())
    } else {
        Err(format!(
            "expected 0 < cone <= 180 and softness <= cone (degrees), found cone {} and softness {}",
            cone.to_degrees(),
            softness.to_degrees()
        ))
    }
}

/// A unit direction (to rounding).
fn unit(d: DVec2) -> Checked {
    if d.is_finite() && (d.length() - 1.0).abs() <= 1e-9 {
        Ok(())
    } else {
        Err(format!(
            "expected a unit direction (x, y), found ({}, {})",
            d.x, d.y
        ))
    }
}

fn falloff(f: Falloff) -> Checked {
    match f {
        Falloff::Window { range } => positive(range),
        Falloff::Flatland | Falloff::InverseSquare | Falloff::Constant => Ok(()),
    }
}

fn floor(floor: &Floor) -> Checked {
    match floor {
        Floor::Color(c) => color(*c),
        Floor::Tiles {
            size,
            grout_width,
            tile,
            grout,
            variation,
        } => {
            positive(*size)?;
            non_negative(*grout_width)?;
            color(*tile)?;
            color(*grout)?;
            fraction(*variation)
        }
        Floor::Image {
            width,
            height,
            texels,
        } => {
            if *width == 0 || *height == 0 || texels.len() as u64 != *width as u64 * *height as u64
            {
                return Err(format!(
                    "expected a floor image of {width} x {height} texels, found {} texels",
                    texels.len()
                ));
            }
            texels.iter().try_for_each(|&t| color(t))
        }
    }
}

fn wall(wall: &Wall, bodies: usize) -> Checked {
    let (a, b) = (wall.shape.a(), wall.shape.b());
    point(a.x, a.y)?;
    point(b.x, b.y)?;
    match &wall.shape {
        Shape::Segment(_) if a == b => {
            return Err(format!(
                "a wall needs two different endpoints, found ({}, {}) twice",
                a.x, a.y
            ));
        }
        Shape::Segment(_) => {}
        Shape::Arc(arc) => {
            let c = arc.center;
            point(c.x, c.y)?;
            if !(arc.radius > 0.0 && arc.radius <= MAX_COORDINATE) {
                return Err(format!(
                    "expected an arc's radius from 0 to {MAX_COORDINATE:e}, found {}",
                    arc.radius
                ));
            }
            if !arc.is_full() && a == b {
                return Err(format!(
                    "an arc needs two different ends, found ({}, {}) twice",
                    a.x, a.y
                ));
            }
        }
    }
    match wall.material {
        Material::Diffuse { albedo } => albedo.map_or(Ok(()), color),
        Material::Mirror { tint } | Material::Transparent { tint } => color(tint),
        Material::Rough { roughness: r, tint } => {
            roughness(r)?;
            color(tint)
        }
        Material::Glass { body, .. } => {
            if (body as usize) < bodies {
                Ok(())
            } else {
                Err(format!(
                    "a glass wall of body {body}, but the scene has {bodies} glass bodies"
                ))
            }
        }
    }
}

fn light(light: &Light, walls: usize) -> Checked {
    // A light with a spectrum takes its colour from it.
    match &light.spectrum {
        None => color(light.color)?,
        Some(s) => spectrum(s)?,
    }
    intensity(light.intensity)?;
    falloff(light.falloff)?;
    if light.profile.is_some() {
        let takes_one = matches!(light.shape, LightShape::Line { wall: None, .. })
            && light.falloff == Falloff::Flatland;
        if !takes_one {
            return Err(
                "only a line light that is no wall, of flatland falloff, takes a profile".into(),
            );
        }
    }
    shape(&light.shape, walls)
}

/// The most distinct spectra a scene's lights may have: each is held on
/// a grid of 800 wavelengths (about 13 KiB with what draws from it).
pub const MAX_SPECTRA: usize = 1024;

/// A light's spectrum: a blackbody's temperature within
/// [`crate::spectrum::KELVIN_RANGE`], a table's values finite, at least
/// 0 and not all 0.
pub fn spectrum(s: &Spectrum) -> Checked {
    match *s {
        Spectrum::Blackbody { kelvin } => {
            let (low, high) = crate::spectrum::KELVIN_RANGE;
            if (low..=high).contains(&kelvin) {
                Ok(())
            } else {
                Err(format!(
                    "expected a blackbody's temperature from {low} to {high} kelvin, found {kelvin}"
                ))
            }
        }
        Spectrum::Lamp(_) => Ok(()),
        Spectrum::Table(values) => {
            if values.iter().all(|v| v.is_finite() && *v >= 0.0) && values.iter().any(|&v| v > 0.0)
            {
                Ok(())
            } else {
                Err("expected a spectrum's table of finite values of at least 0, not all 0".into())
            }
        }
    }
}

/// A light's shape alone: what the scene format checks of a beam, whose
/// segment and direction are checked together.
pub fn light_shape(shape_: &LightShape) -> Checked {
    shape(shape_, usize::MAX)
}

fn shape(shape: &LightShape, walls: usize) -> Checked {
    match *shape {
        LightShape::Point { at } => point(at.x, at.y),
        LightShape::Spot {
            at,
            direction,
            cone: c,
            softness,
        } => {
            point(at.x, at.y)?;
            unit(direction)?;
            cone(c, softness)
        }
        LightShape::Line { segment, wall, .. } => {
            let (a, b) = (segment.a, segment.b);
            point(a.x, a.y)?;
            point(b.x, b.y)?;
            if a == b {
                return Err(format!(
                    "a line light needs two different endpoints, found ({}, {}) twice; use a Point light",
                    a.x, a.y
                ));
            }
            match wall {
                Some(w) if w as usize >= walls => Err(format!(
                    "a line light on wall {w}, but the scene has {walls} walls"
                )),
                _ => Ok(()),
            }
        }
        LightShape::Arc { arc, wall } => {
            for p in [arc.a, arc.b, arc.center] {
                point(p.x, p.y)?;
            }
            if !(arc.radius > 0.0 && arc.radius <= MAX_COORDINATE) {
                return Err(format!(
                    "expected an arc light's radius from 0 to {MAX_COORDINATE:e}, found {}",
                    arc.radius
                ));
            }
            match wall {
                Some(w) if w as usize >= walls => Err(format!(
                    "an arc light on wall {w}, but the scene has {walls} walls"
                )),
                _ => Ok(()),
            }
        }
        LightShape::Directional { direction } => unit(direction),
        LightShape::Beam { segment, direction } => {
            let (a, b) = (segment.a, segment.b);
            point(a.x, a.y)?;
            point(b.x, b.y)?;
            unit(direction)?;
            if a == b {
                return Err(format!(
                    "a beam needs two different endpoints, found ({}, {}) twice; use a Laser",
                    a.x, a.y
                ));
            }
            if segment.edge().normalize().perp_dot(direction).abs() < 1e-9 {
                return Err(
                    "a beam's direction runs along its segment: the beam has no width".into(),
                );
            }
            Ok(())
        }
        LightShape::Laser { at, direction } => {
            point(at.x, at.y)?;
            unit(direction)
        }
        LightShape::Circle { at, radius } => {
            point(at.x, at.y)?;
            positive(radius)?;
            if radius > MAX_COORDINATE {
                return Err(format!(
                    "expected a circle light's radius of at most {MAX_COORDINATE:e}, found {radius}"
                ));
            }
            Ok(())
        }
    }
}

fn glass(body: &GlassBody) -> Checked {
    ior(body.ior)?;
    non_negative(body.dispersion)?;
    glass_roughness(body.roughness)?;
    body.absorption
        .to_array()
        .into_iter()
        .try_for_each(non_negative)
}

/// Checks everything a scene is built from; the first failure, with the
/// item it belongs to.
pub(super) fn scene(
    canvas: &Canvas,
    floor_: &Floor,
    small_radius_: f64,
    walls: &[Wall],
    lights: &[Light],
    bodies: &[GlassBody],
) -> Result<(), InvalidScene> {
    let at = |item: Item| move |message: String| InvalidScene { item, message };
    canvas_size(canvas.width, canvas.height)
        .and_then(|()| point(canvas.origin.x, canvas.origin.y))
        .map_err(at(Item::Canvas))?;
    floor(floor_).map_err(at(Item::Floor))?;
    small_radius(small_radius_).map_err(at(Item::SmallRadius))?;
    for (k, body) in bodies.iter().enumerate() {
        glass(body).map_err(at(Item::Glass(k)))?;
    }
    for (k, w) in walls.iter().enumerate() {
        wall(w, bodies.len()).map_err(at(Item::Wall(k)))?;
    }
    let mut spectra = std::collections::HashSet::new();
    for (k, l) in lights.iter().enumerate() {
        light(l, walls.len()).map_err(at(Item::Light(k)))?;
        if let Some(s) = &l.spectrum
            && spectra.insert(s.key())
            && spectra.len() > MAX_SPECTRA
        {
            return Err(InvalidScene {
                item: Item::Light(k),
                message: format!("expected at most {MAX_SPECTRA} different spectra in a scene"),
            });
        }
    }
    Ok(())
}
