//! Writing images: PNG (tone-mapped, sRGB, 8-bit) and EXR (linear f32),
//! both atomically: a temporary file beside the target, then a rename, so a
//! failed write never leaves a truncated image or destroys an older one.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

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

/// Writes a tone-mapped 8-bit sRGB PNG with the walls of `scene` drawn
/// over it (`crate::overlay`), so that the plan shows.
pub fn write_png_with_walls(
    image: &Image,
    tonemap: ToneMap,
    scene: &flatray_tracer::Scene,
    path: &Path,
) -> Result<(), WriteError> {
    let mut bytes = to_srgb8(image, tonemap);
    crate::overlay::draw_walls(&mut bytes, (image.width, image.height), scene, 1.5);
    write_atomically(path, |w| {
        PngEncoder::new(w)
            .write_image(&bytes, image.width, image.height, ExtendedColorType::Rgb8)
            .map_err(|e| e.to_string())
    })
}

/// The PNG file bytes of `image`, for snapshots and in-memory use.
pub fn png_bytes(image: &Image, tonemap: ToneMap) -> Result<Vec<u8>, String> {
    rgb8_png(&to_srgb8(image, tonemap), image.width, image.height)
}

/// The PNG file bytes of 8-bit RGB rows, `width x height`.
pub(crate) fn rgb8_png(bytes: &[u8], width: u32, height: u32) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(bytes, width, height, ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Writes the linear values untouched as 32-bit float EXR. Its blocks are
/// compressed and written one after another, in order, so the same image
/// always gives the same bytes (compressed in parallel, blocks went out in
/// the order they finished, and the offset table with them).
pub fn write_exr(image: &Image, path: &Path) -> Result<(), WriteError> {
    write_atomically(path, |w| encode_exr(image, w))
}

/// The EXR file [`write_exr`] writes, as bytes.
pub fn exr_bytes(image: &Image) -> Result<Vec<u8>, String> {
    let mut out = std::io::Cursor::new(Vec::new());
    encode_exr(image, &mut out)?;
    Ok(out.into_inner())
}

fn encode_exr(image: &Image, w: impl std::io::Write + std::io::Seek) -> Result<(), String> {
    use exr::prelude::{SpecificChannels, Vec2, WritableImage};
    let width = image.width as usize;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let [r, g, b] = image.pixels[p.y() * width + p.x()];
        (r, g, b)
    });
    exr::prelude::Image::from_channels((width, image.height as usize), channels)
        .write()
        .non_parallel()
        .to_buffered(w)
        .map_err(|e| e.to_string())
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomically(path, |w| {
        std::io::Write::write_all(w, bytes).map_err(|e| e.to_string())
    })
}

/// Writes `text` to `path` atomically.
pub fn write_text(path: &Path, text: &str) -> Result<(), WriteError> {
    write_atomically(path, |w| {
        std::io::Write::write_all(w, text.as_bytes()).map_err(|e| e.to_string())
    })
}

/// Reads a linear RGB EXR (as written by [`write_exr`]): a regular file
/// only, within the input budget.
pub fn read_exr(path: &Path) -> Result<Image, String> {
    let bytes = crate::read_within(path, crate::MAX_INPUT_BYTES)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    decode_exr(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Decodes the bytes of a linear RGB EXR file.
pub fn decode_exr(bytes: &[u8]) -> Result<Image, String> {
    let decoded = image::load_from_memory_with_format(bytes, image::ImageFormat::OpenExr)
        .map_err(|e| e.to_string())?;
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
/// untouched. An existing file's permissions are kept. While the file is
/// being written its temporary name is listed for
/// [`remove_pending_files`] (an interrupted render removes it), and
/// temporary files that killed runs left in the folder are removed first.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), String>,
) -> Result<(), WriteError> {
    let fail = |message: String| WriteError::Io {
        path: path.to_path_buf(),
        message,
    };
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    remove_stale_files(&folder);
    let temp = temp_path(&folder);
    let permissions = std::fs::metadata(path).ok().map(|m| m.permissions());
    // Where the system offers a file with no name, the bytes go there
    // and it is named only once whole: a write killed before that leaves
    // nothing in the folder.
    let unnamed = unnamed_file(&folder);
    if unnamed.is_none() {
        pending(|list| list.push(temp.clone()));
    }
    let result = (|| {
        let named = unnamed.is_none();
        let file = match unnamed {
            Some(file) => file,
            None => File::create(&temp).map_err(|e| e.to_string())?,
        };
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.to_string())?;
        file.sync_all().map_err(|e| e.to_string())?;
        if let Some(permissions) = permissions {
            file.set_permissions(permissions)
                .map_err(|e| e.to_string())?;
        }
        if !named {
            pending(|list| list.push(temp.clone()));
            give_name(&file, &temp).map_err(|e| e.to_string())?;
        }
        std::fs::rename(&temp, path).map_err(|e| e.to_string())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    pending(|list| list.retain(|p| *p != temp));
    result.map_err(fail)
}

/// A file with no name in `folder` (Linux's `O_TMPFILE`), where the
/// system and the folder's file system offer one.
#[cfg(target_os = "linux")]
fn unnamed_file(folder: &Path) -> Option<File> {
    use rustix::fs::{Mode, OFlags};
    let flags = OFlags::TMPFILE | OFlags::WRONLY | OFlags::CLOEXEC;
    let fd = rustix::fs::open(folder, flags, Mode::from_raw_mode(0o666)).ok()?;
    Some(File::from(fd))
}

#[cfg(not(target_os = "linux"))]
fn unnamed_file(_folder: &Path) -> Option<File> {
    None
}

/// Gives the unnamed `file` the name `name` (`linkat` through its
/// `/proc/self/fd` entry, which needs no privilege).
#[cfg(target_os = "linux")]
fn give_name(file: &File, name: &Path) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    let entry = format!("/proc/self/fd/{}", file.as_raw_fd());
    rustix::fs::linkat(
        rustix::fs::CWD,
        entry.as_str(),
        rustix::fs::CWD,
        name,
        rustix::fs::AtFlags::SYMLINK_FOLLOW,
    )
    .map_err(std::io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn give_name(_file: &File, _name: &Path) -> std::io::Result<()> {
    Err(std::io::Error::other("no unnamed files here"))
}

/// The prefix of every temporary file flatray writes.
const TEMP_PREFIX: &str = ".flatray-";

/// A short temporary name in `folder`, whatever the target's name (a
/// target's name may already be as long as a name can be):
/// `.flatray-PID-N.tmp`.
fn temp_path(folder: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    folder.join(format!("{TEMP_PREFIX}{}-{n}.tmp", std::process::id()))
}

/// Temporary files being written now.
fn pending<T>(f: impl FnOnce(&mut Vec<PathBuf>) -> T) -> T {
    static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    let mut list = PENDING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    f(&mut list)
}

/// Removes the temporary files being written now: for an interrupted
/// process, before it exits.
pub fn remove_pending_files() {
    pending(|list| {
        for path in list.drain(..) {
            let _ = std::fs::remove_file(path);
        }
    });
}

/// Removes the temporary files in `folder` that flatray processes which
/// no longer run left behind (killed while writing). Where the system
/// cannot tell which processes run (no `/proc`), it leaves them.
fn remove_stale_files(folder: &Path) {
    let proc = Path::new("/proc/self");
    if !proc.exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else {
            continue;
        };
        let pid = name
            .strip_prefix(TEMP_PREFIX)
            .and_then(|rest| rest.strip_suffix(".tmp"))
            .and_then(|rest| rest.split('-').next())
            .and_then(|pid| pid.parse::<u32>().ok());
        if let Some(pid) = pid
            && pid != std::process::id()
            && !Path::new(&format!("/proc/{pid}")).exists()
        {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Writes 8-bit sRGB frames (`width x height` RGB rows each) as an
/// animated PNG that shows each for `delay_ms` and loops: what `flatray
/// day` writes. A viewer without APNG support shows the first frame.
pub fn write_apng(
    frames: &[Vec<u8>],
    width: u32,
    height: u32,
    delay_ms: u16,
    path: &Path,
) -> Result<(), WriteError> {
    write_atomically(path, |w| {
        let failed = |e: png::EncodingError| e.to_string();
        let count = u32::try_from(frames.len()).map_err(|e| e.to_string())?;
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_animated(count.max(1), 0).map_err(failed)?;
        encoder.set_frame_delay(delay_ms, 1000).map_err(failed)?;
        let mut writer = encoder.write_header().map_err(failed)?;
        for frame in frames {
            writer.write_image_data(frame).map_err(failed)?;
        }
        writer.finish().map_err(failed)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// While an image is being written, the folder holds no new name
    /// (Linux: the bytes go to an unnamed file), so a killed write leaves
    /// nothing; once written, the file holds the bytes.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_write_in_progress_has_no_name_in_the_folder() {
        let dir = std::env::temp_dir().join(format!("flatray-unnamed-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.txt");
        let seen = std::cell::Cell::new(usize::MAX);
        write_atomically(&target, |w| {
            std::io::Write::write_all(w, b"whole").map_err(|e| e.to_string())?;
            seen.set(std::fs::read_dir(&dir).unwrap().count());
            Ok(())
        })
        .unwrap();
        assert_eq!(seen.get(), 0);
        assert_eq!(std::fs::read(&target).unwrap(), b"whole");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
