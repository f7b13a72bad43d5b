//! SVG drawings: `usvg` resolves units, `viewBox`, transforms, CSS, `use`
//! and shapes into absolute paths; each path becomes walls, lights or
//! glass by the `id` of the element or of its nearest marked group.

use std::collections::HashMap;
use std::path::Path;

use flatray_geometry::DVec2;
use usvg::tiny_skia_path::PathSegment;

use super::{
    ImportError, ImportOptions, Imported, ImportedFloor, ImportedGlass, ImportedLight,
    ImportedWall, LAMP_INTENSITY, LINE_INTENSITY, WallKind, edges, invalid, linear,
};

/// What an element's `id` (or its group's) makes of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mark {
    Wall,
    Mirror,
    Pane,
    Door,
    Glass,
    Lamp,
    Light,
    Emit,
    Skip,
}

/// The mark an `id` names by its prefix, case aside, if any.
fn mark_of(id: &str) -> Option<Mark> {
    let id = id.to_ascii_lowercase();
    [
        ("mirror", Mark::Mirror),
        ("pane", Mark::Pane),
        ("window", Mark::Pane),
        ("door", Mark::Door),
        ("glass", Mark::Glass),
        ("lamp", Mark::Lamp),
        ("light", Mark::Light),
        ("emit", Mark::Emit),
        ("skip", Mark::Skip),
        ("wall", Mark::Wall),
    ]
    .into_iter()
    .find(|(prefix, _)| id.starts_with(prefix))
    .map(|(_, mark)| mark)
}

/// `data-flatray-*` attributes by the `id` of the element that has them
/// or whose ancestor has them (the nearest wins).
fn attributes(text: &str) -> HashMap<String, HashMap<String, String>> {
    let mut by_id = HashMap::new();
    let Ok(doc) = roxmltree::Document::parse(text) else {
        return by_id;
    };
    for node in doc.descendants().filter(|n| n.is_element()) {
        let Some(id) = node.attribute("id") else {
            continue;
        };
        let mut found: HashMap<String, String> = HashMap::new();
        for ancestor in node.ancestors().filter(|n| n.is_element()) {
            for attribute in ancestor.attributes() {
                if let Some(name) = attribute.name().strip_prefix("data-flatray-") {
                    found
                        .entry(name.to_string())
                        .or_insert_with(|| attribute.value().to_string());
                }
            }
        }
        if !found.is_empty() {
            by_id.insert(id.to_string(), found);
        }
    }
    by_id
}

/// Elements the import reads nothing from, counted by name.
fn unsupported(text: &str, floor_image: bool) -> Vec<String> {
    let Ok(doc) = roxmltree::Document::parse(text) else {
        return Vec::new();
    };
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for node in doc.descendants().filter(|n| n.is_element()) {
        let name = node.tag_name().name();
        let ignored = match name {
            "text" | "foreignObject" | "video" | "audio" => true,
            "image" => !floor_image,
            _ => false,
        };
        if ignored {
            match counts.iter_mut().find(|(n, _)| *n == name) {
                Some((_, count)) => *count += 1,
                None => counts.push((name, 1)),
            }
        }
    }
    counts
        .into_iter()
        .map(|(name, count)| {
            format!(
                "{count} <{name}> element{}",
                if count == 1 { "" } else { "s" }
            )
        })
        .collect()
}

/// Reads an SVG drawing.
pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    let usvg_options = usvg::Options {
        resources_dir: path.parent().map(Path::to_path_buf),
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_data(bytes, &usvg_options).map_err(|e| {
        let location = match &e {
            usvg::Error::ParsingFailed(xml) => {
                let p = xml.pos();
                Some((p.row as usize, p.col as usize))
            }
            _ => None,
        };
        invalid(path, location, format!("not a valid SVG drawing: {e}"))
    })?;
    let text = String::from_utf8_lossy(bytes);
    let size = tree.size();
    let canvas = (
        ((size.width() as f64 * options.scale_or(1.0)).ceil() as u32).max(1),
        ((size.height() as f64 * options.scale_or(1.0)).ceil() as u32).max(1),
    );
    let mut reader = Reader {
        options,
        attributes: attributes(&text),
        imported: Imported {
            source: String::new(),
            kind: "SVG drawing",
            canvas,
            origin: DVec2::ZERO,
            plan_unit: options.scale_or(1.0),
            floor: ImportedFloor::Color([0.8, 0.8, 0.8]),
            walls: Vec::new(),
            lights: Vec::new(),
            glass: Vec::new(),
            warnings: unsupported(&text, options.floor_image),
            notes: Vec::new(),
            mapping: Vec::new(),
            floor_file: None,
        },
        stem: path
            .file_stem()
            .map_or("plan".to_string(), |s| s.to_string_lossy().into_owned()),
    };
    reader.group(tree.root(), Mark::Wall, "");
    Ok(reader.imported)
}

/// One subpath of a drawing's path, in world units.
#[derive(Clone, Debug, Default, PartialEq)]
struct Subpath {
    points: Vec<DVec2>,
    /// Per edge (from point `i` to the next, the last one closing a closed
    /// subpath), the point an arc passes through; `None` for a segment.
    through: Vec<Option<DVec2>>,
    closed: bool,
}

impl Subpath {
    fn at(start: DVec2) -> Subpath {
        Subpath {
            points: vec![start],
            ..Subpath::default()
        }
    }

    fn last(&self) -> DVec2 {
        self.points.last().copied().unwrap_or_default()
    }

    fn push(&mut self, to: DVec2, through: Option<DVec2>) {
        self.points.push(to);
        self.through.push(through);
    }

    /// Leaves out edges of no length (a point repeated).
    fn drop_repeats(&mut self) {
        let n = self.points.len();
        let mut points: Vec<DVec2> = Vec::with_capacity(n);
        let mut through = Vec::with_capacity(n);
        for (k, &p) in self.points.iter().enumerate() {
            if k > 0 {
                if points.last() == Some(&p) {
                    continue;
                }
                through.push(self.through.get(k - 1).copied().flatten());
            }
            points.push(p);
        }
        if self.closed {
            if points.len() > 1 && points.last() == points.first() {
                // The edge into the repeated first point closes it.
                points.pop();
            } else {
                through.push(self.through.get(n.wrapping_sub(1)).copied().flatten());
            }
        }
        self.points = points;
        self.through = through;
    }

    /// Its edges: ends, and the point an arc passes through.
    fn edges(&self) -> Vec<(DVec2, DVec2, Option<DVec2>)> {
        super::arc_edges(&self.points, &self.through, self.closed)
    }
}

/// Where a cubic curve `at(t)`, `t` from 0 to 1, is a circular arc to
/// within `tolerance` (its points at eighths of `t` within that of the
/// circle through its ends and middle, and it turns less than half a
/// circle): its middle, the point the arc passes through.
fn circular(at: impl Fn(f64) -> DVec2, tolerance: f64) -> Option<DVec2> {
    let (from, middle, to) = (at(0.0), at(0.5), at(1.0));
    let arc = flatray_geometry::Arc::through(from, middle, to).ok()?;
    if arc.sweep > std::f64::consts::PI {
        return None;
    }
    (1..8)
        .all(|k| {
            let p = at(k as f64 / 8.0);
            (p.distance(arc.center) - arc.radius).abs() <= tolerance
        })
        .then_some(middle)
}

struct Reader<'a> {
    options: &'a ImportOptions,
    attributes: HashMap<String, HashMap<String, String>>,
    imported: Imported,
    stem: String,
}

impl Reader<'_> {
    /// A `data-flatray-NAME` number given to `id` (or its ancestors).
    fn number(&self, id: &str, name: &str) -> Option<f64> {
        self.attributes
            .get(id)
            .and_then(|a| a.get(name))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite())
    }

    fn group(&mut self, group: &usvg::Group, inherited: Mark, marked_by: &str) {
        let own = mark_of(group.id());
        let (mark, marked_by) = match own {
            Some(mark) => (mark, group.id()),
            None => (inherited, marked_by),
        };
        for node in group.children() {
            match node {
                usvg::Node::Group(g) => self.group(g, mark, marked_by),
                usvg::Node::Path(p) => {
                    let (mark, by) = match mark_of(p.id()) {
                        Some(m) => (m, p.id()),
                        None => (mark, marked_by),
                    };
                    if mark != Mark::Skip && p.is_visible() {
                        self.path(p, mark, if p.id().is_empty() { by } else { p.id() });
                    }
                }
                usvg::Node::Image(image) => self.image(image),
                usvg::Node::Text(_) => {}
            }
        }
    }

    fn image(&mut self, image: &usvg::Image) {
        if !self.options.floor_image || self.imported.floor_file.is_some() {
            return;
        }
        let (bytes, extension) = match image.kind() {
            usvg::ImageKind::PNG(data) => (data.as_ref().clone(), "png"),
            usvg::ImageKind::JPEG(data) => (data.as_ref().clone(), "jpg"),
            _ => {
                self.imported
                    .warnings
                    .push("an image that is neither PNG nor JPEG, for the floor".to_string());
                return;
            }
        };
        let name = format!("{}-floor.{extension}", self.stem);
        self.imported.floor = ImportedFloor::Image(name.clone());
        self.imported.floor_file = Some((name, bytes));
    }

    /// The subpaths of `p` in world units: each with the point each edge
    /// passes through where it is a circular arc, and whether it is
    /// closed. A cubic curve that is a circular arc to within the
    /// tolerance (usvg draws a `<circle>`, a round `<ellipse>` and a path's
    /// `A` command as such cubics, a quarter turn at most each) becomes an
    /// arc where `arcs` allows; any other curve is flattened into
    /// segments, each within the tolerance of it.
    fn subpaths(&self, p: &usvg::Path, arcs: bool) -> Vec<Subpath> {
        let transform = p.abs_transform();
        let scale = self.options.scale_or(1.0);
        let tolerance = self.options.tolerance * scale;
        let world = |pt: usvg::tiny_skia_path::Point| {
            let mut q = [pt];
            transform.map_points(&mut q);
            DVec2::new(single(q[0].x as f64 * scale), single(q[0].y as f64 * scale))
        };
        // Pieces per curve, from how far its control points stray from
        // its chord (a bound on the curve's own distance from it).
        let pieces = |from: DVec2, controls: &[DVec2], to: DVec2| -> usize {
            let chord = to - from;
            let length = chord.length();
            let stray = controls
                .iter()
                .map(|&c| {
                    if length > 0.0 {
                        chord.perp_dot(c - from).abs() / length
                    } else {
                        c.distance(from)
                    }
                })
                .fold(0.0, f64::max);
            ((stray / tolerance).sqrt().ceil() as usize).clamp(1, 256)
        };
        let mut out: Vec<Subpath> = Vec::new();
        let mut current = Subpath::default();
        for segment in p.data().segments() {
            match segment {
                PathSegment::MoveTo(pt) => {
                    if current.points.len() > 1 {
                        out.push(std::mem::take(&mut current));
                    }
                    current = Subpath::at(world(pt));
                }
                PathSegment::LineTo(pt) => current.push(world(pt), None),
                PathSegment::QuadTo(c, pt) => {
                    let from = current.last();
                    let (c, to) = (world(c), world(pt));
                    let n = pieces(from, &[c], to);
                    for k in 1..n {
                        let t = k as f64 / n as f64;
                        let s = 1.0 - t;
                        current.push(from * (s * s) + c * (2.0 * s * t) + to * (t * t), None);
                    }
                    current.push(to, None);
                }
                PathSegment::CubicTo(c1, c2, pt) => {
                    let from = current.last();
                    let (c1, c2, to) = (world(c1), world(c2), world(pt));
                    let cubic = |t: f64| {
                        let s = 1.0 - t;
                        from * (s * s * s)
                            + c1 * (3.0 * s * s * t)
                            + c2 * (3.0 * s * t * t)
                            + to * (t * t * t)
                    };
                    if let Some(middle) = arcs.then(|| circular(cubic, tolerance)).flatten() {
                        current.push(to, Some(middle));
                        continue;
                    }
                    let n = pieces(from, &[c1, c2], to);
                    for k in 1..n {
                        current.push(cubic(k as f64 / n as f64), None);
                    }
                    current.push(to, None);
                }
                PathSegment::Close => {
                    current.closed = true;
                    if current.points.len() > 1 && current.points.first() == current.points.last() {
                        // The last edge ends where the path began: it is
                        // the closing edge, arc or not.
                        current.points.pop();
                    } else {
                        current.through.push(None);
                    }
                    if current.points.len() > 1 {
                        let first = current.points[0];
                        out.push(std::mem::replace(&mut current, Subpath::at(first)));
                    } else {
                        current = Subpath::at(current.points.first().copied().unwrap_or_default());
                    }
                }
            }
        }
        if current.points.len() > 1 {
            out.push(current);
        }
        // Repeated points make no edge.
        for subpath in &mut out {
            subpath.drop_repeats();
        }
        out
    }

    fn path(&mut self, p: &usvg::Path, mark: Mark, id: &str) {
        let paint = |paint: &usvg::Paint| match paint {
            usvg::Paint::Color(c) => Some(linear([c.red, c.green, c.blue])),
            _ => None,
        };
        let stroke = p.stroke().and_then(|s| paint(s.paint()));
        let fill = p.fill().and_then(|f| paint(f.paint()));
        let colour = stroke.or(fill);
        let source = if id.is_empty() {
            "an unnamed path".to_string()
        } else {
            id.to_string()
        };
        // Arcs make walls (emitting ones too) and glass; a line light is
        // straight.
        let arcs = !matches!(mark, Mark::Light | Mark::Lamp);
        let subpaths = self.subpaths(p, arcs);
        match mark {
            Mark::Lamp => {
                let points: Vec<DVec2> = subpaths.iter().flat_map(|s| s.points.clone()).collect();
                if points.is_empty() {
                    return;
                }
                let (low, high) = points.iter().fold(
                    (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                    |(lo, hi), &q| (lo.min(q), hi.max(q)),
                );
                self.imported.lights.push(ImportedLight::Point {
                    at: (low + high) * 0.5,
                    color: fill.or(stroke).unwrap_or([1.0; 3]),
                    intensity: self.number(id, "intensity").unwrap_or(LAMP_INTENSITY),
                    range: None,
                    source,
                });
            }
            Mark::Light => {
                for subpath in &subpaths {
                    for (a, b) in edges(&subpath.points, subpath.closed) {
                        self.imported.lights.push(ImportedLight::Line {
                            a,
                            b,
                            color: colour.unwrap_or([1.0; 3]),
                            intensity: self.number(id, "intensity").unwrap_or(LINE_INTENSITY),
                            source: source.clone(),
                        });
                    }
                }
            }
            Mark::Glass => {
                for subpath in &subpaths {
                    let arcs = subpath.through.iter().any(Option::is_some);
                    let enough = subpath.points.len() >= 3 || (arcs && subpath.points.len() == 2);
                    if subpath.closed && enough {
                        self.imported.glass.push(ImportedGlass {
                            points: subpath.points.clone(),
                            through: if arcs {
                                subpath.through.clone()
                            } else {
                                Vec::new()
                            },
                            ior: self.number(id, "ior").unwrap_or(1.5),
                            source: source.clone(),
                        });
                    } else {
                        self.imported.warnings.push(format!(
                            "{source}: a glass body must be a closed shape of at least 3 points, or 2 joined by arcs"
                        ));
                    }
                }
            }
            Mark::Wall | Mark::Mirror | Mark::Pane | Mark::Door | Mark::Emit => {
                let kind = match mark {
                    Mark::Mirror => WallKind::Mirror,
                    Mark::Door => WallKind::Door,
                    Mark::Pane => WallKind::Pane(colour.unwrap_or([1.0; 3])),
                    _ => WallKind::Diffuse(colour),
                };
                let emit = (mark == Mark::Emit).then(|| {
                    (
                        colour.unwrap_or([1.0; 3]),
                        self.number(id, "intensity").unwrap_or(LINE_INTENSITY),
                    )
                });
                let kind = if emit.is_some() {
                    WallKind::Diffuse(self.number(id, "albedo").map(|a| [a; 3]))
                } else {
                    kind
                };
                for subpath in &subpaths {
                    for (a, b, through) in subpath.edges() {
                        self.imported.walls.push(ImportedWall {
                            a,
                            b,
                            through,
                            kind,
                            emit,
                            source: source.clone(),
                        });
                    }
                }
            }
            Mark::Skip => {}
        }
    }
}

/// `v` to the precision of the drawing's own numbers (usvg's are 32-bit):
/// the shortest decimal that reads back as the same 32-bit number, so that
/// 5 mm is written `18.897638`, not `18.89763832092285`.
fn single(v: f64) -> f64 {
    let narrow = v as f32;
    if !narrow.is_finite() {
        return v;
    }
    format!("{narrow}").parse().unwrap_or(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_keep_the_drawings_precision() {
        // 5 mm in user units, as usvg computes it in 32 bits.
        let five_mm = (5.0f32 * 96.0 / 25.4) as f64;
        assert_eq!(format!("{five_mm}"), "18.89763832092285");
        assert_eq!(format!("{}", single(five_mm)), "18.897638");
        assert_eq!(single(100.0), 100.0);
        assert_eq!(single(0.1f32 as f64), 0.1);
    }
}
