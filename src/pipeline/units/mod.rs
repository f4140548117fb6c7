//! The units of Figure 5, one file per box, in dataflow order. Each is an `async fn` that
//! takes its [`Ctx`](super::runtime::Ctx), calls the functional model and adds only time;
//! none reaches into the runtime beyond `Ctx`.

pub mod framebuffer;
pub mod interval_manager;
pub mod minmax;
pub mod rasterizer;
pub mod rop;
pub mod segmenter;
pub mod setup;
pub mod subsegmenter;
pub mod triangle_rasterizer;
pub mod triangle_setup;
