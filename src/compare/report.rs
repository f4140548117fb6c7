//! `compare.json`: both paths' reports, how the tessellation level was chosen, the match
//! the search found and the two paths' cycle and byte ratios.

use super::matching::{MatchReport, TessChoice};
use crate::report::Report;
use serde::Serialize;

/// Version of the `compare.json` layout.
pub const COMPARE_SCHEMA_VERSION: u32 = 3;

/// Cost ratios of the two paths on this scene and architecture.
#[derive(Clone, Debug, Serialize)]
pub struct Ratios {
    /// The architecture both paths ran on.
    pub arch: String,
    /// Frame cycles per lembo \[cycles\].
    pub cycles_per_lembo: f64,
    /// Frame cycles per triangle \[cycles\].
    pub cycles_per_triangle: f64,
    /// cycles_per_lembo / cycles_per_triangle: a ratio per primitive. It is the paper's
    /// "a lembo costs 2-3 triangles" only at tessellation 1, where a triangle spans its
    /// lembo's corners; at level n a lembo's surface is n² triangles.
    pub lembo_over_triangle_cycles_per_primitive: f64,
    /// Frame cycles per covered pixel of the lembo path \[cycles\]; null when none is
    /// covered.
    pub lembo_cycles_per_covered_pixel: Option<f64>,
    /// Frame cycles per covered pixel of the triangle path \[cycles\].
    pub triangle_cycles_per_covered_pixel: Option<f64>,
    /// Triangle frame cycles over lembo frame cycles.
    pub triangle_over_lembo_cycles: f64,
    /// Triangle primitive bytes over lembo primitive bytes, as stored in memory
    /// (`primitives.bytes`).
    pub triangle_over_lembo_bytes: f64,
    /// Triangle primitive bytes over lembo primitive bytes, as the geometry fetch read them
    /// (`fetch.bytes`: a mesh's vertices once per vertex-cache miss).
    pub triangle_over_lembo_bytes_fetched: f64,
}

/// `compare.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    /// [`COMPARE_SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The triangle path's level and how it was chosen.
    pub tess: TessChoice,
    /// The search that matched the two paths' accuracy: its metric, target, levels tried,
    /// the level chosen and how close it came; null when both knobs were given.
    #[serde(rename = "match")]
    pub matched: Option<MatchReport>,
    /// Cycle and byte ratios of the two paths; null in functional mode or for an empty frame.
    pub ratios: Option<Ratios>,
    /// The lembo path's report, as `render --reference` writes it.
    pub lembo: Report,
    /// The triangle path's report, as `render --path triangle --reference` writes it.
    pub triangle: Report,
}
