//! The tracer's modules form layers: counting the `crate::` references
//! between its top-level modules (a folder is one module), outside their
//! tests, no module reaches back to one that reaches it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Each module's text without comments and without its `#[cfg(test)]`
/// module.
fn modules(src: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut read = |name: String, path: &Path| {
        let text = std::fs::read_to_string(path).unwrap_or_default();
        let code: String = text
            .lines()
            .map(|l| l.split("//").next().unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n");
        let code = code
            .split("#[cfg(test)]\nmod tests")
            .next()
            .unwrap_or_default()
            .to_string();
        out.entry(name).or_insert_with(String::new).push_str(&code);
    };
    for entry in std::fs::read_dir(src).unwrap().flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            let mut stack = vec![path];
            while let Some(dir) = stack.pop() {
                for e in std::fs::read_dir(&dir).unwrap().flatten() {
                    if e.path().is_dir() {
                        stack.push(e.path());
                    } else if e.path().extension().is_some_and(|x| x == "rs") {
                        read(name.clone(), &e.path());
                    }
                }
            }
        } else if let Some(stem) = name.strip_suffix(".rs")
            && stem != "lib"
        {
            read(stem.to_string(), &path);
        }
    }
    out
}

/// The modules each module names as `crate::m` or in `crate::{m, ..}`.
fn uses(modules: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let names: BTreeSet<&String> = modules.keys().collect();
    let word = |s: &str| {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect::<String>()
    };
    modules
        .iter()
        .map(|(m, text)| {
            let mut used = BTreeSet::new();
            for part in text.split("crate::").skip(1) {
                if let Some(group) = part.strip_prefix('{') {
                    for item in group.split('}').next().unwrap_or_default().split(',') {
                        used.insert(word(item.trim()));
                    }
                } else {
                    used.insert(word(part));
                }
            }
            let used = used
                .into_iter()
                .filter(|u| u != m && names.contains(u))
                .collect();
            (m.clone(), used)
        })
        .collect()
}

#[test]
fn the_tracers_modules_form_no_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tracer/src");
    let modules = modules(&src);
    assert!(
        modules.contains_key("render") && modules.contains_key("lights"),
        "{:?}",
        modules.keys()
    );
    let uses = uses(&modules);
    // Depth-first search for a path back to the start.
    for start in uses.keys() {
        let mut stack: Vec<(String, Vec<String>)> = vec![(start.clone(), vec![start.clone()])];
        let mut seen = BTreeSet::new();
        while let Some((m, path)) = stack.pop() {
            for next in &uses[&m] {
                if next == start {
                    panic!("a cycle: {} -> {start}", path.join(" -> "));
                }
                if seen.insert(next.clone()) {
                    let mut longer = path.clone();
                    longer.push(next.clone());
                    stack.push((next.clone(), longer));
                }
            }
        }
    }
    // The bottom and the top: the scene uses no module but the spectra
    // its lights may have, which use none; the render loop is used by
    // none.
    assert!(
        uses["scene"].iter().all(|m| m == "spectrum"),
        "{:?}",
        uses["scene"]
    );
    assert!(uses["spectrum"].is_empty(), "{:?}", uses["spectrum"]);
    assert!(uses.values().all(|u| !u.contains("render")), "{uses:?}");
}
