//! The `render` job: load the scene and the architecture, run one path (lembo or triangle)
//! on the timed pipeline (or the functional model alone), optionally the exact reference
//! and its metrics, and write the outputs. Flags arrive here already parsed; this module
//! validates them once into a [`RenderJob`] and nothing downstream re-checks them.
//! [`run_path`] is the part `compare` reuses for each path.
//!
//! Layout, in the order a run meets them: `validate` (the request and its flags' checks),
//! `memory` (the estimate a run is refused on), `route` (the [`Model`] and [`Route`] a run
//! is, decided once), `reference` (the exact reference and a frame's accuracy against it),
//! `path` (one lembo or triangle route drawn, measured and priced), `discoids` (a discoid
//! scene's passes), `sections` (the report sections every route fills in), `render` (the
//! command: load, run, write).

mod culling;
mod discoids;
mod memory;
mod path;
mod reference;
mod render;
mod route;
mod sections;
mod validate;

pub use discoids::{CURVED_DISCOID_BYTES, PLANAR_DISCOID_BYTES};
pub use memory::{check_available, check_memory, memory_estimate};
pub use path::run_path;
pub use reference::{
    check_reference_scene, measure_frame, measure_frame_and_flip, reference_scene,
    render_reference, render_reference_with, see_through_px, visibility, ErrorMaps,
};
pub use render::{load_arch, load_scene, run_render, RenderOutput};
pub use route::{
    check_samples, check_triangle_budget, Model, PathRun, Route, LEMBO_BYTES, MAX_TRIANGLES,
};
pub use validate::{
    check_count, check_tess_range, check_threshold, machine_threads, Given, Mode, PrimitivePath,
    RenderJob, TechSource, TraceSettings, AA_SUPERSAMPLE, MAX_HOST_THREADS, MAX_SUPERSAMPLE,
    MAX_TESS, MAX_THREADS,
};
