//! The ROP: depth test, shading of the fragments that pass, and the frame buffer.
pub mod framebuffer;
pub mod shade;

pub use framebuffer::{FrameBuffer, NO_PRIMITIVE};
pub use shade::{Light, Shader};
