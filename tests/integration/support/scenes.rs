//! Scenes shared by the integration tests and the benchmarks (`benches/render.rs` includes
//! this file with `#[path]` and uses part of it, hence the `allow`).
#![allow(dead_code)]

use lembo_sim::scene::Scene;
use std::path::{Path, PathBuf};

/// Every scene shipped in `traces/` and `traces/extremes/`, sorted: its name from the
/// crate's root (`traces/extremes/huge.json`) and its path.
pub fn shipped_files() -> Vec<(String, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["traces", "traces/extremes"] {
        for entry in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = entry.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if name.ends_with(".json") && name != "expect.json" {
                files.push((format!("{dir}/{name}"), p));
            }
        }
    }
    files.sort();
    files
}

/// A scene of `traces/`, at `side` x `side` pixels when given.
pub fn trace(name: &str, side: Option<u32>) -> Scene {
    let mut s = Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("traces")
            .join(name),
    )
    .expect("trace loads");
    if let Some(n) = side {
        s.set_viewport(n, n).unwrap();
    }
    s
}

/// sphere24 in view at `side` x `side` pixels, then `copies` more far to the side, out of
/// the viewport.
pub fn with_offscreen_copies(copies: usize, side: u32) -> Scene {
    let mut objects = vec![r#"{"builtin": "sphere24", "color": [0.8, 0.3, 0.2]}"#.to_string()];
    for c in 0..copies {
        objects.push(format!(
            r#"{{"builtin": "sphere24", "transform": {{"translate": [{}, 0, 0]}}}}"#,
            40.0 + 5.0 * c as f64
        ));
    }
    let json = format!(
        r#"{{"name": "offscreen", "viewport": {{"width": {side}, "height": {side}}},
            "camera": {{"eye": [0, 1.2, 3.8], "target": [0, 0, 0],
                        "projection": {{"kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 100}}}},
            "objects": [{}]}}"#,
        objects.join(", ")
    );
    Scene::from_json(&json, "offscreen", Path::new(".")).unwrap()
}
