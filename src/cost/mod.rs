//! What the simulated unit costs in silicon: operation counts taken by the code that does
//! the arithmetic ([`counted`]), a technology file of cited energies and areas ([`tech`]),
//! and each unit's area and energy from both ([`model`]). DESIGN.md §12 defines the model.
//!
//! The counting runs ([`lembo_ops`], [`triangle_ops`]) are the functional driver's
//! single-threaded frame ([`draw_in_order`]) in a counting datapath, with a sink that charges
//! the ROP's operations to it (`ChargedToRop`); each stage charges its own kind.

pub mod counted;
pub mod model;
pub mod tech;

use crate::camera::View;
use crate::datapath::{Datapath, Real};
use crate::error::Result;
use crate::graph::UnitKind;
use crate::raster::driver::draw_in_order;
use crate::raster::fragment::FragmentSink;
use crate::raster::frame::{frame_with, Frame};
use crate::raster::lembo_path::LemboPath;
use crate::raster::screen::ScreenLembo;
use crate::raster::subsegmenter::Subsegment;
use crate::raster::triangle::{
    ScreenTriangle, TriangleFragment, TrianglePath, TriangleSink, TriangleSource,
};
use crate::raster::DEFAULT_SEGMENT_CAP;
use crate::scene::Scene;
use crate::tolerance::Tolerance;
use counted::{counting, Counted, OpTable};

/// A sink that charges what its inner sink (the ROP) does to the ROP, and hands the charge
/// back to the rasterizer that called it.
struct ChargedToRop<'a, S> {
    inner: &'a mut S,
    caller: UnitKind,
}

impl<R: Real, S: FragmentSink<R>> FragmentSink<R> for ChargedToRop<'_, S> {
    #[inline]
    fn fragment(
        &mut self,
        l: &ScreenLembo<R>,
        sub: &Subsegment<R>,
        i: u32,
        j: u32,
        u: R,
        v: R,
        z: R,
    ) {
        R::charge(UnitKind::Rop);
        self.inner.fragment(l, sub, i, j, u, v, z);
        R::charge(self.caller);
    }
}

impl<R: Real, S: TriangleSink<R>> TriangleSink<R> for ChargedToRop<'_, S> {
    #[inline]
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        R::charge(UnitKind::Rop);
        self.inner.fragment(t, i, j, f);
        R::charge(self.caller);
    }
}

/// The lembo path's frame drawn by the functional model in a counting datapath, with the
/// operations of each kind: the same pixels as [`crate::raster::render_functional`] (the
/// counting words do the same IEEE operations; `tests/integration/cost.rs`).
pub fn lembo_ops(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
) -> Result<(Frame, OpTable)> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => lembo_ops_in::<f32>(scene, view, tol),
        Datapath::F64 => lembo_ops_in::<f64>(scene, view, tol),
    }
}

fn lembo_ops_in<R: Real>(scene: &Scene, view: &View, tol: Tolerance) -> Result<(Frame, OpTable)> {
    let (frame, ops) = counting(UnitKind::Setup, || {
        frame_with::<Counted<R>>(scene, view, false, |rop, counts| {
            let mut sink = ChargedToRop {
                inner: rop,
                caller: UnitKind::FragmentRasterizer,
            };
            let cap = DEFAULT_SEGMENT_CAP;
            let path = LemboPath::new(scene, view, tol.k, tol.perspective, cap);
            draw_in_order(&path, &mut sink, counts)?;
            Ok(None)
        })
    });
    Ok((frame?, ops))
}

/// The triangle path's frame drawn by the functional model in a counting datapath, with
/// the operations of each kind (as [`lembo_ops`]).
pub fn triangle_ops(
    scene: &Scene,
    view: &View,
    source: &dyn TriangleSource,
    datapath: Datapath,
) -> (Frame, OpTable) {
    match datapath {
        Datapath::F32 => triangle_ops_in::<f32>(scene, view, source),
        Datapath::F64 => triangle_ops_in::<f64>(scene, view, source),
    }
}

fn triangle_ops_in<R: Real>(
    scene: &Scene,
    view: &View,
    source: &dyn TriangleSource,
) -> (Frame, OpTable) {
    let (frame, ops) = counting(UnitKind::TriangleSetup, || {
        frame_with::<Counted<R>>(scene, view, false, |rop, counts| {
            let mut sink = ChargedToRop {
                inner: rop,
                caller: UnitKind::TriangleRasterizer,
            };
            draw_in_order(&TrianglePath::new(source, view), &mut sink, counts)?;
            Ok(None)
        })
    });
    (frame.expect("the triangle path records no error"), ops)
}
