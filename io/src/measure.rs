//! Illuminance per room, as a lighting designer reads it: the floor's
//! fluence on the grid of EN 12464-1 in each room, and the room's E_min,
//! E_avg, E_max and uniformity U0 = E_min / E_avg, each with its standard
//! error; the table, JSON, CSV and false-colour map that `flatray measure`
//! writes.
//!
//! Illuminance here is the fluence at the floor (the model's `Flatland`
//! quantity, the image's value over exposure and the floor's albedo) in
//! the photopic luminance weights of Rec. 709. The uncertainty comes from
//! independent renders ("batches") of the same scene under different
//! seeds: every figure is computed from the batches' mean, and its
//! standard error by the jackknife over batches (leave one batch out), so
//! that a minimum or a ratio gets an honest error as an average does.

use flatray_geometry::DVec2;
use flatray_tracer::{Image, Scene};
use serde_json::{Value, json};

use crate::rooms::Rooms;

/// Luminance weights of linear Rec. 709 RGB.
const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The luminance of a linear Rec. 709 colour.
pub(crate) fn luminance((r, g, b): (f64, f64, f64)) -> f64 {
    LUMINANCE[0] * r + LUMINANCE[1] * g + LUMINANCE[2] * b
}

/// A floor albedo channel below this is too dark to read the fluence
/// through: such pixels are left out of the grid.
const LEAST_ALBEDO: f64 = 0.02;

/// EN 12464-1 caps the grid spacing at 10 m.
const MOST_SPACING_METRES: f64 = 10.0;

/// Most grid points over all rooms (each holds a mean per batch).
pub const MAX_POINTS: usize = 1 << 18;

/// The illuminance at each pixel of `image` (row by row), rendered of
/// `scene` at `exposure`: the value over exposure and the pixel's mean
/// floor albedo, weighted to luminance; NaN where the floor is too dark
/// to read it.
pub fn illuminance(image: &Image, scene: &Scene, exposure: f64) -> Vec<f64> {
    let canvas = scene.canvas();
    let step = canvas.pixel_step((image.width, image.height));
    let mut out = Vec::with_capacity(image.width as usize * image.height as usize);
    for y in 0..image.height {
        for x in 0..image.width {
            let lo = canvas.origin + DVec2::new(x as f64, y as f64) * step;
            let albedo = scene.floor().mean_albedo(canvas, lo, lo + step);
            let value = image.get(x, y);
            let mut e = 0.0;
            for c in 0..3 {
                let a = albedo[c] * exposure;
                if !(albedo[c] >= LEAST_ALBEDO && a.is_finite()) {
                    e = f64::NAN;
                    break;
                }
                e += LUMINANCE[c] * value[c] as f64 / a;
            }
            out.push(e);
        }
    }
    out
}

/// The EN 12464-1 grid spacing for a room whose longer side is `d`
/// metres: `0.2 * 5^log10(d)`, at most 10 m.
pub fn spacing_metres(d: f64) -> f64 {
    (0.2 * 5f64.powf(d.max(1e-9).log10())).min(MOST_SPACING_METRES)
}

/// A figure and its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Figure {
    pub value: f64,
    pub se: f64,
}

/// One point of a room's grid: the mean illuminance over its cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPoint {
    /// The cell's centre in world units.
    pub at: DVec2,
    pub room: u32,
    pub e: Figure,
}

/// What a room measures.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomFigures {
    pub name: String,
    /// Square world units.
    pub area: f64,
    /// The grid's spacing in world units.
    pub spacing: f64,
    pub points: usize,
    pub e_min: Figure,
    pub e_avg: Figure,
    pub e_max: Figure,
    pub u0: Figure,
    /// E_avg over the unobstructed sky's, in per cent, where the scene's
    /// only light is a sky.
    pub daylight_factor: Option<Figure>,
    /// The grid's cells as ranges of the image's pixels (the points'
    /// order), for the map.
    cells: Vec<Cell>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

/// Every room's figures and grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    pub rooms: Vec<RoomFigures>,
    pub points: Vec<GridPoint>,
    pub batches: usize,
    /// Samples per pixel of each batch.
    pub batch_spp: u32,
    /// What one world unit measures in metres, when the scene says.
    pub metres: Option<f64>,
    /// The target the figures were rendered to, where one was asked for.
    pub target: Option<Target>,
}

/// A target error of the room figures, and whether the figures met it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Per cent of each figure's value.
    pub percent: f64,
    pub met: bool,
}

/// Why a scene cannot be measured.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MeasureError {
    #[error("{0} batches: the uncertainty needs at least 2")]
    Batches(usize),
    #[error("the grid would have more than {MAX_POINTS} points: a coarser --scale")]
    TooManyPoints,
}

/// The mean and its jackknife standard error of `f` over batch means:
/// `f` is given the mean with one batch left out (or none, `None`).
fn jackknife(batches: usize, f: impl Fn(Option<usize>) -> f64) -> Figure {
    let value = f(None);
    let n = batches as f64;
    let leave: Vec<f64> = (0..batches).map(|k| f(Some(k))).collect();
    let mean = leave.iter().sum::<f64>() / n;
    let var = leave.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() * (n - 1.0) / n;
    Figure {
        value,
        se: var.sqrt(),
    }
}

/// Measures each room of `rooms` on `maps`, the illuminance of each
/// batch's render ([`illuminance`]), all of `rooms.size`. `metres` is
/// what one world unit measures (grid spacing by EN 12464-1 in metres;
/// without it, the formula is applied to world units). `sky` is the
/// unobstructed illuminance of the scene's sky, where it is the only
/// light, for the daylight factor.
pub fn measure(
    maps: &[Vec<f64>],
    rooms: &Rooms,
    scene: &Scene,
    metres: Option<f64>,
    sky: Option<f64>,
) -> Result<Measured, MeasureError> {
    let batches = maps.len();
    if batches < 2 {
        return Err(MeasureError::Batches(batches));
    }
    let (w, h) = (rooms.size.0 as usize, rooms.size.1 as usize);
    let step = scene.canvas().pixel_step(rooms.size);
    let origin = scene.canvas().origin;
    let mut figures = Vec::with_capacity(rooms.rooms.len());
    let mut points = Vec::new();
    for (index, room) in rooms.rooms.iter().enumerate() {
        let side = (room.hi - room.lo).max_element();
        let unit = metres.unwrap_or(1.0);
        let spacing = (spacing_metres(side * unit) / unit).max(step.max_element());
        // Cells centred on the room's bounding box, whole pixels each.
        let n = ((room.hi - room.lo) / spacing).ceil().max(DVec2::ONE);
        let start = (room.lo + room.hi) * 0.5 - n * spacing * 0.5;
        let to_pixel = |p: DVec2| ((p - origin) / step).round();
        let mut cells = Vec::new();
        // Per cell, per batch, the mean illuminance over its room pixels.
        let mut means: Vec<Vec<f64>> = Vec::new();
        for j in 0..n.y as usize {
            for i in 0..n.x as usize {
                let lo = to_pixel(start + DVec2::new(i as f64, j as f64) * spacing)
                    .clamp(DVec2::ZERO, DVec2::new(w as f64, h as f64));
                let hi = to_pixel(start + DVec2::new(i as f64 + 1.0, j as f64 + 1.0) * spacing)
                    .clamp(DVec2::ZERO, DVec2::new(w as f64, h as f64));
                let cell = Cell {
                    x0: lo.x as usize,
                    y0: lo.y as usize,
                    x1: hi.x as usize,
                    y1: hi.y as usize,
                };
                let all = (cell.x1 - cell.x0) * (cell.y1 - cell.y0);
                let mut sums = vec![0.0; batches];
                let mut inside = 0usize;
                for y in cell.y0..cell.y1 {
                    for x in cell.x0..cell.x1 {
                        let k = y * w + x;
                        if rooms.of_pixel[k] != Some(index as u32)
                            || maps.iter().any(|m| !m[k].is_finite())
                        {
                            continue;
                        }
                        inside += 1;
                        for (s, m) in sums.iter_mut().zip(maps) {
                            *s += m[k];
                        }
                    }
                }
                // A cell counts when at least half of it lies in the room.
                if inside == 0 || 2 * inside < all {
                    continue;
                }
                if points.len() + cells.len() >= MAX_POINTS {
                    return Err(MeasureError::TooManyPoints);
                }
                cells.push(cell);
                means.push(sums.iter().map(|s| s / inside as f64).collect());
            }
        }
        let n_b = batches as f64;
        let cell_value = |c: usize, leave: Option<usize>| {
            let total: f64 = means[c].iter().sum();
            match leave {
                None => total / n_b,
                Some(k) => (total - means[c][k]) / (n_b - 1.0),
            }
        };
        let over = |leave: Option<usize>, pick: fn(&[f64]) -> f64| {
            let values: Vec<f64> = (0..cells.len()).map(|c| cell_value(c, leave)).collect();
            pick(&values)
        };
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let ratio = |v: &[f64]| {
            let a = v.iter().sum::<f64>() / v.len() as f64;
            let m = v.iter().copied().fold(f64::INFINITY, f64::min);
            if a > 0.0 { m / a } else { 0.0 }
        };
        let nothing = Figure {
            value: f64::NAN,
            se: f64::NAN,
        };
        let figure = |pick: fn(&[f64]) -> f64| {
            if cells.is_empty() {
                nothing
            } else {
                jackknife(batches, |leave| over(leave, pick))
            }
        };
        let e_avg = figure(avg);
        for (c, cell) in cells.iter().enumerate() {
            let centre = origin
                + DVec2::new(
                    (cell.x0 + cell.x1) as f64 * 0.5,
                    (cell.y0 + cell.y1) as f64 * 0.5,
                ) * step;
            points.push(GridPoint {
                at: centre,
                room: index as u32,
                e: jackknife(batches, |leave| cell_value(c, leave)),
            });
        }
        figures.push(RoomFigures {
            name: room.name.clone(),
            area: room.area,
            spacing,
            points: cells.len(),
            e_min: figure(min),
            e_avg,
            e_max: figure(max),
            u0: figure(ratio),
            daylight_factor: sky.filter(|s| *s > 0.0).map(|s| Figure {
                value: 100.0 * e_avg.value / s,
                se: 100.0 * e_avg.se / s,
            }),
            cells,
        });
    }
    Ok(Measured {
        rooms: figures,
        points,
        batches,
        batch_spp: 0,
        metres,
        target: None,
    })
}

/// What a measurement asks for beyond the scene's own settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    /// Samples per pixel over all batches; `None`: the scene's.
    pub spp: Option<u32>,
    /// Independent renders, at least 2.
    pub batches: u32,
    /// Image size relative to the canvas.
    pub scale: f64,
    /// Door gaps narrower than this (world units) part rooms; `None`:
    /// [`DOOR_WIDTH_METRES`] where the scene gives its units, else 0.
    pub door_width: Option<f64>,
    /// Render until every room's E_min, E_avg and U0 have a standard
    /// error of at most this per cent of their value, doubling the
    /// samples each round ([`run`]); `None`: one round.
    pub target_error: Option<f64>,
}

/// Most samples per pixel of one batch that a target error renders to:
/// past it, the figures are given with `met: false`.
pub const MAX_TARGET_BATCH_SPP: u32 = 1 << 14;

/// Whether every room's E_min, E_avg and U0 have a standard error of at
/// most `percent` per cent of their value (a figure of zero with no
/// error meets any target; a room without grid points has none).
pub fn target_met(measured: &Measured, percent: f64) -> bool {
    measured.rooms.iter().all(|room| {
        [room.e_min, room.e_avg, room.u0]
            .iter()
            .filter(|f| f.value.is_finite())
            .all(|f| f.se <= percent / 100.0 * f.value.abs())
    })
}

/// The default door width where the scene gives its units: the widest
/// common door leaf.
pub const DOOR_WIDTH_METRES: f64 = 1.2;

/// Most batches: each is a render of its own.
pub const MAX_BATCHES: u32 = 64;

/// Measures `loaded` as `request` asks: finds its rooms, renders it
/// `request.batches` times by `render` (given each batch's options, seeds
/// far apart), and measures the rooms on the renders. `render` is the
/// caller's: this crate never renders.
///
/// With a target error, while some room's figures miss it, each round
/// renders as many batches again at the same samples, each averaged with
/// one of the last round's: the batches stay independent and alike, with
/// twice the samples, and the standard error falls by about `sqrt 2` a
/// round, up to [`MAX_TARGET_BATCH_SPP`] per batch.
pub fn run(
    loaded: &crate::Loaded,
    request: &Request,
    mut render: impl FnMut(&flatray_tracer::RenderOptions) -> Image,
) -> Result<(Rooms, Measured), String> {
    if !(request.scale.is_finite() && request.scale > 0.0) {
        return Err(format!(
            "scale: expected a finite number > 0, found {}",
            request.scale
        ));
    }
    if !(2..=MAX_BATCHES).contains(&request.batches) {
        return Err(format!(
            "batches: expected 2 to {MAX_BATCHES}, found {}",
            request.batches
        ));
    }
    if let Some(t) = request.target_error
        && !(t.is_finite() && t > 0.0)
    {
        return Err(format!(
            "target error: expected a finite per cent > 0, found {t}"
        ));
    }
    if let Some(d) = request.door_width
        && !(d.is_finite() && d >= 0.0)
    {
        return Err(format!(
            "door width: expected a finite number >= 0, found {d}"
        ));
    }
    let size = flatray_tracer::checked_image_size(&loaded.scene, request.scale)
        .map_err(|why| format!("scale {}: {why}", request.scale))?;
    let door_width = request.door_width.unwrap_or_else(|| {
        loaded
            .metres_per_unit
            .map_or(0.0, |m| DOOR_WIDTH_METRES / m)
    });
    let found = crate::rooms::find(
        &loaded.scene,
        size,
        &loaded.rooms,
        &loaded.doors,
        door_width,
    )
    .map_err(|e| e.to_string())?;
    if found.rooms.is_empty() {
        return Err("no room: name one with `rooms: [Room(name: \"..\", at: (x, y))]`".to_string());
    }
    let batches = request.batches;
    let mut spp = batch_samples(loaded, request);
    let mut maps = Vec::with_capacity(batches as usize);
    for k in 0..batches {
        let options = batch_options(loaded, spp, request.scale, k);
        let image = render(&options);
        maps.push(illuminance(&image, &loaded.scene, options.exposure));
    }
    for round in 1u32.. {
        let mut measured = measure(
            &maps,
            &found,
            &loaded.scene,
            loaded.metres_per_unit,
            loaded.sky,
        )
        .map_err(|e| e.to_string())?;
        measured.batch_spp = spp;
        let Some(percent) = request.target_error else {
            return Ok((found, measured));
        };
        let met = target_met(&measured, percent);
        if met || spp > MAX_TARGET_BATCH_SPP / 2 {
            measured.target = Some(Target { percent, met });
            return Ok((found, measured));
        }
        // As many batches again, each averaged into one of the last
        // round's: seeds apart from every earlier batch's.
        for (k, map) in maps.iter_mut().enumerate() {
            let index = round * batches + k as u32;
            let options = batch_options(loaded, spp, request.scale, index);
            let image = render(&options);
            let more = illuminance(&image, &loaded.scene, options.exposure);
            for (e, m) in map.iter_mut().zip(more) {
                *e = 0.5 * (*e + m);
            }
        }
        spp *= 2;
    }
    Err("the target error's rounds ran out".to_string())
}

/// The samples per pixel of each batch of `request`.
pub fn batch_samples(loaded: &crate::Loaded, request: &Request) -> u32 {
    let total = request.spp.unwrap_or(loaded.options.samples);
    total.div_ceil(request.batches.max(1)).max(1)
}

/// Batch `k`'s render options: the scene's, at `spp` samples and `scale`,
/// its seed moved far from the other batches'.
fn batch_options(
    loaded: &crate::Loaded,
    spp: u32,
    scale: f64,
    k: u32,
) -> flatray_tracer::RenderOptions {
    let mut options = loaded.options;
    options.samples = spp;
    options.scale = scale;
    options.seed = options
        .seed
        .wrapping_add((k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    options
}

/// A figure as "value ± se" with at least `decimals` decimals (`None`:
/// those of the value's three significant digits), and at least those of
/// the error's first.
fn pm(f: Figure, decimals: Option<usize>) -> String {
    // Enough decimals for the value's third significant digit, or the
    // error's first, whichever is finer (at most 6).
    let digits = |v: f64, significant: f64| {
        (significant - 1.0 - v.abs().max(1e-12).log10().floor()).clamp(0.0, 6.0) as usize
    };
    let decimals = decimals
        .unwrap_or_else(|| digits(f.value, 3.0))
        .max(if f.se > 0.0 { digits(f.se, 1.0) } else { 0 })
        .min(6);
    if f.value.is_finite() {
        format!("{:.decimals$} ± {:.decimals$}", f.value, f.se)
    } else {
        "-".to_string()
    }
}

/// The rooms as a table of aligned columns.
pub fn table(measured: &Measured) -> String {
    let daylight = measured.rooms.iter().any(|r| r.daylight_factor.is_some());
    let mut rows = vec![{
        let area = if measured.metres.is_some() {
            "area m²"
        } else {
            "area"
        };
        let mut head = vec!["room", area, "points", "E_min", "E_avg", "E_max", "U0"];
        if daylight {
            head.push("DF %");
        }
        head.into_iter().map(String::from).collect::<Vec<_>>()
    }];
    for r in &measured.rooms {
        let mut row = vec![
            r.name.clone(),
            match measured.metres {
                Some(m) => format!("{:.1}", r.area * m * m),
                None => format!("{:.0}", r.area),
            },
            r.points.to_string(),
            pm(r.e_min, None),
            pm(r.e_avg, None),
            pm(r.e_max, None),
            pm(r.u0, Some(3)),
        ];
        if let Some(df) = r.daylight_factor {
            row.push(pm(df, Some(2)));
        } else if daylight {
            row.push("-".into());
        }
        rows.push(row);
    }
    let columns = rows[0].len();
    let widths: Vec<usize> = (0..columns)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    let mut out = String::new();
    for row in &rows {
        let line: Vec<String> = row
            .iter()
            .enumerate()
            .map(|(c, cell)| {
                let pad = widths[c] - cell.chars().count();
                if c == 0 {
                    format!("{cell}{}", " ".repeat(pad))
                } else {
                    format!("{}{cell}", " ".repeat(pad))
                }
            })
            .collect();
        out.push_str(line.join("  ").trim_end());
        out.push('\n');
    }
    out
}

/// A figure as JSON: `{"value", "se"}`, null where there is none.
fn figure_json(f: Figure) -> Value {
    if f.value.is_finite() {
        json!({"value": f.value, "se": f.se})
    } else {
        Value::Null
    }
}

/// The rooms as JSON: `{"batches", "batch_spp", "metres_per_unit",
/// "target_error": {percent, met} or null, "rooms": [{name, area,
/// spacing, points, e_min, e_avg, e_max, u0, daylight_factor}]}`.
pub fn json(measured: &Measured) -> Value {
    json!({
        "batches": measured.batches,
        "batch_spp": measured.batch_spp,
        "metres_per_unit": measured.metres,
        "target_error": measured.target.map(|t| json!({"percent": t.percent, "met": t.met})),
        "rooms": measured.rooms.iter().map(|r| json!({
            "name": r.name,
            "area": r.area,
            "spacing": r.spacing,
            "points": r.points,
            "e_min": figure_json(r.e_min),
            "e_avg": figure_json(r.e_avg),
            "e_max": figure_json(r.e_max),
            "u0": figure_json(r.u0),
            "daylight_factor": r.daylight_factor.map_or(Value::Null, figure_json),
        })).collect::<Vec<_>>(),
    })
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// One row per grid point: `x,y,room,E,se`.
pub fn csv(measured: &Measured) -> String {
    let mut out = String::from("x,y,room,E,se\n");
    for p in &measured.points {
        let name = measured
            .rooms
            .get(p.room as usize)
            .map_or("", |r| r.name.as_str());
        out.push_str(&format!(
            "{},{},{},{},{}\n",
            p.at.x,
            p.at.y,
            csv_field(name),
            p.e.value,
            p.e.se
        ));
    }
    out
}

/// Viridis at nine stops, a perceptually uniform scale.
const VIRIDIS: [[f64; 3]; 9] = [
    [68.0, 1.0, 84.0],
    [71.0, 44.0, 122.0],
    [59.0, 81.0, 139.0],
    [44.0, 113.0, 142.0],
    [33.0, 144.0, 141.0],
    [39.0, 173.0, 129.0],
    [92.0, 200.0, 99.0],
    [170.0, 220.0, 50.0],
    [253.0, 231.0, 37.0],
];

/// The colour of `t` in `[0, 1]` on the map's scale.
pub fn colour(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    [0, 1, 2].map(|c| (a[c] + f * (b[c] - a[c])).round() as u8)
}

/// A round step for isolines over `0..top`: 1, 2 or 5 times a power of
/// ten, the finest giving at most 8 lines.
pub fn round_step(top: f64) -> f64 {
    if !(top.is_finite() && top > 0.0) {
        return 1.0;
    }
    let raw = top / 6.0;
    let power = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|s| top / s <= 8.0)
        .unwrap_or(10.0 * power)
}

/// Each pixel's grid value: its cell's mean where the pixel lies in a
/// measured cell of its room, NaN elsewhere.
pub fn cell_map(measured: &Measured, rooms: &Rooms) -> Vec<f64> {
    let (w, h) = (rooms.size.0 as usize, rooms.size.1 as usize);
    let mut map = vec![f64::NAN; w * h];
    let mut next = 0;
    for (index, room) in measured.rooms.iter().enumerate() {
        for cell in &room.cells {
            let value = measured.points[next].e.value;
            next += 1;
            for y in cell.y0..cell.y1 {
                for x in cell.x0..cell.x1 {
                    if rooms.of_pixel[y * w + x] == Some(index as u32) {
                        map[y * w + x] = value;
                    }
                }
            }
        }
    }
    map
}

/// The width in pixels of the map's legend.
const LEGEND: u32 = 150;

/// The false-colour map of `measured` as PNG bytes: each grid cell in its
/// illuminance's colour (viridis, from 0 to the top of the scale), lines
/// where the cells cross a round value, the walls of `scene` over it,
/// each room's name, E_avg and U0 written in it, and the scale's legend
/// to the right.
pub fn map_png(measured: &Measured, rooms: &Rooms, scene: &Scene) -> Result<Vec<u8>, String> {
    use plotters::prelude::*;
    let (w, h) = (rooms.size.0 as usize, rooms.size.1 as usize);
    let values = cell_map(measured, rooms);
    let top_value = measured
        .rooms
        .iter()
        .map(|r| r.e_max.value)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let step = round_step(top_value);
    let top = ((top_value / step).ceil() * step).max(step);
    let mut plan = vec![0u8; w * h * 3];
    for k in 0..w * h {
        let v = values[k];
        let c = if v.is_finite() {
            let level = (v / step).floor();
            let (x, y) = (k % w, k / w);
            let differs = |n: usize| {
                values[n].is_finite()
                    && rooms.of_pixel[n] == rooms.of_pixel[k]
                    && (values[n] / step).floor() != level
            };
            if (x + 1 < w && differs(k + 1)) || (y + 1 < h && differs(k + w)) {
                [20, 20, 20]
            } else {
                colour(v / top)
            }
        } else {
            [48, 48, 48]
        };
        plan[3 * k..3 * k + 3].copy_from_slice(&c);
    }
    crate::overlay::draw_walls(&mut plan, rooms.size, scene, 1.5);
    let (width, height) = (rooms.size.0 + LEGEND, rooms.size.1.max(240));
    let mut buffer = vec![255u8; (width * height * 3) as usize];
    for y in 0..h {
        let row = &plan[3 * y * w..3 * (y + 1) * w];
        let at = 3 * y * width as usize;
        buffer[at..at + 3 * w].copy_from_slice(row);
    }
    crate::report::register_font()?;
    let font = crate::report::FONT;
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        let failed = |e: DrawingAreaErrorKind<_>| e.to_string();
        let pixel_step = scene.canvas().pixel_step(rooms.size);
        let origin = scene.canvas().origin;
        for room in &measured.rooms {
            let Some(r) = rooms.rooms.iter().find(|r| r.name == room.name) else {
                continue;
            };
            let centre = ((r.lo + r.hi) * 0.5 - origin) / pixel_step;
            let (x, y) = (centre.x as i32, centre.y as i32);
            let lines = [
                room.name.clone(),
                format!("E avg {:.3}", room.e_avg.value),
                format!("U0 {:.2}", room.u0.value),
            ];
            for (k, line) in lines.iter().enumerate() {
                let style = TextStyle::from((font, 14).into_font()).color(&WHITE).pos(
                    plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Center,
                        plotters::style::text_anchor::VPos::Center,
                    ),
                );
                let at = (x, y + 16 * k as i32 - 16);
                root.draw(&Text::new(
                    line.as_str(),
                    (at.0 + 1, at.1 + 1),
                    style.color(&BLACK),
                ))
                .map_err(failed)?;
                root.draw(&Text::new(line.as_str(), at, style))
                    .map_err(failed)?;
            }
        }
        // The legend: a bar from 0 (bottom) to the top of the scale.
        let (bar_x, bar_top, bar_bottom) = (w as i32 + 20, 30i32, height as i32 - 20);
        let span = (bar_bottom - bar_top).max(1);
        for y in bar_top..bar_bottom {
            let t = (bar_bottom - y) as f64 / span as f64;
            let [r, g, b] = colour(t);
            root.draw(&Rectangle::new(
                [(bar_x, y), (bar_x + 24, y + 1)],
                RGBColor(r, g, b).filled(),
            ))
            .map_err(failed)?;
        }
        root.draw(&Text::new("E", (bar_x, 8), (font, 15).into_font()))
            .map_err(failed)?;
        let ticks = (top / step).round() as i32;
        for k in 0..=ticks {
            let v = k as f64 * step;
            let y = bar_bottom - (v / top * span as f64).round() as i32;
            root.draw(&PathElement::new(
                vec![(bar_x + 24, y), (bar_x + 30, y)],
                BLACK.stroke_width(1),
            ))
            .map_err(failed)?;
            let decimals = if step < 1.0 {
                (-step.log10()).ceil() as usize
            } else {
                0
            };
            root.draw(&Text::new(
                format!("{v:.decimals$}"),
                (bar_x + 34, y - 7),
                (font, 13).into_font(),
            ))
            .map_err(failed)?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    crate::output::rgb8_png(&buffer, width, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_spacing_follows_en_12464_1() {
        // p = 0.2 * 5^log10(d): 0.2 m at 1 m, 1 m at 10 m, 5 m at 100 m.
        assert!((spacing_metres(1.0) - 0.2).abs() < 1e-12);
        assert!((spacing_metres(10.0) - 1.0).abs() < 1e-12);
        assert!((spacing_metres(100.0) - 5.0).abs() < 1e-12);
        assert_eq!(spacing_metres(1e4), 10.0);
    }

    #[test]
    fn the_jackknife_of_a_mean_is_its_standard_error() {
        let xs = [1.0, 2.0, 4.0, 7.0];
        let n = xs.len() as f64;
        let mean = |leave: Option<usize>| {
            let (s, c) = xs
                .iter()
                .enumerate()
                .filter(|(k, _)| Some(*k) != leave)
                .fold((0.0, 0.0), |(s, c), (_, x)| (s + x, c + 1.0));
            s / c
        };
        let f = jackknife(xs.len(), mean);
        let m = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
        assert!((f.value - 3.5).abs() < 1e-12);
        assert!((f.se - (var / n).sqrt()).abs() < 1e-12, "{f:?}");
    }

    #[test]
    fn isolines_fall_on_round_values_and_the_scale_runs_dark_to_light() {
        assert_eq!(round_step(10.0), 2.0);
        assert_eq!(round_step(0.35), 0.05);
        assert_eq!(round_step(700.0), 100.0);
        assert_eq!(colour(0.0), [68, 1, 84]);
        assert_eq!(colour(1.0), [253, 231, 37]);
        let light = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        assert!(light(colour(0.3)) < light(colour(0.7)));
    }
}
