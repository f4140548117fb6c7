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
//! lembo path's ([`lembo_path`]) or the triangle path's ([`triangle::TrianglePath`]), on
//! one thread ([`render_lembos`], [`render_functional`], the cost model's counting runs) or
//! in bands on several ([`parallel`]). The types every stage shares are in leaf files that
//! import no driver: [`counts`], [`screen`] (the set-up lembo) and [`frame`].

pub mod counts;
pub mod driver;
pub mod facing;
pub mod fragment;
pub mod frame;
pub mod interval;
pub mod lembo_path;
pub mod minmax;
pub mod parallel;
pub mod probe;
pub mod refine;
pub mod screen;
pub mod segmenter;
pub mod setup;
pub mod subsegmenter;
pub mod triangle;
pub mod v2;

use crate::camera::View;
use crate::datapath::{Datapath, Real};
use crate::error::Result;
use crate::scene::Scene;
use crate::tolerance::Tolerance;
pub use counts::Counts;
use driver::draw_in_order;
use fragment::FragmentSink;
use frame::frame_with;
pub use frame::Frame;
use lembo_path::LemboPath;
use triangle::{TrianglePath, TriangleSource};

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

/// Renders `scene` with the functional model in the given datapath. With `analyse`, the
/// frame buffer keeps normals and every fragment is measured by a [`probe::Probe`] (slower).
///
/// `tol` is k \[pixels\] (with the default perspective tolerance) or a [`Tolerance`].
pub fn render_functional(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    analyse: bool,
) -> Result<Frame> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => render_in::<f32>(scene, view, tol, analyse),
        Datapath::F64 => render_in::<f64>(scene, view, tol, analyse),
    }
}

/// [`render_functional`] or [`render_functional_triangles`] (with `triangles`) on `threads`
/// host threads: the same frame, bit for bit, for every count ([`parallel`]). The analysed
/// frame is drawn on one thread whatever `threads` says.
pub fn render_functional_on(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    triangles: Option<&dyn TriangleSource>,
    datapath: Datapath,
    analyse: bool,
    threads: u32,
) -> Result<Frame> {
    if analyse || threads <= 1 {
        return match triangles {
            Some(t) => Ok(render_functional_triangles(
                scene, view, t, datapath, analyse,
            )),
            None => render_functional(scene, view, tol, datapath, analyse),
        };
    }
    match datapath {
        Datapath::F32 => in_bands::<f32>(scene, view, tol, triangles, threads),
        Datapath::F64 => in_bands::<f64>(scene, view, tol, triangles, threads),
    }
}

/// The frame drawn in bands on `threads` threads in datapath `R`: the triangle path's of
/// `triangles`, or else the lembo path's.
fn in_bands<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    triangles: Option<&dyn TriangleSource>,
    threads: u32,
) -> Result<Frame> {
    match triangles {
        Some(t) => {
            parallel::render_in_bands::<R, _>(scene, view, &TrianglePath::new(t, view), threads)
        }
        None => {
            let path =
                LemboPath::<R>::new(scene, view, tol.k, tol.perspective, DEFAULT_SEGMENT_CAP);
            parallel::render_in_bands(scene, view, &path, threads)
        }
    }
}

/// Renders the triangle path (the scene's lembos tessellated) with the functional model in
/// the given datapath. With `analyse`, the frame buffer keeps normals and double hits on
/// shared edges are counted ([`triangle::TriangleProbe`]).
pub fn render_functional_triangles(
    scene: &Scene,
    view: &View,
    tessellation: &dyn TriangleSource,
    datapath: Datapath,
    analyse: bool,
) -> Frame {
    match datapath {
        Datapath::F32 => triangles_in::<f32>(scene, view, tessellation, analyse),
        Datapath::F64 => triangles_in::<f64>(scene, view, tessellation, analyse),
    }
}

fn triangles_in<R: Real>(
    scene: &Scene,
    view: &View,
    tessellation: &dyn TriangleSource,
    analyse: bool,
) -> Frame {
    let drawn = frame_with::<R>(scene, view, analyse, |rop, counts| {
        Ok(if analyse {
            let mut p = triangle::TriangleProbe::new(view.viewport.width, rop);
            triangle::render_triangles::<R, _>(tessellation, view, &mut p, counts);
            Some(probe::ProbeReport {
                double_hit_pixels: p.double_hit_pixels(),
                fragments: counts.fragments,
                ..Default::default()
            })
        } else {
            triangle::render_triangles::<R, _>(tessellation, view, rop, counts);
            None
        })
    });
    drawn.expect("the triangle path records no error")
}

fn render_in<R: Real>(scene: &Scene, view: &View, tol: Tolerance, analyse: bool) -> Result<Frame> {
    frame_with::<R>(scene, view, analyse, |rop, counts| {
        let cap = DEFAULT_SEGMENT_CAP;
        Ok(if analyse {
            let mut p = probe::Probe::new(scene, view.viewport, rop);
            render_lembos::<R, _>(scene, view, tol, cap, &mut p, counts)?;
            Some(p.report())
        } else {
            render_lembos::<R, _>(scene, view, tol, cap, rop, counts)?;
            None
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::driver::Stages;
    use crate::rop::{FrameBuffer, RopSink};

    /// The shipped scene at `path` (from the crate's root) on a 384x384 viewport, and its view.
    fn shipped(path: &str) -> (Scene, View) {
        shipped_at(path, 384, 384)
    }

    /// The shipped scene at `path` (from the crate's root) on a `width` x `height`
    /// viewport, and its view (the raster modules' tests).
    pub(super) fn shipped_at(path: &str, width: u32, height: u32) -> (Scene, View) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
        let mut scene = Scene::load(&path).expect("a shipped scene");
        scene.set_viewport(width, height).expect("a valid viewport");
        let view = View::new(&scene.camera, scene.viewport);
        (scene, view)
    }

    /// The triangle path's rows as dispatched (compiled for AVX2 where the CPU has it) draw
    /// the frame and counts of the rows compiled for the baseline instruction set, bit for
    /// bit, through the functional ROP, for the bunny tessellated once and twice, in both
    /// datapaths.
    fn triangle_rows_as_compiled<R: Real>(level: u32) {
        if !crate::isa::avx2_comparable("the AVX2 triangle rows") {
            return;
        }
        let (scene, view) = shipped("traces/bunny.json");
        let tessellation = crate::lembo::tessellate::Tessellation::new(&scene, level);
        let source: &dyn TriangleSource = &tessellation;
        let [dispatched, compiled] = [true, false].map(|dispatched| {
            let mut fb = FrameBuffer::new(384, 384, [0; 3], false);
            let mut counts = Counts::default();
            let mut rop = RopSink::<R>::new(&mut fb, &scene.light, &view);
            let path = TrianglePath::new(source, &view);
            let all = 0..Stages::<R>::primitives(&path);
            let mut pieces = Vec::new();
            driver::set_up(
                &path,
                all,
                &mut Default::default(),
                &mut pieces,
                |_, _| {},
                &mut counts,
            );
            for st in &pieces {
                if dispatched {
                    triangle::rasterize::rasterize_rows(st, 0, 384, &mut rop, &mut counts);
                } else {
                    triangle::rasterize::rasterize_rows_as_compiled(
                        st,
                        0,
                        384,
                        &mut rop,
                        &mut counts,
                    );
                }
            }
            (counts.fragments_passed_depth, counts.pixels_covered) = rop.finish();
            (fb, counts)
        });
        assert!(
            dispatched.1.fragments > 10_000,
            "{}",
            dispatched.1.fragments
        );
        assert_eq!(dispatched.1, compiled.1);
        let bits =
            |fb: &FrameBuffer| -> Vec<u32> { fb.depth.iter().map(|d| d.to_bits()).collect() };
        assert!(
            bits(&dispatched.0) == bits(&compiled.0),
            "the depths differ"
        );
        assert!(
            dispatched.0.primitive[..] == compiled.0.primitive[..],
            "the winners differ"
        );
        assert!(
            dispatched.0.color[..] == compiled.0.color[..],
            "the colours differ"
        );
    }

    #[test]
    fn triangle_rows_compiled_for_avx2_give_the_same_bits() {
        for level in [1, 2] {
            triangle_rows_as_compiled::<f32>(level);
            triangle_rows_as_compiled::<f64>(level);
        }
    }
}
