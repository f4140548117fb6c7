//! The units of Figure 5, one file per box, in dataflow order. Each file holds the unit's
//! body, an `async fn run` that takes its [`Ctx`](super::runtime::Ctx) and its own context,
//! calls the functional model and adds only time, and its [`Unit`] declaration: its kind,
//! the items it reads and writes, and how its context is taken from a run. None reaches into
//! the runtime beyond `Ctx`.
//!
//! Adding a unit: its kind in [`crate::graph`] (and the boundaries that reach it), its
//! configuration section in [`crate::config`], its file here, and its line in [`bodies`].

pub mod domain_eval;
pub mod fetch;
pub mod framebuffer;
pub mod interval_manager;
pub mod minmax;
pub mod rasterizer;
pub mod rop;
pub mod segmenter;
pub mod setup;
pub mod subsegmenter;
pub mod tessellator;
pub mod triangle_rasterizer;
pub mod triangle_setup;

use super::unit::{Elaborate, ErasedUnit, Unit};
use crate::datapath::Real;

/// Every unit with a body, as the builder elaborates them; a kind of the graph missing here
/// is refused by the builder's check before a run starts.
pub fn bodies<R: Real>() -> Vec<Box<dyn Elaborate<R>>> {
    fn entry<R: Real, U: Unit<R>>() -> Box<dyn Elaborate<R>> {
        Box::new(ErasedUnit::<U>::new())
    }
    vec![
        entry::<R, fetch::GeometryFetch>(),
        entry::<R, setup::Setup>(),
        entry::<R, minmax::MinMax>(),
        entry::<R, interval_manager::IntervalManager>(),
        entry::<R, segmenter::Segmenter>(),
        entry::<R, subsegmenter::Subsegmenter>(),
        entry::<R, rasterizer::FragmentRasterizer>(),
        entry::<R, tessellator::Tessellator>(),
        entry::<R, domain_eval::DomainEval>(),
        entry::<R, triangle_setup::TriangleSetup>(),
        entry::<R, triangle_rasterizer::TriangleRasterizer>(),
        entry::<R, rop::Rop>(),
        entry::<R, framebuffer::FrameBufferPort>(),
    ]
}
