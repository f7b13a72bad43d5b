//! `flatray serve` in a real browser: headless Chromium loads the page
//! the real binary serves, waits for the render, drags a lamp with the
//! mouse through the page's own handles, checks that the light moved in
//! the image, saves through the page's button and checks the file; and
//! with an edit of the page's own, sees a change made to the file on disk
//! offered as a choice, and keeps each side once.
//!
//! Chromium is Debian's `chromium` package (`apt-get install chromium`),
//! or the browser `FLATRAY_CHROMIUM` names. The screenshot it takes is
//! written to `FLATRAY_SCREENSHOTS` (a folder) when that is set: that is
//! how `docs/images/serve.png` and `docs/images/serve-conflict.png` are
//! made.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use headless_chrome::protocol::cdp::{Input, Page};
use headless_chrome::{Browser, LaunchOptions, Tab};

mod common;

fn chromium() -> PathBuf {
    if let Some(path) = std::env::var_os("FLATRAY_CHROMIUM") {
        return PathBuf::from(path);
    }
    for candidate in [
        "/usr/bin/chromium",
        "/usr/bin/chromium-browser",
        "/usr/bin/google-chrome",
    ] {
        if Path::new(candidate).exists() {
            return PathBuf::from(candidate);
        }
    }
    panic!(
        "this test drives a real browser: install Chromium (`apt-get install chromium`) or name one in FLATRAY_CHROMIUM"
    );
}

/// The mean sRGB value of the PNG's pixels within `radius` of `(x, y)`.
fn brightness(png: &[u8], (x, y): (f64, f64), radius: f64) -> f64 {
    let image = image::load_from_memory(png).unwrap().to_rgb8();
    let mut sum = 0.0;
    let mut n = 0.0;
    for (px, py, p) in image.enumerate_pixels() {
        let (dx, dy) = (px as f64 + 0.5 - x, py as f64 + 0.5 - y);
        if dx * dx + dy * dy <= radius * radius {
            sum += p.0.iter().map(|&c| c as f64).sum::<f64>() / 3.0;
            n += 1.0;
        }
    }
    sum / n
}

fn evaluate(tab: &Tab, js: &str) -> serde_json::Value {
    tab.evaluate(js, false)
        .unwrap_or_else(|e| panic!("{js}: {e}"))
        .value
        .unwrap_or_default()
}

/// Waits, up to 60 s, for the page's image to be a full-size frame of at
/// least `spp` samples for a scene after version `after`.
fn wait_for_render(tab: &Tab, after: u64, spp: u64) -> u64 {
    let started = Instant::now();
    loop {
        let state = evaluate(
            tab,
            "JSON.stringify(document.getElementById('render').dataset)",
        );
        let state: serde_json::Value =
            serde_json::from_str(state.as_str().unwrap_or("{}")).unwrap_or_default();
        let job = state["job"]
            .as_str()
            .and_then(|j| j.parse().ok())
            .unwrap_or(0u64);
        let samples = state["spp"]
            .as_str()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0u64);
        if job > after && state["quick"] == "false" && samples >= spp {
            return job;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "no render: {state}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn mouse(tab: &Tab, kind: Input::DispatchMouseEventTypeOption, (x, y): (f64, f64)) {
    let pressed = !matches!(kind, Input::DispatchMouseEventTypeOption::MouseReleased);
    tab.call_method(Input::DispatchMouseEvent {
        Type: kind,
        x,
        y,
        modifiers: None,
        timestamp: None,
        button: Some(Input::MouseButton::Left),
        buttons: Some(if pressed { 1 } else { 0 }),
        click_count: Some(1),
        force: None,
        tangential_pressure: None,
        tilt_x: None,
        tilt_y: None,
        twist: None,
        delta_x: None,
        delta_y: None,
        pointer_Type: None,
    })
    .unwrap();
}

/// Where world point `(x, y)` is on the screen.
fn on_screen(tab: &Tab, (x, y): (f64, f64)) -> (f64, f64) {
    let js = format!(
        "(() => {{ const s = document.getElementById('plan'); const p = s.createSVGPoint(); p.x = {x}; p.y = {y}; const q = p.matrixTransform(s.getScreenCTM()); return JSON.stringify([q.x, q.y]); }})()"
    );
    let v: Vec<f64> =
        serde_json::from_str(evaluate(tab, &js).as_str().unwrap_or("[]")).unwrap_or_default();
    (v[0], v[1])
}

/// Headless Chromium with a profile of its own in `dir`, showing the page
/// at `url`.
fn open(dir: &Path, url: &str) -> (Browser, std::sync::Arc<Tab>) {
    let options = LaunchOptions::default_builder()
        .path(Some(chromium()))
        .headless(true)
        .sandbox(false)
        .window_size(Some((1100, 760)))
        .user_data_dir(Some(dir.join("profile")))
        .args(
            [
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-quic",
                "--no-first-run",
            ]
            .iter()
            .map(std::ffi::OsStr::new)
            .collect(),
        )
        .build()
        .unwrap();
    let browser = Browser::new(options).unwrap();
    let tab = browser.new_tab().unwrap();
    tab.set_default_timeout(Duration::from_secs(30));
    tab.navigate_to(&format!("{url}/"))
        .unwrap()
        .wait_until_navigated()
        .unwrap();
    (browser, tab)
}

/// Drags with the mouse from world point `from` to `to`, in ten steps.
fn drag(tab: &Tab, from: (f64, f64), to: (f64, f64)) {
    let start = on_screen(tab, from);
    let end = on_screen(tab, to);
    mouse(tab, Input::DispatchMouseEventTypeOption::MouseMoved, start);
    mouse(
        tab,
        Input::DispatchMouseEventTypeOption::MousePressed,
        start,
    );
    for k in 1..=10 {
        let t = k as f64 / 10.0;
        let p = (
            start.0 + (end.0 - start.0) * t,
            start.1 + (end.1 - start.1) * t,
        );
        mouse(tab, Input::DispatchMouseEventTypeOption::MouseMoved, p);
    }
    mouse(tab, Input::DispatchMouseEventTypeOption::MouseReleased, end);
}

/// With `FLATRAY_SCREENSHOTS` set (a folder), clicks `click` first, then
/// writes the page as it is to `name` in that folder: how the live view's
/// pictures in the docs are taken.
fn screenshot(tab: &Tab, click: Option<&str>, name: &str) {
    let Some(folder) = std::env::var_os("FLATRAY_SCREENSHOTS") else {
        return;
    };
    if let Some(selector) = click {
        tab.find_element(selector).unwrap().click().unwrap();
    }
    let shot = tab
        .capture_screenshot(Page::CaptureScreenshotFormatOption::Png, None, None, true)
        .unwrap();
    std::fs::write(Path::new(&folder).join(name), &shot).unwrap();
}

/// Waits, up to 30 s, for the page's `js` to give `true`.
fn wait_until(tab: &Tab, what: &str, js: &str) {
    let started = Instant::now();
    while evaluate(tab, js) != serde_json::Value::Bool(true) {
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "{what}: the page says {}",
            evaluate(tab, "document.getElementById('message').textContent")
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A new, empty folder of this test process's own, named `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flatray-browser{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The body of a response, read whole (up to 64 MiB).
fn body(mut r: ureq::http::Response<ureq::Body>) -> Vec<u8> {
    r.body_mut()
        .with_config()
        .limit(64 << 20)
        .read_to_vec()
        .unwrap()
}

/// What the server at `url` answers a `GET` of `path` with.
fn get(url: &str, path: &str) -> Vec<u8> {
    body(ureq::get(&format!("{url}{path}")).call().unwrap())
}

#[test]
fn a_lamp_dragged_in_the_page_moves_in_the_render_and_is_saved() {
    let dir = scratch("");
    let scene = dir.join("room.ron");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    std::fs::copy(&room, &scene).unwrap();
    let server = common::serve(&scene);
    let url = server.url.clone();

    let (browser, tab) = open(&dir, &url);
    tab.wait_for_element("circle[data-light='1']").unwrap();
    let first_job = wait_for_render(&tab, 0, 64);
    let export = |path: &str| get(&url, path);
    let before = export("/api/export.png");

    // Drag the second lamp, (313, 134), to (420, 420), as a user would.
    let (from, to) = ((313.0, 134.0), (420.0, 420.0));
    drag(&tab, from, to);
    wait_for_render(&tab, first_job, 64);
    let after = export("/api/export.png");
    let near_new = (brightness(&before, to, 12.0), brightness(&after, to, 12.0));
    let near_old = (
        brightness(&before, from, 12.0),
        brightness(&after, from, 12.0),
    );
    assert!(
        near_new.1 > near_new.0 + 20.0,
        "brighter where the lamp went: {near_new:?}"
    );
    assert!(
        near_old.1 < near_old.0 - 20.0,
        "darker where it was: {near_old:?}"
    );

    screenshot(&tab, None, "serve.png");

    // Save through the page's button: the file holds the lamp's new place,
    // its comments, and a backup of what it was.
    tab.find_element("#save").unwrap().click().unwrap();
    let started = Instant::now();
    let saved = loop {
        let text = std::fs::read_to_string(&scene).unwrap();
        if text != std::fs::read_to_string(&room).unwrap() {
            break text;
        }
        if started.elapsed() > Duration::from_secs(60) {
            let said = tab
                .find_element("#message")
                .and_then(|m| m.get_inner_text())
                .unwrap_or_default();
            panic!("not saved; the page says {said:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let lamp = saved
        .lines()
        .filter(|l| l.trim_start().starts_with("Point("))
        .nth(1)
        .unwrap_or_default()
        .to_string();
    let at: Vec<f64> = lamp
        .split("at: (")
        .nth(1)
        .and_then(|r| r.split(')').next())
        .map(|xy| {
            xy.split(',')
                .filter_map(|v| v.trim().parse().ok())
                .collect()
        })
        .unwrap_or_default();
    assert_eq!(at.len(), 2, "{lamp}");
    assert!(
        (at[0] - to.0).abs() < 3.0 && (at[1] - to.1).abs() < 3.0,
        "{lamp}"
    );
    assert!(
        saved.starts_with("// The original project's room"),
        "the comments are kept"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("room.ron.bak")).unwrap(),
        std::fs::read_to_string(&room).unwrap()
    );
    let message = evaluate(&tab, "document.getElementById('message').textContent");
    assert!(
        message.as_str().unwrap_or_default().starts_with("saved"),
        "{message}"
    );
    drop(browser);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_change_on_disk_never_replaces_the_pages_edit_and_each_side_can_be_kept() {
    let dir = std::env::temp_dir().join(format!("flatray-conflict-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("room.ron");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    std::fs::copy(&room, &scene).unwrap();
    let original = std::fs::read_to_string(&scene).unwrap();
    let server = common::serve(&scene);
    let (browser, tab) = open(&dir, &server.url);
    tab.wait_for_element("circle[data-light='1']").unwrap();
    let first = wait_for_render(&tab, 0, 16);
    let lamp = "JSON.stringify(items.lights[1].at.map(Math.round))";
    let conflict_shown = "!document.getElementById('conflict').hidden";

    // Keep mine: the page's lamp stays where it was dragged, the editor's
    // text is in the backup after the page saves.
    drag(&tab, (313.0, 134.0), (420.0, 420.0));
    wait_until(&tab, "the edit", &format!("{lamp} === '[420,420]'"));
    let editor = original.replace("intensity: 0.02", "intensity: 0.05");
    std::fs::write(&scene, &editor).unwrap();
    wait_until(&tab, "the conflict shown", conflict_shown);
    assert_eq!(
        evaluate(&tab, lamp),
        "[420,420]",
        "the page's edit is not replaced"
    );
    assert_eq!(
        evaluate(&tab, "document.getElementById('save').textContent"),
        "Save*"
    );
    screenshot(&tab, Some("#conflict summary"), "serve-conflict.png");
    tab.find_element("#keep-mine").unwrap().click().unwrap();
    wait_until(
        &tab,
        "the conflict settled",
        &format!("!({conflict_shown})"),
    );
    tab.find_element("#save").unwrap().click().unwrap();
    wait_until(
        &tab,
        "saved",
        "document.getElementById('message').textContent.startsWith('saved')",
    );
    let saved = std::fs::read_to_string(&scene).unwrap();
    assert!(saved.contains("Point(at: (420, 420)"), "{saved}");
    assert!(saved.contains("intensity: 0.02"), "mine, whole: {saved}");
    assert_eq!(
        std::fs::read_to_string(dir.join("room.ron.bak")).unwrap(),
        editor
    );

    // Take the file's: the editor's lamp is shown and rendered; Undo
    // brings the page's edit back.
    std::thread::sleep(Duration::from_millis(600));
    drag(&tab, (420.0, 420.0), (100.0, 400.0));
    wait_until(&tab, "the second edit", &format!("{lamp} === '[100,400]'"));
    let editor2 = saved.replace("Point(at: (420, 420)", "Point(at: (250, 250)");
    std::fs::write(&scene, &editor2).unwrap();
    wait_until(&tab, "the second conflict shown", conflict_shown);
    assert_eq!(evaluate(&tab, lamp), "[100,400]");
    tab.find_element("#take-file").unwrap().click().unwrap();
    wait_until(&tab, "the file's lamp", &format!("{lamp} === '[250,250]'"));
    wait_until(
        &tab,
        "the conflict settled",
        &format!("!({conflict_shown})"),
    );
    assert_eq!(
        evaluate(&tab, "document.getElementById('save').textContent"),
        "Save"
    );
    wait_for_render(&tab, first, 16);
    tab.find_element("#undo").unwrap().click().unwrap();
    wait_until(
        &tab,
        "the page's edit back",
        &format!("{lamp} === '[100,400]'"),
    );
    assert_eq!(
        std::fs::read_to_string(&scene).unwrap(),
        editor2,
        "the file's text kept"
    );
    drop(browser);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sodium lamp, a lens, a spot and the sun, as the page must draw and
/// edit them.
const OPTICS: &str = "Scene(
    canvas: (300, 200),
    floor: Color((0.6, 0.6, 0.6)),
    walls: [Wall(a: (20, 20), b: (280, 20))],
    lights: [
        Point(at: (60, 100), intensity: 20, spectrum: Lamp(Sodium)),
        Spot(at: (240, 150), direction: (-1, 0), cone: 30, intensity: 20),
        Directional(direction: (1, 1), intensity: 0.5),
    ],
    glass: [Glass(points: [(150, 50), (150, 190)], through: [(175, 120), (125, 120)], ior: 1.5)],
    render: (samples: 4),
)
";

#[test]
fn spectra_lenses_spots_and_the_sun_are_drawn_as_they_are_and_can_be_changed() {
    let dir = std::env::temp_dir().join(format!("flatray-optics-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("optics.ron");
    std::fs::write(&scene, OPTICS).unwrap();
    let server = common::serve(&scene);
    let (browser, tab) = open(&dir, &server.url);
    tab.wait_for_element("circle[data-light='0']").unwrap();
    let text = || {
        ureq::get(&format!("{}/api/scene.ron", server.url))
            .call()
            .unwrap()
            .body_mut()
            .read_to_string()
            .unwrap()
    };
    // The sodium lamp in its spectrum's orange, not white; the lens with
    // its two arcs; a handle for the spot's and the sun's directions.
    let fill = evaluate(
        &tab,
        "document.querySelector(\"circle[data-light='0']\").getAttribute('fill')",
    );
    let rgb: Vec<u32> = fill
        .as_str()
        .unwrap_or_default()
        .trim_start_matches("rgb(")
        .trim_end_matches(')')
        .split(',')
        .filter_map(|v| v.trim().parse().ok())
        .collect();
    assert!(
        rgb.len() == 3 && rgb[0] == 255 && rgb[1] < 200 && rgb[2] < 60,
        "{fill}"
    );
    let lens = evaluate(
        &tab,
        "document.querySelector('#plan path').getAttribute('d')",
    );
    assert_eq!(
        lens.as_str().unwrap_or_default().matches(" A ").count(),
        2,
        "{lens}"
    );
    tab.wait_for_element("circle[data-direction='1']").unwrap();
    tab.wait_for_element("circle[data-direction='2']").unwrap();
    wait_for_render(&tab, 0, 4);

    // The lamp's colour comes from its lines, and the picker opens on
    // their colour; a blackbody, then a plain colour, replace it.
    tab.find_element("circle[data-light='0']")
        .unwrap()
        .click()
        .unwrap();
    tab.wait_for_element("#colour-from").unwrap();
    assert_eq!(
        evaluate(&tab, "document.getElementById('colour-from').value"),
        "Lamp"
    );
    assert_eq!(
        evaluate(&tab, "document.getElementById('lamp').value"),
        "Sodium"
    );
    assert_ne!(
        evaluate(&tab, "document.getElementById('color').value"),
        "#ffffff"
    );
    evaluate(
        &tab,
        "(() => { const s = document.getElementById('colour-from'); s.value = 'Blackbody'; s.dispatchEvent(new Event('change')); return true; })()",
    );
    wait_until(
        &tab,
        "a blackbody",
        "items.lights[0].spectrum && items.lights[0].spectrum.kind === 'Blackbody'",
    );
    assert!(
        text().contains("Point(at: (60, 100), intensity: 20, spectrum: Blackbody(2700))"),
        "{}",
        text()
    );
    tab.find_element("circle[data-light='0']")
        .unwrap()
        .click()
        .unwrap();
    evaluate(
        &tab,
        "(() => { const s = document.getElementById('colour-from'); s.value = 'Colour'; s.dispatchEvent(new Event('change')); return true; })()",
    );
    wait_until(&tab, "a plain colour", "items.lights[0].spectrum === null");
    let now = text();
    assert!(
        now.contains("Point(at: (60, 100), intensity: 20, color: ("),
        "{now}"
    );
    assert!(!now.contains("Blackbody"), "{now}");
    assert!(
        evaluate(&tab, "document.getElementById('message').textContent")
            .as_str()
            .unwrap_or_default()
            .is_empty()
    );

    // The sun turned by its handle: from (1, 1) to straight down.
    let [w, h] = [300.0, 200.0];
    let centre = (w / 2.0, h / 2.0);
    let reach = 0.3 * f64::min(w, h);
    let knob = (
        centre.0 + reach * std::f64::consts::FRAC_1_SQRT_2,
        centre.1 + reach * std::f64::consts::FRAC_1_SQRT_2,
    );
    drag(&tab, knob, (centre.0, centre.1 + reach));
    wait_until(
        &tab,
        "the sun turned",
        "Math.abs(items.lights[2].direction[0]) < 0.01 && items.lights[2].direction[1] > 0.99",
    );
    // The status line is whole: nothing of it is cut off.
    wait_for_render(&tab, 0, 4);
    screenshot(&tab, Some("circle[data-light='0']"), "serve-optics.png");
    let cut = evaluate(
        &tab,
        "(() => { const s = document.getElementById('status'); return s.scrollHeight > s.clientHeight || s.scrollWidth > s.clientWidth; })()",
    );
    assert_eq!(cut, serde_json::Value::Bool(false));
    assert!(
        evaluate(&tab, "document.getElementById('status').textContent")
            .as_str()
            .unwrap_or_default()
            .ends_with(" s"),
        "the seconds are shown"
    );
    drop(browser);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The "measure the rooms" switch draws each room's illuminance map over
/// the render, at the render's place and scale, with its legend beside;
/// after a lamp is dragged, the map is measured again and changes.
#[test]
fn the_measure_switch_draws_the_rooms_map_over_the_render_and_follows_edits() {
    let dir = scratch("-measure");
    let scene = dir.join("room.ron");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.ron");
    std::fs::copy(&room, &scene).unwrap();
    let server = common::serve(&scene);
    let url = server.url.clone();
    let (browser, tab) = open(&dir, &url);
    tab.wait_for_element("circle[data-light='1']").unwrap();
    let first_job = wait_for_render(&tab, 0, 16);
    tab.find_element("#showmeasure").unwrap().click().unwrap();
    wait_until(
        &tab,
        "the map",
        "document.getElementById('measure').dataset.version !== undefined",
    );
    // The map's plan part lies over the render, the same size; the rest
    // of its picture is the legend, in the side panel.
    let layout: serde_json::Value = serde_json::from_str(
        evaluate(
            &tab,
            "JSON.stringify((() => { const r = document.getElementById('render').getBoundingClientRect(); const m = document.getElementById('measure').getBoundingClientRect(); const i = document.querySelector('#measure img'); return {r: [r.x, r.y, r.width, r.height], m: [m.x, m.y, m.width, m.height], natural: i.naturalWidth, canvas: items.canvas, legend: document.getElementById('legend').getBoundingClientRect().width, hidden: document.getElementById('measure').hidden}; })())",
        )
        .as_str()
        .unwrap(),
    )
    .unwrap();
    assert_eq!(layout["hidden"], false, "{layout}");
    for k in 0..4 {
        let (r, m) = (
            layout["r"][k].as_f64().unwrap(),
            layout["m"][k].as_f64().unwrap(),
        );
        assert!((r - m).abs() < 1.0, "the map over the render: {layout}");
    }
    let canvas_width = layout["canvas"][0].as_f64().unwrap();
    let natural = layout["natural"].as_f64().unwrap();
    assert!(natural > canvas_width, "{layout}");
    assert!(
        (layout["legend"].as_f64().unwrap() - (natural - canvas_width)).abs() < 1.0,
        "{layout}"
    );
    // Asked as the page asks: a POST with the page's token.
    let token = evaluate(&tab, "token")
        .as_str()
        .unwrap_or_default()
        .to_string();
    let map = |url: &str| -> image::RgbImage {
        let r = ureq::post(&format!("{url}/api/measure.png"))
            .header("content-type", "application/json")
            .header("x-flatray-token", &token)
            .send("{}")
            .unwrap();
        image::load_from_memory(&body(r)).unwrap().to_rgb8()
    };
    let before = map(&url);
    // Inside the room the cells take the colour scale, not the grey of
    // what no room holds.
    let inside = before.get_pixel(200, 200).0;
    assert_ne!(inside, [48, 48, 48], "{inside:?}");
    // Drag the second lamp: the page measures the edited scene again.
    let measured = evaluate(&tab, "document.getElementById('measure').dataset.version");
    drag(&tab, (313.0, 134.0), (420.0, 420.0));
    wait_for_render(&tab, first_job, 16);
    wait_until(
        &tab,
        "the map of the edited scene",
        &format!("document.getElementById('measure').dataset.version !== {measured}"),
    );
    let after = map(&url);
    assert_eq!(before.dimensions(), after.dimensions());
    assert_ne!(before.as_raw(), after.as_raw(), "the map follows the edit");
    screenshot(&tab, None, "serve-measure.png");
    // Without the token, no page but its own makes the server measure.
    let refused = ureq::post(&format!("{url}/api/measure.png"))
        .header("content-type", "application/json")
        .send("{}");
    assert!(
        matches!(refused, Err(ureq::Error::StatusCode(403))),
        "{refused:?}"
    );
    // Off, the map is gone from over the render.
    tab.find_element("#showmeasure").unwrap().click().unwrap();
    wait_until(
        &tab,
        "the map hidden",
        "document.getElementById('measure').hidden",
    );
    drop(browser);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two rooms, a lamp in the west one, a sky outside; the door between
/// them shut and the east room's window shuttered whole: the east room
/// is dark. Opening the door in the page, then drawing the shutter back,
/// each lights it; a door's end dragged moves in the scene's text.
#[test]
fn doors_open_and_shutters_draw_back_in_the_page() {
    let dir = scratch("-doors");
    let scene = dir.join("flat.ron");
    let wall = |a: (f64, f64), b: (f64, f64)| {
        format!(
            "Wall(a: ({}, {}), b: ({}, {})),",
            4.0 * a.0,
            4.0 * a.1,
            4.0 * b.0,
            4.0 * b.1
        )
    };
    let walls = [
        wall((10.0, 10.0), (110.0, 10.0)),
        wall((110.0, 10.0), (110.0, 25.0)),
        wall((110.0, 55.0), (110.0, 70.0)),
        wall((110.0, 70.0), (10.0, 70.0)),
        wall((10.0, 70.0), (10.0, 10.0)),
        wall((60.0, 10.0), (60.0, 30.0)),
        wall((60.0, 50.0), (60.0, 70.0)),
    ]
    .join("\n        ");
    std::fs::write(
        &scene,
        format!(
            r#"Scene(
    canvas: (480, 320),
    floor: Color((0.8, 0.8, 0.8)),
    walls: [{walls}],
    doors: [Door(a: (240, 120), b: (240, 200))],
    windows: [Window(a: (440, 100), b: (440, 220), shutter: 1)],
    lights: [
        Point(at: (120, 160), intensity: 4),
        Sky(intensity: 0.05),
    ],
)"#
        ),
    )
    .unwrap();
    let server = common::serve(&scene);
    let url = server.url.clone();
    let (browser, tab) = open(&dir, &url);
    tab.wait_for_element("line[data-door='0']").unwrap();
    let mut job = wait_for_render(&tab, 0, 16);
    let export = |path: &str| get(&url, path);
    let east = (360.0, 160.0);
    let shut = brightness(&export("/api/export.png"), east, 20.0);
    assert!(shut < 1.0, "the east room, shut: {shut}");

    // Click the door, tick "open".
    tab.find_element("line[data-door='0']")
        .unwrap()
        .click()
        .unwrap();
    tab.wait_for_element("#door-open").unwrap().click().unwrap();
    job = wait_for_render(&tab, job, 16);
    let opened = brightness(&export("/api/export.png"), east, 20.0);
    assert!(opened > shut + 5.0, "the door opened: {shut} -> {opened}");
    let text = String::from_utf8(export("/api/scene.ron")).unwrap();
    assert!(
        text.contains("Door(a: (240, 120), b: (240, 200), open: true)"),
        "{text}"
    );

    // Click the window, draw its shutter back.
    tab.find_element("line[data-window='0']")
        .unwrap()
        .click()
        .unwrap();
    tab.wait_for_element("#shutter").unwrap();
    evaluate(
        &tab,
        "(() => { const s = document.getElementById('shutter'); s.value = 0; s.dispatchEvent(new Event('change')); return true; })()",
    );
    job = wait_for_render(&tab, job, 16);
    let drawn = brightness(&export("/api/export.png"), east, 20.0);
    assert!(
        drawn > opened + 2.0,
        "the shutter drawn back: {opened} -> {drawn}"
    );
    let text = String::from_utf8(export("/api/scene.ron")).unwrap();
    assert!(text.contains("shutter: 0)"), "{text}");

    // Drag the door's lower end down the partition.
    drag(&tab, (240.0, 200.0), (240.0, 180.0));
    wait_for_render(&tab, job, 16);
    let text = String::from_utf8(export("/api/scene.ron")).unwrap();
    let door = text
        .lines()
        .find(|l| l.contains("Door("))
        .unwrap_or_default()
        .to_string();
    let b: Vec<f64> = door
        .split("b: (")
        .nth(1)
        .and_then(|r| r.split(')').next())
        .map(|xy| {
            xy.split(',')
                .filter_map(|v| v.trim().parse().ok())
                .collect()
        })
        .unwrap_or_default();
    assert_eq!(b.len(), 2, "{door}");
    assert!(
        (b[0] - 240.0).abs() < 3.0 && (b[1] - 180.0).abs() < 3.0,
        "{door}"
    );
    screenshot(&tab, Some("line[data-window='0']"), "serve-doors.png");
    drop(browser);
    let _ = std::fs::remove_dir_all(&dir);
}
