//! Images are a pure function of (scene, options): bit-identical for any
//! number of threads, and for any order in which tiles finish.

use flatray_tests::{TempDir, render_on, scene, workspace_root};
use flatray_tracer::Integrator;

#[test]
fn one_thread_and_several_threads_give_bit_identical_images() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    for (integrator, memo) in [
        (Integrator::Path, true),
        (Integrator::Path, false),
        (Integrator::Original, true),
    ] {
        let options = {
            let mut options = loaded.options;
            options.samples = 3;
            options.bounces = 2;
            options.scale = 0.3;
            options.integrator = integrator;
            options.memo.enabled = memo;
            options
        };
        let one = render_on(&loaded.scene, &options, 1);
        for threads in [2, 5] {
            let many = render_on(&loaded.scene, &options, threads);
            assert_eq!(
                one.image, many.image,
                "{integrator:?}, memo {memo}, {threads} threads"
            );
            assert_eq!(
                one.stats, many.stats,
                "{integrator:?}, memo {memo}, {threads} threads"
            );
        }
        assert!(one.image.pixels.iter().any(|p| p[0] > 0.0));
    }
}

#[test]
fn a_floor_plan_of_many_lights_renders_the_same_on_any_number_of_threads() {
    // The light table, its tiles' shadow lists, the coherence masks drawn
    // a few lights at a time, the onward memo and the caustic pass.
    let plan = flatray_io::generate::Apartment {
        rooms: 6,
        lamps_per_room: 3,
        mirrors: 1.0,
        seed: 3,
        ..Default::default()
    };
    let loaded = scene(&plan.to_ron());
    let options = {
        let mut options = loaded.options;
        options.samples = 4;
        options.bounces = 3;
        options.scale = 0.3;
        options
    };
    let table = flatray_tracer::Plan::new(&loaded.scene, &options);
    assert!(table.light_table && table.floor_coherence);
    let one = render_on(&loaded.scene, &options, 1);
    for threads in [2, 3] {
        let many = render_on(&loaded.scene, &options, threads);
        assert_eq!(one.image, many.image, "{threads} threads");
        assert_eq!(one.stats, many.stats, "{threads} threads");
    }
    assert!(one.stats.work.listed_shadow_rays > 0);
}

#[test]
fn a_different_seed_gives_a_different_image() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    let options = {
        let mut options = loaded.options;
        options.samples = 2;
        options.scale = 0.2;
        options
    };
    let a = render_on(&loaded.scene, &options, 2);
    let b = render_on(
        &loaded.scene,
        &{
            let mut options = options;
            options.seed = 1;
            options
        },
        2,
    );
    assert_ne!(a.image, b.image);
}

#[test]
fn a_pixel_sample_can_be_rerendered_alone() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/room.ron")).unwrap();
    // Without the memo, a pixel is the mean of its samples alone.
    let options = {
        let mut options = loaded.options;
        options.samples = 1;
        options.scale = 0.1;
        options.exposure = 1.0;
        options.memo.enabled = false;
        options
    };
    let whole = render_on(&loaded.scene, &options, 2);
    let size = (whole.image.width, whole.image.height);
    let (x, y) = (23, 17);
    let mut stats = flatray_tracer::Stats::default();
    let fluence = flatray_tracer::pixel_sample(&loaded.scene, &options, size, x, y, 0, &mut stats);
    // The pixel's square: 10 units at scale 0.1.
    let lo = loaded.scene.canvas().origin + glam::DVec2::new(x as f64, y as f64) * 10.0;
    let albedo = loaded
        .scene
        .floor()
        .mean_albedo(loaded.scene.canvas(), lo, lo + 10.0);
    let value = fluence * albedo;
    assert_eq!(
        whole.image.get(x, y),
        [value.x as f32, value.y as f32, value.z as f32]
    );
}

/// The same image gives the same EXR bytes every time, whatever the
/// threads are doing: blocks go out in order (written in parallel, they
/// went out in the order they finished, 5 files in 24 differing). The
/// values read back are the image's, to the bit.
#[test]
fn an_exr_is_byte_identical_across_identical_writes() {
    let (width, height) = (640u32, 360u32);
    let mut image = flatray_tracer::Image::new(width, height);
    for (k, p) in image.pixels.iter_mut().enumerate() {
        // Values that compress unevenly, so blocks take different times.
        let v = if (k / 977) % 3 == 0 {
            0.25
        } else {
            (k as f32 * 0.618).sin() * 7.0
        };
        *p = [v, v * 0.5, (k % 13) as f32];
    }
    let dir = TempDir::new("exr-bytes");
    let path = dir.path().join("out.exr");
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(4).build() {
        Ok(pool) => pool,
        Err(e) => panic!("no thread pool: {e}"),
    };
    let write = || {
        pool.install(|| flatray_io::write_exr(&image, &path))
            .unwrap_or_else(|e| panic!("{e}"));
        std::fs::read(&path).unwrap_or_else(|e| panic!("{e}"))
    };
    let first = write();
    for run in 1..24 {
        assert!(write() == first, "write {run} gave other bytes");
    }
    assert_eq!(flatray_io::read_exr(&path), Ok(image));
}

/// The glass pentagon under a circle light, whose floor inside the glass
/// takes the light through one edge in closed form and whose caustic pass
/// aims the circle light's photons at the glass: the same image on any
/// number of threads.
#[test]
fn light_through_glass_renders_the_same_on_any_number_of_threads() {
    let loaded = flatray_io::load(&workspace_root().join("scenes/pentagon.ron")).unwrap();
    let mut options = loaded.options;
    options.samples = 4;
    options.scale = 0.25;
    let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
    assert!(plan.closed_forms.glass_lights.runs && plan.area_photons);
    let one = render_on(&loaded.scene, &options, 1);
    for threads in [2, 5] {
        let many = render_on(&loaded.scene, &options, threads);
        assert_eq!(one.image, many.image, "{threads} threads");
        assert_eq!(one.stats, many.stats, "{threads} threads");
    }
    assert!(one.image.pixels.iter().any(|p| p[0] > 0.0));
}
