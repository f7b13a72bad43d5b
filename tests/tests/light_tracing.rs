//! The light tracer against the path tracer and the closed forms. Light
//! tracing spreads one photon's flight over many pixels, so pixels are not
//! independent: every tolerance here uses the spread of block totals over
//! independent runs (fixed seeds), stated in standard errors.

use std::f64::consts::TAU;

use flatray_geometry::DVec2;
use flatray_tests::{Agreement, render, scene, workspace_root};
use flatray_tracer::{Integrator, MemoOptions, RenderOptions, Scene};

const BLOCK: u32 = 8;

/// Mean and standard error of each block total over `runs` seeds.
fn block_stats(scene: &Scene, options: RenderOptions, runs: u64) -> Vec<(f64, f64)> {
    flatray_tests::block_stats(scene, options, BLOCK, runs, 1000)
}

fn options(integrator: Integrator, samples: u32, bounces: u32) -> RenderOptions {
    {
        let mut options = RenderOptions::default();
        options.samples = samples;
        options.bounces = bounces;
        options.integrator = integrator;
        options.memo = MemoOptions::default();
        options.memo.enabled = false;
        options
    }
}

/// Independent runs per integrator, and the tolerance in standard errors.
/// With standard errors estimated from 24 runs, the statistic follows a
/// t distribution with 23 degrees of freedom: beyond 5, once in 25,000
/// blocks.
const RUNS: u64 = 24;
const K: f64 = 5.0;

/// Light and path tracing agree on every kept block within `K` combined
/// standard errors.
fn assert_agree(name: &str, scene: &Scene, scale: f64, bounces: u32, keep: impl Fn(usize) -> bool) {
    let agreement = Agreement {
        block: BLOCK,
        runs: RUNS,
        first_seed: 1000,
        k: K,
        min_blocks: 10,
    };
    let options = {
        let mut options = options(Integrator::Path, 8, bounces);
        options.scale = scale;
        options
    };
    agreement.check(name, scene, options, keep);
}

fn polygon(n: usize, centre: DVec2, radius: f64, extra: &str) -> String {
    (0..n)
        .map(|k| {
            let (a0, a1) = (TAU * k as f64 / n as f64, TAU * (k + 1) as f64 / n as f64);
            let a = centre + radius * DVec2::new(a0.cos(), a0.sin());
            let b = centre + radius * DVec2::new(a1.cos(), a1.sin());
            format!(
                "Wall(a: ({:?}, {:?}), b: ({:?}, {:?}){extra})",
                a.x, a.y, b.x, b.y
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[test]
fn light_and_path_tracing_agree_in_the_circle_room() {
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}],
               lights: [Point(at: (32.3, 31.6), intensity: 2.0)])",
        polygon(
            48,
            DVec2::new(32.0, 32.0),
            28.0,
            ", material: Diffuse(albedo: (0.7, 0.5, 0.3))"
        )
    );
    let loaded = scene(&text);
    // The block holding the light differs by definition (the path tracer
    // clamps 1/r below r0 at the light, the light tracer integrates it).
    let light_block = (31 / BLOCK * (64 / BLOCK) + 32 / BLOCK) as usize;
    assert_agree("circle room", &loaded.scene, 1.0, 2, |b| b != light_block);
}

#[test]
fn light_tracing_meets_the_flatland_furnace() {
    let (l_e, rho): (f64, f64) = (0.25, 0.5);
    let text = format!(
        "Scene(canvas: (64, 64), floor: Color((1, 1, 1)), walls: [{}])",
        polygon(
            7,
            DVec2::new(32.0, 32.0),
            30.0,
            &format!(
                ", material: Diffuse(albedo: ({rho}, {rho}, {rho})), emit: (intensity: {l_e})"
            )
        )
    );
    let loaded = scene(&text);
    for bounces in [0, 2] {
        let expected = TAU * l_e * (0..=bounces).map(|k| rho.powi(k)).sum::<f64>();
        let stats = block_stats(
            &loaded.scene,
            options(Integrator::Light, 8, bounces as u32),
            RUNS,
        );
        // Blocks well inside the heptagon (inradius 27).
        let mut checked = 0;
        for (b, (mean, se)) in stats.iter().enumerate() {
            let (bx, by) = ((b as u32 % 8) * BLOCK, (b as u32 / 8) * BLOCK);
            let centre = DVec2::new(bx as f64 + 4.0, by as f64 + 4.0);
            if centre.distance(DVec2::new(32.0, 32.0)) > 20.0 {
                continue;
            }
            let per_pixel = mean / (3.0 * (BLOCK * BLOCK) as f64);
            let se = se / (3.0 * (BLOCK * BLOCK) as f64);
            assert!(
                (per_pixel - expected).abs() <= K * se,
                "D = {bounces}, block {b}: {per_pixel}, expected {expected}, {K} SE = {}",
                K * se
            );
            checked += 1;
        }
        assert!(checked >= 12);
    }
}

#[test]
fn light_and_path_tracing_agree_on_the_room_without_its_mirror() {
    // The room's own kernel (Window), lights and floor, at a fifth of its
    // resolution, the mirror made an ordinary wall: every path is seen by
    // both integrators.
    let text = std::fs::read_to_string(workspace_root().join("scenes/room.ron"))
        .unwrap()
        .replace("material: Mirror()", "material: Diffuse()");
    let loaded = scene(&text);
    assert_agree("room without mirror", &loaded.scene, 0.2, 1, |_| true);
}

/// A point light facing a mirror: both the light tracer and the default
/// render (path tracing with its caustic pass) light the patch that the
/// mirror image of the light sees through the mirror, by the virtual
/// light's `I / r`, and add nothing outside it.
#[test]
fn both_integrators_see_a_point_light_in_a_mirror() {
    let text = "Scene(canvas: (160, 120), floor: Color((1, 1, 1)),
        walls: [Wall(a: (120, 50), b: (120, 70), material: Mirror())],
        lights: [Point(at: (80.0, 60.0), intensity: 4.0)],
        render: (bounces: 1))";
    let loaded = scene(text);
    let light = DVec2::new(80.0, 60.0);
    let virtual_light = DVec2::new(160.0, 60.0);
    let lt = render(&loaded.scene, &options(Integrator::Light, 64, 1)).image;
    let pt = render(&loaded.scene, &options(Integrator::Path, 64, 1)).image;
    // Where does the geometry say the reflection lands? The segment from a
    // floor point to the virtual light must cross the mirror.
    let reflected = |p: DVec2| {
        let t = (120.0 - p.x) / (virtual_light.x - p.x);
        let y = p.y + t * (virtual_light.y - p.y);
        p.x < 120.0 && (50.0..=70.0).contains(&y)
    };
    // The mirror is opaque: it shadows the light behind it.
    let shadowed = |p: DVec2| {
        let t = (120.0 - p.x) / (light.x - p.x);
        let y = p.y + t * (light.y - p.y);
        p.x > 120.0 && (50.0..=70.0).contains(&y)
    };
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    let (mut path_inside, mut path_outside) = (Vec::new(), Vec::new());
    for y in 2..118 {
        for x in 2..158 {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let near_edge = [(-0.7, -0.7), (0.7, -0.7), (-0.7, 0.7), (0.7, 0.7)]
                .iter()
                .any(|&(dx, dy)| shadowed(p + DVec2::new(dx, dy)) != shadowed(p));
            if p.distance(light) < 4.0 || near_edge || (p.x - 120.0).abs() < 2.0 {
                continue;
            }
            let direct = if shadowed(p) {
                0.0
            } else {
                4.0 / p.distance(light)
            };
            let extra = lt.get(x, y)[0] as f64 - direct;
            let path_extra = pt.get(x, y)[0] as f64 - direct;
            // Away from the patch's edges, sort pixels by the geometry.
            let corners = [(-0.7, -0.7), (0.7, -0.7), (-0.7, 0.7), (0.7, 0.7)]
                .map(|(dx, dy)| reflected(p + DVec2::new(dx, dy)));
            let image = 4.0 / p.distance(virtual_light);
            if corners.iter().all(|&c| c) {
                inside.push(extra / image);
                path_inside.push(path_extra / image);
            } else if corners.iter().all(|&c| !c) {
                outside.push(extra);
                path_outside.push(path_extra);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    // Inside the patch the extra light is the virtual light's I / r: the
    // mean ratio is 1 within 2 % (64 photons per pixel, thousands of
    // pixels); outside it is zero.
    assert!(inside.len() > 2000 && outside.len() > 2000);
    assert!(
        (mean(&inside) - 1.0).abs() < 0.02,
        "ratio inside the patch {}",
        mean(&inside)
    );
    assert!(
        mean(&outside).abs() < 0.002,
        "extra light outside the patch {}",
        mean(&outside)
    );
    // The same for the default render: 0.4 photons per pixel aimed at the
    // mirror (it takes 8 % of the light's power: `caustics::photon_rate`),
    // each lighting a whole line of the patch.
    assert!(
        (mean(&path_inside) - 1.0).abs() < 0.02,
        "default render: ratio inside the patch {}",
        mean(&path_inside)
    );
    assert!(
        mean(&path_outside).abs() < 0.002,
        "default render: extra light outside the patch {}",
        mean(&path_outside)
    );
}

#[test]
fn light_tracing_is_bit_identical_for_any_thread_count() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    let options = {
        let mut options = loaded.options;
        options.samples = 2;
        options.scale = 0.2;
        options.integrator = Integrator::Light;
        options
    };
    let one = flatray_tests::render_on(&loaded.scene, &options, 1);
    let three = flatray_tests::render_on(&loaded.scene, &options, 3);
    assert!(one.image == three.image);
    assert_eq!(one.stats, three.stats);
}

/// The model's pixel value near a light, by quadrature: the mean over the
/// unit pixel at `(x, y)` of `fluence(p)`, an `n` x `n` midpoint rule.
fn pixel_mean(x: u32, y: u32, n: u32, fluence: impl Fn(DVec2) -> f64) -> f64 {
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            let p = DVec2::new(
                x as f64 + (i as f64 + 0.5) / n as f64,
                y as f64 + (j as f64 + 0.5) / n as f64,
            );
            sum += fluence(p);
        }
    }
    sum / (n * n) as f64
}

/// Every kernel's light tracing meets the model in the light's own pixel
/// and around it: a point light's fluence is `I G(max(r, r0))` and a line
/// light's `I` times the integral of `G(r') r'` over the angle it
/// subtends, averaged over each pixel. The kernel's factor is integrated
/// exactly along each pixel crossing (at the crossing's middle it was 10
/// to 19 % too bright in the light's pixel, and off by 1.5 to 15 % around
/// it and at a window's cutoff). Per pixel, 5 standard errors over 24
/// seeded runs.
#[test]
fn light_tracing_meets_every_kernel_next_to_the_light() {
    let (at, r0, intensity) = (DVec2::new(6.3, 5.6), 0.5, 2.0);
    let (a, b) = (DVec2::new(3.2, 8.4), DVec2::new(9.1, 8.9));
    let kernels = [
        ("Flatland", "Flatland"),
        ("InverseSquare", "InverseSquare"),
        ("Window", "Window(range: 3.7)"),
        ("Constant", "Constant"),
    ];
    for (name, falloff) in kernels {
        let g = |r: f64| {
            let r = r.max(r0);
            match name {
                "Flatland" => 1.0 / r,
                "InverseSquare" => 1.0 / (r * r),
                "Window" => (1.0 - r / 3.7).max(0.0).powi(2),
                _ => 1.0,
            }
        };
        for light in ["point", "line"] {
            let text = match light {
                "point" => format!(
                    "Scene(canvas: (12, 12), floor: Color((1, 1, 1)), falloff: {falloff},
                       lights: [Point(at: ({:?}, {:?}), intensity: {intensity:?})])",
                    at.x, at.y
                ),
                _ => format!(
                    "Scene(canvas: (12, 12), floor: Color((1, 1, 1)), falloff: {falloff},
                       lights: [Line(a: ({:?}, {:?}), b: ({:?}, {:?}), intensity: {intensity:?})])",
                    a.x, a.y, b.x, b.y
                ),
            };
            let loaded = scene(&text);
            let fluence = |p: DVec2| match light {
                "point" => intensity * g(p.distance(at)),
                _ => {
                    // I G(r') r' cos / r per unit length, along the light.
                    let (edge, n) = (b - a, 2000);
                    let normal = edge.perp().normalize();
                    (0..n)
                        .map(|k| {
                            let q = a + edge * ((k as f64 + 0.5) / n as f64);
                            let r = p.distance(q);
                            let cos = normal.dot(p - q).abs() / r;
                            intensity * g(r) * r.max(r0) * cos / r
                        })
                        .sum::<f64>()
                        * edge.length()
                        / n as f64
                }
            };
            let runs: Vec<flatray_tracer::Image> = (0..RUNS)
                .map(|seed| {
                    let options = {
                        let mut options = options(Integrator::Light, 400, 0);
                        options.seed = 7000 + seed;
                        options
                    };
                    render(&loaded.scene, &options).image
                })
                .collect();
            // The light's pixel and its neighbours (for the line, the
            // pixels it crosses and those beside them), and for the
            // window the pixels its cutoff crosses.
            let pixels: Vec<(u32, u32)> = match light {
                "point" => (3..10)
                    .flat_map(|y| (3..10).map(move |x| (x, y)))
                    .filter(|&(x, y)| {
                        let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                        let d = c.distance(at);
                        d < 2.2 || (name == "Window" && (d - 3.7).abs() < 0.8)
                    })
                    .collect(),
                _ => (3..10).flat_map(|x| (7..11).map(move |y| (x, y))).collect(),
            };
            for (x, y) in pixels {
                let exact = pixel_mean(x, y, if light == "point" { 200 } else { 24 }, fluence);
                let values: Vec<f64> = runs.iter().map(|i| i.get(x, y)[0] as f64).collect();
                let mean = values.iter().sum::<f64>() / RUNS as f64;
                let var =
                    values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (RUNS as f64 - 1.0);
                let se = (var / RUNS as f64).sqrt();
                // f32 pixels, and the quadrature's own error.
                let tolerance = K * se + 2e-4 * exact.abs() + 1e-9;
                assert!(
                    (mean - exact).abs() <= tolerance,
                    "{light} light, {name}, pixel ({x}, {y}): light tracing {mean}, model {exact}, {K} SE = {}",
                    K * se
                );
            }
        }
    }
}
