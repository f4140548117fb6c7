//! A functional frame drawn: the rasterizer's driver (`raster`) into the ROP (`rop`) over a
//! fresh frame buffer, for a scene (`scene`). It sits above all three, so none of them
//! imports another to assemble a frame.
//!
//! [`functional`] (the [`Frame`] and [`frame_with`], a fresh frame buffer and the ROP over
//! it), [`draw`] (the entry points: [`render_functional`], [`render_functional_triangles`],
//! [`render_functional_on`] for `--threads`), [`bands`] (the frame drawn in bands of rows on
//! several host threads, bit for bit the single-threaded one) and [`discoid`] (the three
//! discoid passes). This file only declares and re-exports.

pub mod bands;
pub mod discoid;
pub mod draw;
pub mod functional;

pub use draw::{render_functional, render_functional_on, render_functional_triangles};
pub use functional::{frame_with, Frame};

#[cfg(test)]
mod tests;
