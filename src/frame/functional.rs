//! A functional frame ([`Frame`]): the image the ROP wrote into a fresh frame buffer, what
//! the stages counted and, when analysed, the probe's measurements. The driver
//! (`raster::driver`) draws into the ROP [`frame_with`] makes, or into the ROPs of the bands
//! [`super::bands`] makes.

use crate::camera::View;
use crate::datapath::Real;
use crate::error::Result;
use crate::raster::counts::Counts;
use crate::raster::probe::ProbeReport;
use crate::rop::{FrameBuffer, RopSink};
use crate::scene::Scene;

/// A rendered frame and what it took.
pub struct Frame {
    /// The image, depth and winners.
    pub framebuffer: FrameBuffer,
    /// What the stages produced.
    pub counts: Counts,
    /// Fragment-level measurements, when requested.
    pub probe: Option<ProbeReport>,
}

impl Frame {
    /// This frame, drawn on the sample grid of `samples` per pixel, resolved into its image
    /// ([`FrameBuffer::resolve`]); the counts and the probe stay the sample grid's.
    pub fn resolve(self, samples: crate::camera::Samples) -> Frame {
        Frame {
            framebuffer: self.framebuffer.resolve(samples),
            ..self
        }
    }
}

/// A frame drawn by `draw` into a ROP over a fresh frame buffer (keeping normals when
/// analysing); `draw` returns the probe's report when it measured one.
pub fn frame_with<R: Real>(
    scene: &Scene,
    view: &View,
    analyse: bool,
    draw: impl FnOnce(&mut RopSink<R>, &mut Counts) -> Result<Option<ProbeReport>>,
) -> Result<Frame> {
    let vp = view.viewport;
    let bg = scene.background.map(crate::rop::shade::to_u8::<f64>);
    let mut fb = FrameBuffer::new(vp.width, vp.height, bg, analyse);
    let mut counts = Counts::default();
    let mut rop = RopSink::<R>::new(&mut fb, &scene.light, view);
    let probe = draw(&mut rop, &mut counts)?;
    (counts.fragments_passed_depth, counts.pixels_covered) = rop.finish();
    Ok(Frame {
        framebuffer: fb,
        counts,
        probe,
    })
}
