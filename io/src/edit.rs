//! Edits to a scene file's text, as a live view makes them (a light
//! dragged, a wall's, a door's or a window's end moved, an intensity, a
//! colour or a material changed, a door opened, a shutter drawn), and the
//! scene's items as the view draws them.
//!
//! An edit rewrites only the value it changes, in place, so the rest of
//! the file (its comments, its layout, every other number as written)
//! stays as it was. The edited text is checked by the same loader as any
//! scene: an edit that makes the scene invalid is refused with the
//! loader's message, and the text is not changed.

use std::path::Path;

use flatray_geometry::DVec2;
use serde::{Deserialize, Serialize};

use crate::format::{LightSpec, MaterialSpec};
use crate::locate;

/// One edit, by the item's place in its list (counting from 0, as the
/// loader's messages do).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum Edit {
    /// Moves a point, spot or circle light to `to`.
    MoveLight { index: usize, to: (f64, f64) },
    /// Moves one end (`a` or `b`) of a line light.
    MoveLightEnd {
        index: usize,
        end: End,
        to: (f64, f64),
    },
    /// Moves one end of a wall.
    MoveWallEnd {
        index: usize,
        end: End,
        to: (f64, f64),
    },
    /// Sets a light's intensity.
    LightIntensity { index: usize, value: f64 },
    /// Sets a light's colour (a light that had a spectrum takes the
    /// colour in its place).
    LightColor {
        index: usize,
        value: (f64, f64, f64),
    },
    /// Gives a light a spectrum in place of its colour.
    LightSpectrum {
        index: usize,
        spectrum: SpectrumKind,
    },
    /// Turns a spot or the sun: its direction, which need not be of unit
    /// length.
    LightDirection { index: usize, to: (f64, f64) },
    /// Sets a wall's material.
    WallMaterial {
        index: usize,
        material: MaterialKind,
    },
    /// Moves one end of a door.
    MoveDoorEnd {
        index: usize,
        end: End,
        to: (f64, f64),
    },
    /// Opens or shuts a door.
    DoorOpen { index: usize, open: bool },
    /// Moves one end of a window.
    MoveWindowEnd {
        index: usize,
        end: End,
        to: (f64, f64),
    },
    /// Sets the share of a window (from its end `a`) that its shutter
    /// covers, 0 to 1.
    WindowShutter { index: usize, value: f64 },
}

/// An end of a segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum End {
    A,
    B,
}

impl End {
    fn field(self) -> &'static str {
        match self {
            End::A => "a",
            End::B => "b",
        }
    }
}

/// The spectra the live view offers.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub enum SpectrumKind {
    /// Planck's law at a temperature in kelvin.
    Blackbody(f64),
    /// A gas-discharge lamp: `Sodium`, `Mercury`, `Neon` or `Hydrogen`.
    Lamp(crate::format::LampName),
}

/// The materials a wall can be switched to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum MaterialKind {
    Diffuse,
    Mirror,
    /// A rough mirror of the format's default roughness.
    Rough,
    Transparent,
}

/// `text` with `edit` made: only the edited value is rewritten (or, when
/// the item does not give it, added at the item's end). The result is
/// checked as a scene (`path` names it in messages, `base` resolves its
/// floor image), and given back with what it loads as; an edit that
/// leaves no valid scene is refused with the loader's message.
pub fn apply(
    text: &str,
    edit: &Edit,
    path: &Path,
    base: &Path,
) -> Result<(String, crate::Loaded), String> {
    let (list, index) = match *edit {
        Edit::MoveLight { index, .. }
        | Edit::MoveLightEnd { index, .. }
        | Edit::LightIntensity { index, .. }
        | Edit::LightColor { index, .. }
        | Edit::LightSpectrum { index, .. }
        | Edit::LightDirection { index, .. } => ("lights", index),
        Edit::MoveWallEnd { index, .. } | Edit::WallMaterial { index, .. } => ("walls", index),
        Edit::MoveDoorEnd { index, .. } | Edit::DoorOpen { index, .. } => ("doors", index),
        Edit::MoveWindowEnd { index, .. } | Edit::WindowShutter { index, .. } => ("windows", index),
    };
    let item = locate::item_range(text, list, index)
        .ok_or_else(|| format!("there is no item {index} in `{list}` (counting from 0)"))?;
    // A light takes its colour from `color` or from `spectrum`: setting
    // one drops the other.
    let (text, item) = match *edit {
        Edit::LightColor { .. } => without_field(text, item, "spectrum"),
        Edit::LightSpectrum { .. } => without_field(text, item, "color"),
        _ => (text.to_string(), item),
    };
    let text = text.as_str();
    let (field, value) = match *edit {
        Edit::MoveLight { to, .. } => ("at", point(to)?),
        Edit::MoveLightEnd { end, to, .. }
        | Edit::MoveWallEnd { end, to, .. }
        | Edit::MoveDoorEnd { end, to, .. }
        | Edit::MoveWindowEnd { end, to, .. } => (end.field(), point(to)?),
        Edit::DoorOpen { open, .. } => ("open", open.to_string()),
        Edit::WindowShutter { value, .. } => ("shutter", number(value)?),
        Edit::LightIntensity { value, .. } => ("intensity", number(value)?),
        Edit::LightColor {
            value: (r, g, b), ..
        } => (
            "color",
            format!("({}, {}, {})", number(r)?, number(g)?, number(b)?),
        ),
        Edit::LightSpectrum { spectrum, .. } => (
            "spectrum",
            match spectrum {
                SpectrumKind::Blackbody(kelvin) => format!("Blackbody({})", number(kelvin)?),
                SpectrumKind::Lamp(lamp) => format!("Lamp({lamp:?})"),
            },
        ),
        Edit::LightDirection { to, .. } => ("direction", point(to)?),
        Edit::WallMaterial { material, .. } => (
            "material",
            match material {
                MaterialKind::Diffuse => "Diffuse()",
                MaterialKind::Mirror => "Mirror()",
                MaterialKind::Rough => "Rough()",
                MaterialKind::Transparent => "Transparent()",
            }
            .to_string(),
        ),
    };
    let edited = match locate::item_field(text, item, field) {
        Some((start, end)) => format!("{}{value}{}", &text[..start], &text[end..]),
        None => {
            // Before the item's closing bracket, after a comma if the
            // last field has none.
            let close = item.1.saturating_sub(1);
            if !text[..item.1].ends_with(')') {
                return Err(format!("item {index} of `{list}` has no `{field}` to set"));
            }
            let before = text[item.0..close].trim_end();
            let comma = if before.ends_with('(') {
                ""
            } else if before.ends_with(',') {
                " "
            } else {
                ", "
            };
            let at = item.0 + before.len();
            format!("{}{comma}{field}: {value}{}", &text[..at], &text[at..])
        }
    };
    let loaded = crate::parse(&edited, path, base).map_err(|e| match e {
        crate::SceneError::Invalid { message, .. } => message,
        other => other.to_string(),
    })?;
    Ok((edited, loaded))
}

/// `text` without `field` (its name, value and comma) in `item`, and the
/// item's new range; as it was when the item has no such field.
fn without_field(text: &str, item: (usize, usize), field: &str) -> (String, (usize, usize)) {
    let Some((start, end)) = locate::item_field(text, item, field) else {
        return (text.to_string(), item);
    };
    let Some(name) = text[item.0..start].rfind(field).map(|i| item.0 + i) else {
        return (text.to_string(), item);
    };
    let rest = &text[end..item.1];
    let after = rest.trim_start();
    let (from, to) = if let Some(tail) = after.strip_prefix(',') {
        // `field: v, next` -> `next`
        let skip = rest.len() - tail.trim_start().len();
        (name, end + skip)
    } else {
        // The last field: take the comma before it instead.
        let before = text[item.0..name].trim_end();
        let from = match before.strip_suffix(',') {
            Some(kept) => item.0 + kept.len(),
            None => name,
        };
        (from, end)
    };
    let mut out = String::with_capacity(text.len());
    out.push_str(&text[..from]);
    out.push_str(&text[to..]);
    (out, (item.0, item.1 - (to - from)))
}

/// A number as a scene writes it: at most a thousandth of a unit, no
/// trailing zeros.
fn number(v: f64) -> Result<String, String> {
    if !v.is_finite() {
        return Err(format!("expected a finite number, found {v}"));
    }
    let rounded = (v * 1000.0).round() / 1000.0;
    let rounded = if rounded == 0.0 { 0.0 } else { rounded };
    Ok(format!("{rounded}"))
}

fn point((x, y): (f64, f64)) -> Result<String, String> {
    Ok(format!("({}, {})", number(x)?, number(y)?))
}

/// What a live view draws of a scene: the canvas, and the items in the
/// file's own order (so that an edit names them by the same index).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Items {
    pub canvas: (u32, u32),
    pub origin: (f64, f64),
    pub walls: Vec<WallItem>,
    pub lights: Vec<LightItem>,
    pub glass: Vec<GlassItem>,
    pub doors: Vec<DoorItem>,
    pub windows: Vec<WindowItem>,
}

/// A door as drawn: its ends, and whether it is open.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DoorItem {
    pub a: (f64, f64),
    pub b: (f64, f64),
    pub open: bool,
}

/// A window as drawn: its ends, and the share its shutter covers from
/// `a`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WindowItem {
    pub a: (f64, f64),
    pub b: (f64, f64),
    pub shutter: f64,
}

/// A glass body as drawn: its corners, and its outline as SVG path data
/// in world units, each edge straight or the arc it is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GlassItem {
    pub points: Vec<(f64, f64)>,
    pub path: String,
}

/// What a light's spectrum is, for the live view to offer.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind")]
pub enum SpectrumItem {
    Blackbody { kelvin: f64 },
    Lamp { lamp: &'static str },
    Table,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WallItem {
    pub a: (f64, f64),
    pub b: (f64, f64),
    /// For an arc or a circle, its curve as SVG path data in world units
    /// (`M a A r r 0 large sweep b`; a circle as two half circles).
    pub curve: Option<String>,
    /// Whether its ends can be moved: not a circle's, which has none.
    pub ends: bool,
    /// `Diffuse`, `Mirror` or `Transparent`.
    pub material: &'static str,
    /// The wall's own colour (albedo or tint), `None` for a diffuse wall
    /// that takes the floor's.
    pub color: Option<(f64, f64, f64)>,
    pub emits: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightItem {
    /// `Point`, `Spot`, `Line`, `Circle` or `Directional`.
    pub kind: &'static str,
    /// Where a point, spot or circle light stands.
    pub at: Option<(f64, f64)>,
    /// A line light's ends.
    pub a: Option<(f64, f64)>,
    pub b: Option<(f64, f64)>,
    pub radius: Option<f64>,
    pub direction: Option<(f64, f64)>,
    pub intensity: f64,
    /// Its colour: the `color` given, or for a light with a spectrum the
    /// spectrum's colour, brightest channel 1 (how the page shows it).
    pub color: (f64, f64, f64),
    pub spectrum: Option<SpectrumItem>,
}

/// An arc's or circle's SVG path data, in world units; `None` for a
/// segment.
fn svg_curve(shape: &flatray_geometry::Shape) -> Option<String> {
    let arc = shape.as_arc()?;
    let r = arc.radius;
    if arc.is_full() {
        let (a, c) = (arc.a, arc.center);
        let b = c * 2.0 - a;
        return Some(format!(
            "M {} {} A {r} {r} 0 0 1 {} {} A {r} {r} 0 0 1 {} {}",
            a.x, a.y, b.x, b.y, a.x, a.y
        ));
    }
    // SVG's sweep flag 1 turns towards positive angles (x towards y), as
    // the arc's `turn` +1 does.
    let large = u8::from(arc.sweep > std::f64::consts::PI);
    let sweep = u8::from(arc.turn > 0.0);
    Some(format!(
        "M {} {} A {r} {r} 0 {large} {sweep} {} {}",
        arc.a.x, arc.a.y, arc.b.x, arc.b.y
    ))
}

/// A glass body's corners and outline.
fn glass_item(g: &crate::format::GlassSpec) -> GlassItem {
    let corners: Vec<DVec2> = g.points.iter().map(|p| DVec2::new(p.0, p.1)).collect();
    let mut path = String::new();
    if let Some(first) = corners.first() {
        path = format!("M {} {}", first.x, first.y);
    }
    match crate::load::glass_edges(&corners, &g.through) {
        Ok(edges) => {
            for edge in &edges {
                match svg_curve(edge) {
                    // `M a A ...`: the arc from where the path stands.
                    Some(curve) => match curve.find(" A ") {
                        Some(at) if !edge.as_arc().is_some_and(|a| a.is_full()) => {
                            path.push_str(&curve[at..]);
                        }
                        _ => path.push_str(&format!(" {curve}")),
                    },
                    None => {
                        let b = edge.chord().b;
                        path.push_str(&format!(" L {} {}", b.x, b.y));
                    }
                }
            }
        }
        Err(_) => {
            for c in corners.iter().skip(1) {
                path.push_str(&format!(" L {} {}", c.x, c.y));
            }
        }
    }
    path.push_str(" Z");
    GlassItem {
        points: g.points.iter().map(|p| (p.0, p.1)).collect(),
        path,
    }
}

/// The file's doors and windows as drawn.
fn openings(file: &crate::format::SceneFile) -> (Vec<DoorItem>, Vec<WindowItem>) {
    let doors = file
        .doors
        .iter()
        .map(|d| DoorItem {
            a: (d.a.0, d.a.1),
            b: (d.b.0, d.b.1),
            open: d.open,
        })
        .collect();
    let windows = file
        .windows
        .iter()
        .map(|w| WindowItem {
            a: (w.a.0, w.a.1),
            b: (w.b.0, w.b.1),
            shutter: w.shutter.0,
        })
        .collect();
    (doors, windows)
}

/// The items of a scene `text` that loads (`loaded`, its canvas).
pub fn items(text: &str, loaded: &crate::Loaded) -> Result<Items, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let file = crate::load::scene_file(text).map_err(|e| e.to_string())?;
    let canvas = loaded.scene.canvas();
    let walls = file
        .walls
        .iter()
        .map(|w| {
            let (material, color) = match w.material {
                MaterialSpec::FloorDiffuse | MaterialSpec::Diffuse { albedo: None } => {
                    ("Diffuse", None)
                }
                MaterialSpec::Diffuse { albedo: Some(c) } => ("Diffuse", Some((c.0, c.1, c.2))),
                MaterialSpec::Mirror { tint } => ("Mirror", Some((tint.0, tint.1, tint.2))),
                MaterialSpec::Rough { tint, .. } => ("Rough", Some((tint.0, tint.1, tint.2))),
                MaterialSpec::Transparent { tint } => {
                    ("Transparent", Some((tint.0, tint.1, tint.2)))
                }
            };
            WallItem {
                a: (w.a.0, w.a.1),
                b: (w.b.0, w.b.1),
                curve: svg_curve(&w.geometry()),
                ends: !matches!(w.shape, crate::format::WallShape::Circle { .. }),
                material,
                color,
                emits: w.emit.is_some(),
            }
        })
        .collect();
    let lights = file
        .lights
        .iter()
        .map(|l| {
            let mut item = LightItem {
                kind: "Point",
                at: None,
                a: None,
                b: None,
                radius: None,
                direction: None,
                intensity: 0.0,
                color: (1.0, 1.0, 1.0),
                spectrum: None,
            };
            let (color, intensity) = match *l {
                LightSpec::Point {
                    at,
                    color,
                    intensity,
                    ..
                } => {
                    item.at = Some((at.0, at.1));
                    (color, intensity)
                }
                LightSpec::Spot {
                    at,
                    direction,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Spot";
                    item.at = Some((at.0, at.1));
                    item.direction = Some((direction.0, direction.1));
                    (color, intensity)
                }
                LightSpec::Line {
                    a,
                    b,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Line";
                    item.a = Some((a.0, a.1));
                    item.b = Some((b.0, b.1));
                    (color, intensity)
                }
                LightSpec::Circle {
                    at,
                    radius,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Circle";
                    item.at = Some((at.0, at.1));
                    item.radius = Some(radius.0);
                    (color, intensity)
                }
                LightSpec::Directional {
                    direction,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Directional";
                    item.direction = Some((direction.0, direction.1));
                    (color, intensity)
                }
                LightSpec::Beam {
                    a,
                    b,
                    direction,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Beam";
                    item.a = Some((a.0, a.1));
                    item.b = Some((b.0, b.1));
                    item.direction = Some((direction.0, direction.1));
                    (color, intensity)
                }
                LightSpec::Sun {
                    north,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Sun";
                    // Drawn as its rays' direction; at night, as none.
                    item.direction = crate::daylight::place_of(l)
                        .and_then(Result::ok)
                        .filter(|p| p.elevation > 0.0)
                        .map(|p| {
                            let d = crate::daylight::sun_direction(p.azimuth, north.0);
                            (d.x, d.y)
                        });
                    (color, intensity)
                }
                LightSpec::Sky {
                    color, intensity, ..
                } => {
                    item.kind = "Sky";
                    (color, intensity)
                }
                LightSpec::Laser {
                    at,
                    direction,
                    color,
                    intensity,
                    ..
                } => {
                    item.kind = "Laser";
                    item.at = Some((at.0, at.1));
                    item.direction = Some((direction.0, direction.1));
                    (color, intensity)
                }
            };
            item.color = (color.0, color.1, color.2);
            item.intensity = intensity.0;
            if let Some(spec) = l.spectrum() {
                use crate::format::{LampName, SpectrumSpec};
                item.spectrum = Some(match spec {
                    SpectrumSpec::Blackbody(kelvin) => SpectrumItem::Blackbody { kelvin: *kelvin },
                    SpectrumSpec::Lamp(lamp) => SpectrumItem::Lamp {
                        lamp: match lamp {
                            LampName::Sodium => "Sodium",
                            LampName::Mercury => "Mercury",
                            LampName::Neon => "Neon",
                            LampName::Hydrogen => "Hydrogen",
                        },
                    },
                    SpectrumSpec::Table(_) => SpectrumItem::Table,
                });
                if let Ok(Some(spectrum)) = crate::load::light_spectrum(Some(spec), color) {
                    let rgb = spectrum.sampled().rgb();
                    let top = rgb[0].max(rgb[1]).max(rgb[2]);
                    if top > 0.0 && top.is_finite() {
                        let shown = |v: f64| (v / top).clamp(0.0, 1.0);
                        item.color = (shown(rgb[0]), shown(rgb[1]), shown(rgb[2]));
                    }
                }
            }
            item
        })
        .collect();
    let glass = file.glass.iter().map(glass_item).collect();
    let (doors, windows) = openings(&file);
    Ok(Items {
        canvas: (canvas.width, canvas.height),
        origin: (canvas.origin.x, canvas.origin.y),
        walls,
        lights,
        glass,
        doors,
        windows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "// The test room.
Scene(
    canvas: (100, 80),
    floor: Color((0.5, 0.5, 0.5)),
    walls: [
        Wall(a: (10, 10), b: (90, 10)), // the north wall
        Wall(a: (10, 70), b: (90, 70), material: Mirror(tint: (0.9, 0.9, 0.9))),
    ],
    lights: [
        Point(at: (50, 40), intensity: 20), // the lamp
        Line(a: (20, 60), b: (40, 60),),
    ],
)
";

    fn edit(e: Edit) -> Result<String, String> {
        apply(TEXT, &e, Path::new("t.ron"), Path::new(".")).map(|(text, _)| text)
    }

    #[test]
    fn an_edit_rewrites_its_value_and_keeps_the_rest() {
        let moved = edit(Edit::MoveLight {
            index: 0,
            to: (61.25, 33.0),
        })
        .unwrap();
        assert_eq!(
            moved,
            TEXT.replace("Point(at: (50, 40)", "Point(at: (61.25, 33)")
        );
        let wall = edit(Edit::MoveWallEnd {
            index: 1,
            end: End::B,
            to: (95.0, 75.5),
        })
        .unwrap();
        assert!(wall.contains("Wall(a: (10, 70), b: (95, 75.5), material: Mirror"));
        assert!(wall.contains("// the north wall") && wall.starts_with("// The test room."));
        let material = edit(Edit::WallMaterial {
            index: 1,
            material: MaterialKind::Transparent,
        })
        .unwrap();
        assert!(material.contains("b: (90, 70), material: Transparent()),"));
        // A field the item does not give is added at its end.
        let added = edit(Edit::WallMaterial {
            index: 0,
            material: MaterialKind::Mirror,
        })
        .unwrap();
        assert!(
            added.contains("Wall(a: (10, 10), b: (90, 10), material: Mirror()), // the north wall")
        );
        let colour = edit(Edit::LightColor {
            index: 1,
            value: (1.0, 0.5, 0.25),
        })
        .unwrap();
        assert!(
            colour.contains("Line(a: (20, 60), b: (40, 60), color: (1, 0.5, 0.25))"),
            "{colour}"
        );
        let end = edit(Edit::MoveLightEnd {
            index: 1,
            end: End::A,
            to: (25.0, 61.0),
        })
        .unwrap();
        assert!(end.contains("Line(a: (25, 61), b: (40, 60),)"));
    }

    #[test]
    fn an_edit_that_breaks_the_scene_is_refused() {
        let e = edit(Edit::LightIntensity {
            index: 0,
            value: -1.0,
        });
        assert!(e.unwrap_err().contains("expected an intensity from 0"));
        let e = edit(Edit::MoveLightEnd {
            index: 1,
            end: End::A,
            to: (40.0, 60.0),
        });
        assert!(e.unwrap_err().contains("two different endpoints"));
        assert!(
            edit(Edit::MoveLight {
                index: 7,
                to: (1.0, 1.0)
            })
            .unwrap_err()
            .contains("no item 7")
        );
        assert!(
            edit(Edit::LightIntensity {
                index: 0,
                value: f64::NAN
            })
            .is_err()
        );
    }

    #[test]
    fn items_follow_the_files_order() {
        let loaded = crate::parse(TEXT, Path::new("t.ron"), Path::new(".")).unwrap();
        let items = items(TEXT, &loaded).unwrap();
        assert_eq!(items.canvas, (100, 80));
        assert_eq!(items.walls.len(), 2);
        assert_eq!(items.walls[1].material, "Mirror");
        assert_eq!(items.lights[0].at, Some((50.0, 40.0)));
        assert_eq!(items.lights[0].intensity, 20.0);
        assert_eq!(items.lights[1].kind, "Line");
        assert!(items.walls.iter().all(|w| w.curve.is_none() && w.ends));
    }

    /// An arc is drawn as its curve, through its ends, turning through its
    /// middle point (SVG's sweep flag 1 where its angle grows, from x
    /// towards y); a circle as two half circles, with no ends to drag.
    #[test]
    fn arcs_and_circles_are_drawn_as_curves() {
        let text = "Scene(canvas: (100, 80), floor: Color((0.5, 0.5, 0.5)),
            walls: [Wall(a: (10, 40), through: (50, 70), b: (90, 40)),
                    Wall(a: (10, 40), through: (50, 10), b: (90, 40)),
                    Wall(center: (50, 40), radius: 5)],
            lights: [Point(at: (50, 40))])";
        let loaded = crate::parse(text, Path::new("t.ron"), Path::new(".")).unwrap();
        let items = items(text, &loaded).unwrap();
        // The numbers of a path: its command letters left out.
        let numbers = |d: &str| -> Vec<f64> {
            d.split_whitespace()
                .filter_map(|w| w.parse().ok())
                .collect()
        };
        // Through (50, 70) from (10, 40): the circle of centre (50, 85/3),
        // radius 125/3, a minor arc whose angle about the centre falls
        // (from 164 degrees through 90 to 16: SVG's sweep flag 0); through
        // (50, 10), the other way.
        for (k, sweep) in [(0, 0.0), (1, 1.0)] {
            let d = items.walls[k].curve.clone().unwrap_or_default();
            let v = numbers(&d);
            assert_eq!(v.len(), 9, "{d}");
            assert_eq!((v[0], v[1], v[7], v[8]), (10.0, 40.0, 90.0, 40.0), "{d}");
            assert!((v[2] - 125.0 / 3.0).abs() < 1e-9 && v[2] == v[3], "{d}");
            assert_eq!((v[4], v[5], v[6]), (0.0, 0.0, sweep), "{d}");
        }
        assert!(items.walls[0].ends && items.walls[1].ends);
        assert_eq!(
            items.walls[2].curve.as_deref(),
            Some("M 55 40 A 5 5 0 0 1 45 40 A 5 5 0 0 1 55 40")
        );
        assert!(!items.walls[2].ends);
    }

    #[test]
    fn a_spectrum_and_a_colour_replace_each_other() {
        let text = "Scene(canvas: (100, 80), floor: Color((0.5, 0.5, 0.5)),
            lights: [
                Point(at: (50, 40), spectrum: Lamp(Sodium), intensity: 3), // sodium
                Point(at: (20, 40), color: (1, 0.5, 0.25)),
                Spot(at: (10, 10), direction: (1, 0), cone: 30, spectrum: Blackbody(2700)),
            ])";
        let apply_to = |e: Edit| {
            apply(text, &e, Path::new("t.ron"), Path::new("."))
                .map(|(t, loaded)| (t.clone(), items(&t, &loaded).unwrap()))
        };
        let loaded = crate::parse(text, Path::new("t.ron"), Path::new(".")).unwrap();
        let before = items(text, &loaded).unwrap();
        // A sodium lamp is shown orange-yellow (in linear values, as
        // `color` is given), not white.
        let (r, g, b) = before.lights[0].color;
        assert!(
            r == 1.0 && g > 0.1 && g < 0.5 && b < 0.05,
            "{:?}",
            before.lights[0].color
        );
        assert_eq!(
            before.lights[0].spectrum,
            Some(SpectrumItem::Lamp { lamp: "Sodium" })
        );
        assert_eq!(
            before.lights[2].spectrum,
            Some(SpectrumItem::Blackbody { kelvin: 2700.0 })
        );
        // A colour for the sodium lamp: its spectrum goes, the rest stays.
        let (t, i) = apply_to(Edit::LightColor {
            index: 0,
            value: (0.2, 0.4, 1.0),
        })
        .unwrap();
        assert!(
            t.contains("Point(at: (50, 40), intensity: 3, color: (0.2, 0.4, 1)), // sodium"),
            "{t}"
        );
        assert_eq!(i.lights[0].spectrum, None);
        // A spectrum for the coloured lamp: its colour goes.
        let (t, i) = apply_to(Edit::LightSpectrum {
            index: 1,
            spectrum: SpectrumKind::Blackbody(4000.0),
        })
        .unwrap();
        assert!(
            t.contains("Point(at: (20, 40), spectrum: Blackbody(4000))"),
            "{t}"
        );
        assert_eq!(
            i.lights[1].spectrum,
            Some(SpectrumItem::Blackbody { kelvin: 4000.0 })
        );
        // Another spectrum in place of the first, from JSON as the page
        // sends it.
        let e: Edit = serde_json::from_str(
            r#"{"op": "light_spectrum", "index": 2, "spectrum": {"Lamp": "Neon"}}"#,
        )
        .unwrap();
        let (t, _) = apply_to(e).unwrap();
        assert!(t.contains("cone: 30, spectrum: Lamp(Neon))"), "{t}");
        // A spot turned.
        let (t, i) = apply_to(Edit::LightDirection {
            index: 2,
            to: (0.0, -2.0),
        })
        .unwrap();
        assert!(t.contains("direction: (0, -2)"), "{t}");
        assert_eq!(i.lights[2].direction, Some((0.0, -1.0)));
        assert!(
            apply_to(Edit::LightDirection {
                index: 2,
                to: (0.0, 0.0)
            })
            .is_err()
        );
    }

    #[test]
    fn a_lens_is_drawn_with_its_arcs() {
        let text = "Scene(canvas: (300, 200), floor: Color((0.5, 0.5, 0.5)),
            lights: [Point(at: (20, 20))],
            glass: [Glass(points: [(170, 50), (170, 190)], through: [(198.59, 120), (141.41, 120)]),
                    Glass(points: [(10, 10), (30, 10), (20, 30)])])";
        let loaded = crate::parse(text, Path::new("t.ron"), Path::new(".")).unwrap();
        let items = items(text, &loaded).unwrap();
        let lens = &items.glass[0].path;
        assert!(lens.starts_with("M 170 50 A "), "{lens}");
        assert_eq!(lens.matches(" A ").count(), 2, "{lens}");
        assert!(lens.ends_with(" 170 50 Z"), "{lens}");
        assert_eq!(items.glass[1].path, "M 10 10 L 30 10 L 20 30 L 10 10 Z");
        assert_eq!(
            items.glass[1].points,
            vec![(10.0, 10.0), (30.0, 10.0), (20.0, 30.0)]
        );
    }

    /// A wall with a door and a window in it: each end moves, the door
    /// opens and shuts, the shutter is drawn; the rest of the text stays,
    /// the items say so, and a shutter past the window's end is refused.
    #[test]
    fn doors_and_windows_are_moved_opened_and_shuttered_in_place() {
        const PLAN: &str = "Scene(
    canvas: (100, 80),
    floor: Color((0.5, 0.5, 0.5)),
    walls: [
        Wall(a: (10, 10), b: (40, 10)),
        Wall(a: (50, 10), b: (60, 10)),
        Wall(a: (80, 10), b: (90, 10)),
    ],
    doors: [Door(a: (40, 10), b: (50, 10))], // the front door
    windows: [Window(a: (60, 10), b: (80, 10), shutter: 0.5)],
    lights: [Point(at: (50, 40), intensity: 20)],
)
";
        let run = |text: &str, e: Edit| {
            apply(text, &e, Path::new("t.ron"), Path::new(".")).map(|(text, _)| text)
        };
        let opened = run(
            PLAN,
            Edit::DoorOpen {
                index: 0,
                open: true,
            },
        )
        .unwrap();
        assert!(
            opened
                .contains("doors: [Door(a: (40, 10), b: (50, 10), open: true)], // the front door"),
            "{opened}"
        );
        let shut = run(
            &opened,
            Edit::DoorOpen {
                index: 0,
                open: false,
            },
        )
        .unwrap();
        assert!(shut.contains("open: false)], // the front door"), "{shut}");
        let moved = run(
            PLAN,
            Edit::MoveDoorEnd {
                index: 0,
                end: End::B,
                to: (48.5, 10.0),
            },
        )
        .unwrap();
        assert!(
            moved.contains("Door(a: (40, 10), b: (48.5, 10))"),
            "{moved}"
        );
        let drawn = run(
            PLAN,
            Edit::WindowShutter {
                index: 0,
                value: 0.25,
            },
        )
        .unwrap();
        assert!(
            drawn.contains("Window(a: (60, 10), b: (80, 10), shutter: 0.25)"),
            "{drawn}"
        );
        let window = run(
            PLAN,
            Edit::MoveWindowEnd {
                index: 0,
                end: End::A,
                to: (62.0, 10.0),
            },
        )
        .unwrap();
        assert!(
            window.contains("Window(a: (62, 10), b: (80, 10)"),
            "{window}"
        );
        // Only the edited value changed.
        assert_eq!(
            drawn.replace("shutter: 0.25", "shutter: 0.5"),
            PLAN,
            "the rest of the text stays"
        );
        let loaded = crate::parse(&opened, Path::new("t.ron"), Path::new(".")).unwrap();
        let listed = items(&opened, &loaded).unwrap();
        assert_eq!(
            listed.doors,
            vec![DoorItem {
                a: (40.0, 10.0),
                b: (50.0, 10.0),
                open: true
            }]
        );
        assert_eq!(listed.windows[0].shutter, 0.5);
        assert!(
            run(
                PLAN,
                Edit::WindowShutter {
                    index: 0,
                    value: 1.5
                }
            )
            .is_err()
        );
        assert!(
            run(
                PLAN,
                Edit::DoorOpen {
                    index: 1,
                    open: true
                }
            )
            .is_err()
        );
        // As the page sends them.
        let sent: Edit =
            serde_json::from_str(r#"{"op": "door_open", "index": 0, "open": true}"#).unwrap();
        assert_eq!(
            sent,
            Edit::DoorOpen {
                index: 0,
                open: true
            }
        );
        let sent: Edit =
            serde_json::from_str(r#"{"op": "window_shutter", "index": 0, "value": 0.3}"#).unwrap();
        assert_eq!(
            sent,
            Edit::WindowShutter {
                index: 0,
                value: 0.3
            }
        );
    }
}
