//! `--json`: what `check`, `plan` and `render --stats` print, as one JSON
//! object each, for scripts. The fields are listed in `docs/cli.md`
//! ("Machine-readable output"); a field once there keeps its name and
//! meaning, and new ones may be added.

use std::path::Path;

use flatray_io::{Loaded, Warning};
use flatray_tracer::{Plan, RenderOptions, Stats};
use serde_json::{Value, json};

/// The version of these objects' layout: raised when a field changes
/// name or meaning (never when one is added).
pub(crate) const FORMAT: u32 = 1;

/// A scene's warnings: `[{line, column, message}]`.
pub(crate) fn warnings(warnings: &[Warning]) -> Value {
    Value::Array(
        warnings
            .iter()
            .map(|w| json!({"line": w.line, "column": w.column, "message": w.message}))
            .collect(),
    )
}

/// One scene as `check` found it.
pub(crate) fn checked(path: &Path, loaded: &Loaded) -> Value {
    let c = loaded.counts;
    json!({
        "path": path.display().to_string(),
        "ok": true,
        "walls": c.walls,
        "emitting_walls": c.emitting_walls,
        "lights": c.lights,
        "glass": c.glass,
        "canvas": [loaded.scene.canvas().width, loaded.scene.canvas().height],
        "warnings": warnings(&loaded.warnings),
    })
}

/// One scene that `check` refused: its error, located where it points.
pub(crate) fn refused(path: &Path, error: &flatray_io::SceneError) -> Value {
    let (line, column) = match error.location() {
        Some((l, c)) => (json!(l), json!(c)),
        None => (Value::Null, Value::Null),
    };
    json!({
        "path": path.display().to_string(),
        "ok": false,
        "error": {"line": line, "column": column, "message": match error {
            flatray_io::SceneError::Invalid { message, .. } => message.clone(),
            other => other.to_string(),
        }},
    })
}

/// The plan: the settings it read, and every effect with whether it runs
/// and why.
pub(crate) fn plan(plan: &Plan, options: &RenderOptions) -> Value {
    let effects: Vec<Value> = plan
        .effects()
        .iter()
        .map(|e| json!({"name": e.name, "runs": e.runs, "why": e.why, "internal": e.is_internal()}))
        .collect();
    json!({
        "settings": {
            "integrator": options.integrator.name(),
            "bounces": options.bounces,
            "specular": options.specular,
            "cache": options.memo.mode(),
            "caustics": options.caustics,
        },
        "effects": effects,
    })
}

/// A render's counts: what was simulated (`physics`), the work it took
/// (`work`), and the estimated noise.
pub(crate) fn stats(stats: &Stats) -> Value {
    flatray_io::report::stats_json(stats)
}
