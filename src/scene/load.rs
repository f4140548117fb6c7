//! Reading a scene: a file, JSON text, or the embedded default, parsed strictly
//! ([`crate::json`]) into the file's shape ([`format`](super::format)) and validated
//! ([`validate`](super::validate)) into a [`Scene`]; and the command line's viewport
//! override, validated like the file's.

use super::format::SceneSpec;
use super::validate::Check;
use super::Scene;
use crate::camera::Viewport;
use crate::error::{parent_dir, read_text_file, Result};
use crate::json::parse_strict;
use std::path::Path;

/// The embedded default scene (`lembo-sim` with no arguments renders it).
const DEFAULT_SCENE_JSON: &str = include_str!("../../traces/default.json");
/// Where the embedded default scene's relative paths point.
const DEFAULT_SCENE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/traces");

impl Scene {
    /// Reads and validates a scene file; mesh paths in it are relative to its directory.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = read_text_file(path)?;
        let mut scene = Scene::from_json(&text, &path.display().to_string(), parent_dir(path))?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses and validates a scene from JSON text. `file` is the name used in error
    /// messages; mesh paths are relative to `base_dir`.
    pub fn from_json(text: &str, file: &str, base_dir: &Path) -> Result<Scene> {
        let spec: SceneSpec = parse_strict(text, file)?;
        spec.validate(&Check { file }, base_dir)
    }

    /// The embedded `traces/default.json`: the sphere of 24 lembos.
    pub fn default_scene() -> Scene {
        // The text is part of the binary and checked by a unit test, so failing here is a
        // build defect, not bad input.
        Scene::from_json(
            DEFAULT_SCENE_JSON,
            "traces/default.json (embedded)",
            Path::new(DEFAULT_SCENE_DIR),
        )
        .expect("the embedded default scene is valid")
    }

    /// Sets the viewport (CLI override), validated like the file's.
    pub fn set_viewport(&mut self, width: u32, height: u32) -> Result<()> {
        let viewport = Viewport { width, height };
        Check {
            file: "command line",
        }
        .viewport(&viewport)?;
        self.viewport = viewport;
        Ok(())
    }
}
