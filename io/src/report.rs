//! The files of a convergence study: a CSV of every run, a Markdown
//! summary, and a log-log chart of error against seconds.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use flatray_tracer::metrics::{ErrorMetric, log_log_slope, reach};
use plotters::prelude::*;

use crate::error::WriteError;
use crate::output::write_atomically;

/// One render of a convergence study.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyRow {
    pub config: String,
    pub samples: u32,
    /// Wall-clock seconds of the render, memo fill included.
    pub seconds: f64,
    /// Rays cast, memo fill included.
    pub rays: u64,
    /// RMSE against the reference, as measured.
    pub rmse: f64,
    /// `rmse` relative to the reference's RMS value, as measured.
    pub raw_relative_rmse: f64,
    /// The relative RMSE with the reference's own noise taken out in
    /// quadrature: the run's error against the truth.
    pub relative_rmse: f64,
    /// Mean of (run - reference): the bias estimate.
    pub mean_error: f64,
    /// The root of relMSE against the reference, as measured.
    pub raw_relmse: f64,
    /// The same with the reference's own relMSE taken out in quadrature.
    pub relmse: f64,
}

impl StudyRow {
    /// The run's error (the reference's noise taken out) by `metric`.
    pub fn error(&self, metric: ErrorMetric) -> f64 {
        match metric {
            ErrorMetric::RelMse => self.relmse,
            ErrorMetric::Rms => self.relative_rmse,
        }
    }
}

/// What the report says about its reference.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceInfo {
    pub description: String,
    /// The reference's own estimated relative RMSE.
    pub relative_noise: f64,
    /// The reference's own estimated relMSE (its root).
    pub relmse_noise: f64,
}

impl ReferenceInfo {
    /// The reference's own noise by `metric`.
    pub fn noise(&self, metric: ErrorMetric) -> f64 {
        match metric {
            ErrorMetric::RelMse => self.relmse_noise,
            ErrorMetric::Rms => self.relative_noise,
        }
    }
}

/// The accuracy targets of the summary table.
pub const TARGETS: [f64; 3] = [0.10, 0.03, 0.01];

/// The configurations in `rows`, in order of first appearance.
pub fn configs(rows: &[StudyRow]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for row in rows {
        if !out.contains(&row.config) {
            out.push(row.config.clone());
        }
    }
    out
}

fn rows_of<'a>(rows: &'a [StudyRow], config: &str) -> Vec<&'a StudyRow> {
    rows.iter().filter(|r| r.config == config).collect()
}

/// The fitted slope of the error by `metric` against samples, for one
/// configuration.
pub fn slope(rows: &[StudyRow], config: &str, metric: ErrorMetric) -> Option<f64> {
    let points: Vec<(f64, f64)> = rows_of(rows, config)
        .iter()
        .map(|r| (r.samples as f64, r.error(metric)))
        .collect();
    log_log_slope(&points)
}

/// The CSV text of `rows`.
pub fn csv(rows: &[StudyRow]) -> String {
    let mut out = String::from(
        "config,samples,seconds,rays,rmse,raw_relative_rmse,relative_rmse,mean_error,raw_relmse,relmse\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{:.6},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}",
            r.config,
            r.samples,
            r.seconds,
            r.rays,
            r.rmse,
            r.raw_relative_rmse,
            r.relative_rmse,
            r.mean_error,
            r.raw_relmse,
            r.relmse
        );
    }
    out
}

/// What the report calls the error by `metric`, and its column in the
/// CSV.
fn described(metric: ErrorMetric) -> (&'static str, &'static str) {
    match metric {
        ErrorMetric::RelMse => (
            "relMSE (the root of the mean, over pixels and channels, of each error squared over the reference's value squared, floored at 0.03)",
            "relmse",
        ),
        ErrorMetric::Rms => (
            "relative RMSE (the RMS error over the reference's RMS value)",
            "relative_rmse",
        ),
    }
}

/// The Markdown summary: the reference, each configuration's fitted slope,
/// and the seconds and samples it needs to reach each target of the error
/// by `metric`.
pub fn markdown(
    rows: &[StudyRow],
    reference: &ReferenceInfo,
    scene: &str,
    metric: ErrorMetric,
) -> String {
    let mut out = String::new();
    let (what, column) = described(metric);
    let _ = writeln!(out, "# Convergence of `{scene}`\n");
    let _ = writeln!(
        out,
        "Error: {what}. Reference: {}; its own estimated {} is {:.3} % ({:.3} % relative RMSE, {:.3} % relMSE). Every error below has that noise taken out in quadrature (`{column}` in the CSV; `raw_{column}` is as measured), so errors well below it are uncertain.\n",
        reference.description,
        metric.name(),
        reference.noise(metric) * 100.0,
        reference.relative_noise * 100.0,
        reference.relmse_noise * 100.0
    );
    let _ = writeln!(
        out,
        "Seconds (wall clock) and samples per pixel needed to reach a {}, by log-log interpolation between measured runs (— where no run reached it).\n",
        metric.name()
    );
    let mut header = String::from("| configuration | slope |");
    let mut rule = String::from("|---|---|");
    for t in TARGETS {
        let _ = write!(header, " {:.0} %: s | {:.0} %: spp |", t * 100.0, t * 100.0);
        rule.push_str("---|---|");
    }
    let _ = writeln!(out, "{header}\n{rule}");
    for config in configs(rows) {
        let mine = rows_of(rows, &config);
        let by_seconds: Vec<(f64, f64)> =
            mine.iter().map(|r| (r.seconds, r.error(metric))).collect();
        let by_samples: Vec<(f64, f64)> = mine
            .iter()
            .map(|r| (r.samples as f64, r.error(metric)))
            .collect();
        let slope = slope(rows, &config, metric).map_or("—".to_string(), |s| format!("{s:.2}"));
        let _ = write!(out, "| {config} | {slope} |");
        for t in TARGETS {
            let s = reach(&by_seconds, t).map_or("—".to_string(), |v| format!("{v:.3}"));
            let n = reach(&by_samples, t).map_or("—".to_string(), |v| format!("{v:.0}"));
            let _ = write!(out, " {s} | {n} |");
        }
        out.push('\n');
    }
    let _ = writeln!(
        out,
        "\nThe slope is the least-squares slope of log({}) against log(samples): -0.5 for an unbiased estimator whose error is all noise; flatter where a bias floor is reached.",
        metric.name()
    );
    out
}

/// Writes the CSV, the Markdown summary and the chart into `dir`.
pub fn write_study(
    dir: &Path,
    rows: &[StudyRow],
    reference: &ReferenceInfo,
    scene: &str,
    metric: ErrorMetric,
) -> Result<(), WriteError> {
    let text = csv(rows);
    write_atomically(&dir.join("convergence.csv"), |w| {
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })?;
    let text = markdown(rows, reference, scene, metric);
    write_atomically(&dir.join("convergence.md"), |w| {
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })?;
    let png = chart_png(rows, reference, scene, metric).map_err(|message| WriteError::Io {
        path: dir.join("convergence.png"),
        message,
    })?;
    write_atomically(&dir.join("convergence.png"), |w| {
        w.write_all(&png).map_err(|e| e.to_string())
    })
}

pub(crate) const FONT: &str = "flatray-sans";

pub(crate) fn register_font() -> Result<(), String> {
    plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "the embedded DejaVu font did not load".to_string())
}

/// A label at `v` of a log axis whose range spans a factor `span`: on a
/// range of a decade or more, its value at 1, 2 and 5 times a power of
/// ten and nothing elsewhere, so that the ticks between do not run into
/// each other; on a shorter range, at every tick. With as many decimals
/// as the value needs.
fn log_label(v: f64, span: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return String::new();
    }
    let power = v.log10().floor();
    let mantissa = v / 10f64.powf(power);
    let near = |m: f64| (mantissa - m).abs() < 1e-6 * m;
    if span >= 10.0 && !(near(1.0) || near(2.0) || near(5.0)) {
        return String::new();
    }
    let decimals = if power < 0.0 { -power as usize } else { 0 };
    format!("{v:.decimals$}")
}

/// The chart: the error by `metric` against seconds, log-log, a line per
/// configuration, a slope -1/2 guide and the reference's noise level.
pub fn chart_png(
    rows: &[StudyRow],
    reference: &ReferenceInfo,
    scene: &str,
    metric: ErrorMetric,
) -> Result<Vec<u8>, String> {
    register_font()?;
    let (width, height) = (900u32, 600u32);
    let mut buffer = vec![0u8; (width * height * 3) as usize];
    let positive = |v: f64| v.is_finite() && v > 0.0;
    let xs: Vec<f64> = rows
        .iter()
        .map(|r| r.seconds)
        .filter(|v| positive(*v))
        .collect();
    let ys: Vec<f64> = rows
        .iter()
        .map(|r| r.error(metric))
        .chain([reference.noise(metric)])
        .filter(|v| positive(*v))
        .collect();
    if xs.is_empty() || ys.is_empty() {
        return Err("no run with a positive time and error to plot".to_string());
    }
    let fold = |v: &[f64]| {
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(0.0, f64::max),
        )
    };
    let (x0, x1) = fold(&xs);
    let (y0, y1) = fold(&ys);
    let (x0, x1) = (x0 / 1.5, x1 * 1.5);
    let (y0, y1) = (y0 / 1.5, y1 * 1.5);
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Error against time: {scene}"), (FONT, 24))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("seconds (wall clock)")
            .y_desc(metric.name())
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .x_label_formatter(&|v| log_label(*v, x1 / x0))
            .y_label_formatter(&|v| log_label(*v, y1 / y0))
            .draw()
            .map_err(|e| e.to_string())?;
        let palette = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
            RGBColor(148, 103, 189),
            RGBColor(255, 127, 14),
        ];
        for (k, config) in configs(rows).iter().enumerate() {
            let color = palette[k % palette.len()];
            let points: Vec<(f64, f64)> = rows_of(rows, config)
                .iter()
                .map(|r| (r.seconds, r.error(metric)))
                .filter(|(x, y)| positive(*x) && positive(*y))
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(config.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| e.to_string())?;
        }
        // A slope -1/2 guide through the first run of the first config.
        if let Some(first) = rows
            .iter()
            .find(|r| positive(r.seconds) && positive(r.error(metric)))
        {
            let guide = |x: f64| first.error(metric) * (x / first.seconds).powf(-0.5);
            chart
                .draw_series(LineSeries::new(
                    [(x0, guide(x0)), (x1, guide(x1))],
                    BLACK.mix(0.4).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?
                .label("slope -1/2")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
        }
        if positive(reference.noise(metric)) {
            let level = reference.noise(metric);
            chart
                .draw_series(LineSeries::new(
                    [(x0, level), (x1, level)],
                    RGBColor(120, 120, 120).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?
                .label("reference noise")
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(120, 120, 120))
                });
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 15))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    crate::output::rgb8_png(&buffer, width, height)
}

/// A render's counts: what was simulated (`physics`), the work it took
/// (`work`), and the estimated noise with the sums it is made of (so
/// that the noise of renders of disjoint windows can be put together), as
/// `render --json` prints them (`docs/cli.md`).
pub fn stats_json(stats: &flatray_tracer::Stats) -> serde_json::Value {
    let p = &stats.physics;
    let w = &stats.work;
    serde_json::json!({
        "noise": {
            "relmse": stats.noise.relmse(),
            "relative": stats.noise.relative(),
            "relative_per_channel": stats.noise.relative_per_channel(),
            "pixels": stats.noise.pixels,
            "error_squared": stats.noise.error_squared,
            "value_squared": stats.noise.value_squared,
            "relative_squared": stats.noise.relative_squared,
        },
        "physics": {
            "camera_samples": p.camera_samples,
            "light_paths": p.light_paths,
            "caustic_photons": p.caustic_photons,
            "paths_to_walls": p.paths_to_walls,
            "paths_escaped": p.paths_escaped,
            "paths_bounce_limit": p.paths_bounce_limit,
            "paths_roulette": p.paths_roulette,
            "paths_onward": p.paths_onward,
            "paths_absorbed": p.paths_absorbed,
            "mirror_reflections": p.mirror_reflections,
            "transparent_passes": p.transparent_passes,
            "glass_events": p.glass_events,
            "nonfinite_samples": p.nonfinite_samples,
        },
        "work": {
            "rays": stats.rays(),
            "shadow_rays": w.shadow_rays,
            "bounce_rays": w.bounce_rays,
            "culled_rays": w.culled_rays,
            "memo_entries": w.memo_entries,
            "memo_bytes": w.memo_bytes,
            "memo_fill_rays": w.memo_fill_rays,
            "memo_lookups": w.memo_lookups,
            "memo_checks": w.memo_checks,
            "floor_memo_reuses": w.floor_memo_reuses,
            "lines": w.lines,
            "line_pieces": w.line_pieces,
            "floor_shared_visibility": w.floor_shared_visibility,
            "floor_square_lights": w.floor_square_lights,
            "chosen_lights": w.chosen_lights,
            "light_table_bytes": w.light_table_bytes,
            "onward_lookups": w.onward_lookups,
            "onward_rays": w.onward_rays,
            "onward_bytes": w.onward_bytes,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::log_label;

    #[test]
    fn log_axes_label_one_two_and_five_times_a_power_of_ten() {
        for (v, label) in [
            (0.01, "0.01"),
            (0.02, "0.02"),
            (0.05, "0.05"),
            (0.1, "0.1"),
            (0.30000000000000004, ""),
            (1.0, "1"),
            (2.0, "2"),
            (4.0, ""),
            (5.0, "5"),
            (6.0, ""),
            (9.0, ""),
            (10.0, "10"),
            (20.000000000000004, "20"),
            (500.0, "500"),
            (0.0, ""),
            (f64::NAN, ""),
        ] {
            assert_eq!(log_label(v, 100.0), label, "{v}");
        }
        // A range short of a decade may hold none of those: every tick
        // is labelled.
        assert_eq!(log_label(3.0, 4.0), "3");
        assert_eq!(log_label(0.7, 4.0), "0.7");
    }
}
