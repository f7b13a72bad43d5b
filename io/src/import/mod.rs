//! Floor plans from other tools, turned into scene files: SVG drawings
//! (`svg.rs`), Tiled maps in TMX or JSON (`tiled.rs`), black-and-white
//! wall masks (`mask.rs`) and Universal VTT maps from Dungeondraft,
//! DungeonFog and Arkenforge (`uvtt.rs`). Each reader fills an
//! [`Imported`] plan of walls, lights and glass in world units;
//! [`Imported::to_ron`] writes it as a commented scene file that `render`
//! reads and a user can edit, and [`Imported::write`] writes it with its
//! floor image. `docs/import.md` gives every convention.

use std::fmt;
use std::path::{Path, PathBuf};

use flatray_geometry::DVec2;

mod mask;
mod svg;
mod tiled;
mod uvtt;

/// How a plan is read.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    /// World units (pixels of the scene's canvas) per unit of the plan:
    /// an SVG user unit (1/96 inch), a Tiled map pixel, a mask pixel, a
    /// Universal VTT grid cell. `None`: 1, and for a Universal VTT map its
    /// `pixels_per_grid` (the map image's own scale).
    pub scale: Option<f64>,
    /// Curves are flattened, traced outlines simplified, and windows and
    /// doors matched to the wall they lie on, to within this distance, in
    /// the plan's own units (as `scale`; a Universal VTT map's in pixels of
    /// its image).
    pub tolerance: f64,
    /// The Tiled object layer whose objects are walls.
    pub walls_layer: String,
    /// The Tiled object layer whose objects are lights.
    pub lights_layer: String,
    /// Use the plan's bitmap (an SVG's first image) as the floor. A
    /// Universal VTT map's image is always the floor.
    pub floor_image: bool,
    /// The state of a Universal VTT map's doors.
    pub doors: Doors,
    /// What a Universal VTT portal that does not block light is.
    pub open_portals: OpenPortals,
    /// Whether a Universal VTT map's lights are imported.
    pub lights: bool,
}

impl ImportOptions {
    /// `scale`, or `default` where none is given.
    pub fn scale_or(&self, default: f64) -> f64 {
        self.scale.unwrap_or(default)
    }
}

/// The state of imported doors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Doors {
    /// As the map draws each: a portal that blocks light is shut.
    #[default]
    AsDrawn,
    /// Every door open: a gap in its wall.
    Open,
    /// Every door shut: an opaque wall.
    Closed,
}

/// What a Universal VTT portal whose `closed` is false is: the format
/// has one kind of portal for both, and Dungeondraft writes its windows
/// as portals that do not block light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OpenPortals {
    /// A window: a clear pane in the wall.
    #[default]
    Windows,
    /// A door standing open.
    Doors,
}

impl Default for ImportOptions {
    fn default() -> ImportOptions {
        ImportOptions {
            scale: None,
            tolerance: 1.0,
            walls_layer: "walls".to_string(),
            lights_layer: "lights".to_string(),
            floor_image: false,
            doors: Doors::AsDrawn,
            open_portals: OpenPortals::Windows,
            lights: true,
        }
    }
}

/// Why a plan could not be imported.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The file could not be read.
    #[error("{}: cannot read the plan: {message}", path.display())]
    Read { path: PathBuf, message: String },
    /// The file is not a plan flatray can read, or is malformed; with the
    /// line and column where the reader gives them.
    #[error("{}{}: {message}", path.display(), location.map_or(String::new(), |(l, c)| format!(":{l}:{c}")))]
    Invalid {
        path: PathBuf,
        location: Option<(usize, usize)>,
        message: String,
    },
}

/// A wall's material, as imported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WallKind {
    /// Diffuse with its own albedo (linear), or the floor's.
    Diffuse(Option<[f64; 3]>),
    Mirror,
    /// A transparent pane with its tint (linear).
    Pane([f64; 3]),
    /// A door: drawn on a wall's line, an opening cut in the wall; it
    /// becomes no wall of its own.
    Door,
    /// A door standing open in a map whose walls already leave a gap for
    /// it: it cuts the wall it lies on as `Door` does, and where none lies
    /// under it the gap is there already.
    OpenDoor,
    /// A shut door: an opaque wall of the floor's albedo that, lying on a
    /// wall, is put in the gap it cuts there (as a window is), so that the
    /// two are never one on top of the other.
    ShutDoor,
}

/// One imported wall.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedWall {
    pub a: DVec2,
    pub b: DVec2,
    /// A point the wall passes through between its ends, where it is a
    /// circular arc.
    pub through: Option<DVec2>,
    pub kind: WallKind,
    /// Light the wall emits: colour (linear) and intensity.
    pub emit: Option<([f64; 3], f64)>,
    /// Where it came from, for the comment beside it.
    pub source: String,
}

/// One imported light.
#[derive(Clone, Debug, PartialEq)]
pub enum ImportedLight {
    Point {
        at: DVec2,
        color: [f64; 3],
        intensity: f64,
        /// The reach of a `Window` falloff, where the plan gives the light
        /// one; else the scene's falloff.
        range: Option<f64>,
        source: String,
    },
    Line {
        a: DVec2,
        b: DVec2,
        color: [f64; 3],
        intensity: f64,
        source: String,
    },
}

/// One imported glass body.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedGlass {
    pub points: Vec<DVec2>,
    /// Per edge (from point `i` to the next), the point an arc edge passes
    /// through; empty for a polygon.
    pub through: Vec<Option<DVec2>>,
    pub ior: f64,
    pub source: String,
}

/// The floor of an imported plan.
#[derive(Clone, Debug, PartialEq)]
pub enum ImportedFloor {
    Color([f64; 3]),
    /// An image file, relative to the scene file.
    Image(String),
}

/// A plan read from another tool, in world units.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// What it was read from, for the header comment.
    pub source: String,
    /// The kind of plan (`SVG drawing`, `Tiled map`, `wall mask`,
    /// `Universal VTT map`).
    pub kind: &'static str,
    pub canvas: (u32, u32),
    /// The world position of the canvas's top-left corner.
    pub origin: DVec2,
    /// World units per unit of the plan's own (in which `tolerance` is
    /// given).
    pub plan_unit: f64,
    pub floor: ImportedFloor,
    pub walls: Vec<ImportedWall>,
    pub lights: Vec<ImportedLight>,
    pub glass: Vec<ImportedGlass>,
    /// What was in the plan and was not imported, one line each.
    pub warnings: Vec<String>,
    /// What the import changed to make the plan mean what its drawer
    /// meant, one line each: walls cut where a window or door lies on them.
    pub notes: Vec<String>,
    /// What the plan's elements became, where it is not plain: doors and
    /// windows as walls and panes, lights' reach as falloffs. One line
    /// each.
    pub mapping: Vec<String>,
    /// A bitmap to write beside the scene for the floor: its file name
    /// (as `floor` names it) and bytes.
    pub floor_file: Option<(String, Vec<u8>)>,
}

/// The default intensity of an imported point light: bright enough to
/// see under the default `Flatland` falloff at a few hundred units.
pub const LAMP_INTENSITY: f64 = 50.0;
/// The default intensity (per unit length) of an imported line light or
/// emitting wall.
pub const LINE_INTENSITY: f64 = 1.0;

/// Reads the plan at `path`, its kind told by its extension, else by its
/// first bytes.
pub fn import(path: &Path, options: &ImportOptions) -> Result<Imported, ImportError> {
    let bytes =
        crate::read_within(path, crate::MAX_INPUT_BYTES).map_err(|e| ImportError::Read {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    if let Some(scale) = options.scale
        && !(scale.is_finite() && scale > 0.0 && scale <= 1e6)
    {
        return Err(invalid(
            path,
            None,
            format!("--scale: expected a number > 0 and at most 1e6, found {scale}"),
        ));
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return Err(invalid(
            path,
            None,
            format!(
                "--tolerance: expected a number > 0, found {}",
                options.tolerance
            ),
        ));
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(512)]).to_ascii_lowercase();
    let head = head.trim_start_matches('\u{feff}').trim_start();
    let mut imported = match extension.as_str() {
        "dd2vtt" | "uvtt" | "df2vtt" => uvtt::read(path, &bytes, options)?,
        "svg" | "svgz" => svg::read(path, &bytes, options)?,
        "tmx" => tiled::read_tmx(path, &bytes, options)?,
        "json" if uvtt::looks_like(&bytes) => uvtt::read(path, &bytes, options)?,
        "json" | "tmj" => tiled::read_json(path, &bytes, options)?,
        "png" | "bmp" | "gif" | "jpg" | "jpeg" | "tif" | "tiff" | "webp" => {
            mask::read(path, &bytes, options)?
        }
        _ if head.starts_with("<svg") || (head.starts_with("<?xml") && head.contains("<svg")) => {
            svg::read(path, &bytes, options)?
        }
        _ if head.starts_with("<map") || (head.starts_with("<?xml") && head.contains("<map")) => {
            tiled::read_tmx(path, &bytes, options)?
        }
        _ if head.starts_with('{') && uvtt::looks_like(&bytes) => {
            uvtt::read(path, &bytes, options)?
        }
        _ if head.starts_with('{') => tiled::read_json(path, &bytes, options)?,
        _ if bytes.starts_with(b"\x89PNG") => mask::read(path, &bytes, options)?,
        _ => {
            return Err(invalid(
                path,
                None,
                "not a plan flatray imports: expected an SVG drawing (.svg), a Tiled map (.tmx, .json, .tmj), a Universal VTT map (.dd2vtt, .uvtt, .df2vtt) or a wall mask image (.png)".to_string(),
            ));
        }
    };
    imported.source = path.display().to_string();
    let tolerance = options.tolerance * imported.plan_unit;
    cut_openings(&mut imported, tolerance);
    let (w, h) = imported.canvas;
    if w > crate::format::MAX_CANVAS_SIDE
        || h > crate::format::MAX_CANVAS_SIDE
        || w as u64 * h as u64 > crate::format::MAX_CANVAS_PIXELS
    {
        return Err(invalid(
            path,
            None,
            format!(
                "the canvas would be {w} x {h} pixels, more than flatray renders: import with a smaller --scale"
            ),
        ));
    }
    // What is written must load: numbers finite and within the scene
    // format's bounds, walls and glass valid (checked with a plain floor:
    // the floor image is written later).
    let mut check = imported.clone();
    check.floor = ImportedFloor::Color([0.5; 3]);
    if let Err(e) = crate::parse(
        &check.to_ron(),
        Path::new("(imported scene)"),
        Path::new("."),
    ) {
        return Err(invalid(
            path,
            None,
            format!("the plan does not make a valid scene: {e}"),
        ));
    }
    if imported.walls.is_empty() && imported.lights.is_empty() && imported.glass.is_empty() {
        imported
            .warnings
            .push("the plan has no walls, lights or glass that flatray imports".to_string());
    }
    Ok(imported)
}

/// At most this many (opening, wall) pairs are compared by
/// [`cut_openings`].
const OPENING_PAIRS_BUDGET: usize = 1 << 26;

/// Windows and doors drawn on a wall's line are what plan drawers mean by
/// an opening: each wall that a window or door lies along (within
/// `tolerance`, in world units) is cut there; a window stays in the gap,
/// and a door leaves it open. Emitting walls are not cut. A door that lies
/// on no wall is dropped with a warning. Each cut is noted.
fn cut_openings(imported: &mut Imported, tolerance: f64) {
    use flatray_geometry::{Segment, overlap};
    let walls = std::mem::take(&mut imported.walls);
    let segments: Vec<Segment> = walls.iter().map(|w| Segment::new(w.a, w.b)).collect();
    // An arc is neither cut nor an opening: only straight walls lie
    // along each other.
    let is_opening = |w: &ImportedWall| {
        w.through.is_none()
            && matches!(
                w.kind,
                WallKind::Pane(_) | WallKind::Door | WallKind::OpenDoor | WallKind::ShutDoor
            )
    };
    let openings: Vec<usize> = (0..walls.len())
        .filter(|&i| is_opening(&walls[i]))
        .collect();
    // Each opening against each wall: a plan has few openings. Past the
    // budget nothing is cut (the renderer's rule for walls that overlap
    // still applies).
    if openings.len().saturating_mul(walls.len()) > OPENING_PAIRS_BUDGET {
        imported.warnings.push(format!(
            "{} windows and doors against {} walls is more than the import compares: no wall was cut for them",
            openings.len(),
            walls.len()
        ));
        imported.walls = walls;
        return;
    }
    let tolerance = overlap::Tolerance::Distance(tolerance);
    let mut cut: Vec<Option<Vec<ImportedWall>>> = vec![None; walls.len()];
    let mut on_a_wall = vec![false; walls.len()];
    for host in 0..walls.len() {
        if is_opening(&walls[host]) || walls[host].emit.is_some() || walls[host].through.is_some() {
            continue;
        }
        let on_it: Vec<usize> = openings
            .iter()
            .copied()
            .filter(|&o| overlap::overlap(&segments[host], &segments[o], tolerance))
            .collect();
        if on_it.is_empty() {
            continue;
        }
        let group: Vec<usize> = std::iter::once(host).chain(on_it.iter().copied()).collect();
        let pieces = overlap::pieces(&segments, &group);
        // The host is the group's first member.
        let forward = pieces.forward[0];
        let mut kept: Vec<ImportedWall> = Vec::new();
        for k in 0..pieces.points.len().saturating_sub(1) {
            // Only the host there: neither window nor door.
            if !pieces.covers(0, k) || (1..group.len()).any(|g| pieces.covers(g, k)) {
                continue;
            }
            let (p, q) = (pieces.points[k], pieces.points[k + 1]);
            // Consecutive kept pieces join into one wall.
            match kept.last_mut() {
                Some(last) if forward && last.b == p => last.b = q,
                Some(last) if !forward && last.a == p => last.a = q,
                _ => kept.push(ImportedWall {
                    a: if forward { p } else { q },
                    b: if forward { q } else { p },
                    ..walls[host].clone()
                }),
            }
        }
        for &o in &on_it {
            on_a_wall[o] = true;
            let (what, gap) = match walls[o].kind {
                WallKind::Door | WallKind::OpenDoor => ("door", ", an opening"),
                WallKind::ShutDoor => ("door", " and the shut door put in the gap"),
                _ => ("window", " and the window put in the gap"),
            };
            imported.notes.push(format!(
                "the {what} {} lies on the wall {}: the wall is cut there{gap}",
                walls[o].source, walls[host].source
            ));
        }
        cut[host] = Some(kept);
    }
    for (i, (wall, replacement)) in walls.into_iter().zip(cut).enumerate() {
        match replacement {
            Some(pieces) => imported.walls.extend(pieces),
            // Its gap is in the walls already.
            None if wall.kind == WallKind::OpenDoor => {}
            None if wall.kind == WallKind::Door => {
                if !on_a_wall[i] {
                    imported.warnings.push(format!(
                        "{}: a door lies on no wall (a door is an opening cut in the wall it is drawn on)",
                        wall.source
                    ));
                }
            }
            None => imported.walls.push(wall),
        }
    }
}

pub(crate) fn invalid(
    path: &Path,
    location: Option<(usize, usize)>,
    message: String,
) -> ImportError {
    ImportError::Invalid {
        path: path.to_path_buf(),
        location,
        message,
    }
}

/// An sRGB colour of 8-bit channels as linear values.
pub(crate) fn linear(rgb: [u8; 3]) -> [f64; 3] {
    rgb.map(crate::output::srgb_to_linear)
}

/// An sRGB colour written `#rgb`, `#rrggbb` or `#aarrggbb` (Tiled's form)
/// as linear values.
pub(crate) fn parse_hex_color(text: &str) -> Option<[f64; 3]> {
    let hex = text.trim().strip_prefix('#')?;
    let digits: Vec<u8> = hex
        .chars()
        .map(|c| c.to_digit(16).map(|d| d as u8))
        .collect::<Option<_>>()?;
    let rgb = match digits.len() {
        3 => [digits[0] * 17, digits[1] * 17, digits[2] * 17],
        6 => [
            digits[0] * 16 + digits[1],
            digits[2] * 16 + digits[3],
            digits[4] * 16 + digits[5],
        ],
        8 => [
            digits[2] * 16 + digits[3],
            digits[4] * 16 + digits[5],
            digits[6] * 16 + digits[7],
        ],
        _ => return None,
    };
    Some(linear(rgb))
}

/// The edges of an outline with the point each arc edge passes through
/// (`through[i]` for the edge from point `i`; `None`, or missing, for a
/// straight one), and its closing edge when closed; none of zero length.
pub(crate) fn arc_edges(
    points: &[DVec2],
    through: &[Option<DVec2>],
    closed: bool,
) -> Vec<(DVec2, DVec2, Option<DVec2>)> {
    let n = points.len();
    let count = if closed && n > 2 || (closed && n == 2 && through.iter().any(Option::is_some)) {
        n
    } else {
        n.saturating_sub(1)
    };
    (0..count)
        .map(|i| {
            (
                points[i],
                points[(i + 1) % n],
                through.get(i).copied().flatten(),
            )
        })
        .filter(|(a, b, _)| a != b)
        .collect()
}

/// The edges of a polyline, and its closing edge when closed; none of
/// zero length.
pub(crate) fn edges(points: &[DVec2], closed: bool) -> Vec<(DVec2, DVec2)> {
    let mut out: Vec<(DVec2, DVec2)> = points.windows(2).map(|w| (w[0], w[1])).collect();
    if closed && points.len() > 2 {
        out.push((points[points.len() - 1], points[0]));
    }
    out.retain(|(a, b)| a != b);
    out
}

/// Points `(x, y)`, in order, simplified by Douglas-Peucker: the first
/// and last are kept, and a run of points becomes one edge when the
/// middles of its edges lie within `tolerance` of it.
pub(crate) fn simplify(points: &[DVec2], tolerance: f64) -> Vec<DVec2> {
    if points.len() < 3 {
        return points.to_vec();
    }
    let mut keep = vec![false; points.len()];
    keep[0] = true;
    keep[points.len() - 1] = true;
    let mut stack = vec![(0, points.len() - 1)];
    while let Some((first, last)) = stack.pop() {
        let (a, b) = (points[first], points[last]);
        let edge = b - a;
        let length = edge.length();
        let off = |p: DVec2| {
            if length > 0.0 {
                edge.perp_dot(p - a).abs() / length
            } else {
                p.distance(a)
            }
        };
        let mut farthest = (0.0, first);
        for (k, &p) in points.iter().enumerate().take(last).skip(first + 1) {
            let d = off(p);
            if d > farthest.0 {
                farthest = (d, k);
            }
        }
        // The chord stands for the points between when the middles of
        // their edges lie within the tolerance: a staircase of pixels, of
        // any slope, is the straight line it draws, not a zigzag of its
        // corners (which lie up to half a step further out).
        let stray = (first..last)
            .map(|j| off((points[j] + points[j + 1]) * 0.5))
            .fold(0.0, f64::max);
        if stray > tolerance && farthest.1 != first {
            keep[farthest.1] = true;
            stack.push((first, farthest.1));
            stack.push((farthest.1, last));
        }
    }
    points
        .iter()
        .zip(keep)
        .filter_map(|(&p, k)| k.then_some(p))
        .collect()
}

/// A closed loop of points (the last joining the first), simplified to
/// within `tolerance`; it keeps its first point and the point farthest
/// from it, so its corners stay exactly where they were.
pub(crate) fn simplify_loop(points: &[DVec2], tolerance: f64) -> Vec<DVec2> {
    if points.len() < 4 {
        return points.to_vec();
    }
    let far = (1..points.len())
        .max_by(|&i, &j| {
            points[i]
                .distance_squared(points[0])
                .total_cmp(&points[j].distance_squared(points[0]))
        })
        .unwrap_or(1);
    let mut first: Vec<DVec2> = simplify(&points[..=far], tolerance);
    let mut second: Vec<DVec2> = points[far..].to_vec();
    second.push(points[0]);
    let second = simplify(&second, tolerance);
    first.pop();
    first.extend_from_slice(&second[..second.len() - 1]);
    first
}

fn number(x: f64) -> String {
    // The shortest text that reads back as the same number.
    let text = format!("{x:?}");
    text.strip_suffix(".0").map_or(text.clone(), str::to_string)
}

fn point(p: DVec2) -> String {
    format!("({}, {})", number(p.x), number(p.y))
}

fn color(c: [f64; 3]) -> String {
    let round = |v: f64| (v * 1e4).round() / 1e4;
    format!(
        "({}, {}, {})",
        number(round(c[0])),
        number(round(c[1])),
        number(round(c[2]))
    )
}

/// A comment's text on one line, without anything that would end it.
fn comment(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

impl Imported {
    /// The plan as a commented scene file.
    pub fn to_ron(&self) -> String {
        let mut out = String::new();
        out.push_str(&format!(
            "// Imported by `flatray import` from the {} {}.\n",
            self.kind,
            comment(&self.source)
        ));
        out.push_str(&format!(
            "// {}, {}, {}. Edit freely: every field is in\n// docs/scene-format.md.\n",
            crate::counted(self.walls.len(), "wall", "walls"),
            crate::counted(self.lights.len(), "light", "lights"),
            crate::counted(self.glass.len(), "glass body", "glass bodies"),
        ));
        for line in &self.mapping {
            out.push_str(&format!("// Imported: {}\n", comment(line)));
        }
        for note in &self.notes {
            out.push_str(&format!("// Cut: {}\n", comment(note)));
        }
        for warning in &self.warnings {
            out.push_str(&format!("// Not imported: {}\n", comment(warning)));
        }
        out.push_str("Scene(\n");
        out.push_str(&format!(
            "    canvas: ({}, {}),\n",
            self.canvas.0, self.canvas.1
        ));
        if self.origin != DVec2::ZERO {
            out.push_str(&format!("    origin: {},\n", point(self.origin)));
        }
        match &self.floor {
            ImportedFloor::Color(c) => out.push_str(&format!("    floor: Color({}),\n", color(*c))),
            ImportedFloor::Image(name) => {
                out.push_str(&format!("    floor: Image({name:?}),\n"));
            }
        }
        out.push_str("    walls: [\n");
        for wall in &self.walls {
            let material = match wall.kind {
                WallKind::Diffuse(None) | WallKind::ShutDoor => String::new(),
                WallKind::Diffuse(Some(albedo)) => {
                    format!(", material: Diffuse(albedo: {})", color(albedo))
                }
                WallKind::Mirror => ", material: Mirror()".to_string(),
                WallKind::Pane(tint) => format!(", material: Transparent(tint: {})", color(tint)),
                // Doors were cut into their walls, and are no walls.
                WallKind::Door | WallKind::OpenDoor => continue,
            };
            let emit = wall.emit.map_or(String::new(), |(c, i)| {
                format!(", emit: (color: {}, intensity: {})", color(c), number(i))
            });
            let through = wall
                .through
                .map_or(String::new(), |m| format!(", through: {}", point(m)));
            out.push_str(&format!(
                "        Wall(a: {}{through}, b: {}{material}{emit}), // {}\n",
                point(wall.a),
                point(wall.b),
                comment(&wall.source)
            ));
        }
        out.push_str("    ],\n    lights: [\n");
        for light in &self.lights {
            match light {
                ImportedLight::Point {
                    at,
                    color: c,
                    intensity,
                    range,
                    source,
                } => out.push_str(&format!(
                    "        Point(at: {}, color: {}, intensity: {}{}), // {}\n",
                    point(*at),
                    color(*c),
                    number(*intensity),
                    range.map_or(String::new(), |r| format!(
                        ", falloff: Window(range: {})",
                        number(r)
                    )),
                    comment(source)
                )),
                ImportedLight::Line {
                    a,
                    b,
                    color: c,
                    intensity,
                    source,
                } => out.push_str(&format!(
                    "        Line(a: {}, b: {}, color: {}, intensity: {}), // {}\n",
                    point(*a),
                    point(*b),
                    color(*c),
                    number(*intensity),
                    comment(source)
                )),
            }
        }
        out.push_str("    ],\n");
        if !self.glass.is_empty() {
            out.push_str("    glass: [\n");
            for body in &self.glass {
                let points: Vec<String> = body.points.iter().map(|&p| point(p)).collect();
                let through = if body.through.iter().any(Option::is_some) {
                    let each: Vec<String> = body
                        .through
                        .iter()
                        .map(|m| m.map_or("None".to_string(), |m| format!("Some({})", point(m))))
                        .collect();
                    format!(", through: [{}]", each.join(", "))
                } else {
                    String::new()
                };
                out.push_str(&format!(
                    "        Glass(points: [{}]{through}, ior: {}), // {}\n",
                    points.join(", "),
                    number(body.ior),
                    comment(&body.source)
                ));
            }
            out.push_str("    ],\n");
        }
        out.push_str("    render: (samples: 64, bounces: 2),\n)\n");
        out
    }
}

impl Imported {
    /// Names the floor image (if the plan has one) after the scene file
    /// `output`, as `NAME-floor.png` beside `NAME.ron`, so that plans
    /// imported into one folder never share one; returns its path.
    pub fn name_floor_for(&mut self, output: &Path) -> Option<PathBuf> {
        let (name, _) = self.floor_file.as_mut()?;
        let stem = output
            .file_stem()
            .map_or("scene".to_string(), |s| s.to_string_lossy().into_owned());
        let extension = Path::new(name.as_str())
            .extension()
            .map_or("png".to_string(), |e| e.to_string_lossy().into_owned());
        *name = format!("{stem}-floor.{extension}");
        self.floor = ImportedFloor::Image(name.clone());
        let folder = output.parent().unwrap_or(Path::new(""));
        Some(folder.join(name.as_str()))
    }

    /// Writes the scene to `output` and its floor image (if any) beside
    /// it, named for it ([`Imported::name_floor_for`]). No file is
    /// replaced without `force`, the plan at `plan` never, and every file
    /// is checked before any is written. Returns the paths written, the
    /// floor image's first.
    pub fn write(
        &mut self,
        output: &Path,
        plan: &Path,
        force: bool,
    ) -> Result<Vec<PathBuf>, String> {
        self.name_floor_for(output);
        let folder = match output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !folder.is_dir() {
            return Err(format!(
                "{}: cannot write it: the folder {} does not exist",
                output.display(),
                folder.display()
            ));
        }
        let mut paths = Vec::new();
        if let Some((name, _)) = &self.floor_file {
            paths.push(folder.join(name));
        }
        paths.push(output.to_path_buf());
        let plan = std::fs::canonicalize(plan).ok();
        for path in &paths {
            let exists = std::fs::symlink_metadata(path).is_ok();
            if exists && plan.is_some() && std::fs::canonicalize(path).ok() == plan {
                return Err(format!(
                    "{}: the output is the plan being imported; choose another name",
                    path.display()
                ));
            }
            if exists && !force {
                return Err(format!(
                    "{}: the file exists; flatray will not replace it without --force (or choose another name)",
                    path.display()
                ));
            }
        }
        if let Some((_, bytes)) = &self.floor_file {
            crate::write_bytes(&paths[0], bytes).map_err(|e| e.to_string())?;
        }
        crate::write_text(output, &self.to_ron()).map_err(|e| e.to_string())?;
        Ok(paths)
    }
}

impl fmt::Display for Imported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}, {}, {} on a {} x {} canvas",
            crate::counted(self.walls.len(), "wall", "walls"),
            crate::counted(self.lights.len(), "light", "lights"),
            crate::counted(self.glass.len(), "glass body", "glass bodies"),
            self.canvas.0,
            self.canvas.1
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_staircase_simplifies_to_its_diagonal_and_a_loop_keeps_its_corners() {
        let stairs: Vec<DVec2> = (0..20)
            .flat_map(|k| {
                let k = k as f64;
                [DVec2::new(k, k), DVec2::new(k + 1.0, k)]
            })
            .collect();
        let simple = simplify(&stairs, 1.0);
        assert_eq!(simple, vec![stairs[0], stairs[stairs.len() - 1]]);
        let square = [
            DVec2::new(0.0, 0.0),
            DVec2::new(5.0, 0.0),
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 10.0),
            DVec2::new(0.0, 10.0),
        ];
        assert_eq!(
            simplify_loop(&square, 0.1),
            vec![square[0], square[2], square[3], square[4]]
        );
    }

    /// A staircase of 3 across and 2 down, as a mask traces a line of
    /// that slope: its corners stray up to 1.66 from the chord through
    /// its outer corners, its edges' middles 0.83, so at tolerance 1 it is
    /// one edge, not a zigzag; real steps of 3 by 3 stay.
    #[test]
    fn a_staircase_of_any_slope_is_its_line() {
        let stairs = |run: f64, rise: f64| -> Vec<DVec2> {
            (0..10)
                .flat_map(|k| {
                    let k = k as f64;
                    [
                        DVec2::new(k * run, k * rise),
                        DVec2::new((k + 1.0) * run, k * rise),
                    ]
                })
                .chain(std::iter::once(DVec2::new(10.0 * run, 10.0 * rise)))
                .collect()
        };
        let s = stairs(3.0, 2.0);
        assert_eq!(simplify(&s, 1.0), vec![s[0], s[s.len() - 1]]);
        let s = stairs(1.0, 4.0);
        assert_eq!(simplify(&s, 1.0).len(), 2);
        let s = stairs(3.0, 3.0);
        assert!(simplify(&s, 1.0).len() > 2);
    }

    #[test]
    fn hex_colours_read_as_tiled_and_css_write_them() {
        assert_eq!(parse_hex_color("#ffffff"), Some([1.0; 3]));
        assert_eq!(parse_hex_color("#80ff0000"), Some([1.0, 0.0, 0.0]));
        assert_eq!(parse_hex_color("#0f0"), Some([0.0, 1.0, 0.0]));
        assert_eq!(parse_hex_color("red"), None);
    }
}
