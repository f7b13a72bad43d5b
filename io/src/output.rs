//! Writing images: PNG (tone-mapped, sRGB, 8-bit) and EXR (linear f32),
//! both atomically: a temporary file beside the target, then a rename, so a
//! failed write never leaves a truncated image or destroys an older one.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use flatray_tracer::Image;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

use crate::error::WriteError;
use crate::format::ToneMap;

/// The formats flatray writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Exr,
}

impl Format {
    /// The format that the name of `path` asks for.
    pub fn from_path(path: &Path) -> Result<Format, WriteError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            _ => Err(WriteError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Writes `image` to `path` in the format its extension names.
pub fn write_image(image: &Image, tonemap: ToneMap, path: &Path) -> Result<(), WriteError> {
    match Format::from_path(path)? {
        Format::Png => write_png(image, tonemap, path),
        Format::Exr => write_exr(image, path),
    }
}

/// Tone-maps one linear value to `[0, 1]`.
pub fn tone_map(tonemap: ToneMap, x: f32) -> f32 {
    let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
    let y = match tonemap {
        ToneMap::Clamp => x,
        ToneMap::Reinhard { white } => {
            let w2 = (white.0 * white.0) as f32;
            x * (1.0 + x / w2) / (1.0 + x)
        }
    };
    y.min(1.0)
}

/// Encodes a linear value in `[0, 1]` as an 8-bit sRGB value.
pub fn linear_to_srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Decodes an 8-bit sRGB value to linear `[0, 1]`.
pub fn srgb_to_linear(v: u8) -> f64 {
    let s = v as f64 / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// The 8-bit sRGB bytes of `image`, tone-mapped: what a PNG holds.
pub fn to_srgb8(image: &Image, tonemap: ToneMap) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| linear_to_srgb(tone_map(tonemap, c))))
        .collect()
}

/// Writes a tone-mapped 8-bit sRGB PNG.
pub fn write_png(image: &Image, tonemap: ToneMap, path: &Path) -> Result<(), WriteError> {
    let bytes = to_srgb8(image, tonemap);
    write_atomically(path, |w| {
        PngEncoder::new(w)
            .write_image(&bytes, image.width, image.height, ExtendedColorType::Rgb8)
            .map_err(|e| e.to_string())
    })
}

/// The PNG file bytes of `image`, for snapshots and in-memory use.
pub fn png_bytes(image: &Image, tonemap: ToneMap) -> Result<Vec<u8>, String> {
    let bytes = to_srgb8(image, tonemap);
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(&bytes, image.width, image.height, ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Writes the linear values untouched as 32-bit float EXR. Its blocks are
/// compressed and written one after another, in order, so the same image
/// always gives the same bytes (compressed in parallel, blocks went out in
/// the order they finished, and the offset table with them).
pub fn write_exr(image: &Image, path: &Path) -> Result<(), WriteError> {
    use exr::prelude::{SpecificChannels, Vec2, WritableImage};
    let width = image.width as usize;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let [r, g, b] = image.pixels[p.y() * width + p.x()];
        (r, g, b)
    });
    write_atomically(path, |w| {
        exr::prelude::Image::from_channels((width, image.height as usize), channels)
            .write()
            .non_parallel()
            .to_buffered(w)
            .map_err(|e| e.to_string())
    })
}

/// Reads a linear RGB EXR (as written by [`write_exr`]).
pub fn read_exr(path: &Path) -> Result<Image, String> {
    let decoded = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let rgb = decoded.to_rgb32f();
    let (width, height) = rgb.dimensions();
    let pixels = rgb.pixels().map(|p| p.0).collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// Runs `write` into a temporary file beside `path`, then renames it over
/// `path`. On any failure the temporary file is removed and `path` is
/// untouched.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), String>,
) -> Result<(), WriteError> {
    let fail = |message: String| WriteError::Io {
        path: path.to_path_buf(),
        message,
    };
    let temp = temp_path(path);
    let result = (|| {
        let file = File::create(&temp).map_err(|e| e.to_string())?;
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.to_string())?;
        file.sync_all().map_err(|e| e.to_string())?;
        std::fs::rename(&temp, path).map_err(|e| e.to_string())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    result.map_err(fail)
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}
