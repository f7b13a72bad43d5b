//! Criterion benchmarks of flatray: ray queries against the room and
//! against mazes of 1k to 100k walls (brute force with each kernel, and
//! BVH), four rays at a time, rays culled by direction as the floor's are,
//! where the BVH starts to pay, and the room
//! rendered end to end at a reduced size with the memo on and off (in rays
//! per second), a generated plan of 17 to 193 lights with a shadow ray
//! to every light and with the light table, and arcs against the segments
//! they replace.
//!
//! Run: `cargo bench -p flatray-benches` (all), or with a filter, e.g.
//! `cargo bench -p flatray-benches -- closest_hit`.

use std::hint::black_box;
use std::path::Path;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use flatray_benches::{Inputs, maze, room_walls};
use flatray_geometry::{ArcCandidates, DVec2, Kernel, Ray, Segment, SegmentSet, Skip, Strategy};
use flatray_tracer::LightChoice;

/// Nanoseconds per query: `rays` closest-hit queries against `set`.
fn bench_set(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: BenchmarkId,
    set: &SegmentSet,
    rays: &[flatray_geometry::Ray],
) {
    group.bench_with_input(id, set, |b, set| {
        b.iter(|| {
            let mut found = 0u32;
            for ray in rays {
                if let Some((i, _)) = set.closest_hit(black_box(ray), f64::INFINITY, Skip::NONE) {
                    found = found.wrapping_add(i);
                }
            }
            found
        })
    });
}

/// The kernels this processor runs: scalar, and AVX where it has it.
fn kernels() -> Vec<Kernel> {
    let mut kernels = vec![Kernel::Scalar];
    if Kernel::detect() != Kernel::Scalar {
        kernels.push(Kernel::detect());
    }
    kernels
}

fn closest_hit(c: &mut Criterion) {
    let mut group = c.benchmark_group("closest_hit");
    let rays = Inputs::new(1).rays(4096, 500.0);
    group.throughput(Throughput::Elements(rays.len() as u64));
    let mut sets = vec![("room-13".to_string(), room_walls())];
    for walls in [1_000, 10_000, 100_000] {
        sets.push((format!("maze-{walls}"), maze(walls, 500.0, 2)));
    }
    for (name, segments) in sets {
        // The kernels matter only to brute force (a BVH's leaves are
        // scalar).
        if segments.len() <= 20_000 {
            for kernel in kernels() {
                let set = SegmentSet::with_strategy(segments.clone(), Strategy::BruteForce)
                    .with_kernel(kernel);
                bench_set(
                    &mut group,
                    BenchmarkId::new(format!("BruteForce-{kernel:?}"), &name),
                    &set,
                    &rays,
                );
            }
        }
        let set = SegmentSet::with_strategy(segments, Strategy::Bvh);
        bench_set(&mut group, BenchmarkId::new("Bvh", &name), &set, &rays);
    }
    let set = SegmentSet::new(room_walls());
    // The floor's rays as the render loop casts them: each tests only the
    // walls its 4x4-pixel block and its 1/64 turn of directions can meet.
    let mut inputs = Inputs::new(3);
    let blocks: Vec<(ArcCandidates, Vec<(Ray, usize)>)> = (0..64)
        .map(|_| {
            let lo = DVec2::new(
                4.0 * (inputs.uniform() * 125.0).floor(),
                4.0 * (inputs.uniform() * 125.0).floor(),
            );
            let mut arcs = ArcCandidates::default();
            arcs.fill(&set, lo, lo + DVec2::splat(4.0), 64, None);
            let rays = (0..64)
                .map(|_| {
                    let origin = lo + DVec2::new(inputs.uniform(), inputs.uniform()) * 4.0;
                    let u = inputs.uniform();
                    let angle = std::f64::consts::TAU * u;
                    (
                        Ray::new(origin, DVec2::new(angle.cos(), angle.sin())),
                        (u * 64.0) as usize,
                    )
                })
                .collect();
            (arcs, rays)
        })
        .collect();
    group.throughput(Throughput::Elements(64 * 64));
    group.bench_function(BenchmarkId::new("culled-by-arc", "room-13"), |b| {
        b.iter(|| {
            let mut found = 0u32;
            for (arcs, rays) in &blocks {
                for (ray, arc) in rays {
                    let walls = arcs.arc(*arc);
                    if let Some((i, _)) =
                        set.closest_hit_among(black_box(ray), f64::INFINITY, Skip::NONE, walls)
                    {
                        found = found.wrapping_add(i);
                    }
                }
            }
            found
        })
    });
    group.finish();
}

/// Where a BVH starts to beat brute force with the fastest kernel: `n`
/// random walls spread over the rays' square, as a room's are, for small
/// `n` (sets `BVH_THRESHOLD`).
fn bvh_threshold(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh_threshold");
    let rays = Inputs::new(1).rays(4096, 500.0);
    group.throughput(Throughput::Elements(rays.len() as u64));
    let mut inputs = Inputs::new(3);
    let walls: Vec<Segment> = (0..64)
        .map(|_| {
            let a = DVec2::new(inputs.uniform(), inputs.uniform()) * 500.0;
            let d = DVec2::new(inputs.uniform() - 0.5, inputs.uniform() - 0.5) * 200.0;
            Segment::new(a, a + d)
        })
        .collect();
    for n in [8, 12, 16, 24, 32, 48, 64] {
        let segments = walls[..n].to_vec();
        for strategy in [Strategy::BruteForce, Strategy::Bvh] {
            let set = SegmentSet::with_strategy(segments.clone(), strategy);
            bench_set(
                &mut group,
                BenchmarkId::new(format!("{strategy:?}"), n),
                &set,
                &rays,
            );
        }
    }
    group.finish();
}

fn room_render(c: &mut Criterion) {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    let loaded = match flatray_io::load(&scene_path) {
        Ok(l) => l,
        Err(e) => panic!("{e}"),
    };
    let mut group = c.benchmark_group("room_render");
    group.sample_size(10);
    for memo in [true, false] {
        let options = {
            let mut options = loaded.options;
            options.samples = 32;
            options.scale = 0.2;
            options.memo.enabled = memo;
            options
        };
        // Throughput in rays (shadow, bounce and memo-filling rays), so that
        // criterion reports rays per second of a whole render.
        let stats = flatray_tracer::render(&loaded.scene, &options, &|_| {}).stats;
        group.throughput(Throughput::Elements(
            stats.rays() + stats.work.memo_fill_rays,
        ));
        group.bench_function(
            BenchmarkId::new("memo", if memo { "on" } else { "off" }),
            |b| b.iter(|| flatray_tracer::render(&loaded.scene, &options, &|_| {})),
        );
    }
    group.finish();
}

/// Each scene rendered with its plan and with every effect forced on: what
/// skipping buys.
fn plan(c: &mut Criterion) {
    let direct_only = "Scene(canvas: (200, 200), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (20, 20), b: (180, 20), material: Transparent()), Wall(a: (180, 20), b: (180, 180), material: Transparent())],
        lights: [Point(at: (60, 60), intensity: 3.0), Line(a: (100, 150), b: (150, 160), intensity: 0.1)],
        render: (bounces: 1))";
    let no_mirror = "Scene(canvas: (200, 200), floor: Color((0.8, 0.8, 0.8)),
        walls: [Wall(a: (20, 20), b: (180, 20), material: Diffuse(albedo: (0.9, 0.2, 0.2))), Wall(a: (180, 20), b: (180, 180)),
                Wall(a: (40, 120), b: (90, 140))],
        lights: [Point(at: (60, 60), intensity: 3.0), Line(a: (100, 150), b: (150, 160), intensity: 0.1)],
        render: (bounces: 2))";
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    for (name, text) in [("direct-only", direct_only), ("no-mirror", no_mirror)] {
        let loaded = match flatray_io::parse(text, Path::new("bench.ron"), Path::new(".")) {
            Ok(l) => l,
            Err(e) => panic!("{e}"),
        };
        for force in [false, true] {
            let options = {
                let mut options = loaded.options;
                options.samples = 16;
                options = options.with_reference(force);
                options
            };
            let label = if force { "reference" } else { "planned" };
            group.bench_function(BenchmarkId::new(name, label), |b| {
                b.iter(|| flatray_tracer::render(&loaded.scene, &options, &|_| {}))
            });
        }
    }
    group.finish();
}

/// A generated 16-room plan with 1, 3 and 12 lamps a room (17, 49 and 193
/// lights, 3 bounces, at a quarter of its size, 16 spp), with a shadow
/// ray to every light and with the light table: how a sample's cost grows
/// with the lights.
fn many_lights(c: &mut Criterion) {
    let mut group = c.benchmark_group("many_lights");
    group.sample_size(10);
    for lamps in [1, 3, 12] {
        let plan = flatray_io::generate::Apartment {
            lamps_per_room: lamps,
            ..flatray_io::generate::Apartment::default()
        };
        let loaded = match flatray_io::parse(&plan.to_ron(), Path::new("plan.ron"), Path::new("."))
        {
            Ok(l) => l,
            Err(e) => panic!("{e}"),
        };
        let lights = loaded.scene.lights().len();
        for choice in [LightChoice::Every, LightChoice::Table] {
            let options = {
                let mut options = loaded.options;
                options.scale = 0.25;
                options.light_choice = choice;
                options
            };
            let label = format!("{lights}-lights");
            let name = if choice == LightChoice::Every {
                "every"
            } else {
                "table"
            };
            group.bench_function(BenchmarkId::new(name, label), |b| {
                b.iter(|| flatray_tracer::render(&loaded.scene, &options, &|_| {}))
            });
        }
    }
    group.finish();
}

/// What an arc costs against the segments it replaces: rays from inside a
/// circle of radius 100 against the circle as one arc and as a polygon of
/// 32 and 96 segments (brute force and BVH), and the lens of
/// `scenes/lens.ron` (two arcs) against `scenes/lens-polygon.ron` (96
/// facets), light traced at half size.
fn arcs(c: &mut Criterion) {
    use flatray_geometry::{Arc, Shape};
    let mut group = c.benchmark_group("arcs");
    let mut inputs = Inputs::new(5);
    let centre = DVec2::new(250.0, 250.0);
    let rays: Vec<Ray> = (0..4096)
        .map(|_| {
            let o = centre + DVec2::new(inputs.uniform() - 0.5, inputs.uniform() - 0.5) * 100.0;
            let a = inputs.uniform() * std::f64::consts::TAU;
            Ray::new(o, DVec2::new(a.cos(), a.sin()))
        })
        .collect();
    group.throughput(Throughput::Elements(rays.len() as u64));
    let circle = SegmentSet::of_shapes(vec![Shape::Arc(Arc::circle(centre, 100.0, 0.0))]);
    bench_set(
        &mut group,
        BenchmarkId::new("circle", "1 arc"),
        &circle,
        &rays,
    );
    for n in [32, 96] {
        let corner = |k: usize| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            centre + 100.0 * DVec2::new(a.cos(), a.sin())
        };
        let polygon: Vec<Segment> = (0..n)
            .map(|k| Segment::new(corner(k), corner(k + 1)))
            .collect();
        for strategy in [Strategy::BruteForce, Strategy::Bvh] {
            let set = SegmentSet::with_strategy(polygon.clone(), strategy);
            bench_set(
                &mut group,
                BenchmarkId::new("circle", format!("{n} segments, {strategy:?}")),
                &set,
                &rays,
            );
        }
    }
    group.sample_size(10);
    for name in ["lens", "lens-polygon"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.ron"));
        let loaded = match flatray_io::load(&path) {
            Ok(l) => l,
            Err(e) => panic!("{e}"),
        };
        let options = {
            let mut options = loaded.options;
            options.samples = 8;
            options.scale = 0.5;
            options.integrator = flatray_tracer::Integrator::Light;
            options
        };
        group.throughput(Throughput::Elements(1));
        group.bench_function(BenchmarkId::new("render", name), |b| {
            b.iter(|| flatray_tracer::render(&loaded.scene, &options, &|_| {}))
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    closest_hit,
    bvh_threshold,
    room_render,
    plan,
    many_lights,
    arcs
);
criterion_main!(benches);
