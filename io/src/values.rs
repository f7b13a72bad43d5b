//! Scene values given in code (JSON's syntax, as a binding passes them to
//! [`crate::from_json`]) written as the scene file's text, so that a scene
//! built from values can be saved, edited and loaded as any other.
//!
//! JSON and the scene format tell values apart the same way but for two
//! things, which the format's own types settle: a list of numbers is
//! always a tuple (a point, a colour, a table's pair; no list of the
//! format holds bare numbers), and a string is a variant's name except as
//! a floor image's path. The text is read back before it is given out,
//! and must give the same values.

use serde_json::Value;

/// The scene text of `json`, a scene's values; `Err` with why when they
/// are not a scene's values or (never expected) their text would read
/// back as other values.
pub fn to_text(json: &str) -> Result<String, String> {
    let value: Value = serde_json::from_str(json).map_err(|e| format!("not scene values: {e}"))?;
    let from_values: crate::format::SceneFile =
        serde_json::from_str(json).map_err(|e| format!("not scene values: {e}"))?;
    let mut text = String::new();
    write(&mut text, &value, Some("Scene"), None, 0);
    text.push('\n');
    let from_text = crate::load::scene_file(&text)
        .map_err(|e| format!("the values' text does not read back ({e}):\n{text}"))?;
    if format!("{from_values:?}") != format!("{from_text:?}") {
        return Err(format!(
            "the values' text reads back as other values:\n{text}"
        ));
    }
    Ok(text)
}

/// What a list's items are called in the format, for its key.
fn item_name(key: &str) -> Option<&'static str> {
    match key {
        "walls" => Some("Wall"),
        "glass" => Some("Glass"),
        _ => None,
    }
}

fn indent(out: &mut String, depth: usize) {
    for _ in 0..depth {
        out.push_str("    ");
    }
}

/// Writes `value`; `name` is a struct's name to write before its fields,
/// `key` the field (or variant) it is the value of.
fn write(out: &mut String, value: &Value, name: Option<&str>, key: Option<&str>, depth: usize) {
    match value {
        Value::Null => out.push_str("None"),
        Value::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
        Value::Number(n) => out.push_str(&n.to_string()),
        Value::String(s) if key != Some("Image") && is_identifier(s) => out.push_str(s),
        Value::String(s) => out.push_str(&ron::to_string(s).unwrap_or_else(|_| format!("{s:?}"))),
        Value::Array(items) if !items.is_empty() && items.iter().all(Value::is_number) => {
            entries(out, ('(', ')'), items.len(), false, depth, |out, k| {
                write(out, &items[k], None, None, depth);
            });
        }
        Value::Array(items) => {
            let item = key.and_then(item_name);
            // A list of structs, an item a line; others inline.
            let lines = items.iter().any(Value::is_object);
            entries(out, ('[', ']'), items.len(), lines, depth, |out, k| {
                write(out, &items[k], item, None, depth + 1);
            });
        }
        Value::Object(fields) => {
            // An object of one capitalised key is a variant with its value.
            if fields.len() == 1
                && let Some((variant, inner)) = fields.iter().next()
                && variant.starts_with(|c: char| c.is_ascii_uppercase())
            {
                out.push_str(variant);
                match inner {
                    Value::Object(_) => write(out, inner, Some(""), Some(variant), depth),
                    _ => {
                        out.push('(');
                        write(out, inner, None, Some(variant), depth);
                        out.push(')');
                    }
                }
                return;
            }
            out.push_str(name.unwrap_or(""));
            // The scene's own fields a line each; a struct within, inline.
            let top = name == Some("Scene");
            let fields: Vec<(&String, &Value)> = fields.iter().collect();
            entries(out, ('(', ')'), fields.len(), top, depth, |out, k| {
                let (field, v) = fields[k];
                out.push_str(field);
                out.push_str(": ");
                write(out, v, None, Some(field), depth + 1);
            });
        }
    }
}

/// Writes `n` entries between `open` and `close`, each by `entry`: one a
/// line, indented and followed by a comma, when `lines`; else inline,
/// separated by commas.
fn entries(
    out: &mut String,
    (open, close): (char, char),
    n: usize,
    lines: bool,
    depth: usize,
    mut entry: impl FnMut(&mut String, usize),
) {
    out.push(open);
    for k in 0..n {
        if lines {
            out.push('\n');
            indent(out, depth + 1);
        } else if k > 0 {
            out.push_str(", ");
        }
        entry(out, k);
        if lines {
            out.push(',');
        }
    }
    if lines {
        out.push('\n');
        indent(out, depth);
    }
    out.push(close);
}

fn is_identifier(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_alphabetic())
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_of_every_kind_read_back_as_themselves() {
        let json = r#"{
            "canvas": [200, 100], "origin": [-10.5, 0],
            "floor": {"Tiles": {"size": 20, "tile": [0.7, 0.7, 0.6]}},
            "falloff": {"Window": {"range": 500}},
            "walls": [
                {"a": [100, 10], "b": [100, 60], "material": {"Mirror": {}}},
                {"a": [10, 10], "b": [60, 10], "through": [35, 20], "material": {"Rough": {"roughness": 0.2}}},
                {"center": [150, 50], "radius": 10, "material": {"Transparent": {"tint": [0.5, 0.6, 1]}}},
                {"a": [0, 90], "b": [50, 90], "emit": {"intensity": 2}}
            ],
            "lights": [
                {"Point": {"at": [50, 50], "intensity": 2.0, "spectrum": {"Blackbody": 2700}}},
                {"Spot": {"at": [20, 20], "direction": [1, 0], "cone": 30}},
                {"Line": {"a": [10, 95], "b": [40, 95], "spectrum": {"Table": [[400, 0.1], [550, 1], [700, 0.4]]}}},
                {"Laser": {"at": [5, 5], "direction": [1, 0.2], "spectrum": {"Lamp": "Sodium"}}}
            ],
            "glass": [{"points": [[120, 20], [140, 20], [130, 40]], "through": [null, [138, 32], null], "ior": 1.6}],
            "render": {"samples": 8, "integrator": "Light", "cache": "Direct", "tonemap": {"Reinhard": {"white": 2}}}
        }"#;
        let text = to_text(json).unwrap();
        assert!(
            text.starts_with("Scene(\n    canvas: (200, 100),"),
            "{text}"
        );
        assert!(
            text.contains("Wall(a: (100, 10), b: (100, 60), material: Mirror())"),
            "{text}"
        );
        assert!(text.contains("spectrum: Lamp(Sodium)"), "{text}");
        assert!(text.contains("through: [None, (138, 32), None]"), "{text}");
        // A floor image's path is a string, whatever it spells.
        let image = r#"{"canvas": [10, 10], "floor": {"Image": "Mirror"}}"#;
        assert!(
            to_text(image)
                .unwrap()
                .contains(r#"floor: Image("Mirror")"#)
        );
        assert!(to_text("[1, 2]").is_err());
        assert!(to_text(r#"{"canvas": [10, 10]}"#).is_err(), "no floor");
    }
}
