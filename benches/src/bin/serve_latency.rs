//! How long `flatray serve` takes from an edit to the first new picture,
//! and to 3 % estimated noise: the documented command behind the live
//! view's figures in `docs/performance.md`.
//!
//!     cargo run --release -p flatray-benches --bin serve_latency -- SCENE [FLATRAY] [EDITS]
//!
//! It starts `FLATRAY serve SCENE` (default `target/release/flatray`) on a
//! free port, waits for the first full-size frame, then moves the first
//! light 15 units back and forth `EDITS` times (default 5), and prints
//! each edit's two times and their medians.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(scene) = args.get(1) else {
        eprintln!("usage: serve_latency SCENE [FLATRAY] [EDITS]");
        std::process::exit(2);
    };
    let binary = args.get(2).map_or("target/release/flatray", String::as_str);
    let edits: usize = args.get(3).and_then(|n| n.parse().ok()).unwrap_or(5);
    let mut child = Command::new(binary)
        .args(["serve", scene, "--port", "0"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {binary}: {e}"));
    let mut first = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .ok();
    let url = first
        .split(" at ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap_or_else(|| panic!("no address in {first:?}"))
        .trim_end_matches('/')
        .to_string();
    // Changes carry the token the page was served with.
    let page = ureq::get(&format!("{url}/"))
        .call()
        .expect("the page")
        .into_body()
        .read_to_string()
        .expect("the page");
    let token = page
        .split("name=\"flatray-token\" content=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .unwrap_or_default()
        .to_string();
    let (tx, rx) = mpsc::channel::<(Instant, serde_json::Value)>();
    let events = format!("{url}/api/events");
    std::thread::spawn(move || {
        let response = ureq::get(&events).call().expect("events");
        for line in BufReader::new(response.into_body().into_reader()).lines() {
            let Ok(line) = line else { return };
            if let Some(data) = line.strip_prefix("data: ")
                && let Ok(v) = serde_json::from_str(data)
                && tx.send((Instant::now(), v)).is_err()
            {
                return;
            }
        }
    });
    let wait = |job: u64, ok: &dyn Fn(&serde_json::Value) -> bool| -> Instant {
        loop {
            let (at, e) = rx
                .recv_timeout(Duration::from_secs(120))
                .expect("no frame within 120 s");
            if e["job"].as_u64() == Some(job) && ok(&e) {
                return at;
            }
        }
    };
    wait(1, &|e| e["quick"] == false);
    let items: serde_json::Value = serde_json::from_str(
        &ureq::get(&format!("{url}/api/items"))
            .call()
            .expect("items")
            .into_body()
            .read_to_string()
            .expect("items"),
    )
    .expect("items");
    let at = &items["lights"][0]["at"];
    let (x, y) = (
        at[0].as_f64().expect("the first light stands at a point"),
        at[1].as_f64().unwrap_or(0.0),
    );
    let (mut firsts, mut threes) = (Vec::new(), Vec::new());
    for k in 0..edits {
        let dx = if k % 2 == 0 { 15.0 } else { 0.0 };
        let body = format!(
            r#"{{"op": "move_light", "index": 0, "to": [{}, {y}]}}"#,
            x + dx
        );
        let sent = Instant::now();
        let reply = ureq::post(&format!("{url}/api/edit"))
            .content_type("application/json")
            .header("x-flatray-token", &token)
            .send(body)
            .expect("edit")
            .into_body()
            .read_to_string()
            .expect("edit");
        let job = serde_json::from_str::<serde_json::Value>(&reply).expect("edit")["version"]
            .as_u64()
            .expect("a version");
        let picture = wait(job, &|_| true) - sent;
        let three = wait(job, &|e| {
            e["quick"] == false && e["noise"].as_f64().is_some_and(|n| n <= 0.03)
        }) - sent;
        println!(
            "edit {k}: first picture {:.3} s, 3 % noise {:.3} s",
            picture.as_secs_f64(),
            three.as_secs_f64()
        );
        firsts.push(picture.as_secs_f64());
        threes.push(three.as_secs_f64());
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{scene}: median first picture {:.3} s, median to 3 % noise {:.3} s",
        median(&mut firsts),
        median(&mut threes)
    );
    let _ = child.kill();
    let _ = child.wait();
}
