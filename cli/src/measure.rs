//! `flatray measure`: each room's illuminance figures (E_min, E_avg,
//! E_max, U0 on the EN 12464-1 grid, and the daylight factor under a
//! sky), each with its standard error from independent renders, as a
//! table, JSON, a CSV of the grid, and a false-colour map.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use flatray_io::Format;
use flatray_io::measure::{self, MAX_BATCHES};

use crate::{Failure, check_output, checked_size, load, progress_bar, warn};

#[derive(Debug, clap::Args)]
pub(crate) struct MeasureArgs {
    /// The scene file (RON).
    scene: PathBuf,
    /// Samples per pixel over all batches; default: the scene's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    spp: Option<u32>,
    /// Independent renders the uncertainty is estimated from (at least 2).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..=MAX_BATCHES as i64))]
    batches: u32,
    /// Image size relative to the canvas: the finest the rooms and the
    /// grid can be.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Openings between two walls' ends narrower than this (world units)
    /// part rooms; default: 1.2 m where the scene gives `units`, else 0.
    #[arg(long)]
    door_width: Option<f64>,
    /// Print the figures as one JSON object.
    #[arg(long)]
    json: bool,
    /// Write the grid, one row per point (x, y, room, E, se).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write the false-colour map (PNG).
    #[arg(long)]
    map: Option<PathBuf>,
    /// Render until every room's E_min, E_avg and U0 have a standard
    /// error of at most this per cent of their value: each round doubles
    /// the samples of every batch (up to 16384 spp a batch).
    #[arg(long, value_name = "PERCENT")]
    target_error: Option<f64>,
    /// Every `Sun` of the scene off: under a sky alone, the rooms'
    /// daylight factor.
    #[arg(long)]
    sun_off: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

pub(crate) fn measure(
    args: MeasureArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<(), Failure> {
    let started = Instant::now();
    if !(args.scale.is_finite() && args.scale > 0.0) {
        return Err(Failure::usage(format!(
            "--scale: expected a finite number > 0, found {}",
            args.scale
        )));
    }
    let mut loaded = load(&args.scene)?;
    if args.sun_off {
        let text = flatray_io::read_within(&args.scene, flatray_io::MAX_INPUT_BYTES)
            .map_err(|e| Failure::usage(format!("{}: {e}", args.scene.display())))?;
        let base = args
            .scene
            .parent()
            .map_or_else(|| std::path::PathBuf::from("."), std::path::PathBuf::from);
        loaded = flatray_io::parse_sun_off(&String::from_utf8_lossy(&text), &args.scene, &base)
            .map_err(|e| Failure::usage(e.to_string()))?;
    }
    warn(&args.scene, &loaded, err);
    if let Some(map) = &args.map {
        if Format::from_path(map).map_err(Failure::usage)? != Format::Png {
            return Err(Failure::usage(format!(
                "--map: a map is a .png; {} is not",
                map.display()
            )));
        }
        check_output(map, &loaded.inputs, "measure")?;
    }
    if let Some(csv) = &args.csv {
        check_output(csv, &loaded.inputs, "measure")?;
    }
    let request = measure::Request {
        spp: args.spp,
        batches: args.batches,
        scale: args.scale,
        door_width: args.door_width,
        target_error: args.target_error,
    };
    if let Some(t) = args.target_error
        && !(t.is_finite() && t > 0.0)
    {
        return Err(Failure::usage(format!(
            "--target-error: expected a finite per cent > 0, found {t}"
        )));
    }
    let (width, height) = checked_size(&loaded, args.scale)?;
    // Each batch adds its work as it starts: with a target error, the
    // rounds are not known ahead.
    let bar = progress_bar(0, args.quiet, "measuring");
    let progress = |n: u64| bar.inc(n);
    let (found, measured) = measure::run(&loaded, &request, |options| {
        bar.inc_length(options.samples as u64 * width as u64 * height as u64);
        flatray_tracer::render(&loaded.scene, options, &progress).image
    })
    .map_err(|e| Failure::usage(format!("{}: {e}", args.scene.display())))?;
    bar.finish_and_clear();
    if let Some(t) = measured.target
        && !t.met
    {
        let _ = writeln!(
            err,
            "warning: some room's E_min, E_avg or U0 has a standard error over {} % of its value at {} spp a batch, the most a target renders to",
            t.percent,
            measure::MAX_TARGET_BATCH_SPP
        );
    }
    if let Some(csv) = &args.csv {
        flatray_io::write_text(csv, &measure::csv(&measured))
            .map_err(|e| Failure::other(e.to_string()))?;
    }
    if let Some(map) = &args.map {
        let png = measure::map_png(&measured, &found, &loaded.scene).map_err(Failure::other)?;
        flatray_io::write_bytes(map, &png).map_err(|e| Failure::other(e.to_string()))?;
    }
    if args.json {
        let _ = writeln!(out, "{}", measure::json(&measured));
    } else {
        let _ = write!(out, "{}", measure::table(&measured));
        let target = match measured.target {
            Some(t) if t.met => format!("; every room's figures within {} %", t.percent),
            Some(t) => format!(
                "; some room's figures over {} % at {} spp a batch (the most)",
                t.percent,
                measure::MAX_TARGET_BATCH_SPP
            ),
            None => String::new(),
        };
        let _ = writeln!(
            out,
            "{} on the EN 12464-1 grid; ± one standard error over {} batches of {} spp{target}; {:.2} s",
            flatray_io::counted(measured.rooms.len(), "room", "rooms"),
            measured.batches,
            measured.batch_spp,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
