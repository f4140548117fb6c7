//! The ROP: depth test, shading of the fragments that pass, and the frame buffer.
pub mod fragment_shader;
pub mod framebuffer;
pub mod lanes;
pub mod plane;
pub mod shade;
pub mod sink;

pub use framebuffer::{FrameBuffer, NO_PRIMITIVE};
pub use shade::Shader;
pub use sink::RopSink;
