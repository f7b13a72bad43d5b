//! flatray's files: the RON scene format, its validation with located
//! messages, floor images, and PNG/EXR output.
//!
//! What it is for: turning a scene file into the plain in-memory
//! `flatray_tracer::Scene` (with the render settings the file asks for),
//! a rendered `flatray_tracer::Image` into a file, atomically, and a floor
//! plan from another tool (SVG, Tiled, a wall mask) into scene text;
//! the rooms of a plan and their illuminance figures from rendered images
//! (`rooms`, `measure`: the images are rendered by the caller).
//!
//! What it never does: render, sample, or decide physics. Every error it
//! returns names the file, and for scene text the line and column, and
//! says what was expected; no input makes it panic.

pub mod daylight;
pub mod edit;
mod error;
mod explain;
pub use explain::did_you_mean;
pub mod format;
pub mod generate;
pub mod import;
mod input;
mod lint;
mod load;
mod locate;
pub mod measure;
mod output;
pub mod overlay;
pub mod report;
pub mod rooms;
pub mod values;

pub use error::{SceneError, WriteError};
pub use format::ToneMap;
pub use input::{MAX_INPUT_BYTES, read_within};
pub use load::{
    Counts, Loaded, SunClock, Warning, from_json, load, parse, parse_at, parse_sun_off,
};
pub use output::{
    Format, decode_exr, exr_bytes, linear_to_srgb, png_bytes, read_exr, remove_pending_files,
    srgb_to_linear, to_srgb8, tone_map, write_apng, write_bytes, write_exr, write_image, write_png,
    write_png_with_walls, write_text,
};

/// `n` and the noun, singular for one: "1 wall", "2 walls", "0 glass
/// bodies".
pub fn counted(n: usize, one: &str, many: &str) -> String {
    if n == 1 {
        format!("1 {one}")
    } else {
        format!("{n} {many}")
    }
}
