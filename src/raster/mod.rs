//! The functional extreme method (Martinelli 2006 section 5): what is drawn, with no notion of
//! time. One file per stage of Figure 5, in dataflow order:
//!
//! ```text
//! setup ─► minmax ─► interval ─► segmenter ─► subsegmenter ─► fragment ─► FragmentSink (ROP)
//! ```
//!
//! Every stage is generic over the datapath [`Real`] (`f32` or `f64`) and works on one item
//! at a time into reused buffers, so the timed pipeline can call the same functions per
//! message. One driver ([`driver`]) runs a path's stages in order for a whole scene: the
//! lembo path's ([`lembo_path`]) or the triangle path's ([`triangle::TrianglePath`]), into
//! any sink ([`render_lembos`]). The rasterizer knows no ROP: a frame (a fresh frame buffer
//! and the ROP over it, on one thread or in bands on several) is put together above it, in
//! `frame`. The types every stage shares are in leaf files that import no driver:
//! [`counts`] and [`screen`] (the set-up lembo).

pub mod counts;
pub mod driver;
pub mod facing;
pub mod fragment;
pub mod interval;
pub mod lembo_path;
pub mod minmax;
pub mod probe;
pub mod refine;
pub mod screen;
pub mod segmenter;
pub mod setup;
pub mod subsegmenter;
pub mod triangle;
pub mod v2;

use crate::camera::View;
use crate::datapath::Real;
use crate::error::Result;
use crate::scene::Scene;
use crate::tolerance::Tolerance;
pub use counts::Counts;
use driver::draw_in_order;
use fragment::FragmentSink;
use lembo_path::LemboPath;

/// Default cap on segments per interval (DESIGN.md §8): far above what a visible patch needs
/// at k >= 1e-4 px on a 16384-pixel viewport, low enough to refuse runaway walks quickly.
pub const DEFAULT_SEGMENT_CAP: usize = 1 << 16;

/// Runs the extreme method over every lembo of `scene`, in scene order, into `sink`.
pub fn render_lembos<R: Real, S: FragmentSink<R>>(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
) -> Result<()> {
    let tol = tol.into();
    let path = LemboPath::<R>::new(scene, view, tol.k, tol.perspective, segment_cap);
    draw_in_order(&path, sink, counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped scene at `path` (from the crate's root) on a `width` x `height`
    /// viewport, and its view (the raster modules' tests).
    pub(super) fn shipped_at(path: &str, width: u32, height: u32) -> (Scene, View) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
        let mut scene = Scene::load(&path).expect("a shipped scene");
        scene.set_viewport(width, height).expect("a valid viewport");
        let view = View::new(&scene.camera, scene.viewport);
        (scene, view)
    }
}
