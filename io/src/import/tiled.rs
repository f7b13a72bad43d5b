//! Tiled maps, in TMX (XML) or JSON: the objects of one object layer are
//! walls, those of another lights; object properties set materials,
//! colours and intensities. Group layers and layer offsets are followed.

use std::collections::HashMap;
use std::path::Path;

use flatray_geometry::DVec2;
use serde_json::Value;

use super::{
    ImportError, ImportOptions, Imported, ImportedFloor, ImportedGlass, ImportedLight,
    ImportedWall, LAMP_INTENSITY, LINE_INTENSITY, WallKind, arc_edges, edges, invalid,
    parse_hex_color,
};

/// The shape of a Tiled object.
#[derive(Clone, Debug, PartialEq)]
enum Shape {
    Rectangle,
    Polygon(Vec<DVec2>),
    Polyline(Vec<DVec2>),
    Point,
    /// An ellipse in the object's box: a circle becomes two arcs, any
    /// other ellipse a polygon within the tolerance.
    Ellipse,
    /// Text, tiles: not imported.
    Other(&'static str),
}

/// A Tiled object, its position already offset by its layers'.
#[derive(Clone, Debug)]
struct Object {
    name: String,
    id: String,
    x: f64,
    y: f64,
    width: f64,
    height: f64,
    /// Degrees, clockwise about `(x, y)`.
    rotation: f64,
    shape: Shape,
    properties: HashMap<String, String>,
}

impl Object {
    fn label(&self) -> String {
        if self.name.is_empty() {
            format!("object {}", self.id)
        } else {
            format!("object {} ({})", self.id, self.name)
        }
    }

    /// The object's outline in map pixels: its points turned about
    /// `(x, y)` and placed there; with whether it is closed.
    /// Its outline in the map's units: points, the point each edge passes
    /// through where it is an arc (empty for none), and whether it is
    /// closed. An ellipse that is not a circle is a polygon whose edges
    /// stray at most `tolerance` from it.
    fn outline(&self, tolerance: f64) -> Option<(Vec<DVec2>, Vec<Option<DVec2>>, bool)> {
        let mut through = Vec::new();
        let (local, closed) = match &self.shape {
            Shape::Ellipse if self.width == self.height && self.width > 0.0 => {
                // Two half circles, from the left end to the right one
                // through the top, and back through the bottom.
                let (w, h) = (self.width, self.height);
                through = vec![Some(DVec2::new(0.5 * w, 0.0)), Some(DVec2::new(0.5 * w, h))];
                (vec![DVec2::new(0.0, 0.5 * h), DVec2::new(w, 0.5 * h)], true)
            }
            Shape::Ellipse => {
                let (rx, ry) = (0.5 * self.width, 0.5 * self.height);
                let n = ellipse_sides(rx.max(ry), tolerance);
                let points = (0..n)
                    .map(|k| {
                        let a = std::f64::consts::TAU * k as f64 / n as f64;
                        DVec2::new(rx + rx * a.cos(), ry + ry * a.sin())
                    })
                    .collect();
                (points, true)
            }
            Shape::Rectangle => (
                vec![
                    DVec2::ZERO,
                    DVec2::new(self.width, 0.0),
                    DVec2::new(self.width, self.height),
                    DVec2::new(0.0, self.height),
                ],
                true,
            ),
            Shape::Polygon(points) => (points.clone(), true),
            Shape::Polyline(points) => (points.clone(), false),
            Shape::Point => (vec![DVec2::ZERO], false),
            Shape::Other(_) => return None,
        };
        let (s, c) = self.rotation.to_radians().sin_cos();
        let origin = DVec2::new(self.x, self.y);
        let place = |p: DVec2| {
            if self.rotation == 0.0 {
                origin + p
            } else {
                origin + DVec2::new(c * p.x - s * p.y, s * p.x + c * p.y)
            }
        };
        let placed = local.into_iter().map(place).collect();
        let through = through.into_iter().map(|m| m.map(place)).collect();
        Some((placed, through, closed))
    }

    fn number(&self, name: &str) -> Option<f64> {
        self.properties
            .get(name)
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite())
    }

    fn color(&self) -> Option<[f64; 3]> {
        self.properties
            .get("color")
            .and_then(|c| parse_hex_color(c))
    }
}

/// A map: its size in pixels and its object layers by name.
struct Map {
    width: f64,
    height: f64,
    layers: Vec<(String, Vec<Object>)>,
}

/// Reads a TMX map.
pub(super) fn read_tmx(
    path: &Path,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| invalid(path, None, format!("not UTF-8 text: {e}")))?;
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        invalid(
            path,
            Some((p.row as usize, p.col as usize)),
            format!("not a valid TMX map: {e}"),
        )
    })?;
    let root = doc.root_element();
    let located = |node: roxmltree::Node, message: String| {
        let p = doc.text_pos_at(node.range().start);
        invalid(path, Some((p.row as usize, p.col as usize)), message)
    };
    if root.tag_name().name() != "map" {
        return Err(located(root, "expected a Tiled <map>".to_string()));
    }
    let attr = |node: roxmltree::Node, name: &str| -> Result<f64, ImportError> {
        let value = node.attribute(name).unwrap_or("0");
        value.trim().parse::<f64>().map_err(|_| {
            located(
                node,
                format!("expected a number for `{name}`, found {value:?}"),
            )
        })
    };
    let width = attr(root, "width")? * attr(root, "tilewidth")?;
    let height = attr(root, "height")? * attr(root, "tileheight")?;
    let mut layers = Vec::new();
    let mut warnings = Vec::new();
    fn walk(
        node: roxmltree::Node,
        offset: DVec2,
        layers: &mut Vec<(String, Vec<Object>)>,
        attr: &dyn Fn(roxmltree::Node, &str) -> Result<f64, ImportError>,
    ) -> Result<(), ImportError> {
        for child in node.children().filter(|n| n.is_element()) {
            let here = offset + DVec2::new(attr(child, "offsetx")?, attr(child, "offsety")?);
            match child.tag_name().name() {
                "group" => walk(child, here, layers, attr)?,
                "objectgroup" => {
                    let name = child.attribute("name").unwrap_or("").to_string();
                    let mut objects = Vec::new();
                    for o in child.children().filter(|n| n.has_tag_name("object")) {
                        objects.push(tmx_object(o, here, attr)?);
                    }
                    layers.push((name, objects));
                }
                _ => {}
            }
        }
        Ok(())
    }
    walk(root, DVec2::ZERO, &mut layers, &attr)?;
    for layer in root
        .descendants()
        .filter(|n| n.has_tag_name("imagelayer") || n.has_tag_name("layer"))
    {
        warnings.push(format!(
            "the {} layer {:?} (export the floor from Tiled as an image: File > Export As Image)",
            if layer.has_tag_name("layer") {
                "tile"
            } else {
                "image"
            },
            layer.attribute("name").unwrap_or("")
        ));
    }
    build(
        Map {
            width,
            height,
            layers,
        },
        options,
        warnings,
    )
}

fn tmx_object(
    o: roxmltree::Node,
    offset: DVec2,
    attr: &dyn Fn(roxmltree::Node, &str) -> Result<f64, ImportError>,
) -> Result<Object, ImportError> {
    let points = |node: roxmltree::Node| -> Vec<DVec2> {
        node.attribute("points")
            .unwrap_or("")
            .split_whitespace()
            .filter_map(|pair| {
                let (x, y) = pair.split_once(',')?;
                Some(DVec2::new(x.trim().parse().ok()?, y.trim().parse().ok()?))
            })
            .collect()
    };
    let mut shape = Shape::Rectangle;
    let mut properties = HashMap::new();
    for child in o.children().filter(|n| n.is_element()) {
        match child.tag_name().name() {
            "polygon" => shape = Shape::Polygon(points(child)),
            "polyline" => shape = Shape::Polyline(points(child)),
            "point" => shape = Shape::Point,
            "ellipse" => shape = Shape::Ellipse,
            "text" => shape = Shape::Other("text"),
            "properties" => {
                for p in child.children().filter(|n| n.has_tag_name("property")) {
                    let value = p
                        .attribute("value")
                        .map(str::to_string)
                        .or_else(|| p.text().map(str::to_string))
                        .unwrap_or_default();
                    properties.insert(
                        p.attribute("name").unwrap_or("").to_ascii_lowercase(),
                        value,
                    );
                }
            }
            _ => {}
        }
    }
    if o.attribute("gid").is_some() {
        shape = Shape::Other("tile");
    }
    Ok(Object {
        name: o.attribute("name").unwrap_or("").to_string(),
        id: o.attribute("id").unwrap_or("?").to_string(),
        x: offset.x + attr(o, "x")?,
        y: offset.y + attr(o, "y")?,
        width: attr(o, "width")?,
        height: attr(o, "height")?,
        rotation: attr(o, "rotation")?,
        shape,
        properties,
    })
}

/// Reads a JSON map (`.json` or `.tmj`).
pub(super) fn read_json(
    path: &Path,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    let value: Value = serde_json::from_slice(bytes).map_err(|e| {
        invalid(
            path,
            Some((e.line(), e.column())),
            format!("not a valid JSON map: {e}"),
        )
    })?;
    let number = |v: &Value, name: &str| v.get(name).and_then(Value::as_f64).unwrap_or(0.0);
    if value.get("layers").and_then(Value::as_array).is_none() {
        return Err(invalid(
            path,
            None,
            "expected a Tiled map: a JSON object with `layers`".to_string(),
        ));
    }
    let width = number(&value, "width") * number(&value, "tilewidth");
    let height = number(&value, "height") * number(&value, "tileheight");
    let mut layers = Vec::new();
    let mut warnings = Vec::new();
    fn walk(
        layer_list: &Value,
        offset: DVec2,
        layers: &mut Vec<(String, Vec<Object>)>,
        warnings: &mut Vec<String>,
    ) {
        let number = |v: &Value, name: &str| v.get(name).and_then(Value::as_f64).unwrap_or(0.0);
        for layer in layer_list.as_array().into_iter().flatten() {
            let here = offset + DVec2::new(number(layer, "offsetx"), number(layer, "offsety"));
            let name = layer
                .get("name")
                .and_then(Value::as_str)
                .unwrap_or("")
                .to_string();
            match layer.get("type").and_then(Value::as_str) {
                Some("group") => walk(
                    layer.get("layers").unwrap_or(&Value::Null),
                    here,
                    layers,
                    warnings,
                ),
                Some("objectgroup") => {
                    let objects = layer
                        .get("objects")
                        .and_then(Value::as_array)
                        .into_iter()
                        .flatten()
                        .map(|o| json_object(o, here))
                        .collect();
                    layers.push((name, objects));
                }
                Some("tilelayer") => warnings.push(format!(
                    "the tile layer {name:?} (export the floor from Tiled as an image: File > Export As Image)"
                )),
                Some("imagelayer") => warnings.push(format!(
                    "the image layer {name:?} (export the floor from Tiled as an image: File > Export As Image)"
                )),
                _ => {}
            }
        }
    }
    walk(
        value.get("layers").unwrap_or(&Value::Null),
        DVec2::ZERO,
        &mut layers,
        &mut warnings,
    );
    build(
        Map {
            width,
            height,
            layers,
        },
        options,
        warnings,
    )
}

fn json_object(o: &Value, offset: DVec2) -> Object {
    let number = |name: &str| o.get(name).and_then(Value::as_f64).unwrap_or(0.0);
    let points = |name: &str| -> Vec<DVec2> {
        o.get(name)
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .map(|p| {
                DVec2::new(
                    p.get("x").and_then(Value::as_f64).unwrap_or(0.0),
                    p.get("y").and_then(Value::as_f64).unwrap_or(0.0),
                )
            })
            .collect()
    };
    let flag = |name: &str| o.get(name).and_then(Value::as_bool).unwrap_or(false);
    let shape = if o.get("polygon").is_some() {
        Shape::Polygon(points("polygon"))
    } else if o.get("polyline").is_some() {
        Shape::Polyline(points("polyline"))
    } else if flag("point") {
        Shape::Point
    } else if flag("ellipse") {
        Shape::Ellipse
    } else if o.get("text").is_some() {
        Shape::Other("text")
    } else if o.get("gid").is_some() {
        Shape::Other("tile")
    } else {
        Shape::Rectangle
    };
    let properties = o
        .get("properties")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(|p| {
            let name = p.get("name")?.as_str()?.to_ascii_lowercase();
            let value = match p.get("value")? {
                Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            Some((name, value))
        })
        .collect();
    Object {
        name: o
            .get("name")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string(),
        id: o.get("id").map_or("?".to_string(), |v| v.to_string()),
        x: offset.x + number("x"),
        y: offset.y + number("y"),
        width: number("width"),
        height: number("height"),
        rotation: number("rotation"),
        shape,
        properties,
    }
}

/// Sides of a polygon inscribed in a circle of `radius` whose edges stray
/// at most `tolerance` from it: `r (1 - cos(pi / n)) <= tolerance`, from 8
/// to 256.
fn ellipse_sides(radius: f64, tolerance: f64) -> usize {
    let ratio = (1.0 - tolerance / radius).clamp(-1.0, 1.0);
    let n = std::f64::consts::PI / ratio.acos();
    if n.is_finite() {
        (n.ceil() as usize).clamp(8, 256)
    } else {
        256
    }
}

/// Walls from the walls layer, lights from the lights layer.
fn build(
    map: Map,
    options: &ImportOptions,
    mut warnings: Vec<String>,
) -> Result<Imported, ImportError> {
    let scale = options.scale_or(1.0);
    let world = |p: DVec2| p * scale;
    let mut walls = Vec::new();
    let mut lights = Vec::new();
    let mut glass = Vec::new();
    let mut found = (false, false);
    for (name, objects) in &map.layers {
        let is_walls = name.eq_ignore_ascii_case(&options.walls_layer);
        let is_lights = name.eq_ignore_ascii_case(&options.lights_layer);
        found.0 |= is_walls;
        found.1 |= is_lights;
        if !(is_walls || is_lights) {
            if !objects.is_empty() {
                warnings.push(format!(
                    "the object layer {name:?} ({} objects): neither --walls-layer nor --lights-layer",
                    objects.len()
                ));
            }
            continue;
        }
        for object in objects {
            let Some((points, through, closed)) = object.outline(options.tolerance) else {
                if let Shape::Other(kind) = object.shape {
                    warnings.push(format!(
                        "{}: {kind} objects are not imported",
                        object.label()
                    ));
                }
                continue;
            };
            let points: Vec<DVec2> = points.into_iter().map(world).collect();
            let through: Vec<Option<DVec2>> = through.into_iter().map(|m| m.map(world)).collect();
            if object.shape == Shape::Ellipse && through.is_empty() {
                warnings.push(format!(
                    "{}: an ellipse that is not a circle, imported as a polygon of {} sides within the tolerance",
                    object.label(),
                    points.len()
                ));
            }
            if points.is_empty() {
                warnings.push(format!("{}: a shape without points", object.label()));
                continue;
            }
            let colour = object.color();
            if is_lights {
                let intensity = object.number("intensity");
                if points.len() == 1 || closed {
                    let centre = points.iter().copied().sum::<DVec2>() / points.len() as f64;
                    lights.push(ImportedLight::Point {
                        at: centre,
                        color: colour.unwrap_or([1.0; 3]),
                        intensity: intensity.unwrap_or(LAMP_INTENSITY),
                        range: None,
                        source: object.label(),
                    });
                } else {
                    for (a, b) in edges(&points, false) {
                        lights.push(ImportedLight::Line {
                            a,
                            b,
                            color: colour.unwrap_or([1.0; 3]),
                            intensity: intensity.unwrap_or(LINE_INTENSITY),
                            source: object.label(),
                        });
                    }
                }
                continue;
            }
            let material = object
                .properties
                .get("material")
                .map_or("diffuse".to_string(), |m| m.trim().to_ascii_lowercase());
            if points.len() < 2 {
                warnings.push(format!("{}: a point in the walls layer", object.label()));
                continue;
            }
            if material == "glass" {
                if closed && (points.len() >= 3 || !through.is_empty()) {
                    glass.push(ImportedGlass {
                        points,
                        through,
                        ior: object.number("ior").unwrap_or(1.5),
                        source: object.label(),
                    });
                } else {
                    warnings.push(format!(
                        "{}: a glass body must be a rectangle or polygon",
                        object.label()
                    ));
                }
                continue;
            }
            let kind = match material.as_str() {
                "mirror" => WallKind::Mirror,
                "pane" | "transparent" | "window" => WallKind::Pane(colour.unwrap_or([1.0; 3])),
                "door" | "opening" => WallKind::Door,
                "diffuse" | "" => WallKind::Diffuse(colour),
                other => {
                    warnings.push(format!(
                        "{}: unknown material {other:?}, imported as diffuse",
                        object.label()
                    ));
                    WallKind::Diffuse(colour)
                }
            };
            let emit = object
                .number("emit")
                .filter(|&i| i > 0.0)
                .map(|i| (colour.unwrap_or([1.0; 3]), i));
            for (a, b, through) in arc_edges(&points, &through, closed) {
                walls.push(ImportedWall {
                    a,
                    b,
                    through,
                    kind,
                    emit,
                    source: object.label(),
                });
            }
        }
    }
    if !found.0 {
        warnings.push(format!(
            "no object layer named {:?} (choose one with --walls-layer)",
            options.walls_layer
        ));
    }
    if !found.1 {
        warnings.push(format!(
            "no object layer named {:?} (choose one with --lights-layer)",
            options.lights_layer
        ));
    }
    Ok(Imported {
        source: String::new(),
        kind: "Tiled map",
        origin: DVec2::ZERO,
        plan_unit: scale,
        canvas: (
            ((map.width * scale).ceil() as u32).max(1),
            ((map.height * scale).ceil() as u32).max(1),
        ),
        floor: ImportedFloor::Color([0.8, 0.8, 0.8]),
        walls,
        lights,
        glass,
        warnings,
        notes: Vec::new(),
        mapping: Vec::new(),
        floor_file: None,
    })
}
