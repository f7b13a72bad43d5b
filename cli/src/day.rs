//! `flatray day`: a scene's day, one frame every so often from one time
//! to another, every `Sun` of the scene set to each frame's time, each
//! frame stamped with it, written as an animated PNG.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use flatray_io::format::{Date, TimeOfDay};
use flatray_io::{Format, SunClock};
use flatray_tracer::RenderOptions;

use crate::{Failure, check_output, checked_size, load, progress_bar, warn};

/// Most frames one day may have.
pub(crate) const MAX_FRAMES: u32 = 1440;

#[derive(Debug, clap::Args)]
pub(crate) struct DayArgs {
    /// The scene file (RON), with at least one `Sun` light.
    scene: PathBuf,
    /// The date, "YYYY-MM-DD"; default: each sun's own.
    #[arg(long, value_parser = date)]
    date: Option<Date>,
    /// The first frame's local time, "HH:MM".
    #[arg(long, value_parser = time, default_value = "06:00")]
    from: TimeOfDay,
    /// The last frame's local time at the latest, "HH:MM".
    #[arg(long, value_parser = time, default_value = "18:00")]
    to: TimeOfDay,
    /// Time between frames: minutes ("30m", "45") or hours ("1h").
    #[arg(long, value_parser = every, default_value = "30m")]
    every: u32,
    /// How long each frame shows, in milliseconds.
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u16).range(10..))]
    delay: u16,
    /// Samples per pixel per frame; default: the scene's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    spp: Option<u32>,
    /// Image size relative to the canvas.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// The animated PNG to write.
    #[arg(short, long, default_value = "day.png")]
    output: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn date(text: &str) -> Result<Date, String> {
    Date::try_from(text.to_string())
}

fn time(text: &str) -> Result<TimeOfDay, String> {
    TimeOfDay::try_from(text.to_string())
}

/// Minutes from "30m", "1h", "1.5h" or "45".
fn every(text: &str) -> Result<u32, String> {
    let bad = || format!("expected minutes (\"30m\", \"45\") or hours (\"1h\"), found {text:?}");
    let (number, per) = match text.strip_suffix('h') {
        Some(hours) => (hours, 60.0),
        None => (text.strip_suffix('m').unwrap_or(text), 1.0),
    };
    let minutes = number.trim().parse::<f64>().map_err(|_| bad())? * per;
    if !(1.0..=24.0 * 60.0).contains(&minutes) || minutes.fract() != 0.0 {
        return Err(format!(
            "expected a whole number of minutes from 1 to 1440, found {text:?}"
        ));
    }
    Ok(minutes as u32)
}

fn minutes(t: TimeOfDay) -> u32 {
    60 * t.hour + t.minute
}

/// The frames' times: from `from` to `to` every `every` minutes.
fn frame_times(from: TimeOfDay, to: TimeOfDay, every: u32) -> Vec<TimeOfDay> {
    (minutes(from)..=minutes(to))
        .step_by(every.max(1) as usize)
        .map(|m| TimeOfDay {
            hour: m / 60,
            minute: m % 60,
            second: 0,
        })
        .collect()
}

pub(crate) fn day(args: DayArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<(), Failure> {
    let started = Instant::now();
    if Format::from_path(&args.output).map_err(Failure::usage)? != Format::Png {
        return Err(Failure::usage(format!(
            "--output: a day is written as an animated PNG; {} is not a .png",
            args.output.display()
        )));
    }
    if !(args.scale.is_finite() && args.scale > 0.0) {
        return Err(Failure::usage(format!(
            "--scale: expected a finite number > 0, found {}",
            args.scale
        )));
    }
    if minutes(args.to) < minutes(args.from) {
        return Err(Failure::usage(format!(
            "--to {:02}:{:02} is before --from {:02}:{:02}",
            args.to.hour, args.to.minute, args.from.hour, args.from.minute
        )));
    }
    let times = frame_times(args.from, args.to, args.every);
    if times.len() > MAX_FRAMES as usize {
        return Err(Failure::usage(format!(
            "{} frames: at most {MAX_FRAMES} (a longer --every)",
            times.len()
        )));
    }
    let loaded = load(&args.scene)?;
    warn(&args.scene, &loaded, err);
    check_output(&args.output, &loaded.inputs, "day")?;
    let text = flatray_io::read_within(&args.scene, flatray_io::MAX_INPUT_BYTES)
        .map_err(|e| Failure::usage(format!("{}: {e}", args.scene.display())))?;
    let text = String::from_utf8_lossy(&text).into_owned();
    if loaded.counts.suns == 0 {
        return Err(Failure::usage(format!(
            "{}: no Sun(date: .., time: .., ..) light: nothing in the scene changes with the time of day",
            args.scene.display()
        )));
    }
    let options = {
        let mut options: RenderOptions = loaded.options;
        options.samples = args.spp.unwrap_or(options.samples);
        options.scale = args.scale;
        options
    };
    let (width, height) = checked_size(&loaded, args.scale)?;
    let work = options.samples as u64 * width as u64 * height as u64 * times.len() as u64;
    let bar = progress_bar(work, args.quiet, "rendering the day");
    let progress = |n: u64| bar.inc(n);
    let base = args
        .scene
        .parent()
        .map_or_else(|| PathBuf::from("."), PathBuf::from);
    let mut frames = Vec::with_capacity(times.len());
    for &time in &times {
        let clock = SunClock {
            date: args.date,
            time,
        };
        let at = flatray_io::parse_at(&text, &args.scene, &base, clock)
            .map_err(|e| Failure::usage(e.to_string()))?;
        let rendered = flatray_tracer::render(&at.scene, &options, &progress);
        let mut bytes = flatray_io::to_srgb8(&rendered.image, at.tonemap);
        let scale = (rendered.image.height / 100).clamp(1, 8);
        flatray_io::overlay::draw_label(
            &mut bytes,
            (rendered.image.width, rendered.image.height),
            &format!("{:02}:{:02}", time.hour, time.minute),
            scale,
        );
        frames.push(bytes);
    }
    bar.finish_and_clear();
    flatray_io::write_apng(&frames, width, height, args.delay, &args.output)
        .map_err(|e| Failure::other(e.to_string()))?;
    let (first, last) = (times[0], times[times.len() - 1]);
    let _ = writeln!(
        out,
        "wrote {} ({width} x {height}, {}, {:02}:{:02} to {:02}:{:02} every {} min, {} spp) in {:.2} s",
        args.output.display(),
        flatray_io::counted(times.len(), "frame", "frames"),
        first.hour,
        first.minute,
        last.hour,
        last.minute,
        args.every,
        options.samples,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_reads_minutes_and_hours() {
        assert_eq!(every("30m"), Ok(30));
        assert_eq!(every("45"), Ok(45));
        assert_eq!(every("1h"), Ok(60));
        assert_eq!(every("1.5h"), Ok(90));
        for bad in ["0m", "-5", "1.5", "25h", "abc", ""] {
            assert!(every(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn frames_run_from_the_first_time_to_the_last_at_most() {
        let t = |h, m| TimeOfDay {
            hour: h,
            minute: m,
            second: 0,
        };
        let times = frame_times(t(7, 0), t(8, 10), 30);
        assert_eq!(times, vec![t(7, 0), t(7, 30), t(8, 0)]);
        assert_eq!(frame_times(t(9, 5), t(9, 5), 60), vec![t(9, 5)]);
    }
}
