//! The datapath study (issue 7, item 2): the paper's guarantee and the coverage errors of the
//! `f32` datapath against the `f64` one, over seeded random lembos in families that matter
//! for numerics.
//!
//! ```text
//!  (seed, family, index) ─► case(): two lembos sharing a curved edge, as scene JSON
//!        ─► Scene::from_json ─► exact reference once ─► for each datapath and k:
//!           render_functional(analyse) ─► Accuracy, probe ─► Measurement
//!  measurements ─► summarise(): per family, datapath and k ─► markdown, JSON, CSV
//! ```
//!
//! A case is a pair of lembos sharing a curved edge (the same three world points), so that
//! besides the guarantee metric (`max_scanline_deviation_px`, which the segmenter promises
//! is at most k) the shared edge's cracks and double hits are measured too. Every case is a
//! function of the study seed, its family and its index alone ([`case`]), through the
//! crate's one seeded generator, SplitMix64 (`lembo_sim::testkit`): no `rand` dependency,
//! and no upstream change of a distribution's algorithm can change the cases. A case's scene JSON
//! is a complete scene file: `lembo-sim render FILE --reference` reproduces it.
//!
//! The families ([`Family`]) are drawn on a 256 x 256 viewport; all but the perspective one
//! use an orthographic camera down −z, one world unit per pixel, so the screen coordinates
//! are the world ones shifted. The study measures the scan-line datapath only: Setup
//! projects in `f64` and rounds the six screen points to the datapath (as
//! `raster::setup` does), so world-space magnitudes reach `f32` only through the screen
//! coordinates. The probe measures the deviation against the datapath's own screen
//! quadratic, so rounding the six screen points shows in the coverage errors, not in the
//! guarantee metric.
//!
//! Not measured: the triangle path, the timed pipeline (its image equals the functional
//! one bit for bit, tested elsewhere), and f32 world-space input to Setup.

mod cases;
mod measure;
mod summary;

pub use cases::*;
pub use measure::*;
pub use summary::*;
