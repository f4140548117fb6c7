//! What the simulated unit costs in silicon: operation counts taken by the code that does
//! the arithmetic ([`counted`]), a technology file of cited energies and areas ([`tech`]),
//! and each unit's area and energy from both ([`model`]). DESIGN.md §12 defines the model.
//!
//! The counting runs ([`lembo_ops`], [`triangle_ops`]) are the functional driver's
//! single-threaded frame ([`draw_in_order`]) in a counting datapath, with a sink that charges
//! the ROP's operations to it (`ChargedToRop`); each stage charges its own kind, and the
//! triangle rasterizer's walk tallies its hardware events, which [`built`] prices the units
//! built differently from the model by (applied in [`model::cost`]). A discoid
//! scene's ([`discoid_ops`]) is the functional model's passes in counting words, whose
//! discoid sink charges the ROP itself, the blend the blend units and the resolve the ROPs.

pub mod built;
pub mod counted;
pub mod design_point;
pub mod memory_kind;
pub mod model;
pub mod onchip;
pub mod tech;

#[cfg(test)]
mod tests;

use crate::camera::View;
use crate::datapath::{Datapath, Real};
use crate::discoid::blend::BlendMode;
use crate::error::Result;
use crate::frame::discoid::{render_discoids_in, DiscoidFrame};
use crate::frame::{frame_with, Frame};
use crate::graph::UnitKind;
use crate::raster::driver::draw_in_order;
use crate::raster::fragment::FragmentSink;
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
/// operations of each kind: the same pixels as [`crate::frame::render_functional`] (the
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

/// A discoid scene's frame drawn by the functional model in counting words, with the
/// operations of each kind: both passes through the path's units (the ROP's discoid work
/// charged to the ROP), the blend in the blend ALU's counting `f32` charged to the blend
/// units, the resolve to the ROPs. The same image as
/// [`crate::frame::discoid::render_discoids`] (the counting words do the same IEEE
/// operations; `tests/integration/cost.rs`).
pub fn discoid_ops(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    blend: (BlendMode, f64),
) -> Result<(DiscoidFrame, OpTable)> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => discoid_ops_in::<f32>(scene, view, tol, blend),
        Datapath::F64 => discoid_ops_in::<f64>(scene, view, tol, blend),
    }
}

fn discoid_ops_in<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    blend: (BlendMode, f64),
) -> Result<(DiscoidFrame, OpTable)> {
    let first = if scene.lembo_count() > 0 {
        UnitKind::Setup
    } else {
        UnitKind::TriangleSetup
    };
    let (frame, ops) = counting(first, || {
        render_discoids_in::<Counted<R>, Counted<f32>>(scene, view, tol, blend, false)
    });
    Ok((frame?, ops))
}
