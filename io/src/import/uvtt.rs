//! Universal VTT maps (`.dd2vtt` from Dungeondraft, `.df2vtt` from
//! DungeonFog, `.uvtt` from Arkenforge and others): JSON whose
//! coordinates are in grid cells. Walls come from `line_of_sight` and
//! `objects_line_of_sight`, doors and windows from `portals`, lamps from
//! `lights`, and the floor from the base64 `image`. Every bad value is
//! named by its JSON path (`portals[3].bounds[1].x`).

use std::path::Path;

use base64::Engine as _;
use flatray_geometry::DVec2;
use serde_json::Value;

use super::{
    Doors, ImportError, ImportOptions, Imported, ImportedFloor, ImportedLight, ImportedWall,
    OpenPortals, WallKind, edges, invalid, parse_hex_color,
};
use crate::load::{ImageFailure, MAX_FLOOR_TEXELS, decode_within};

/// A lamp's intensity per unit of the map's `intensity`: under its
/// `Window` falloff the fluence is `2 (1 - r / range)^2`, about 1 (a
/// well-lit floor) a quarter of the way to the edge of its reach.
pub const MAP_LAMP_INTENSITY: f64 = 2.0;

/// What a window pane lets through: clear glass, 90 % in each channel.
pub const WINDOW_TINT: [f64; 3] = [0.9, 0.9, 0.9];

/// At most this many pixels in a map's image (8192 x 8192), checked from
/// its header before it is decoded; past the floor's own budget it is
/// reduced to fit.
pub const MAX_MAP_IMAGE_PIXELS: u64 = 1 << 26;

/// At most this many grid cells along a side of a map, and this far from
/// the origin (in cells) any point of it.
const MAX_CELLS: f64 = 1e6;
const MAX_COORDINATE: f64 = 1e9;

/// Whether a JSON file is a Universal VTT map rather than a Tiled one:
/// it names `pixels_per_grid`, which only the former has.
pub(super) fn looks_like(bytes: &[u8]) -> bool {
    const KEY: &[u8] = b"\"pixels_per_grid\"";
    bytes.windows(KEY.len()).any(|w| w == KEY)
}

/// A bad value: its JSON path and what was expected.
struct Bad {
    at: String,
    message: String,
}

/// A value of the map with the JSON path that names it in messages.
struct At<'a> {
    value: &'a Value,
    path: String,
}

impl<'a> At<'a> {
    fn bad(&self, message: impl Into<String>) -> Bad {
        Bad {
            at: self.path.clone(),
            message: message.into(),
        }
    }

    fn child(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// The field `key`, where it is given and not `null`.
    fn opt(&self, key: &str) -> Result<Option<At<'a>>, Bad> {
        let Value::Object(map) = self.value else {
            return Err(self.bad(format!("expected an object, found {}", kind(self.value))));
        };
        Ok(map.get(key).filter(|v| !v.is_null()).map(|value| At {
            value,
            path: self.child(key),
        }))
    }

    /// The field `key`, which must be given; `what` says what it holds.
    fn get(&self, key: &str, what: &str) -> Result<At<'a>, Bad> {
        self.opt(key)?.ok_or_else(|| Bad {
            at: self.child(key),
            message: format!("missing: expected {what}"),
        })
    }

    fn items(&self) -> Result<Vec<At<'a>>, Bad> {
        let Value::Array(items) = self.value else {
            return Err(self.bad(format!("expected a list, found {}", kind(self.value))));
        };
        Ok(items
            .iter()
            .enumerate()
            .map(|(i, value)| At {
                value,
                path: format!("{}[{i}]", self.path),
            })
            .collect())
    }

    fn number(&self) -> Result<f64, Bad> {
        match self.value.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(self.bad(format!("expected a number, found {}", kind(self.value)))),
        }
    }

    fn boolean(&self) -> Result<bool, Bad> {
        self.value.as_bool().ok_or_else(|| {
            self.bad(format!(
                "expected true or false, found {}",
                kind(self.value)
            ))
        })
    }

    fn string(&self) -> Result<&'a str, Bad> {
        self.value
            .as_str()
            .ok_or_else(|| self.bad(format!("expected a string, found {}", kind(self.value))))
    }

    /// A point `{"x": .., "y": ..}` in grid cells.
    fn point(&self) -> Result<DVec2, Bad> {
        let coordinate = |key: &str| -> Result<f64, Bad> {
            let at = self.get(key, "a number (grid cells)")?;
            let v = at.number()?;
            if v.abs() > MAX_COORDINATE {
                return Err(at.bad(format!(
                    "expected a coordinate within ±{MAX_COORDINATE:e} grid cells, found {v}"
                )));
            }
            Ok(v)
        };
        Ok(DVec2::new(coordinate("x")?, coordinate("y")?))
    }
}

/// A JSON value's kind and, where short, the value, for messages.
fn kind(value: &Value) -> String {
    match value {
        Value::Null => "null".to_string(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => format!("{n} (out of range)"),
        Value::String(s) if s.len() <= 40 => format!("the string {s:?}"),
        Value::String(_) => "a string".to_string(),
        Value::Array(_) => "a list".to_string(),
        Value::Object(_) => "an object".to_string(),
    }
}

/// The map's size and scale.
struct Grid {
    /// World units per grid cell.
    scale: f64,
    pixels_per_grid: f64,
    origin: DVec2,
    size: DVec2,
}

impl Grid {
    fn world(&self, p: DVec2) -> DVec2 {
        p * self.scale
    }
}

/// Reads a Universal VTT map.
pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    let root: Value = serde_json::from_slice(bytes).map_err(|e| {
        let location = (e.line() > 0).then(|| (e.line(), e.column()));
        invalid(path, location, syntax_message(bytes, &e))
    })?;
    let root = At {
        value: &root,
        path: String::new(),
    };
    let stem = path
        .file_stem()
        .map_or("map".to_string(), |s| s.to_string_lossy().into_owned());
    read_map(&root, &stem, options).map_err(|bad| {
        let message = if bad.at.is_empty() {
            bad.message
        } else {
            format!("{}: {}", bad.at, bad.message)
        };
        invalid(path, None, message)
    })
}

/// serde_json's message, said plainly where the file holds what JSON
/// has no words for (`NaN`, `Infinity`, as some writers put).
fn syntax_message(bytes: &[u8], e: &serde_json::Error) -> String {
    let line = bytes
        .split(|&b| b == b'\n')
        .nth(e.line().saturating_sub(1))
        .unwrap_or_default();
    let from = e.column().saturating_sub(1).min(line.len());
    let rest = String::from_utf8_lossy(&line[from..line.len().min(from + 16)]).into_owned();
    let rest = rest.trim_start_matches(['-', '+', ' ']);
    if ["NaN", "nan", "Infinity", "inf"]
        .iter()
        .any(|w| rest.starts_with(w))
    {
        return format!(
            "not a Universal VTT map: a number that is not finite ({}): JSON has none, and every coordinate must be a number",
            rest.split(|c: char| !c.is_alphanumeric())
                .next()
                .unwrap_or(rest)
        );
    }
    format!("not a Universal VTT map: not valid JSON: {e}")
}

fn read_map(root: &At, stem: &str, options: &ImportOptions) -> Result<Imported, Bad> {
    if let Some(format) = root.opt("format")? {
        format.number()?;
    }
    let grid = grid(root, options)?;
    let mut imported = Imported {
        source: String::new(),
        kind: "Universal VTT map",
        canvas: (
            (grid.size.x * grid.scale).ceil().max(1.0) as u32,
            (grid.size.y * grid.scale).ceil().max(1.0) as u32,
        ),
        origin: grid.world(grid.origin),
        plan_unit: grid.scale / grid.pixels_per_grid,
        floor: ImportedFloor::Color([0.5, 0.5, 0.5]),
        walls: Vec::new(),
        lights: Vec::new(),
        glass: Vec::new(),
        warnings: Vec::new(),
        notes: Vec::new(),
        mapping: Vec::new(),
        floor_file: None,
    };
    for key in ["line_of_sight", "objects_line_of_sight"] {
        if let Some(runs) = root.opt(key)? {
            walls(&runs, &grid, &mut imported)?;
        }
    }
    if let Some(portals) = root.opt("portals")? {
        self::portals(&portals, &grid, options, &mut imported)?;
    }
    if let Some(lights) = root.opt("lights")? {
        self::lights(&lights, &grid, options, &mut imported)?;
    }
    if let Some(environment) = root.opt("environment")? {
        self::environment(&environment, &mut imported)?;
    }
    match root.opt("image")? {
        Some(image) => floor(&image, &grid, stem, &mut imported)?,
        None => imported
            .warnings
            .push("the map has no image: the floor is plain grey".to_string()),
    }
    Ok(imported)
}

fn grid(root: &At, options: &ImportOptions) -> Result<Grid, Bad> {
    let resolution = root.get("resolution", "the map's size and grid")?;
    let ppg = resolution.get("pixels_per_grid", "the image's pixels per grid cell")?;
    let pixels_per_grid = ppg.number()?;
    if !(pixels_per_grid > 0.0 && pixels_per_grid <= 1e6) {
        return Err(ppg.bad(format!(
            "expected a number of pixels > 0 and at most 1e6, found {pixels_per_grid}"
        )));
    }
    let size_at = resolution.get("map_size", "the map's size in grid cells")?;
    let size = size_at.point()?;
    for (v, axis) in [(size.x, "x"), (size.y, "y")] {
        if !(v > 0.0 && v <= MAX_CELLS) {
            return Err(Bad {
                at: size_at.child(axis),
                message: format!(
                    "expected a size > 0 and at most {MAX_CELLS:e} grid cells, found {v}"
                ),
            });
        }
    }
    let origin = match resolution.opt("map_origin")? {
        Some(origin) => origin.point()?,
        None => DVec2::ZERO,
    };
    Ok(Grid {
        scale: options.scale_or(pixels_per_grid),
        pixels_per_grid,
        origin,
        size,
    })
}

/// Each run of points is a chain of walls that share their ends exactly.
fn walls(runs: &At, grid: &Grid, imported: &mut Imported) -> Result<(), Bad> {
    for run in runs.items()? {
        let points: Vec<DVec2> = run
            .items()?
            .iter()
            .map(At::point)
            .collect::<Result<_, _>>()?;
        if points.len() < 2 {
            return Err(run.bad(format!(
                "a wall needs at least two points, found {}",
                points.len()
            )));
        }
        let world: Vec<DVec2> = points.iter().map(|&p| grid.world(p)).collect();
        let pieces = edges(&world, false);
        if pieces.is_empty() {
            imported.warnings.push(format!(
                "{}: a wall of no length (every point at ({}, {})), not imported",
                run.path, points[0].x, points[0].y
            ));
        }
        for (a, b) in pieces {
            imported.walls.push(ImportedWall {
                a,
                b,
                through: None,
                kind: WallKind::Diffuse(None),
                emit: None,
                source: run.path.clone(),
            });
        }
    }
    Ok(())
}

/// Doors and windows: a portal's `bounds` are its two ends on the wall's
/// line; `closed` (light blocked) tells a door from a window.
fn portals(
    portals: &At,
    grid: &Grid,
    options: &ImportOptions,
    imported: &mut Imported,
) -> Result<(), Bad> {
    let (mut shut, mut open, mut windows) = (0usize, 0usize, 0usize);
    for portal in portals.items()? {
        let bounds = portal.get("bounds", "the portal's two ends")?;
        let ends = bounds.items()?;
        if ends.len() != 2 {
            return Err(bounds.bad(format!(
                "expected two points (the portal's ends), found {}",
                ends.len()
            )));
        }
        let (a, b) = (ends[0].point()?, ends[1].point()?);
        if grid.world(a) == grid.world(b) {
            return Err(bounds.bad(format!(
                "the portal has zero width: both ends at ({}, {})",
                a.x, a.y
            )));
        }
        if let Some(position) = portal.opt("position")? {
            position.point()?;
        }
        if let Some(rotation) = portal.opt("rotation")? {
            rotation.number()?;
        }
        if let Some(freestanding) = portal.opt("freestanding")? {
            freestanding.boolean()?;
        }
        let closed = match portal.opt("closed")? {
            Some(closed) => closed.boolean()?,
            None => true,
        };
        let door = closed || options.open_portals == OpenPortals::Doors;
        let (kind, what) = if !door {
            windows += 1;
            (WallKind::Pane(WINDOW_TINT), "a window")
        } else {
            let is_shut = match options.doors {
                Doors::AsDrawn => closed,
                Doors::Open => false,
                Doors::Closed => true,
            };
            if is_shut {
                shut += 1;
                (WallKind::ShutDoor, "a door, shut")
            } else {
                open += 1;
                (WallKind::OpenDoor, "a door, open")
            }
        };
        imported.walls.push(ImportedWall {
            a: grid.world(a),
            b: grid.world(b),
            through: None,
            kind,
            emit: None,
            source: format!("{} ({what})", portal.path),
        });
    }
    let parts: Vec<String> = [
        (shut, "door", "doors", "shut (opaque walls)"),
        (open, "door", "doors", "open (gaps in their walls)"),
        (windows, "window", "windows", "(clear panes)"),
    ]
    .iter()
    .filter(|(n, ..)| *n > 0)
    .map(|&(n, one, many, what)| format!("{} {what}", crate::counted(n, one, many)))
    .collect();
    if !parts.is_empty() {
        imported.mapping.push(format!(
            "portals: {}; the scene format has no door or window elements, so they are walls and panes",
            parts.join(", ")
        ));
    }
    Ok(())
}

/// Lamps: each a point light of the map's colour, its reach the map's
/// `range` (a `Window` falloff that ends there).
fn lights(
    lights: &At,
    grid: &Grid,
    options: &ImportOptions,
    imported: &mut Imported,
) -> Result<(), Bad> {
    let items = lights.items()?;
    if !options.lights {
        if !items.is_empty() {
            imported.mapping.push(format!(
                "lights: --lights none, so the map's {} not imported",
                crate::counted(items.len(), "light is", "lights are")
            ));
        }
        return Ok(());
    }
    let mut unshadowed = 0usize;
    for light in &items {
        let at = grid.world(light.get("position", "the light's position")?.point()?);
        let range_at = light.get("range", "the light's reach in grid cells")?;
        let range = range_at.number()?;
        if !(0.0..=MAX_COORDINATE).contains(&range) {
            return Err(range_at.bad(format!(
                "expected a reach of 0 to {MAX_COORDINATE:e} grid cells, found {range}"
            )));
        }
        let intensity = match light.opt("intensity")? {
            Some(at) => {
                let v = at.number()?;
                if !(0.0..=1e6).contains(&v) {
                    return Err(at.bad(format!("expected 0 to 1e6, found {v}")));
                }
                v
            }
            None => 1.0,
        };
        let color = match light.opt("color")? {
            Some(at) => argb(&at)?,
            None => [1.0; 3],
        };
        if let Some(shadows) = light.opt("shadows")?
            && !shadows.boolean()?
        {
            unshadowed += 1;
        }
        if range * grid.scale <= 0.0 || intensity == 0.0 {
            imported.warnings.push(format!(
                "{}: a light of no reach or no intensity",
                light.path
            ));
            continue;
        }
        imported.lights.push(ImportedLight::Point {
            at,
            color,
            intensity: MAP_LAMP_INTENSITY * intensity,
            range: Some(range * grid.scale),
            source: light.path.clone(),
        });
    }
    if unshadowed > 0 {
        imported.warnings.push(format!(
            "{} that cast no shadows in the map (`shadows: false`): flatray's lights always do",
            crate::counted(unshadowed, "light", "lights")
        ));
    }
    if !imported.lights.is_empty() {
        imported.mapping.push(format!(
            "lights: {}, each a Window falloff that ends at its range, intensity {MAP_LAMP_INTENSITY} times the map's",
            crate::counted(imported.lights.len(), "point light", "point lights")
        ));
    }
    Ok(())
}

/// A colour written as hex ARGB (`ffeccd8b`, the alpha first and not
/// used), or RGB.
fn argb(at: &At) -> Result<[f64; 3], Bad> {
    let text = at.string()?;
    let hex = text.trim().trim_start_matches('#');
    match hex.len() {
        6 | 8 => parse_hex_color(&format!("#{hex}")),
        _ => None,
    }
    .ok_or_else(|| {
        at.bad(format!(
            "expected a colour as hex ARGB (as \"ffeccd8b\"), found {}",
            kind(at.value)
        ))
    })
}

fn environment(environment: &At, imported: &mut Imported) -> Result<(), Bad> {
    if let Some(baked) = environment.opt("baked_lighting")?
        && baked.boolean()?
    {
        imported.warnings.push(
            "environment.baked_lighting: the map image has its lighting painted in, so as the floor's albedo its shadows darken flatray's light a second time; export the map without lighting for the floor's own colours".to_string(),
        );
    }
    if let Some(ambient) = environment.opt("ambient_light")? {
        let text = ambient.string()?;
        argb(&ambient)?;
        imported.warnings.push(format!(
            "environment.ambient_light ({text}): the scene format has no sky light for it"
        ));
    }
    Ok(())
}

/// The map's image, decoded from base64, written beside the scene as a
/// PNG and stretched over the canvas, which is the map's extent: the
/// floor at the map's own scale.
fn floor(image: &At, grid: &Grid, stem: &str, imported: &mut Imported) -> Result<(), Bad> {
    let text = image.string()?;
    let text = match text.find(";base64,") {
        Some(k) if text.starts_with("data:") => &text[k + ";base64,".len()..],
        _ => text,
    };
    let compact: Vec<u8> = text.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    if compact.is_empty() {
        imported
            .warnings
            .push("the map's image is empty: the floor is plain grey".to_string());
        return Ok(());
    }
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
    );
    let bytes = engine
        .decode(&compact)
        .map_err(|e| image.bad(format!("not base64: {e}")))?;
    let png = bytes.starts_with(b"\x89PNG\r\n\x1a\n");
    let webp = bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP";
    if !(png || webp) {
        let head: Vec<String> = bytes.iter().take(4).map(|b| format!("{b:02x}")).collect();
        return Err(image.bad(format!(
            "the base64 payload is not a PNG or WebP image (its first bytes are {})",
            head.join(" ")
        )));
    }
    let decoded = decode_within(&bytes, MAX_MAP_IMAGE_PIXELS).map_err(|failure| match failure {
        ImageFailure::TooLarge(w, h) => image.bad(format!(
            "the map image is {w} x {h} pixels, more than the {MAX_MAP_IMAGE_PIXELS} the import reads: export the map with fewer pixels per grid cell"
        )),
        ImageFailure::Unreadable(e) => image.bad(format!("the map image cannot be decoded: {e}")),
    })?;
    let (w, h) = (decoded.width(), decoded.height());
    if w == 0 || h == 0 {
        return Err(image.bad("the map image is empty"));
    }
    let expected = grid.size * grid.pixels_per_grid;
    if (w as f64 - expected.x).abs() > 1.0 || (h as f64 - expected.y).abs() > 1.0 {
        imported.warnings.push(format!(
            "the map image is {w} x {h} pixels, not the map's {} x {} cells at {} pixels each: it is stretched over the map",
            expected.x / grid.pixels_per_grid,
            expected.y / grid.pixels_per_grid,
            grid.pixels_per_grid
        ));
    }
    let bytes = if png && (w as u64) * (h as u64) <= MAX_FLOOR_TEXELS {
        bytes
    } else {
        let (reduced, k) = reduce(&decoded.to_rgb8());
        if k > 1 {
            imported.mapping.push(format!(
                "image: {w} x {h} pixels, reduced to {} x {} for the floor (a floor image holds at most {MAX_FLOOR_TEXELS} pixels; each is the mean of {k} x {k})",
                reduced.width(),
                reduced.height()
            ));
        }
        crate::output::rgb8_png(reduced.as_raw(), reduced.width(), reduced.height())
            .map_err(|e| image.bad(format!("cannot write the floor image: {e}")))?
    };
    let name = format!("{stem}-floor.png");
    imported.floor = ImportedFloor::Image(name.clone());
    imported.floor_file = Some((name, bytes));
    Ok(())
}

/// The image reduced by the smallest whole factor `k` that brings it
/// within the floor's budget, each pixel the mean of a `k x k` block in
/// linear light (blocks at the right and bottom edges the mean of what
/// they hold); with `k`.
fn reduce(image: &image::RgbImage) -> (image::RgbImage, u32) {
    let (w, h) = image.dimensions();
    let fits = |k: u32| (w.div_ceil(k) as u64) * (h.div_ceil(k) as u64) <= MAX_FLOOR_TEXELS;
    let k = (1..=w.max(h)).find(|&k| fits(k)).unwrap_or(w.max(h).max(1));
    if k == 1 {
        return (image.clone(), 1);
    }
    let linear: Vec<f64> = (0..=255u8).map(crate::output::srgb_to_linear).collect();
    let (rw, rh) = (w.div_ceil(k), h.div_ceil(k));
    let mut out = image::RgbImage::new(rw, rh);
    for (x, y, pixel) in out.enumerate_pixels_mut() {
        let mut sum = [0.0f64; 3];
        let mut n = 0.0;
        for yy in y * k..((y + 1) * k).min(h) {
            for xx in x * k..((x + 1) * k).min(w) {
                let p = image.get_pixel(xx, yy).0;
                for c in 0..3 {
                    sum[c] += linear[p[c] as usize];
                }
                n += 1.0;
            }
        }
        *pixel = image::Rgb(sum.map(|s| crate::output::linear_to_srgb((s / n) as f32)));
    }
    (out, k)
}
