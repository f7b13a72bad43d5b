//! The library's API as an embedder meets it: a scene is checked where it
//! is built, its tables cannot fall out of step with its walls and
//! lights, and a scene built in code is the scene a file gives.

use flatray_geometry::{DVec2, Ray, Segment, Skip};
use flatray_tests::scene;
use flatray_tracer::scene::Item;
use flatray_tracer::{
    Canvas, Falloff, Floor, Light, LightShape, Material, RenderOptions, Rgb, Scene, Wall, render,
};

fn canvas() -> Canvas {
    Canvas {
        width: 40,
        height: 30,
        origin: DVec2::ZERO,
    }
}

fn lamp(at: DVec2) -> Light {
    Light {
        profile: None,
        shape: LightShape::Point { at },
        color: Rgb::ONE,
        intensity: 1.0,
        falloff: Falloff::Flatland,
        spectrum: None,
    }
}

fn wall(a: (f64, f64), b: (f64, f64)) -> Wall {
    Wall {
        shape: Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1)).into(),
        material: Material::Diffuse { albedo: None },
    }
}

#[test]
fn a_scene_built_in_code_is_checked_as_a_file_is() {
    let build = |walls: Vec<Wall>, lights: Vec<Light>| {
        Scene::new(canvas(), Floor::Color(Rgb::ONE), 0.5, walls, lights)
    };
    let nan = lamp(DVec2::new(f64::NAN, 1.0));
    assert_eq!(
        build(vec![], vec![lamp(DVec2::ONE), nan]).unwrap_err().item,
        Item::Light(1)
    );
    let mut bright = wall((1.0, 1.0), (5.0, 1.0));
    bright.material = Material::Diffuse {
        albedo: Some(Rgb::new(0.5, 1.5, 0.5)),
    };
    let error = build(vec![wall((0.0, 0.0), (1.0, 0.0)), bright], vec![]).unwrap_err();
    assert_eq!(error.item, Item::Wall(1));
    // The words are the scene file's, for the same value.
    let text = "Scene(canvas: (40, 30), floor: Color((1, 1, 1)),
        walls: [Wall(a: (1, 1), b: (5, 1), material: Diffuse(albedo: (0.5, 1.5, 0.5)))])";
    let file_error = flatray_io::parse(text, "a.ron".as_ref(), ".".as_ref()).unwrap_err();
    let flatray_io::SceneError::Invalid { message, .. } = file_error else {
        panic!("{file_error}")
    };
    assert_eq!(message, error.message);
    let glassy = Wall {
        material: Material::Glass {
            body: 0,
            inside: flatray_geometry::Side::Positive,
        },
        ..wall((1.0, 1.0), (5.0, 1.0))
    };
    assert!(
        build(vec![glassy], vec![])
            .unwrap_err()
            .message
            .contains("0 glass bodies")
    );
    let mut canvas = canvas();
    canvas.width = 0;
    assert_eq!(
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, vec![], vec![])
            .unwrap_err()
            .item,
        Item::Canvas
    );
}

#[test]
fn a_scene_changed_through_its_parts_has_its_tables_rebuilt() {
    // A wall between the lamp and the right half; take it away through
    // the parts, and rays and light pass where it stood.
    let walls = vec![
        wall((20.0, 0.0), (20.0, 30.0)),
        wall((0.0, 2.0), (3.0, 2.0)),
    ];
    let walled = Scene::new(
        canvas(),
        Floor::Color(Rgb::ONE),
        0.5,
        walls,
        vec![lamp(DVec2::new(10.0, 15.0))],
    )
    .unwrap();
    let ray = Ray::new(DVec2::new(10.0, 15.0), DVec2::X);
    assert!(
        walled
            .segments()
            .closest_hit(&ray, 100.0, Skip::NONE)
            .is_some()
    );
    let mut parts = walled.parts();
    parts.walls.remove(0);
    let open = parts.build().unwrap();
    assert_eq!(open.walls().len(), 1);
    assert!(
        open.segments()
            .closest_hit(&ray, 100.0, Skip::NONE)
            .is_none()
    );
    let mut options = RenderOptions::default();
    options.samples = 2;
    let (dark, lit) = (
        render(&walled, &options, &|_| {}).image,
        render(&open, &options, &|_| {}).image,
    );
    assert_eq!(dark.get(30, 15), [0.0; 3]);
    assert!(lit.get(30, 15)[0] > 0.0);
    // The parts of a scene build the same scene again.
    assert_eq!(open.parts().build().unwrap().parts(), open.parts());
}

#[test]
fn a_scene_built_in_code_renders_as_its_file_does() {
    let text = "Scene(canvas: (40, 30), floor: Color((0.5, 0.5, 0.5)),
        walls: [Wall(a: (5, 5), b: (35, 8), material: Mirror()), Wall(a: (35, 8), b: (30, 25))],
        lights: [Point(at: (15, 15), intensity: 2.0)])";
    let loaded = scene(text);
    let mut mirror = wall((5.0, 5.0), (35.0, 8.0));
    mirror.material = Material::Mirror { tint: Rgb::ONE };
    let mut light = lamp(DVec2::new(15.0, 15.0));
    light.intensity = 2.0;
    let built = Scene::new(
        canvas(),
        Floor::Color(Rgb::splat(0.5)),
        0.5,
        vec![mirror, wall((35.0, 8.0), (30.0, 25.0))],
        vec![light],
    )
    .unwrap();
    let mut options = loaded.options;
    options.samples = 4;
    assert_eq!(
        render(&built, &options, &|_| {}).image,
        render(&loaded.scene, &options, &|_| {}).image
    );
}

#[test]
fn scene_values_given_as_json_are_checked_with_their_paths() {
    let good = r#"{"canvas": [40, 30], "floor": {"Color": [1, 1, 1]},
        "lights": [{"Point": {"at": [5, 5]}}]}"#;
    let loaded = flatray_io::from_json(good, "values", ".".as_ref()).unwrap();
    assert_eq!(loaded.scene.lights().len(), 1);
    let bad = r#"{"canvas": [40, 30], "floor": {"Color": [1, 1, 1]},
        "lights": [{"Point": {"at": [5, 5]}}, {"Point": {"at": [5, 5], "intensity": -1}}]}"#;
    let error = flatray_io::from_json(bad, "values", ".".as_ref()).unwrap_err();
    assert_eq!(
        error.to_string(),
        "values: lights[1].Point.intensity: expected an intensity from 0 to 1e9, found -1"
    );
    let spot = r#"{"canvas": [40, 30], "floor": {"Color": [1, 1, 1]},
        "lights": [{"Spot": {"at": [5, 5], "direction": [1, 0], "cone": 30, "softness": 40}}]}"#;
    let error = flatray_io::from_json(spot, "values", ".".as_ref()).unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("values: lights[0].Spot.softness: expected 0 < cone <= 180"),
        "{error}"
    );
}
