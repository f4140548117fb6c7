//! # lembo-sim
//!
//! A simulator of the parallel rasterization unit that Martinelli proposes for *lembos*
//! (quadratic triangular patches with a separate quadratic normal function, WSCG 2006), built
//! so that an architect can measure what such a unit costs and what it buys.
//!
//! ```text
//!  scene ─► Setup ─► MinMax ─► IntervalManager ─► Segmenter ─► Subsegmenter ─► FragmentRasterizer ─► ROP ─► FrameBuffer
//!           project   y range,  per scanline y_j:   walk Y(u,v)=y_j  split so x(t) is   pixel centres, u,v by    depth test,
//!           6 points  cull,     domain-edge roots   with midpoint    linear within k    increments, z and n      Phong shading
//!           + normals clip to   -> intervals        error exactly k                     from the quadratics
//!                     viewport
//! ```
//!
//! Triangle path (the baseline): `Tessellator ─► TriangleSetup ─► TriangleRasterizer ─►` the
//! same ROPs and frame buffer.
//!
//! - [`lembo`]: the model (Martinelli 2006 section 2): six-point construction, evaluation, edges
//!   from vertex normals, meshes, the builtin shapes of Figures 6-8, the tessellator.
//! - [`raster`]: the functional extreme method (section 5), one module per stage, generic
//!   over the datapath ([`datapath::Real`]: `f32` or `f64`); the triangle rasterizer.
//! - [`pipeline`]: the timed pipeline (Figure 5 as actors on bounded channels with cycle
//!   accounting), and the triangle path's timed units; [`config`] its architecture files.
//! - [`rop`]: depth test, per-fragment Phong (Piranda et al. 2006 equation 6), frame buffer.
//! - [`reference`](mod@reference): the exact f64 ray-patch reference and the accuracy metrics.
//! - [`scene`], [`camera`]: the JSON trace format and OpenGL-convention cameras.
//! - [`datapath_study`]: f32 against f64 over seeded random lembos (issue 7), for
//!   `examples/datapath_study.rs` and `tests/datapath.rs`.
//! - [`job`], [`report`]: the `render` command's work and its `report.json` / `report.txt`;
//!   [`output`]: every output file written whole or not at all, also under Ctrl-C;
//!   [`compare`]: lembos against triangles against the exact surface; [`sweep`]: many
//!   runs of a spec (`sim/sweeps/`) into `results.jsonl` and `results.csv`, resumable and
//!   shardable.
//!   [`compare`]: lembos against triangles against the exact surface; [`plot`]: a sweep's
//!   SVG plots.
//!
//! The functional model knows nothing of cycles; the timed pipeline calls the same stage
//! functions and adds only time.

pub mod camera;
pub mod compare;
pub mod config;
pub mod datapath;
pub mod datapath_study;
pub mod discoid;
pub mod error;
pub mod job;
pub mod lembo;
pub mod output;
pub mod pipeline;
pub mod plot;
pub mod raster;
pub mod reference;
pub mod report;
pub mod rop;
pub mod scene;
pub mod sweep;
