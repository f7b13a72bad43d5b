//! The rough mirror: a glossy lobe about the mirror direction, reached by
//! both integrators through the material interface. Roughness 0 is the
//! mirror to the bit; the lobe conserves energy in a furnace; path and
//! light tracing agree on a rotated room with a rough mirror and a lamp;
//! and the default render sees a lamp in a slightly rough mirror.

use std::f64::consts::TAU;

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, block_stats, render, scene};
use flatray_tracer::{Integrator, Material, MemoOptions, RenderOptions, Scene, Wall};

fn polygon(n: usize, centre: DVec2, radius: f64, turn: f64, extra: &str) -> Vec<String> {
    (0..n)
        .map(|k| {
            let (a0, a1) = (
                turn + TAU * k as f64 / n as f64,
                turn + TAU * (k + 1) as f64 / n as f64,
            );
            let a = centre + radius * DVec2::new(a0.cos(), a0.sin());
            let b = centre + radius * DVec2::new(a1.cos(), a1.sin());
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){extra})",
                a.x, a.y, b.x, b.y
            )
        })
        .collect()
}

/// A lamp at (37.3, 26.6) among `walls` on a 64-pixel canvas: light and
/// path tracing with `options` agree on every 8-pixel block but the
/// lamp's within 5 standard errors over 24 seeds from `first_seed`.
fn lamp_agrees(name: &str, walls: &[String], options: RenderOptions, first_seed: u64) {
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: (37.3, 26.6), intensity: 2.0)])",
        walls.join(", ")
    );
    let loaded = scene(&text);
    let block = 8;
    let light_block = (26 / block * (64 / block) + 37 / block) as usize;
    let agreement = Agreement {
        block,
        runs: 24,
        first_seed,
        k: 5.0,
        min_blocks: 20,
    };
    agreement.check(name, &loaded.scene, options, |b| b != light_block);
}

/// A rough mirror of roughness 0, in the scene format and through the
/// API, renders the same bits as the mirror, with every default on (the
/// caustic pass, the memo, the fast paths).
#[test]
fn roughness_zero_is_the_mirror_bit_for_bit() {
    let room = std::fs::read_to_string(flatray_tests::workspace_root().join("scenes/room.ron"))
        .unwrap_or_default();
    assert!(room.contains("material: Mirror()"));
    let rough = room.replace("material: Mirror()", "material: Rough(roughness: 0)");
    let options = {
        let mut options = RenderOptions::default();
        options.scale = 0.25;
        options.samples = 16;
        options
    };
    let mirror = render(&scene(&room).scene, &options);
    let zero = render(&scene(&rough).scene, &options);
    assert_eq!(mirror.image.pixels, zero.image.pixels);
    // Through the API: the scene's walls given as rough mirrors of
    // roughness 0.
    let given = scene(&room).scene;
    let walls = given
        .walls()
        .iter()
        .map(|w| Wall {
            material: match w.material {
                Material::Mirror { tint } => Material::Rough {
                    roughness: 0.0,
                    tint,
                },
                other => other,
            },
            ..*w
        })
        .collect();
    let api = Scene::with_glass(
        *given.canvas(),
        given.floor().clone(),
        given.small_radius(),
        walls,
        given.lights().to_vec(),
        given.glass().to_vec(),
    )
    .expect("a valid scene");
    assert!(api.walls().iter().any(|w| w.material.is_mirror()));
    assert_eq!(render(&api, &options).image.pixels, mirror.image.pixels);
    // A slightly rough one differs.
    let slight = room.replace("material: Mirror()", "material: Rough(roughness: 0.05)");
    let slight = render(&scene(&slight).scene, &options);
    assert_ne!(mirror.image.pixels, slight.image.pixels);
}

/// The flatland furnace with rough white reflectors: every wall of a
/// heptagon emits radiance `L` and reflects it by a lobe of roughness
/// `r`, so a floor point inside receives `2 pi L (D + 1)` with `D`
/// bounces, for every roughness, exactly when the lobe reflects all it
/// receives. Checked for both integrators, on the mean over the inner
/// pixels, within 3 standard errors over independent seeds.
#[test]
fn a_furnace_of_rough_white_mirrors_conserves_energy() {
    let l_e = 0.25;
    let bounces = 2;
    let expected = TAU * l_e * (bounces + 1) as f64;
    for roughness in [0.05, 0.3, 1.0] {
        let walls = polygon(
            7,
            DVec2::new(32.0, 32.0),
            30.0,
            0.3,
            &format!(", material: Rough(roughness: {roughness}), emit: (intensity: {l_e})"),
        )
        .join(", ");
        let text = format!("Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{walls}])");
        let loaded = scene(&text);
        for integrator in [Integrator::Path, Integrator::Light] {
            let options = {
                let mut options = RenderOptions::default();
                options.samples = 4;
                options.bounces = bounces;
                options.integrator = integrator;
                options
            };
            // The mean of the blocks well inside (inradius 27), over runs.
            let runs = 16;
            let block = 8;
            let inside: Vec<usize> = (0..64)
                .filter(|b| {
                    let (bx, by) = ((b % 8) * block + 4, (b / 8) * block + 4);
                    DVec2::new(bx as f64, by as f64).distance(DVec2::new(32.0, 32.0)) <= 20.0
                })
                .collect();
            let stats = block_stats(&loaded.scene, options, block as u32, runs, 7000);
            let per = 3.0 * (block * block) as f64 * inside.len() as f64;
            let mean = inside.iter().map(|&b| stats[b].0).sum::<f64>() / per;
            // Blocks of one run share photons (light tracing) and paths
            // cross blocks: the blocks' errors are added, not assumed
            // independent, which only widens the bound.
            let se = inside.iter().map(|&b| stats[b].1).sum::<f64>() / per;
            assert!(
                (mean - expected).abs() <= 3.0 * se,
                "{integrator:?}, roughness {roughness}: {mean}, expected {expected}, 3 SE = {}",
                3.0 * se
            );
        }
    }
}

/// A rotated, non-convex room with a rough mirror, a mirror and a lamp:
/// light and path tracing agree on every block within 5 standard errors.
#[test]
fn light_and_path_tracing_agree_with_a_rough_mirror() {
    let mut walls = polygon(
        6,
        DVec2::new(32.0, 32.0),
        29.0,
        0.41,
        ", material: Diffuse(albedo: (0.6, 0.6, 0.6))",
    );
    // One side of the hexagon is a rough mirror, one a perfect mirror that
    // sends the lamp's light to it (a chain only the caustic pass follows
    // in path tracing), and a diffuse wall juts in from another.
    walls[1] = walls[1].replace(
        "material: Diffuse(albedo: (0.6, 0.6, 0.6))",
        "material: Rough(roughness: 0.15, tint: (0.9, 0.85, 0.8))",
    );
    walls[4] = walls[4].replace(
        "material: Diffuse(albedo: (0.6, 0.6, 0.6))",
        "material: Mirror()",
    );
    walls.push(
        "Wall(a: (12.0, 40.0), b: (30.0, 47.0), material: Diffuse(albedo: (0.5, 0.5, 0.5)))".into(),
    );
    let options = {
        let mut options = RenderOptions::default();
        options.samples = 8;
        options.bounces = 2;
        options.memo = MemoOptions::default();
        options.memo.enabled = false;
        options
    };
    lamp_agrees("rough mirror room", &walls, options, 3000);
}

/// A lamp lights a corridor's far side only by a slightly rough mirror
/// (a wall blocks its direct light): the default render shows that
/// light, about as much of it as the perfect mirror brings, and none
/// where the mirror is black.
#[test]
fn the_default_render_sees_a_lamp_in_a_slightly_rough_mirror() {
    let text = |material: &str| {
        format!(
            "Scene(canvas: (120, 80), floor: Color((0.8, 0.8, 0.8)),
                   walls: [
                       Wall(a: (0, 5), b: (120, 5), material: {material}),
                       Wall(a: (60, 20), b: (60, 80), material: Diffuse(albedo: (0, 0, 0))),
                   ],
                   lights: [Point(at: (30, 50), intensity: 10)],
                   render: (samples: 32))"
        )
    };
    // The mean over the far side's pixels, away from the divider.
    let far = |material: &str| {
        let loaded = scene(&text(material));
        let rendered = render(&loaded.scene, &RenderOptions::default());
        let image = &rendered.image;
        let mut sum = 0.0;
        let mut count = 0;
        for y in 30..80 {
            for x in 70..110 {
                let p = image.pixels[y * image.width as usize + x];
                sum += p.iter().map(|&c| c as f64).sum::<f64>() / 3.0;
                count += 1;
            }
        }
        sum / count as f64
    };
    let black = far("Diffuse(albedo: (0, 0, 0))");
    let mirror = far("Mirror()");
    let rough = far("Rough(roughness: 0.05)");
    assert!(black < 1e-9, "black mirror: {black}");
    assert!(mirror > 0.0);
    assert!(
        (rough - mirror).abs() < 0.2 * mirror,
        "rough {rough} against mirror {mirror}"
    );
}

/// A lamp's light off a rough mirror at a path's first bounce comes from
/// the caustic pass's photons by default, and from next-event estimation
/// through the lobe without it: the two agree on every block within 5
/// standard errors, for a narrow and a wide lobe. (Without the caustic
/// pass, path tracing cannot see the lamp in a perfect mirror at all: the
/// light tracer checks that case, above.)
#[test]
fn the_caustic_pass_and_next_event_estimation_agree_off_a_rough_mirror() {
    for roughness in [0.04, 0.4] {
        let mut walls = polygon(
            5,
            DVec2::new(32.0, 32.0),
            29.0,
            0.2,
            ", material: Diffuse(albedo: (0.5, 0.5, 0.5))",
        );
        walls[0] = walls[0].replace(
            "material: Diffuse(albedo: (0.5, 0.5, 0.5))",
            &format!("material: Rough(roughness: {roughness})"),
        );
        let text = format!(
            "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}],
                   lights: [Point(at: (30.5, 36.2), intensity: 2.0)])",
            walls.join(", ")
        );
        let loaded = scene(&text);
        let block = 8;
        let at = |caustics| {
            let mut options = RenderOptions::default();
            options.samples = 8;
            options.bounces = 2;
            options.caustics = caustics;
            options
        };
        let photons = block_stats(&loaded.scene, at(true), block, 16, 5000);
        let paths = block_stats(&loaded.scene, at(false), block, 16, 5000);
        let light_block = (36 / block * (64 / block) + 30 / block) as usize;
        let mut checked = 0;
        for (b, ((mp, sp), (mn, sn))) in photons.iter().zip(&paths).enumerate() {
            if b == light_block || *mn == 0.0 {
                continue;
            }
            let se = (sp * sp + sn * sn).sqrt();
            assert!(
                (mp - mn).abs() <= 5.0 * se,
                "roughness {roughness}, block {b}: photons {mp}, paths {mn}, 5 SE = {}",
                5.0 * se
            );
            checked += 1;
        }
        assert!(checked >= 30, "only {checked} blocks");
    }
}

/// Light from a lamp by a mirror onto one rough mirror and from it onto a
/// second (a path class no path finds: the first rough mirror's
/// next-event estimation does not bend at the mirror), in a rotated room:
/// path and light tracing agree on every block within 5 standard errors,
/// at two and three bounces.
#[test]
fn light_by_a_mirror_off_two_rough_mirrors_reaches_the_floor() {
    let mut walls = polygon(
        6,
        DVec2::new(32.0, 32.0),
        29.0,
        0.41,
        ", material: Diffuse(albedo: (0.2, 0.2, 0.2))",
    );
    for k in [1, 2] {
        walls[k] = walls[k].replace(
            "material: Diffuse(albedo: (0.2, 0.2, 0.2))",
            "material: Rough(roughness: 0.1, tint: (0.95, 0.95, 0.95))",
        );
    }
    walls[4] = walls[4].replace(
        "material: Diffuse(albedo: (0.2, 0.2, 0.2))",
        "material: Mirror()",
    );
    for bounces in [2, 3] {
        let mut options = RenderOptions::default();
        options.samples = 8;
        options.bounces = bounces;
        let name = format!("two rough mirrors, {bounces} bounces");
        lamp_agrees(&name, &walls, options, 3100);
    }
}
