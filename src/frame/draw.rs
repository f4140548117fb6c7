//! The entry points of the functional model's frame: the lembo path's
//! ([`render_functional`]) and the triangle path's ([`render_functional_triangles`]) on
//! one thread, through the one driver (`raster::driver`) into the ROP [`frame_with`] makes
//! over a fresh frame buffer, or either on several host threads in bands
//! ([`render_functional_on`], [`super::bands`]), the same frame bit for bit.

use super::bands::{render_in_bands, render_probed_in_bands, WINDOW_PRIMITIVES};
use super::functional::{frame_with, Frame};
use crate::camera::View;
use crate::datapath::{Datapath, Real};
use crate::error::Result;
use crate::raster::lembo_path::LemboPath;
use crate::raster::triangle::{self, TrianglePath, TriangleSource};
use crate::raster::{probe, render_lembos, DEFAULT_SEGMENT_CAP};
use crate::scene::Scene;
use crate::tolerance::Tolerance;

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
/// host threads: the same frame, bit for bit, for every count ([`super::bands`]). The analysed
/// frame of the lembo path is drawn in bands too, its probe's report the same for every
/// count ([`probe::ProbeBoard`]); the triangle path's is drawn on one thread whatever
/// `threads` says.
pub fn render_functional_on(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    triangles: Option<&dyn TriangleSource>,
    datapath: Datapath,
    analyse: bool,
    threads: u32,
) -> Result<Frame> {
    if analyse && triangles.is_none() && threads > 1 {
        return match datapath {
            Datapath::F32 => probed_in_bands::<f32>(scene, view, tol, threads),
            Datapath::F64 => probed_in_bands::<f64>(scene, view, tol, threads),
        };
    }
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
        Some(t) => render_in_bands::<R, _>(scene, view, &TrianglePath::new(t, view), threads),
        None => {
            let path =
                LemboPath::<R>::new(scene, view, tol.k, tol.perspective, DEFAULT_SEGMENT_CAP);
            render_in_bands(scene, view, &path, threads)
        }
    }
}

/// The lembo path's analysed frame drawn in bands on `threads` threads in datapath `R`.
fn probed_in_bands<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    threads: u32,
) -> Result<Frame> {
    let path = LemboPath::<R>::new(scene, view, tol.k, tol.perspective, DEFAULT_SEGMENT_CAP);
    let board = probe::ProbeBoard::new(scene, view.viewport, threads);
    let frame = render_probed_in_bands(scene, view, &path, (threads, WINDOW_PRIMITIVES), &board)?;
    Ok(Frame {
        probe: Some(board.report()),
        ..frame
    })
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
        let (cap, h) = (DEFAULT_SEGMENT_CAP, view.viewport.height);
        Ok(if analyse {
            let board = probe::ProbeBoard::new(scene, view.viewport, 1);
            render_lembos::<R, _>(scene, view, tol, cap, &mut board.probe(0, h, rop), counts)?;
            Some(board.report())
        } else {
            render_lembos::<R, _>(scene, view, tol, cap, rop, counts)?;
            None
        })
    })
}
