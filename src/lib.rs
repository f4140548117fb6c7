//! # lembo-sim
//!
//! A simulator of the parallel rasterization unit that Martinelli proposes for *lembos*
//! (quadratic triangular patches with a separate quadratic normal function, WSCG 2006), built
//! so that an architect can measure what such a unit costs and what it buys.
//!
//! The timed pipeline's unit graph (each path's units, the boundaries between them with
//! their dispatch rules, the shared memory port) is generated from [`graph`]: run
//! `lembo-sim graph [--path lembo|triangle] [--source memory|onchip] [--dot]`, or read
//! ARCHITECTURE.md, "The unit graph", which a test keeps equal to it.
//!
//! Modules, from the model outwards:
//! - [`lembo`]: the model (Martinelli 2006 section 2): six-point construction, evaluation,
//!   edges from vertex normals, meshes, the builtin shapes of Figures 6-8, the tessellator.
//! - [`raster`]: the functional extreme method (section 5), one module per stage, generic
//!   over the datapath ([`datapath::Real`]: `f32` or `f64`); the triangle path's setup and
//!   rasterizer.
//! - [`discoid`]: the atlas of discoids (Piranda et al. 2006): beta textures, the blend
//!   units' arithmetic per precision mode, the EWA kernel, the blend report.
//! - [`rop`]: depth test, per-fragment Phong (Piranda et al. 2006 equation 6), frame buffer.
//! - [`frame`]: a functional frame drawn: the rasterizer into the ROP over a fresh frame
//!   buffer, on one thread or in bands on several, and the three discoid passes.
//! - [`pipeline`]: the timed model (Figure 5 as one resumable unit per instance on bounded
//!   links with cycle accounting, run by a deterministic discrete-event executor), its unit
//!   graph, and the triangle path's and discoid passes' timed units; [`config`] its
//!   architecture files.
//! - [`reference`](mod@reference): the exact f64 ray-patch reference and the accuracy
//!   metrics.
//! - [`scene`], [`camera`]: the JSON trace format and OpenGL-convention cameras.
//! - [`job`], [`report`]: the `render` command's work and its `report.json` /
//!   `report.txt`; [`compare`]: lembos against triangles against the exact surface;
//!   [`sweep`]: many runs of a spec (`sim/sweeps/`) into `results.jsonl` and `results.csv`,
//!   resumable, shardable and locked against a second writer; [`plot`]: a sweep's SVG
//!   plots.
//! - [`output`]: every output file written whole or not at all, also under Ctrl-C;
//!   [`error`]: every error a run can end with, and its exit status; [`json`]: strict
//!   parsing of every input file, errors naming the field path.
//! - [`tolerance`]: the lembo path's tolerances, k and Setup's perspective tolerance, each
//!   with its default, range and check.
//! - [`datapath`]: the `f32`/`f64` datapath.
//! - [`memory`]: the memory system's standalone models, not yet used by the pipeline: tiled
//!   surfaces, ROP caches, tile compression, hierarchical Z, the DRAM controller and its
//!   request traces.
//! - `testkit` (tests, examples and benchmarks only: the `testkit` feature): the seeded
//!   random number generator they share.
//!
//! DESIGN.md (beside the crate) holds the design the code relies on: what a cycle means,
//! the report contract, the bad-input policy and the accuracy metrics' definitions, and
//! (its §13) how the code meets it; ARCHITECTURE.md maps the code.
//!
//! The functional model knows nothing of cycles; the timed pipeline calls the same stage
//! functions and adds only time.

#![warn(missing_docs)]

pub mod camera;
pub mod compare;
pub mod config;
pub mod cost;
pub mod datapath;
pub mod discoid;
pub mod error;
pub mod frame;
pub mod graph;
pub mod isa;
pub mod job;
pub mod json;
pub mod lembo;
pub mod memory;
pub mod output;
pub mod pipeline;
pub mod plot;
pub mod progress;
pub mod raster;
pub mod reference;
pub mod report;
pub mod rop;
pub mod scene;
pub mod sweep;
#[cfg(any(test, feature = "testkit"))]
pub mod testkit;
pub mod tolerance;
