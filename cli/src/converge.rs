//! `flatray converge`: what accuracy costs in time. Renders a reference,
//! then a ladder of sample counts for each configuration, and writes the
//! error of every run against the reference (CSV, Markdown, chart).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use flatray_io::report::{ReferenceInfo, StudyRow, slope, write_study};
use flatray_tracer::metrics::compare;
use flatray_tracer::{Image, Integrator, RenderOptions, Scene};

use crate::{Failure, checked_size, load, progress_bar};

/// The ways of rendering a study can compare.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Config {
    /// Path tracing with the cache of light on walls (`--cache on`).
    #[value(alias = "path-memo")]
    PathCache,
    /// Path tracing with the cache, the floor's indirect light taken by
    /// each pixel's own path samples rather than along lines
    /// (`--indirect samples`).
    PathSamples,
    /// Path tracing without the cache (`--cache off`): every shadow ray
    /// cast.
    Path,
    /// The original project's estimator: uniform bounces aimed at the lights.
    Original,
    /// Light tracing from the lights.
    Light,
    /// Path tracing with the cache and adaptive passes (`--adaptive`):
    /// from the third pass on, only the pixels whose noise is high take
    /// more samples. Its rung's samples are the most a pixel takes.
    Adaptive,
}

impl Config {
    fn name(self) -> &'static str {
        match self {
            Config::PathCache => "path-cache",
            Config::PathSamples => "path-samples",
            Config::Path => "path",
            Config::Original => "original",
            Config::Light => "light",
            Config::Adaptive => "adaptive",
        }
    }

    fn options(self, base: &RenderOptions) -> RenderOptions {
        let (integrator, memo) = match self {
            Config::PathCache | Config::PathSamples | Config::Adaptive => (Integrator::Path, true),
            Config::Path => (Integrator::Path, false),
            Config::Original => (Integrator::Original, false),
            Config::Light => (Integrator::Light, false),
        };
        {
            let mut options = *base;
            options.integrator = integrator;
            options.memo = base.memo;
            options.memo.enabled = memo;
            options.adaptive = self == Config::Adaptive;
            options.floor_lines = self != Config::PathSamples;
            options
        }
    }
}

#[derive(Debug, clap::Args)]
pub(crate) struct ConvergeArgs {
    /// The scene file (RON).
    scene: PathBuf,
    /// The folder for the reference and the report (created if missing).
    /// Default: `converge-<scene name>`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// A reference image (linear EXR of the same size) instead of
    /// rendering one. Its own noise is read from the `.noise.txt` file
    /// beside it, as `converge` saves one, and taken as 0 without it.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Samples per pixel of the rendered reference (path tracing, memo
    /// off, its own seeds). It is saved in the output folder and reused.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(2..=(1 << 20)))]
    reference_spp: u32,
    /// The ladder's last sample count (powers of two from 1).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=(1 << 20)))]
    max_spp: u32,
    /// Seconds per configuration after which its ladder stops.
    #[arg(long, default_value_t = 120.0, allow_negative_numbers = true)]
    budget: f64,
    /// The configurations to compare (comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Config::PathCache, Config::PathSamples, Config::Path, Config::Original, Config::Light])]
    configs: Vec<Config>,
    /// Pixels per world unit, as for `render`.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    scale: f64,
    /// Most diffuse reflections off walls (overrides the scene; default 1).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1000))]
    bounces: Option<u32>,
    /// Most mirror and glass events in a row (overrides the scene;
    /// default 32).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1000))]
    specular: Option<u32>,
    /// The error the table and the chart give: relmse (the root of
    /// relMSE, each pixel's error over its own value) or rms (the image's
    /// RMS error over its RMS value). The CSV has both.
    #[arg(long, value_enum, default_value_t = crate::ErrorMetricArg::Relmse)]
    error_metric: crate::ErrorMetricArg,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

pub(crate) fn converge(
    args: ConvergeArgs,
    out: &mut dyn Write,
    _err: &mut dyn Write,
) -> Result<(), Failure> {
    if !(args.scale.is_finite() && args.scale > 0.0) {
        return Err(Failure::usage(format!(
            "--scale: expected a finite number > 0, found {}",
            args.scale
        )));
    }
    if !(args.budget.is_finite() && args.budget > 0.0) {
        return Err(Failure::usage(format!(
            "--budget: expected seconds > 0, found {}",
            args.budget
        )));
    }
    let loaded = load(&args.scene)?;
    let base = {
        let mut options = loaded.options;
        options.scale = args.scale;
        options.bounces = args.bounces.unwrap_or(loaded.options.bounces);
        options.specular = args.specular.unwrap_or(loaded.options.specular);
        options
    };
    let (width, height) = checked_size(&loaded, base.scale)?;
    let pixels = width as u64 * height as u64;
    let stem = args
        .scene
        .file_stem()
        .map_or("scene".to_string(), |s| s.to_string_lossy().into_owned());
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("converge-{stem}")));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Failure::other(format!("{}: cannot create the folder: {e}", dir.display())))?;

    let ladder: Vec<u32> = (0..=20)
        .map(|k| 1u32 << k)
        .take_while(|&n| n <= args.max_spp)
        .collect();
    let ladder_work: u64 =
        ladder.iter().map(|&n| n as u64).sum::<u64>() * pixels * args.configs.len() as u64;
    let key = reference_key(&loaded, &base, args.reference_spp)?;
    let cached = dir.join(format!(
        "reference-{}spp-{key:016x}.exr",
        args.reference_spp
    ));
    let needs_reference = args.reference.is_none() && !reference_matches(&cached, width, height);
    let reference_work = if needs_reference {
        args.reference_spp as u64 * pixels
    } else {
        0
    };
    let bar = progress_bar(reference_work + ladder_work, args.quiet, "converging");
    let progress = |n: u64| bar.inc(n);

    let (reference, info) = match &args.reference {
        Some(path) => {
            let image = flatray_io::read_exr(path).map_err(Failure::usage)?;
            if (image.width, image.height) != (width, height) {
                return Err(Failure::usage(format!(
                    "{}: the reference is {} x {}, the render {width} x {height}",
                    path.display(),
                    image.width,
                    image.height
                )));
            }
            // Its own noise, where a `converge` run saved it beside it;
            // otherwise taken as none.
            let noise = read_noise(&path.with_extension("noise.txt"));
            let info = ReferenceInfo {
                description: match noise {
                    Some((_, Some(_))) => format!("`{}` (given, with its noise)", path.display()),
                    Some((_, None)) => format!(
                        "`{}` (given, with its relative RMSE; its relMSE unknown: taken as 0)",
                        path.display()
                    ),
                    None => format!(
                        "`{}` (given, its noise unknown: taken as 0)",
                        path.display()
                    ),
                },
                relative_noise: noise.map_or(0.0, |n| n.0),
                relmse_noise: noise.and_then(|n| n.1).unwrap_or(0.0),
            };
            (image, info)
        }
        None => reference(
            &loaded.scene,
            &base,
            args.reference_spp,
            &cached,
            needs_reference,
            &progress,
        )?,
    };

    let mut rows = Vec::new();
    for (k, config) in args.configs.iter().enumerate() {
        let mut spent = 0.0;
        for &samples in &ladder {
            if spent > args.budget {
                bar.inc(samples as u64 * pixels);
                continue;
            }
            let options = {
                let mut options = config.options(&base);
                options.samples = samples;
                options.seed = base
                    .seed
                    .wrapping_add(1 + 7919 * (k as u64 * 64 + samples as u64));
                options
            };
            let started = Instant::now();
            let rendered = flatray_tracer::render(&loaded.scene, &options, &progress);
            let seconds = started.elapsed().as_secs_f64();
            spent += seconds;
            let Some(error) = compare(&rendered.image, &reference) else {
                return Err(Failure::other(
                    "the reference is black: there is no relative error to measure",
                ));
            };
            // The reference's own noise is independent of the run's error
            // and adds to it in quadrature: take it out.
            let without = |raw: f64, noise: f64| (raw * raw - noise * noise).max(0.0).sqrt();
            let raw = error.relative_rmse;
            let relative_rmse = without(raw, info.relative_noise);
            rows.push(StudyRow {
                config: config.name().to_string(),
                samples,
                seconds,
                rays: rendered.stats.rays()
                    + rendered.stats.work.memo_fill_rays
                    + rendered.stats.work.onward_rays,
                rmse: error.rmse,
                raw_relative_rmse: raw,
                relative_rmse,
                mean_error: error.mean_error,
                raw_relmse: error.relmse,
                relmse: without(error.relmse, info.relmse_noise),
            });
        }
    }
    bar.finish_and_clear();
    let scene_name = args.scene.display().to_string();
    let metric = args.error_metric.metric();
    write_study(&dir, &rows, &info, &scene_name, metric).map_err(Failure::other)?;

    let _ = writeln!(
        out,
        "wrote {}/convergence.{{csv,md,png}} ({} runs)",
        dir.display(),
        rows.len()
    );
    let _ = writeln!(
        out,
        "reference: {} (noise {:.3} % {})",
        info.description,
        info.noise(metric) * 100.0,
        metric.name()
    );
    for config in &args.configs {
        let name = config.name();
        let last = rows.iter().rev().find(|r| r.config == name);
        let fitted = slope(&rows, name, metric).map_or("—".to_string(), |s| format!("{s:.2}"));
        if let Some(last) = last {
            let _ = writeln!(
                out,
                "  {name:<10} slope {fitted:>5}   {} spp: {:.3} % {} in {:.2} s",
                last.samples,
                last.error(metric) * 100.0,
                metric.name(),
                last.seconds
            );
        }
    }
    Ok(())
}

/// What a reference depends on, hashed (64-bit FNV-1a): the bytes of the
/// scene's files, the render settings, and the reference's samples. Its
/// file name carries the key, so another scene's or another setting's
/// reference is never taken for this one.
fn reference_key(
    loaded: &flatray_io::Loaded,
    base: &RenderOptions,
    spp: u32,
) -> Result<u64, Failure> {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            hash ^= b as u64;
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for input in &loaded.inputs {
        let bytes = std::fs::read(input)
            .map_err(|e| Failure::other(format!("{}: {e}", input.display())))?;
        eat(&(bytes.len() as u64).to_le_bytes());
        eat(&bytes);
    }
    eat(format!("{base:?} {spp}").as_bytes());
    Ok(hash)
}

/// Whether `path` holds an EXR of the given size, and both its noise
/// estimates beside it (written first, so an EXR without them is a
/// reference whose writing was cut short, or one from before relMSE).
fn reference_matches(path: &Path, width: u32, height: u32) -> bool {
    path.exists()
        && read_noise(&path.with_extension("noise.txt")).is_some_and(|n| n.1.is_some())
        && flatray_io::read_exr(path).is_ok_and(|i| (i.width, i.height) == (width, height))
}

/// The noise stored beside a reference: its relative RMSE on the first
/// line, its relMSE (the root) on the second where it was written.
fn read_noise(path: &Path) -> Option<(f64, Option<f64>)> {
    let text = std::fs::read_to_string(path).ok()?;
    let number = |line: &str| {
        line.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0)
    };
    let mut lines = text.lines();
    let relative = number(lines.next()?)?;
    Some((relative, lines.next().and_then(number)))
}

/// The reference: two independent half renders, averaged. Half their
/// difference estimates the reference's own error. Saved (with its noise in
/// a text file beside it) and reused when present.
fn reference(
    scene: &Scene,
    base: &RenderOptions,
    samples: u32,
    cached: &Path,
    render: bool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Image, ReferenceInfo), Failure> {
    let noise_path = cached.with_extension("noise.txt");
    let description = format!(
        "path tracing without the cache, {samples} spp, saved as `{}`",
        cached.display()
    );
    if !render {
        let image = flatray_io::read_exr(cached).map_err(Failure::other)?;
        let (relative_noise, relmse_noise) = read_noise(&noise_path).ok_or_else(|| {
            Failure::other(format!("{}: no noise estimate", noise_path.display()))
        })?;
        return Ok((
            image,
            ReferenceInfo {
                description,
                relative_noise,
                relmse_noise: relmse_noise.unwrap_or(0.0),
            },
        ));
    }
    let half = |seed: u64| {
        let options = {
            let mut options = Config::Path.options(base);
            options.samples = samples / 2;
            options.seed = seed;
            options
        };
        flatray_tracer::render(scene, &options, progress).image
    };
    let a = half(base.seed.wrapping_add(0x5eed_0001));
    let b = half(base.seed.wrapping_add(0x5eed_0002));
    let mean = Image {
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(x, y)| {
                [
                    (x[0] + y[0]) * 0.5,
                    (x[1] + y[1]) * 0.5,
                    (x[2] + y[2]) * 0.5,
                ]
            })
            .collect(),
        ..a.clone()
    };
    // Each half's error against the truth has RMS e; their difference has
    // RMS e * sqrt(2), and their mean's error is e / sqrt(2): half the
    // difference's RMS.
    let rms_mean = rms(&mean);
    let relative_noise = match compare(&a, &b) {
        Some(difference) if rms_mean > 0.0 => difference.rmse * 0.5 / rms_mean,
        _ => 0.0,
    };
    // The same for relMSE: each pixel's mean has a quarter of its halves'
    // squared difference as its squared error, relative to its value.
    let relmse_noise = {
        let sum: f64 = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .zip(&mean.pixels)
            .flat_map(|((x, y), m)| {
                (0..3).map(move |c| {
                    let d = x[c] as f64 - y[c] as f64;
                    flatray_tracer::metrics::relative_squared(d * d * 0.25, m[c] as f64)
                })
            })
            .sum();
        (sum / (mean.pixels.len() * 3).max(1) as f64).sqrt()
    };
    // The noise first, the image last, each atomically: an image on disk
    // always has its noise beside it.
    flatray_io::write_text(&noise_path, &format!("{relative_noise}\n{relmse_noise}\n"))
        .map_err(Failure::other)?;
    flatray_io::write_exr(&mean, cached).map_err(Failure::other)?;
    Ok((
        mean,
        ReferenceInfo {
            description,
            relative_noise,
            relmse_noise,
        },
    ))
}

fn rms(image: &Image) -> f64 {
    let sum: f64 = image
        .pixels
        .iter()
        .flatten()
        .map(|&v| (v as f64).powi(2))
        .sum();
    (sum / (image.pixels.len() * 3).max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the adaptive configuration takes adaptive passes, and it is
    /// path tracing with the cache otherwise.
    #[test]
    fn the_adaptive_configuration_is_the_cache_with_adaptive_passes() {
        let base = RenderOptions::default();
        let adaptive = Config::Adaptive.options(&base);
        let cache = Config::PathCache.options(&base);
        assert!(adaptive.adaptive && !cache.adaptive);
        assert!(adaptive.memo.enabled && adaptive.integrator == Integrator::Path);
        for config in [Config::Path, Config::Original, Config::Light] {
            assert!(!config.options(&base).adaptive, "{config:?}");
        }
    }
}
