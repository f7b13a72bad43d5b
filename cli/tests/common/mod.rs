//! What the live view's tests share: the real `flatray serve` on a free
//! port, stopped when dropped.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};

pub struct Serving {
    child: Child,
    /// `http://127.0.0.1:PORT`, without a trailing slash.
    pub url: String,
    /// The token the page carries, which every change must send (the
    /// browser's tests let the page send it).
    #[allow(dead_code)]
    pub token: String,
}

/// Starts `flatray serve SCENE --port 0` and reads the address it prints.
pub fn serve(scene: &Path) -> Serving {
    let mut child = Command::new(env!("CARGO_BIN_EXE_flatray"))
        .args(["serve", scene.to_str().unwrap(), "--port", "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The line that gives the address (an imported map's report comes
    // before it).
    let mut first = String::new();
    let mut lines = BufReader::new(child.stdout.take().unwrap());
    while !first.contains(" at http") {
        first.clear();
        if lines.read_line(&mut first).unwrap() == 0 {
            panic!("flatray serve ended before it gave its address");
        }
    }
    let url = first
        .split(" at ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("no address in {first:?}"))
        .trim_end_matches('/')
        .to_string();
    let page = ureq::get(&format!("{url}/"))
        .call()
        .unwrap()
        .body_mut()
        .read_to_string()
        .unwrap();
    let token = page
        .split("name=\"flatray-token\" content=\"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .unwrap_or_else(|| panic!("no token in the page"))
        .to_string();
    Serving { child, url, token }
}

impl Drop for Serving {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
