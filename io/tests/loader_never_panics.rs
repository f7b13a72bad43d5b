//! The scene loader on arbitrary and mutated text: it never panics; it
//! loads, or returns an error that names a line and column.

use std::path::Path;

use proptest::prelude::*;

const VALID: &str = r#"Scene(
    canvas: (50, 40),
    floor: Tiles(size: 10, grout_width: 1, tile: (0.8, 0.8, 0.7), grout: (0.3, 0.3, 0.3)),
    falloff: Window(range: 200.0),
    walls: [
        Wall(a: (5, 5), b: (45, 5)),
        Wall(a: (45, 5), b: (45, 35), material: Mirror(tint: (0.9, 0.9, 0.9))),
        Wall(a: (10, 20), b: (20, 30), material: Transparent()),
        Wall(a: (30, 30), b: (40, 30), material: Diffuse(albedo: (0.2, 0.4, 0.9)), emit: (intensity: 0.1)),
    ],
    lights: [
        Point(at: (10, 10), color: (1, 1, 0.8), intensity: 2.0),
        Spot(at: (25, 25), direction: (1, 0), cone: 40, softness: 10),
        Line(a: (20, 3), b: (30, 3), intensity: 0.2, one_sided: true, solid: true),
        Directional(direction: (1, 2), intensity: 0.1),
        Sun(date: "2026-06-21", time: "09:30", zone: 2, latitude: 48.85, longitude: 2.35, north: 15),
        Sky(color: (0.7, 0.8, 1), intensity: 0.05),
    ],
    glass: [
        Glass(points: [(20, 15), (28, 15), (24, 22)], ior: 1.5, absorption: (0.1, 0, 0), dispersion: 0.01),
    ],
    render: (samples: 4, bounces: 2, seed: 3, exposure: 1.5, integrator: Light, tonemap: Clamp, cache: false),
)"#;

fn check(text: &str) -> Result<(), TestCaseError> {
    match flatray_io::parse(text, Path::new("fuzz.ron"), Path::new("/nonexistent")) {
        Ok(_) => Ok(()),
        Err(e) => {
            let (line, column) = e.location().unwrap_or((0, 0));
            prop_assert!(line >= 1 && column >= 1, "no location: {e}");
            prop_assert!(e.to_string().starts_with("fuzz.ron:"), "{e}");
            Ok(())
        }
    }
}

#[test]
fn the_valid_scene_loads() {
    assert!(flatray_io::parse(VALID, Path::new("fuzz.ron"), Path::new(".")).is_ok());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, rng_seed: proptest::test_runner::RngSeed::Fixed(11), ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        check(&text)?;
    }

    #[test]
    fn mutated_scenes_never_panic(
        edits in prop::collection::vec((0usize..VALID.len(), 0u8..4, "[-+0-9.eE(),:a-zA-Z\\[\\] \"]{0,3}"), 1..4)
    ) {
        let mut text = VALID.to_string();
        for (position, kind, insert) in edits {
            let mut at = position.min(text.len());
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            match kind {
                0 => text.insert_str(at, &insert),
                1 => {
                    let end = (at + insert.len().max(1)).min(text.len());
                    if text.is_char_boundary(end) {
                        text.replace_range(at..end, "");
                    }
                }
                2 => {
                    let end = (at + insert.len()).min(text.len());
                    if text.is_char_boundary(end) {
                        text.replace_range(at..end, &insert);
                    }
                }
                _ => text.truncate(at),
            }
        }
        check(&text)?;
    }

    #[test]
    fn numbers_anywhere_never_panic(value in prop_oneof![
        Just("NaN".to_string()), Just("inf".to_string()), Just("-inf".to_string()),
        Just("1e308".to_string()), Just("-1e308".to_string()), Just("4294967296".to_string()),
        Just("0".to_string()), Just("-0.0".to_string()), Just("1e-320".to_string()),
    ], which in 0usize..40) {
        // Replace the `which`-th number of the valid scene.
        let mut count = 0;
        let mut out = String::new();
        let mut chars = VALID.char_indices().peekable();
        while let Some((_, c)) = chars.next() {
            if c.is_ascii_digit() {
                let mut number = c.to_string();
                while let Some(&(_, d)) = chars.peek() {
                    if d.is_ascii_digit() || d == '.' { number.push(d); chars.next(); } else { break; }
                }
                out.push_str(if count == which { &value } else { &number });
                count += 1;
            } else {
                out.push(c);
            }
        }
        check(&out)?;
    }
}
