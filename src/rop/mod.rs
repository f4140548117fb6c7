//! The ROP: depth test, shading of the fragments that pass, and the frame buffer.
pub mod fragment_shader;
pub mod framebuffer;
pub mod lanes;
pub mod plane;
#[allow(clippy::module_inception)]
pub mod rop;
pub mod shade;

pub use framebuffer::{FrameBuffer, NO_PRIMITIVE};
pub use rop::Rop;
pub use shade::{Light, Shader};
