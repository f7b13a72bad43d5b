//! From scene text to a `flatray_tracer::Scene` and its render settings.

use std::path::{Path, PathBuf};

use flatray_geometry::{DVec2, Segment, Shape, Side};
use flatray_tracer::scene::{
    Canvas, Falloff, Floor, GlassBody, Item, Light, LightShape, Material, Profile, Scene, Wall,
};
use flatray_tracer::{Integrator, LightChoice, RenderOptions, Rgb};
use ron::extensions::Extensions;

use crate::error::SceneError;
use crate::format::MAX_COORDINATE;
use crate::format::{
    Color, EmitSpec, FalloffSpec, Finite, FloorSpec, IntegratorSpec, LampName, LightSpec,
    LightUnits, LightsSpec, MAX_CANVAS_PIXELS, MAX_CANVAS_SIDE, MaterialSpec, NonNegative,
    SceneFile, SpectrumSpec, ToneMap, Units,
};
use crate::locate;

/// A loaded scene with the render settings its file asks for.
#[derive(Clone, Debug)]
pub struct Loaded {
    pub scene: Scene,
    pub options: RenderOptions,
    pub tonemap: ToneMap,
    /// The files the scene was read from: the scene file (when loaded
    /// from one) and its floor image (when it has one). A render must
    /// never write over them.
    pub inputs: Vec<PathBuf>,
    /// What the file lists, as it lists it.
    pub counts: Counts,
    /// What makes the scene render otherwise than it reads, without being
    /// an error, each with its location.
    pub warnings: Vec<Warning>,
    /// The file's doors, open or closed: bounds between rooms.
    pub doors: Vec<Segment>,
    /// The rooms the file names, each by a point inside it.
    pub rooms: Vec<crate::rooms::NamedRoom>,
    /// What one world unit measures in metres, when the file says.
    pub metres_per_unit: Option<f64>,
    /// The illuminance of the file's skies at a point that sees all of
    /// them (`2 pi` times their radiance, in luminance), where they are
    /// the file's only lights: the daylight factor's denominator.
    pub sky: Option<f64>,
}

/// A warning about a scene that loads: where, and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// The line and column of scene text, from 1; both 0 for values given
    /// in code ([`from_json`]), whose messages name the item by its index.
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// What a scene file lists: its walls (of which some emit), its lights
/// (an emitting wall is not counted among them) and its glass bodies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub walls: usize,
    pub emitting_walls: usize,
    pub lights: usize,
    pub glass: usize,
    /// Of `lights`, the suns of a date and time (`Sun`), which `flatray
    /// day` sets to each frame's time.
    pub suns: usize,
}

/// Reads and validates the scene file at `path`. Relative paths inside it
/// resolve against its folder.
pub fn load(path: &Path) -> Result<Loaded, SceneError> {
    let read_error = |source| SceneError::Read {
        path: path.to_path_buf(),
        source,
    };
    let bytes = crate::read_within(path, crate::MAX_INPUT_BYTES).map_err(read_error)?;
    let foreign = foreign(path, &bytes);
    let not_a_scene = |what| SceneError::NotAScene {
        path: path.to_path_buf(),
        what,
    };
    // What a file's first bytes say it is comes first; its name counts
    // only when its text is no scene either.
    if let Some((what, true)) = foreign {
        return Err(not_a_scene(what));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        read_error(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "expected UTF-8 text, but byte {} is not UTF-8 (is it UTF-16, or not a scene?)",
                valid + 1
            ),
        ))
    })?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut loaded = match (parse(&text, path, &base), foreign) {
        (Err(_), Some((what, _))) => return Err(not_a_scene(what)),
        (result, _) => result?,
    };
    loaded.inputs.insert(0, path.to_path_buf());
    Ok(loaded)
}

/// What the file at `path` is, when it is one of the plans that `flatray
/// import` reads rather than a scene, and whether its first bytes say so
/// (otherwise only its name does).
fn foreign(path: &Path, bytes: &[u8]) -> Option<(&'static str, bool)> {
    let start = String::from_utf8_lossy(&bytes[..bytes.len().min(512)]);
    let start = start.trim_start_matches('\u{feff}').trim_start();
    if start.starts_with("<svg") || (start.starts_with("<?xml") && start.contains("<svg")) {
        return Some(("an SVG drawing", true));
    }
    if start.starts_with("<?xml") && start.contains("<map") || start.starts_with("<map") {
        return Some(("a Tiled map (TMX)", true));
    }
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        return Some(("a PNG image", true));
    }
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let what = match extension.as_deref() {
        Some("svg") => "an SVG drawing",
        Some("tmx") => "a Tiled map (TMX)",
        Some("tmj") => "a Tiled map (JSON)",
        Some("json") => "a JSON file (a Tiled map?)",
        Some("png") => "a PNG image",
        _ => return None,
    };
    Some((what, false))
}

/// The serde form of scene `text` (without a byte-order mark), as the
/// format reads it: unvalidated beyond what its types check.
pub(crate) fn scene_file(text: &str) -> Result<SceneFile, ron::error::SpannedError> {
    ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME)
        .from_str(text)
}

/// Parses and validates scene `text`; `path` names it in messages and
/// `base` is the folder that relative paths resolve against.
///
/// ```
/// use std::path::Path;
///
/// let text = "Scene(canvas: (40, 30), floor: Color((0.8, 0.8, 0.8)),
///     lights: [Point(at: (20, 15))], render: (samples: 4))";
/// let loaded = flatray_io::parse(text, Path::new("mine.ron"), Path::new("."))?;
/// let rendered = flatray_tracer::render(&loaded.scene, &loaded.options, &|_| {});
/// assert_eq!(rendered.image.width, 40);
///
/// let bad = "Scene(canvas: (40, 30), floor: Color((0.8, 0.8, 2)))";
/// let error = flatray_io::parse(bad, Path::new("bad.ron"), Path::new(".")).unwrap_err();
/// assert_eq!(error.location(), Some((1, 50))); // where the colour ends
/// assert!(error.to_string().contains("each component in [0, 1], found 2"));
/// # Ok::<(), flatray_io::SceneError>(())
/// ```
pub fn parse(text: &str, path: &Path, base: &Path) -> Result<Loaded, SceneError> {
    parse_with(text, path, base, |_| {})
}

/// The time every `Sun` of a scene is set to by [`parse_at`]: a local time
/// of day, and the date where given (otherwise each sun keeps its own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunClock {
    pub date: Option<crate::format::Date>,
    pub time: crate::format::TimeOfDay,
}

/// [`parse`], with every `Sun` of the scene at `clock`'s time (and date),
/// as `flatray day` renders a day's frames.
pub fn parse_at(
    text: &str,
    path: &Path,
    base: &Path,
    clock: SunClock,
) -> Result<Loaded, SceneError> {
    parse_with(text, path, base, |file| {
        for light in &mut file.lights {
            if let LightSpec::Sun { date, time, .. } = light {
                *time = clock.time;
                if let Some(d) = clock.date {
                    *date = d;
                }
            }
        }
    })
}

/// [`parse`], with every `Sun` of the scene off (of intensity 0), as
/// `flatray measure --sun-off` reads a scene for its daylight factor.
pub fn parse_sun_off(text: &str, path: &Path, base: &Path) -> Result<Loaded, SceneError> {
    parse_with(text, path, base, |file| {
        for light in &mut file.lights {
            if let LightSpec::Sun { intensity, .. } = light {
                *intensity = crate::format::Intensity(0.0);
            }
        }
    })
}

fn parse_with(
    text: &str,
    path: &Path,
    base: &Path,
    adjust: impl FnOnce(&mut SceneFile),
) -> Result<Loaded, SceneError> {
    // A UTF-8 byte-order mark is no part of the scene.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut file = scene_file(text).map_err(|e| {
        let (at, message) = crate::explain::explain(&e, text);
        let (line, column) = locate::position(text, at);
        SceneError::Invalid {
            path: path.to_path_buf(),
            line,
            column,
            message,
        }
    })?;
    adjust(&mut file);
    build(file, &Source::Text { text, path }, base)
}

/// Validates scene values given in code rather than in a file (from JSON
/// text, as a binding passes them: the scene file's fields and variants
/// in JSON's syntax); `name` names them in messages and `base` is the
/// folder that relative paths resolve against. Errors point at the value
/// by its path, as `lights[2].Spot.cone`. Warnings name the item by its
/// index, at line and column 0.
pub fn from_json(json: &str, name: &str, base: &Path) -> Result<Loaded, SceneError> {
    let mut deserializer = serde_json::Deserializer::from_str(json);
    let file: SceneFile = serde_path_to_error::deserialize(&mut deserializer).map_err(|e| {
        let at = e.path().to_string();
        let inner = e.into_inner();
        // The values' path says where; the JSON text's own line and
        // column are the binding's, not the caller's.
        let message = inner.to_string();
        let suffix = format!(" at line {} column {}", inner.line(), inner.column());
        SceneError::Value {
            name: name.to_string(),
            at: if at == "." { String::new() } else { at },
            message: crate::explain::with_suggestion(
                message.strip_suffix(&suffix).unwrap_or(&message),
            ),
        }
    })?;
    build(file, &Source::Values { name }, base)
}

/// Where the scene being built comes from, for its messages.
enum Source<'a> {
    Text { text: &'a str, path: &'a Path },
    Values { name: &'a str },
}

/// What a message is about.
#[derive(Clone, Copy)]
enum Place {
    Floor,
    Wall(usize),
    /// A field of a wall's material.
    WallField(usize, &'static str),
    Light(usize),
    /// A field of a light: its index, its kind's name, the field.
    LightField(usize, &'static str, &'static str),
    Glass(usize),
    Room(usize),
    Door(usize),
    Window(usize),
    Top,
}

impl Source<'_> {
    /// An error about `place`: at its line and column in scene text, or
    /// at its path among values.
    fn error(&self, place: Place, message: String) -> SceneError {
        match *self {
            Source::Text { text, path } => {
                let item = |list, k: usize| locate::list_items(text, list).get(k).copied();
                let offset = match place {
                    Place::Floor => locate::field_value(text, "floor"),
                    Place::Wall(k) => item("walls", k),
                    Place::WallField(k, field) => locate::item_range(text, "walls", k)
                        .map(|(start, end)| {
                            text[start..end].find(field).map_or(start, |i| start + i)
                        })
                        .or_else(|| item("walls", k)),
                    Place::Light(k) => item("lights", k),
                    Place::LightField(k, _, field) => locate::item_range(text, "lights", k)
                        .map(|(start, end)| {
                            text[start..end]
                                .find(&format!("{field}:"))
                                .map_or(start, |i| start + i)
                        })
                        .or_else(|| item("lights", k)),
                    Place::Glass(k) => item("glass", k),
                    Place::Room(k) => item("rooms", k),
                    Place::Door(k) => item("doors", k),
                    Place::Window(k) => item("windows", k),
                    Place::Top => None,
                };
                let (line, column) = locate::position(text, offset.unwrap_or(0));
                SceneError::Invalid {
                    path: path.to_path_buf(),
                    line,
                    column,
                    message,
                }
            }
            Source::Values { name } => SceneError::Value {
                name: name.to_string(),
                at: match place {
                    Place::Floor => "floor".to_string(),
                    Place::Wall(k) => format!("walls[{k}]"),
                    Place::WallField(k, field) => format!("walls[{k}].material.{field}"),
                    Place::Light(k) => format!("lights[{k}]"),
                    Place::LightField(k, kind, field) => format!("lights[{k}].{kind}.{field}"),
                    Place::Glass(k) => format!("glass[{k}]"),
                    Place::Room(k) => format!("rooms[{k}]"),
                    Place::Door(k) => format!("doors[{k}]"),
                    Place::Window(k) => format!("windows[{k}]"),
                    Place::Top => String::new(),
                },
                message,
            },
        }
    }
}

/// The scene and render settings of `file`, validated.
fn build(file: SceneFile, source: &Source, base: &Path) -> Result<Loaded, SceneError> {
    let mut inputs = Vec::new();
    let floor = match &file.floor {
        FloorSpec::Color(c) => Floor::Color(rgb(*c)),
        FloorSpec::Tiles {
            size,
            grout_width,
            tile,
            grout,
            variation,
        } => Floor::Tiles {
            size: size.0,
            grout_width: grout_width.0,
            tile: rgb(*tile),
            grout: rgb(*grout),
            variation: variation.0,
        },
        FloorSpec::Image(relative) => {
            let image_path = base.join(relative);
            inputs.push(image_path.clone());
            load_floor_image(&image_path).map_err(|reason| source.error(Place::Floor, reason))?
        }
    };

    let (width, height) = match (file.canvas, &floor) {
        (Some(c), _) => (c.0, c.1),
        (None, Floor::Image { width, height, .. }) => {
            if *width > MAX_CANVAS_SIDE
                || *height > MAX_CANVAS_SIDE
                || *width as u64 * *height as u64 > MAX_CANVAS_PIXELS
            {
                return Err(source.error(
                    Place::Floor,
                    format!("the floor image is {width} x {height}, too large for a canvas"),
                ));
            }
            (*width, *height)
        }
        (None, _) => {
            return Err(source.error(
                Place::Floor,
                "expected a `canvas: (width, height)`: only an image floor gives its own size"
                    .to_string(),
            ));
        }
    };
    let origin = file.origin.map_or(DVec2::ZERO, |p| DVec2::new(p.0, p.1));
    let canvas = Canvas {
        width,
        height,
        origin,
    };

    let default_falloff = falloff(file.falloff);
    let mut walls = Vec::with_capacity(file.walls.len());
    let mut lights = Vec::with_capacity(file.lights.len());
    // What each of `lights` is to the scene's units of light, and where
    // the file has it.
    let mut photometry = Vec::with_capacity(file.lights.len());
    for (wall_index, wall) in file.walls.iter().enumerate() {
        let shape = wall.geometry();
        let segment = shape.chord();
        let material = match wall.material {
            MaterialSpec::FloorDiffuse => Material::Diffuse { albedo: None },
            MaterialSpec::Diffuse { albedo } => Material::Diffuse {
                albedo: albedo.map(rgb),
            },
            MaterialSpec::Mirror { tint } => Material::Mirror { tint: rgb(tint) },
            MaterialSpec::Rough { roughness, tint } => {
                if let Err(message) = flatray_tracer::scene::checks::roughness(roughness) {
                    return Err(source.error(
                        Place::WallField(wall_index, "roughness"),
                        format!("wall {wall_index}: {message}"),
                    ));
                }
                Material::rough(roughness, rgb(tint))
            }
            MaterialSpec::Transparent { tint } => Material::Transparent { tint: rgb(tint) },
        };
        if let Some(EmitSpec {
            color,
            intensity,
            one_sided,
            falloff: light_falloff,
            ..
        }) = wall.emit
        {
            let wall_of_light = Some(walls.len() as u32);
            lights.push(Light {
                profile: None,
                shape: match shape {
                    Shape::Segment(_) => LightShape::Line {
                        segment,
                        one_sided,
                        wall: wall_of_light,
                    },
                    // Two-sided: the file refuses `one_sided` on an arc.
                    Shape::Arc(arc) => LightShape::Arc {
                        arc,
                        wall: wall_of_light,
                    },
                },
                color: rgb(color),
                intensity: intensity.0,
                falloff: light_falloff.map_or(default_falloff, falloff),
                spectrum: light_spectrum(
                    wall.emit.as_ref().and_then(|e| e.spectrum.as_ref()),
                    color,
                )
                .map_err(|message| {
                    source.error(
                        Place::Wall(wall_index),
                        format!("wall {wall_index}: {message}"),
                    )
                })?,
            });
            photometry.push((Photometry::Lamp, Place::Wall(wall_index)));
        }
        walls.push(Wall { shape, material });
    }
    let doors = doors_and_windows(&file, source, &mut walls)?;
    for (k, spec) in file.lights.iter().enumerate() {
        // A sky's frame encloses every wall: it is built once they are.
        if !matches!(spec, LightSpec::Sky { .. }) {
            lights.push(light(k, spec, default_falloff, source, &mut walls)?);
            photometry.push((Photometry::of(spec), Place::Light(k)));
        }
    }

    let mut bodies = Vec::with_capacity(file.glass.len());
    let mut polygons: Vec<Vec<DVec2>> = Vec::with_capacity(file.glass.len());
    for (k, spec) in file.glass.iter().enumerate() {
        let number = bodies.len() as u32;
        let (body, points) = glass_body(k, spec, source, &polygons, &mut walls, number)?;
        bodies.push(body);
        polygons.push(points);
    }

    for (k, sky) in sky_lights(&file, source, &canvas, &walls)? {
        lights.push(sky);
        photometry.push((Photometry::Sky, Place::Light(k)));
    }
    light_units(&file, &mut lights, &photometry, source)?;

    let warnings = match *source {
        Source::Text { text, .. } => {
            let mut warnings = overlap_warnings(text, &walls, file.walls.len());
            warnings.extend(crate::lint::lint(text, &file, &canvas));
            warnings
        }
        // Values have no lines: the messages name the item by its index.
        Source::Values { .. } => {
            let mut warnings = overlap_warnings("", &walls, file.walls.len());
            warnings.extend(crate::lint::lint("", &file, &canvas));
            for w in &mut warnings {
                (w.line, w.column) = (0, 0);
            }
            warnings
        }
    };
    // What the file's types checked, the scene checks again: a failure
    // here is a bound the format does not know, put at the item it names.
    let file_walls = file.walls.len();
    let scene = Scene::with_glass(canvas, floor, file.small_radius.0, walls, lights, bodies)
        .map_err(|invalid| {
            let place = match invalid.item {
                Item::Wall(k) if k < file_walls => Place::Wall(k),
                Item::Glass(k) => Place::Glass(k),
                Item::Floor => Place::Floor,
                _ => Place::Top,
            };
            source.error(place, invalid.to_string())
        })?;
    let mut warnings = warnings;
    warnings.extend(sealed_warnings(source, &file, &scene));
    let options = render_options(&file.render);
    let rooms = named_rooms(&file.rooms, &canvas, source)?;
    Ok(Loaded {
        scene,
        options,
        tonemap: file.render.tonemap,
        inputs,
        counts: Counts {
            walls: file.walls.len(),
            emitting_walls: file.walls.iter().filter(|w| w.emit.is_some()).count(),
            lights: file.lights.len(),
            glass: file.glass.len(),
            suns: file
                .lights
                .iter()
                .filter(|l| matches!(l, LightSpec::Sun { .. }))
                .count(),
        },
        warnings,
        rooms,
        doors,
        metres_per_unit: file.units.map(|u| u.metres_per_unit.0),
        sky: unobstructed_sky(&file),
    })
}

/// The walls the file's doors and windows stand for, added to `walls`: a
/// closed door is a wall of the floor's albedo, an open one none; a
/// window a pane, its shutter an opaque wall over its first share in
/// place of the pane (the two meet end to end, so no light passes
/// between them). Gives the doors' lines, bounds between rooms.
fn doors_and_windows(
    file: &SceneFile,
    source: &Source,
    walls: &mut Vec<Wall>,
) -> Result<Vec<Segment>, SceneError> {
    let ends = |a: crate::format::Point, b: crate::format::Point, place: Place, what: &str| {
        let (a, b) = (DVec2::new(a.0, a.1), DVec2::new(b.0, b.1));
        if a == b {
            Err(source.error(place, format!("{what}: its ends a and b must differ")))
        } else {
            Ok((a, b))
        }
    };
    let mut doors = Vec::with_capacity(file.doors.len());
    for (k, door) in file.doors.iter().enumerate() {
        let (a, b) = ends(door.a, door.b, Place::Door(k), &format!("door {k}"))?;
        if !door.open {
            walls.push(Wall::segment(a, b, Material::Diffuse { albedo: None }));
        }
        doors.push(Segment::new(a, b));
    }
    for (k, window) in file.windows.iter().enumerate() {
        let (a, b) = ends(window.a, window.b, Place::Window(k), &format!("window {k}"))?;
        let share = window.shutter.0;
        let cut = a + (b - a) * share;
        if share > 0.0 && cut != a {
            walls.push(Wall::segment(a, cut, Material::Diffuse { albedo: None }));
        }
        if share < 1.0 && cut != b {
            walls.push(Wall::segment(
                cut,
                b,
                Material::Transparent {
                    tint: rgb(window.tint),
                },
            ));
        }
    }
    Ok(doors)
}

/// The illuminance of a floor open to the file's skies, where every light
/// of the file is a sky or a sun that is off (of intensity 0, or below the
/// horizon) and no wall emits: `2 pi` times the luminance of their
/// radiance, or in lumens ([`LightUnits::Lumens`]) their intensities.
fn unobstructed_sky(file: &SceneFile) -> Option<f64> {
    let lumens = file
        .units
        .is_some_and(|u| matches!(u.light, LightUnits::Lumens { .. }));
    let off = |l: &LightSpec| match *l {
        LightSpec::Sky { .. } => true,
        LightSpec::Sun { intensity, .. } => {
            intensity.0 == 0.0
                || crate::daylight::place_of(l)
                    .and_then(Result::ok)
                    .is_some_and(|p| p.elevation <= 0.0)
        }
        _ => false,
    };
    let only_skies = file
        .lights
        .iter()
        .any(|l| matches!(l, LightSpec::Sky { .. }))
        && file.walls.iter().all(|w| w.emit.is_none())
        && file.lights.iter().all(off);
    only_skies.then(|| {
        file.lights
            .iter()
            .map(|l| match *l {
                LightSpec::Sky {
                    color,
                    intensity,
                    ref profile,
                    north,
                    ..
                } => {
                    let luminance = crate::measure::luminance((color.0, color.1, color.2));
                    // The radiance's integral over the circle.
                    let around = sky_profile_of(profile.as_deref(), north.0)
                        .ok()
                        .flatten()
                        .map_or(std::f64::consts::TAU, |p| p.total());
                    match lumens {
                        true if luminance > 0.0 => intensity.0,
                        true => 0.0,
                        false => around * intensity.0 * luminance,
                    }
                }
                _ => 0.0,
            })
            .sum()
    })
}

/// The file's rooms, each checked: a name of 1 to
/// [`MAX_ROOM_NAME`](crate::rooms::MAX_ROOM_NAME) characters, a point on
/// the canvas, at most [`MAX_ROOMS`](crate::rooms::MAX_ROOMS) of them.
fn named_rooms(
    specs: &[crate::format::RoomSpec],
    canvas: &Canvas,
    source: &Source,
) -> Result<Vec<crate::rooms::NamedRoom>, SceneError> {
    use crate::rooms::{MAX_ROOM_NAME, MAX_ROOMS, NamedRoom};
    if specs.len() > MAX_ROOMS {
        return Err(source.error(
            Place::Room(MAX_ROOMS),
            format!("{} rooms: at most {MAX_ROOMS}", specs.len()),
        ));
    }
    let mut rooms = Vec::with_capacity(specs.len());
    for (k, spec) in specs.iter().enumerate() {
        let chars = spec.name.chars().count();
        if chars == 0 || chars > MAX_ROOM_NAME {
            return Err(source.error(
                Place::Room(k),
                format!(
                    "room {k}: expected a name of 1 to {MAX_ROOM_NAME} characters, found {chars}"
                ),
            ));
        }
        let at = DVec2::new(spec.at.0, spec.at.1);
        if !canvas.contains(at) {
            return Err(source.error(
                Place::Room(k),
                format!(
                    "room {k} ({:?}): its point ({}, {}) lies off the canvas",
                    spec.name, at.x, at.y
                ),
            ));
        }
        if let Some(j) = specs[..k].iter().position(|r| r.name == spec.name) {
            return Err(source.error(
                Place::Room(k),
                format!("room {k}: the name {:?} is room {j}'s already", spec.name),
            ));
        }
        rooms.push(NamedRoom {
            name: spec.name.clone(),
            at,
        });
    }
    Ok(rooms)
}

/// Glass body `k` of the file, checked against the bodies before it
/// (`polygons`, their outlines) and the walls; its edges are added to
/// `walls` as the edges of body number `body`. Gives the body and its
/// outline.
fn glass_body(
    k: usize,
    spec: &crate::format::GlassSpec,
    source: &Source,
    polygons: &[Vec<DVec2>],
    walls: &mut Vec<Wall>,
    body: u32,
) -> Result<(GlassBody, Vec<DVec2>), SceneError> {
    let corners: Vec<DVec2> = spec.points.iter().map(|p| DVec2::new(p.0, p.1)).collect();
    let located = |message: String| source.error(Place::Glass(k), message);
    let edges = glass_edges(&corners, &spec.through).map_err(located)?;
    // Arcs are checked as fine polygons: every test below is of the
    // outline's shape, not of its rays.
    let points = flattened(&edges);
    validate_polygon(&points).map_err(located)?;
    for (j, other) in polygons.iter().enumerate() {
        if polygons_cross(&points, other) {
            return Err(located(format!(
                "glass {k} crosses glass {j}: glass bodies must not overlap"
            )));
        }
        // Edges apart, one may still hold the other whole.
        if inside_polygon(points[0], other) || inside_polygon(other[0], &points) {
            return Err(located(format!(
                "glass {k} and glass {j} lie one inside the other: glass bodies must not overlap"
            )));
        }
    }
    for (i, shape) in edges.iter().enumerate() {
        let Shape::Segment(edge) = *shape else {
            continue;
        };
        // Along a wall, by the rule for walls that overlap (rule 8),
        // which glass edges take no part in.
        let along = |w: &Wall| {
            w.as_segment().is_some_and(|s| {
                flatray_geometry::overlap::overlap(
                    &edge,
                    s,
                    flatray_geometry::overlap::Tolerance::Rounding,
                )
            })
        };
        if let Some(w) = walls.iter().position(along) {
            return Err(located(format!(
                "glass edge {i} lies along wall {w}: glass may touch a wall at a point, not along an edge"
            )));
        }
    }
    let area: f64 = (0..points.len())
        .map(|i| flatray_geometry::cross(points[i], points[(i + 1) % points.len()]))
        .sum();
    let inside = if area > 0.0 {
        Side::Positive
    } else {
        Side::Negative
    };
    for shape in edges {
        // A segment's `Positive` side is its left; an arc's is away
        // from its centre, and the glass lies towards the centre where
        // the outline turns the arc's way.
        let inside = match shape {
            Shape::Segment(_) => inside,
            Shape::Arc(arc) => {
                if (inside == Side::Positive) == (arc.turn > 0.0) {
                    Side::Negative
                } else {
                    Side::Positive
                }
            }
        };
        walls.push(Wall {
            shape,
            material: Material::Glass { body, inside },
        });
    }
    let glass = GlassBody {
        ior: spec.ior.0,
        dispersion: spec.dispersion.0,
        absorption: spec
            .absorption
            .map_or(Rgb::ZERO, |(r, g, b)| Rgb::new(r.0, g.0, b.0)),
        roughness: spec.roughness.0,
    };
    Ok((glass, points))
}

/// Light `k` of the file, checked; errors stand at the light (or its
/// field).
/// A solid line light's black wall is added to `walls`.
fn light(
    k: usize,
    light: &LightSpec,
    default_falloff: Falloff,
    source: &Source,
    walls: &mut Vec<Wall>,
) -> Result<Light, SceneError> {
    let spectrum = light_spectrum(light.spectrum(), light.color()).map_err(|message| {
        let field = if light.spectrum().is_some() {
            "spectrum"
        } else {
            "color"
        };
        source.error(
            Place::LightField(k, light.kind(), field),
            format!("light {k}: {message}"),
        )
    })?;
    let mut built = match *light {
        LightSpec::Point {
            at,
            color,
            intensity,
            falloff: f,
            ..
        } => lamp(
            LightShape::Point {
                at: DVec2::new(at.0, at.1),
            },
            rgb(color),
            intensity.0,
            f.map_or(default_falloff, falloff),
        ),
        LightSpec::Spot {
            at,
            direction,
            cone,
            softness,
            color,
            intensity,
            falloff: f,
            ..
        } => {
            if cone.0 > 180.0 || softness.0 > cone.0 {
                let field = if cone.0 > 180.0 { "cone" } else { "softness" };
                return Err(source.error(
                    Place::LightField(k, "Spot", field),
                    format!(
                        "expected 0 < cone <= 180 and softness <= cone (degrees), found cone {} and softness {}",
                        cone.0, softness.0
                    ),
                ));
            }
            lamp(
                LightShape::Spot {
                    at: DVec2::new(at.0, at.1),
                    direction: DVec2::new(direction.0, direction.1),
                    cone: cone.0.to_radians(),
                    softness: softness.0.to_radians(),
                },
                rgb(color),
                intensity.0,
                f.map_or(default_falloff, falloff),
            )
        }
        LightSpec::Line {
            a,
            b,
            color,
            intensity,
            one_sided,
            solid,
            falloff: f,
            ..
        } => {
            if a == b {
                return Err(source.error(
                    Place::LightField(k, "Line", "b"),
                    format!(
                        "a line light needs two different endpoints, found ({}, {}) twice; use a Point light",
                        a.0, a.1
                    ),
                ));
            }
            let segment = Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1));
            let wall = if solid {
                walls.push(Wall {
                    shape: Shape::Segment(segment),
                    material: Material::Diffuse {
                        albedo: Some(Rgb::ZERO),
                    },
                });
                Some(walls.len() as u32 - 1)
            } else {
                None
            };
            lamp(
                LightShape::Line {
                    segment,
                    one_sided,
                    wall,
                },
                rgb(color),
                intensity.0,
                f.map_or(default_falloff, falloff),
            )
        }
        LightSpec::Circle {
            at,
            radius,
            color,
            intensity,
            falloff: f,
            ..
        } => {
            if radius.0 > MAX_COORDINATE {
                return Err(source.error(
                    Place::LightField(k, "Circle", "radius"),
                    format!(
                        "expected a circle light's radius of at most {MAX_COORDINATE:e}, found {}",
                        radius.0
                    ),
                ));
            }
            lamp(
                LightShape::Circle {
                    at: DVec2::new(at.0, at.1),
                    radius: radius.0,
                },
                rgb(color),
                intensity.0,
                f.map_or(default_falloff, falloff),
            )
        }
        LightSpec::Directional {
            direction,
            color,
            intensity,
            ..
        } => lamp(
            LightShape::Directional {
                direction: DVec2::new(direction.0, direction.1),
            },
            rgb(color),
            intensity.0,
            Falloff::Constant,
        ),
        LightSpec::Beam {
            a,
            b,
            direction,
            color,
            intensity,
            ..
        } => {
            let segment = Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1));
            let direction = DVec2::new(direction.0, direction.1);
            let shape = LightShape::Beam { segment, direction };
            if let Err(message) = flatray_tracer::scene::checks::light_shape(&shape) {
                return Err(source.error(Place::Light(k), format!("light {k}: {message}")));
            }
            lamp(shape, rgb(color), intensity.0, Falloff::Constant)
        }
        // A sky is built with the walls' frame, in `build` (`sky_lights`).
        LightSpec::Sun { .. } | LightSpec::Sky { .. } => sun(k, light, source)?,
        LightSpec::Laser {
            at,
            direction,
            color,
            intensity,
            ..
        } => lamp(
            LightShape::Laser {
                at: DVec2::new(at.0, at.1),
                direction: DVec2::new(direction.0, direction.1),
            },
            rgb(color),
            intensity.0,
            Falloff::Constant,
        ),
    };
    built.spectrum = spectrum;
    Ok(built)
}

/// A light of `shape`, `color`, `intensity` and `falloff`, without a
/// spectrum (the caller sets the file's) or a profile (a sky's lines
/// have theirs).
fn lamp(shape: LightShape, color: Rgb, intensity: f64, falloff: Falloff) -> Light {
    Light {
        shape,
        color,
        intensity,
        falloff,
        spectrum: None,
        profile: None,
    }
}

/// The render settings a scene's `render: (...)` asks for.
fn render_options(spec: &crate::format::RenderSpec) -> RenderOptions {
    let mut options = RenderOptions::default();
    options.samples = spec.samples.0;
    options.bounces = spec.bounces.0;
    options.specular = spec.specular.0;
    options.seed = spec.seed;
    options.exposure = spec.exposure.0;
    options.scale = 1.0;
    options.integrator = match spec.integrator {
        IntegratorSpec::Path => Integrator::Path,
        IntegratorSpec::Original => Integrator::Original,
        IntegratorSpec::Light => Integrator::Light,
    };
    options.memo.enabled = spec.cache.memo().0;
    options.memo.onward = spec.cache.memo().1;
    options.memo.bin_length = spec.cache_bin.0;
    options.memo.floor_samples = spec.cache_floor_samples.0;
    options.caustics = spec.caustics;
    options.light_choice = match spec.lights {
        LightsSpec::Auto => LightChoice::Auto,
        LightsSpec::Every => LightChoice::Every,
        LightsSpec::Table => LightChoice::Table,
    };
    options
}

/// The line lights of the file's skies, on a frame around `canvas` and
/// every one of `walls` (`crate::daylight::sky_frame`).
fn sky_lights(
    file: &SceneFile,
    source: &Source,
    canvas: &Canvas,
    walls: &[Wall],
) -> Result<Vec<(usize, Light)>, SceneError> {
    let mut lights = Vec::new();
    for (k, spec) in file.lights.iter().enumerate() {
        if let LightSpec::Sky {
            color,
            intensity,
            ref profile,
            north,
            ..
        } = *spec
        {
            let spectrum = light_spectrum(spec.spectrum(), color).map_err(|message| {
                source.error(Place::Light(k), format!("light {k}: {message}"))
            })?;
            let profile = sky_profile_of(profile.as_deref(), north.0)
                .map_err(|message| source.error(Place::Light(k), format!("light {k}: {message}")))?
                .map(std::sync::Arc::new);
            for segment in crate::daylight::sky_frame(canvas, walls) {
                lights.push((
                    k,
                    Light {
                        shape: LightShape::Line {
                            segment,
                            one_sided: true,
                            wall: None,
                        },
                        color: rgb(color),
                        intensity: intensity.0,
                        // Radiance: each radian of sky brings `intensity`.
                        falloff: Falloff::Flatland,
                        spectrum,
                        profile: profile.clone(),
                    },
                ));
            }
        }
    }
    Ok(lights)
}

/// A sky's profile from the file's pairs of azimuth and factor, if it
/// has one.
fn sky_profile_of(
    knots: Option<&[(Finite, NonNegative)]>,
    north: f64,
) -> Result<Option<Profile>, String> {
    let Some(knots) = knots else {
        return Ok(None);
    };
    let pairs: Vec<(f64, f64)> = knots.iter().map(|(a, f)| (a.0, f.0)).collect();
    crate::daylight::sky_profile(&pairs, north)
        .map(Some)
        .map_err(|e| format!("the sky's profile: {e}"))
}

/// The file's lights in the renderer's units: with
/// [`LightUnits::Lumens`], each of `lights` turned from photometric units
/// by what `photometry` says it is ([`in_lumens`]); else as they are.
fn light_units(
    file: &SceneFile,
    lights: &mut [Light],
    photometry: &[(Photometry, Place)],
    source: &Source,
) -> Result<(), SceneError> {
    let Some(Units {
        metres_per_unit,
        light: LightUnits::Lumens { storey },
    }) = file.units
    else {
        return Ok(());
    };
    for (light, &(kind, place)) in lights.iter_mut().zip(photometry) {
        in_lumens(light, kind, (storey.0, metres_per_unit.0)).map_err(|message| {
            let what = match place {
                Place::Wall(w) => format!("wall {w}"),
                Place::Light(k) => format!("light {k}"),
                _ => "a light".to_string(),
            };
            source.error(place, format!("{what}: {message}"))
        })?;
    }
    Ok(())
}

/// What a light is to the scene's units of light ([`LightUnits`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Photometry {
    /// A lamp or an emitting wall: its intensity is a luminous flux.
    Lamp,
    /// A sun or a directional light: its intensity is the illuminance of
    /// a surface facing it.
    Sun,
    /// One of a sky's frame of lines: its intensity is the illuminance of
    /// a floor open to the sky.
    Sky,
}

impl Photometry {
    /// What the file's light `spec` is (not a sky, which is built apart).
    fn of(spec: &LightSpec) -> Photometry {
        match spec {
            LightSpec::Sun { .. } | LightSpec::Directional { .. } => Photometry::Sun,
            _ => Photometry::Lamp,
        }
    }
}

/// `light`'s intensity, given in the photometric units of
/// [`LightUnits::Lumens`] (a storey `storey` metres high, `metres` a world
/// unit), turned into the renderer's, so that the floor's fluence is in
/// lux under the 2.5D reading (`docs/model.md`): a lamp of flux `F` lm
/// sends `F / storey` lm per metre of height, its power in world units
/// `F / (storey metres)`; luminance weights its colour (a spectrum's is
/// 1).
fn in_lumens(
    light: &mut Light,
    kind: Photometry,
    (storey, metres): (f64, f64),
) -> Result<(), String> {
    let luminance = match light.spectrum {
        Some(_) => 1.0,
        None => crate::measure::luminance(light.color.into()),
    };
    if luminance.is_nan() || luminance <= 0.0 {
        // A black light sends nothing, in any units.
        light.intensity = 0.0;
        return Ok(());
    }
    let per_unit = match kind {
        Photometry::Sun => 1.0,
        // The illuminance of an open floor over its radiance.
        Photometry::Sky => light
            .profile
            .as_ref()
            .map_or(std::f64::consts::TAU, |p| p.total()),
        Photometry::Lamp => {
            if matches!(
                light.falloff,
                Falloff::InverseSquare | Falloff::Window { .. }
            ) {
                return Err(
                    "lumens (`units: (light: Lumens(..))`) need the physical falloff: `falloff: Flatland` (the default)"
                        .to_string(),
                );
            }
            let power = light.shape.lamp_power().unwrap_or(0.0);
            if power.is_nan() || power <= 0.0 {
                return Err("a lamp of no size has no luminous flux to spread".to_string());
            }
            storey * metres * power
        }
    };
    light.intensity /= per_unit * luminance;
    Ok(())
}

/// The directional light that sun `light` (light `k` of the file) stands
/// for: along the sun's azimuth, its irradiance on the floor the rays'
/// times the sine of the sun's elevation; below the horizon, nothing.
fn sun(k: usize, light: &LightSpec, source: &Source) -> Result<Light, SceneError> {
    let LightSpec::Sun {
        date,
        time,
        zone,
        latitude,
        longitude,
        north,
        color,
        intensity,
        ..
    } = *light
    else {
        return Err(source.error(
            Place::Light(k),
            format!("light {k}: a sky has no place of its own: it is built around the walls"),
        ));
    };
    let place = crate::daylight::sun_place(date, time, zone.0, latitude.0, longitude.0)
        .map_err(|message| source.error(Place::Light(k), format!("light {k}: {message}")))?;
    let elevation = place.elevation.to_radians();
    Ok(Light {
        profile: None,
        shape: LightShape::Directional {
            direction: crate::daylight::sun_direction(place.azimuth, north.0),
        },
        color: rgb(color),
        intensity: intensity.0 * elevation.sin().max(0.0),
        falloff: Falloff::Constant,
        spectrum: None,
    })
}

/// The warnings that need the built scene (its walls' hierarchy): lights
/// sealed in small loops of walls.
fn sealed_warnings(source: &Source, file: &SceneFile, scene: &Scene) -> Vec<Warning> {
    match *source {
        Source::Text { text, .. } => crate::lint::sealed(text, file, scene),
        // Values have no lines: the messages name the item by its index.
        Source::Values { .. } => crate::lint::sealed("", file, scene)
            .into_iter()
            .map(|w| Warning {
                line: 0,
                column: 0,
                ..w
            })
            .collect(),
    }
}

/// A warning for each wall of the file (the first `listed` walls) that lies
/// on top of an earlier one: the two are resolved into walls that do not
/// overlap (`docs/robustness.md`, rule 8), which may not be what was meant.
fn overlap_warnings(text: &str, walls: &[Wall], listed: usize) -> Vec<Warning> {
    let segments: Vec<Segment> = walls.iter().map(|w| w.shape.chord()).collect();
    let groups = flatray_geometry::overlap::overlap_groups(&segments, |i| {
        i < listed && walls[i].as_segment().is_some()
    });
    if groups.is_empty() {
        return Vec::new();
    }
    let items = locate::list_items(text, "walls");
    let kind = |w: &Wall| w.material.noun();
    let same = |x: &Wall, y: &Wall| {
        let (p, q) = (x.shape.chord(), y.shape.chord());
        x.material == y.material && ((p.a == q.a && p.b == q.b) || (p.a == q.b && p.b == q.a))
    };
    let mut out = Vec::new();
    for group in groups {
        let first = group[0];
        for &i in &group[1..] {
            let (line, column) = locate::position(text, items.get(i).copied().unwrap_or(0));
            let what = match (kind(&walls[i]), kind(&walls[first])) {
                ("pane", "wall" | "mirror") | ("wall" | "mirror", "pane") => {
                    ": the pane lets no light through there; to put a window in a wall, end the wall at the window's ends"
                }
                ("mirror", "wall") | ("wall", "mirror") => ": the mirror is what light meets there",
                ("wall", "wall") if same(&walls[i], &walls[first]) => ": it is the same wall twice",
                _ => "",
            };
            out.push(Warning {
                line,
                column,
                message: format!(
                    "{} {i} lies on top of {} {first} (counting walls from 0), and the two are made one by the rule for walls that overlap (docs/robustness.md, rule 8){what}",
                    kind(&walls[i]),
                    kind(&walls[first]),
                ),
            });
        }
    }
    out
}

/// A closed polygon of at least three points whose edges have length and
/// meet only at shared corners (no edge crosses or touches another).
fn validate_polygon(points: &[DVec2]) -> Result<(), String> {
    let n = points.len();
    if n < 3 {
        return Err(format!(
            "a glass polygon needs at least 3 points, found {n}"
        ));
    }
    let edge = |i: usize| Segment::new(points[i], points[(i + 1) % n]);
    for i in 0..n {
        if edge(i).length() == 0.0 {
            return Err(format!(
                "glass edge {i} has zero length (point {i} repeats)"
            ));
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            let (a, b) = (edge(i), edge(j));
            let touch = if adjacent {
                // Adjacent edges share one corner; they must not fold back
                // over each other.
                let shared = if j == i + 1 { a.b } else { a.a };
                let (u, v) = (
                    if j == i + 1 {
                        a.a - shared
                    } else {
                        a.b - shared
                    },
                    if j == i + 1 {
                        b.b - shared
                    } else {
                        b.a - shared
                    },
                );
                flatray_geometry::cross(u, v) == 0.0 && u.dot(v) > 0.0
            } else {
                flatray_geometry::segments_meet(&a, &b)
            };
            if touch {
                return Err(format!(
                    "the glass polygon intersects itself (edges {i} and {j}): expected a simple polygon"
                ));
            }
        }
    }
    if (0..n)
        .map(|i| flatray_geometry::cross(points[i], points[(i + 1) % n]))
        .sum::<f64>()
        == 0.0
    {
        return Err("the glass polygon has no area".to_string());
    }
    Ok(())
}

/// A glass body's outline as a polygon, its arcs as fine polylines (the
/// corners alone where its edges are not valid).
pub(crate) fn glass_outline(spec: &crate::format::GlassSpec) -> Vec<DVec2> {
    let corners: Vec<DVec2> = spec.points.iter().map(|p| DVec2::new(p.0, p.1)).collect();
    match glass_edges(&corners, &spec.through) {
        Ok(edges) => flattened(&edges),
        Err(_) => corners,
    }
}

/// A glass outline's edges: from each corner to the next, straight, or an
/// arc through the edge's `through` point.
pub(crate) fn glass_edges(
    corners: &[DVec2],
    through: &[Option<crate::format::Point>],
) -> Result<Vec<Shape>, String> {
    let n = corners.len();
    if !through.is_empty() && through.len() != n {
        return Err(format!(
            "expected `through` to give one entry per edge ({n}, as many as points), found {}",
            through.len()
        ));
    }
    if n < 2 || (n == 2 && through.iter().all(Option::is_none)) {
        return Err(format!(
            "a glass body needs at least 3 points, or 2 joined by arcs, found {n}"
        ));
    }
    (0..n)
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            match through.get(i).copied().flatten() {
                None => Ok(Shape::Segment(Segment::new(a, b))),
                Some(m) => flatray_geometry::Arc::through(a, DVec2::new(m.0, m.1), b)
                    .map(Shape::Arc)
                    .map_err(|_| {
                        format!(
                            "glass edge {i}: an arc's three points must not lie on one line, found ({}, {}), through ({}, {}), ({}, {})",
                            a.x, a.y, m.0, m.1, b.x, b.y
                        )
                    }),
            }
        })
        .collect()
}

/// Points along each arc of an outline: its shape to a
/// thousandth of its chord, for the tests of its shape.
const ARC_POINTS: usize = 64;

/// The outline of `edges` as a polygon: each corner, and along each arc
/// [`ARC_POINTS`] points.
fn flattened(edges: &[Shape]) -> Vec<DVec2> {
    let mut points = Vec::new();
    for edge in edges {
        points.push(edge.a());
        if let Shape::Arc(arc) = edge {
            points.extend((1..ARC_POINTS).map(|k| arc.point_at(k as f64 / ARC_POINTS as f64)));
        }
    }
    points
}

/// Whether `p` lies inside the polygon `v` (even-odd rule).
pub(crate) fn inside_polygon(p: DVec2, v: &[DVec2]) -> bool {
    let mut inside = false;
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// Whether any edge of one polygon meets an edge of the other.
fn polygons_cross(p: &[DVec2], q: &[DVec2]) -> bool {
    let edges = |v: &[DVec2]| -> Vec<Segment> {
        (0..v.len())
            .map(|i| Segment::new(v[i], v[(i + 1) % v.len()]))
            .collect()
    };
    let (ep, eq) = (edges(p), edges(q));
    ep.iter()
        .any(|a| eq.iter().any(|b| flatray_geometry::segments_meet(a, b)))
}

fn rgb(c: Color) -> Rgb {
    Rgb::new(c.0, c.1, c.2)
}

fn falloff(f: FalloffSpec) -> Falloff {
    match f {
        FalloffSpec::Flatland => Falloff::Flatland,
        FalloffSpec::InverseSquare => Falloff::InverseSquare,
        FalloffSpec::Window { range } => Falloff::Window { range: range.0 },
        FalloffSpec::Constant => Falloff::Constant,
    }
}

/// Loads an image as linear albedo (its 8-bit values decoded from sRGB).
/// At most this many texels in a floor image (each held as linear RGB in
/// 24 bytes: 384 MiB), checked from its header before it is decoded.
pub const MAX_FLOOR_TEXELS: u64 = 1 << 24;

/// Why an image could not be decoded.
pub(crate) enum ImageFailure {
    /// Its header gives more pixels than allowed: width, height.
    TooLarge(u32, u32),
    /// Not an image, or not one the decoders read.
    Unreadable(String),
}

/// Decodes the image in `bytes`, refusing from its header, before
/// anything is decoded, one of more than `max_pixels`, and decoding under
/// an allocation limit to match.
pub(crate) fn decode_within(
    bytes: &[u8],
    max_pixels: u64,
) -> Result<image::DynamicImage, ImageFailure> {
    let unreadable = |e: image::ImageError| ImageFailure::Unreadable(e.to_string());
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| ImageFailure::Unreadable(e.to_string()))
    };
    let (width, height) = reader()?.into_dimensions().map_err(unreadable)?;
    if width as u64 * height as u64 > max_pixels {
        return Err(ImageFailure::TooLarge(width, height));
    }
    let mut reader = reader()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    limits.max_alloc = Some(max_pixels * 16);
    reader.limits(limits);
    reader.decode().map_err(unreadable)
}

fn load_floor_image(path: &Path) -> Result<Floor, String> {
    let cannot =
        |e: &dyn std::fmt::Display| format!("cannot load the floor image {}: {e}", path.display());
    let bytes = crate::read_within(path, crate::MAX_INPUT_BYTES).map_err(|e| cannot(&e))?;
    let decoded = decode_within(&bytes, MAX_FLOOR_TEXELS).map_err(|failure| match failure {
        ImageFailure::TooLarge(width, height) => format!(
            "the floor image {} is {width} x {height} pixels, more than the {MAX_FLOOR_TEXELS} flatray reads: scale it down (one texel per pixel of the canvas is plenty)",
            path.display()
        ),
        ImageFailure::Unreadable(e) => cannot(&e),
    })?;
    let rgb8 = decoded.to_rgb8();
    let (width, height) = rgb8.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("the floor image {} is empty", path.display()));
    }
    let texels = rgb8
        .pixels()
        .map(|p| {
            Rgb::new(
                crate::output::srgb_to_linear(p.0[0]),
                crate::output::srgb_to_linear(p.0[1]),
                crate::output::srgb_to_linear(p.0[2]),
            )
        })
        .collect();
    Ok(Floor::Image {
        width,
        height,
        texels,
    })
}

/// The spectrum a light gives in place of its `color`, checked: a light
/// takes one or the other, so a colour given beside a spectrum is an
/// error rather than ignored.
pub(crate) fn light_spectrum(
    spec: Option<&SpectrumSpec>,
    color: Color,
) -> Result<Option<flatray_tracer::spectrum::Spectrum>, String> {
    use flatray_tracer::spectrum::{Lamp, Spectrum};
    let Some(spec) = spec else {
        return Ok(None);
    };
    if color != Color::WHITE {
        return Err("a light takes its colour from `color` or from `spectrum`, not both".into());
    }
    let spectrum = match spec {
        SpectrumSpec::Blackbody(kelvin) => Spectrum::Blackbody { kelvin: *kelvin },
        SpectrumSpec::Lamp(name) => Spectrum::Lamp(match name {
            LampName::Sodium => Lamp::Sodium,
            LampName::Mercury => Lamp::Mercury,
            LampName::Neon => Lamp::Neon,
            LampName::Hydrogen => Lamp::Hydrogen,
        }),
        SpectrumSpec::Table(pairs) => Spectrum::table(pairs)?,
    };
    flatray_tracer::scene::checks::spectrum(&spectrum)?;
    Ok(Some(spectrum))
}
