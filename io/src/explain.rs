//! What the RON parser's errors mean for a scene file: each error turned
//! into a message that says what is wrong in the scene's terms, at the
//! place to fix it, with "did you mean" for a misspelt field or variant.
//!
//! The parser knows RON; it does not know that a missing comma belongs at
//! the end of the line before, that `Wall` read as a field means a `)` is
//! missing, or that canvas sides are whole numbers. This module reads the
//! text around the error ([`crate::locate::context`]) to say so.

use crate::locate;

/// The byte offset and message for the parser's `error` in `text`.
pub(crate) fn explain(error: &ron::error::SpannedError, text: &str) -> (usize, String) {
    let at = locate::offset(text, error.span.start.line, error.span.start.col);
    let context = locate::context(text, at);
    let rest = &text[at..];
    let field = context.field.as_deref();
    let for_field = field.map_or(String::new(), |f| format!(" for `{f}`"));
    use ron::Error as E;
    let value = rest.trim_start();
    if let Some(inner) = value.strip_prefix("Some")
        && inner.trim_start().starts_with('(')
        && !matches!(error.code, E::NoSuchEnumVariant { .. })
    {
        return (
            at + (rest.len() - value.len()),
            match field {
                Some(f) => format!(
                    "write the value for `{f}` bare, as `{f}: (...)`, without `Some(...)`: a value that may be left out is written as it is when given"
                ),
                None => "write the value bare, without `Some(...)`: a value that may be left out is written as it is when given".to_string(),
            },
        );
    }
    match &error.code {
        E::ExpectedComma
        | E::ExpectedStructLikeEnd
        | E::ExpectedArrayEnd
        | E::ExpectedInteger
        | E::IntegerOutOfBounds
            if fraction_at(text, at).is_some() =>
        {
            let (start, number) = fraction_at(text, at).unwrap_or((at, String::new()));
            let why = match field {
                Some("canvas") => ": the canvas's sides are whole numbers of pixels",
                Some("samples" | "cache_floor_samples") => ": samples are counted",
                Some("bounces" | "specular") => ": events are counted",
                _ => "",
            };
            (
                start,
                format!("expected a whole number{for_field}, found `{number}`{why}"),
            )
        }
        E::ExpectedComma => match &context.previous {
            Some((_, end, _)) => (
                *end,
                "expected a comma after this value: fields and list items are separated by `,`"
                    .to_string(),
            ),
            None => (at, error.code.to_string()),
        },
        E::NoSuchStructField {
            expected,
            found,
            outer,
        } => {
            let outer = outer.as_deref().unwrap_or("the value");
            if found.starts_with(|c: char| c.is_ascii_uppercase()) && !expected.contains(&&**found)
            {
                // `Wall(a: .., b: ..,` then `Wall(..)`: the second reads as
                // a field of the first.
                let place = match &context.previous {
                    Some((start, _, p)) if p == "," => *start,
                    Some((_, end, _)) => *end,
                    None => at,
                };
                return (
                    place,
                    format!(
                        "expected `)` here to close `{outer}(...)`: without it, the `{found}` that follows reads as one of its fields"
                    ),
                );
            }
            (
                at,
                unknown(&format!("field `{found}` in `{outer}`"), found, expected),
            )
        }
        E::NoSuchEnumVariant {
            expected,
            found,
            outer,
        } => {
            let what = match outer.as_deref() {
                Some("Material") => "material",
                Some("Light") => "light",
                Some("Floor") => "floor",
                Some("Falloff") => "falloff",
                Some("Integrator") => "integrator",
                Some("ToneMap") => "tone map",
                Some("Lights") => "light choice",
                _ => "variant",
            };
            (at, unknown(&format!("{what} `{found}`"), found, expected))
        }
        E::ExpectedAttribute | E::ExpectedAttributeEnd
            if text[..at].trim_end().ends_with('#') || rest.starts_with('#') =>
        {
            let hash = if rest.starts_with('#') {
                at
            } else {
                text[..at].trim_end().len() - 1
            };
            (
                hash,
                "`#` does not start a comment in a scene file: comments start with `//` (or are `/* ... */`)"
                    .to_string(),
            )
        }
        E::SuggestRawIdentifier(found) | E::InvalidIdentifier(found) => {
            let inside = context
                .enclosing
                .as_deref()
                .map_or(String::new(), |name| format!(" inside `{name}(...)`"));
            (
                at,
                format!(
                    "expected a named field{inside}, as `name: value`, found `{found}` (docs/scene-format.md lists the fields)"
                ),
            )
        }
        E::ExpectedStructLike | E::ExpectedNamedStructLike(_) => {
            let blank = rest.len() - rest.trim_start().len();
            let (at, rest) = (at + blank, rest.trim_start());
            let colour = matches!(field, Some("color" | "tint" | "albedo" | "tile" | "grout"));
            if rest.starts_with('"') && colour {
                let name: String = rest.chars().skip(1).take_while(|&c| c != '"').collect();
                return (
                    at,
                    format!(
                        "expected a colour `(r, g, b)` with each component from 0 to 1{for_field}, found the string \"{name}\": colours have no names here (orange is `(1.0, 0.5, 0.0)`)"
                    ),
                );
            }
            if rest.starts_with('"') {
                return (at, format!("expected `(` here{for_field}, found a string"));
            }
            if let Some((_, end, name)) = &context.previous
                && *end == at
                && name.starts_with(|c: char| c.is_ascii_uppercase())
            {
                return (
                    *end,
                    format!(
                        "expected `(` after `{name}`: it takes parentheses even with no fields, as `{name}()`"
                    ),
                );
            }
            (at, error.code.to_string())
        }
        code => (at, code.to_string()),
    }
}

/// A number with a fraction whose `.` stands at `at` (the parser stops
/// there when it reads an integer): its start and its text.
fn fraction_at(text: &str, at: usize) -> Option<(usize, String)> {
    let rest = text.get(at..)?;
    let mut chars = rest.chars();
    if chars.next() != Some('.') || !chars.next().is_some_and(|c| c.is_ascii_digit()) {
        return None;
    }
    let before = &text[..at];
    let digits = before.len() - before.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    if digits == 0 {
        return None;
    }
    let start = at - digits;
    let start = if text[..start].ends_with('-') {
        start - 1
    } else {
        start
    };
    let fraction = 1 + rest[1..]
        .find(|c: char| !(c.is_ascii_digit() || c == '_' || c == 'e' || c == 'E'))
        .unwrap_or(rest.len() - 1);
    Some((start, text[start..at + fraction].to_string()))
}

/// "unknown WHAT: did you mean `x`? (expected one of ...)", or without
/// the question when no name is near `found`.
fn unknown(what: &str, found: &str, expected: &[&str]) -> String {
    match did_you_mean(found, expected) {
        Some(near) => format!(
            "unknown {what}: did you mean `{near}`? (expected {})",
            one_of(expected)
        ),
        None => format!("unknown {what}: expected {}", one_of(expected)),
    }
}

/// serde's "unknown field `x`, expected one of `a`, `b`" (or variant)
/// with the loader's "did you mean" added where a name is near enough.
pub(crate) fn with_suggestion(message: &str) -> String {
    let Some(rest) = message
        .strip_prefix("unknown field `")
        .or_else(|| message.strip_prefix("unknown variant `"))
    else {
        return message.to_string();
    };
    let Some((found, tail)) = rest.split_once('`') else {
        return message.to_string();
    };
    let expected: Vec<&str> = tail.split('`').skip(1).step_by(2).collect();
    match did_you_mean(found, &expected) {
        Some(near) => {
            let (head, list) = message.split_at(message.len() - tail.len());
            format!(
                "{head}: did you mean `{near}`? ({})",
                list.trim_start_matches(", ")
            )
        }
        None => message.to_string(),
    }
}

/// The name among `expected` nearest `found`, when one is near enough to
/// be a slip.
pub fn did_you_mean<'a>(found: &str, expected: &[&'a str]) -> Option<&'a str> {
    let near = expected
        .iter()
        .map(|e| {
            (
                strsim::damerau_levenshtein(&found.to_lowercase(), &e.to_lowercase()),
                *e,
            )
        })
        .filter(|&(d, e)| d <= 2.max(e.len() / 4) && d < e.len())
        .min_by_key(|&(d, _)| d);
    near.map(|(_, e)| e)
}

/// "one of `a`, `b` or `c`", or "`a`" for one.
fn one_of(expected: &[&str]) -> String {
    let quoted: Vec<String> = expected.iter().map(|e| format!("`{e}`")).collect();
    match quoted.as_slice() {
        [] => "nothing here".to_string(),
        [one] => one.clone(),
        [init @ .., last] => format!("one of {} or {last}", init.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_names_are_suggested_and_far_ones_are_not() {
        let fields = ["at", "color", "intensity", "falloff"];
        assert_eq!(did_you_mean("intensty", &fields), Some("intensity"));
        assert_eq!(did_you_mean("colour", &fields), Some("color"));
        assert_eq!(did_you_mean("radius", &fields), None);
        assert_eq!(did_you_mean("x", &fields), None);
    }

    #[test]
    fn a_fraction_is_found_from_its_point() {
        let text = "canvas: (-360.5, 2)";
        let at = text.find('.').unwrap_or(0);
        assert_eq!(fraction_at(text, at), Some((9, "-360.5".to_string())));
        assert_eq!(fraction_at("(a.b)", 2), None);
    }
}

#[cfg(test)]
mod suggestion_tests {
    #[test]
    fn serdes_unknown_names_get_a_suggestion() {
        assert_eq!(
            super::with_suggestion(
                "unknown field `intensty`, expected one of `at`, `intensity`, `color`"
            ),
            "unknown field `intensty`: did you mean `intensity`? (expected one of `at`, `intensity`, `color`)"
        );
        assert_eq!(
            super::with_suggestion("unknown variant `Pint`, expected one of `Point`, `Spot`"),
            "unknown variant `Pint`: did you mean `Point`? (expected one of `Point`, `Spot`)"
        );
        let far = "unknown field `zzzzzz`, expected `at`";
        assert_eq!(super::with_suggestion(far), far);
        assert_eq!(super::with_suggestion("invalid type"), "invalid type");
    }
}
