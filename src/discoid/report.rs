//! The blend units' report: what the discoid passes count and how far the blend mode's
//! sums stray from f64's (`blend` in report.json).

use serde::Serialize;

/// The blend units' counters and error, what the functional passes find (`blend` in
/// report.json, with the timed passes' cycles beside them: `report::BlendSection`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BlendReport {
    /// `rgba8`, `f16` or `f32`.
    pub mode: String,
    /// Accumulation-target bytes per accumulated fragment (read and write) \[bytes\].
    pub bytes_per_fragment: u64,
    /// Size of the accumulation target: a pixel holds half the bytes per fragment \[bytes\].
    pub accumulation_buffer_bytes: u64,
    /// Fragments blended in the accumulation pass.
    pub fragments_accumulated: u64,
    /// Fragments farther than the threshold behind the depth pass's surface.
    pub discarded_threshold: u64,
    /// Fragments outside their discoid (beta = 0).
    pub discarded_beta_zero: u64,
    /// Fragments of discoids facing away from the eye.
    pub culled_backface: u64,
    /// Fragments whose blend saturated an 8-bit word (rgba8 only; 0 otherwise).
    pub saturations: u64,
    /// Largest |L - L_f64| over resolved pixels, L = Ka + Kd cos + Ks cos^N from the
    /// averaged interest values (colour-free luminance).
    pub error_max: f64,
    /// Mean of the same over resolved pixels.
    pub error_mean: f64,
    /// The threshold t used [world units].
    pub threshold: f64,
    /// Uncovered pixels with covered pixels within 3 px to their left, right, top and
    /// bottom (holes inside the silhouette, `frame::discoid::count_holes`), for every kind of discoid.
    pub holes: Option<u64>,
}
