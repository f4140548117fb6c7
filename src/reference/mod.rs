//! The reference: an exact, untimed `f64` renderer of the true surfaces, and the accuracy
//! metrics that hold a rendered frame against it (DESIGN.md §6).
//!
//! [`oracle`] intersects the ray through every sample with the world-space lembos
//! themselves (no projection approximation, no datapath rounding) and shades the nearest
//! hit with the exact normal function; [`metrics`] compares a frame buffer with that image
//! under the names the report carries, with [`outline`] locating the reference's outline
//! between pixel centres and [`see_through`] holding the render against the input mesh's
//! own triangles; [`flip`] is the perceptual difference (FLIP, by its reference
//! implementation); [`heatmap`] draws the difference for a person to read;
//! [`montage`] puts images side by side under their labels.
//!
//! Architecture Invariant: this module knows nothing of cycles, units, the extreme method
//! or the datapath precision. It depends only on the lembo model, the camera, the shading
//! equation and the frame buffer's layout, so it can judge any renderer.

mod distance;
pub mod flip;
pub mod heatmap;
pub mod leak;
pub mod metrics;
pub mod montage;
pub mod oracle;
pub mod outline;
pub mod see_through;
mod surface;

pub use flip::{FlipMap, PixelsPerDegree};
pub use heatmap::{error_heatmap, legend_height};
pub use metrics::{measure, Accuracy};
pub use oracle::{
    intersect_ray, render_reference, ReferenceHit, ReferenceImage, ReferenceInput, Tracer,
};
pub use outline::ReferenceCoverage;
pub use surface::Drawn;
