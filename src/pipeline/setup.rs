//! Setup (paper 001 section 4, Figure 5's first unit): projects a lembo's six reference
//! points, rebuilds the screen-space coefficients of x, y and depth with the paper's linear
//! transform, and culls lembos outside the viewport or behind the eye (one cull test each).
//!
//! Input: the scene's lembos, read from memory in scene order (the unit is the source, so
//! it is never starved until it runs out). Output: [`LemboReady`] per visible lembo to
//! MinMax; the [`ScreenLembo`](crate::raster::setup::ScreenLembo) itself goes to the
//! pipeline's lembo table, as a hardware setup unit writes a primitive's coefficients into
//! a parameter buffer that later stages index.
//!
//! Cost: `setup.cycles_per_lembo` busy cycles per lembo, culled or not; the result is ready
//! `setup.latency_cycles` later. Not modelled: the memory traffic of fetching the lembos.

use super::actor::{ActorError, Ctx};
use super::{Finished, Shared};
use crate::datapath::Real;
use crate::raster::setup::{setup, Cull};
use crate::raster::Counts;

/// A lembo whose screen-space form is in the lembo table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LemboReady {
    pub id: u32,
}

pub fn run<R: Real>(mut ctx: Ctx<(), LemboReady>, sh: &Shared<R>) -> Result<Finished, ActorError> {
    let cost = sh.arch.setup.cycles_per_lembo;
    let mut counts = Counts::default();
    for (id, (lembo, color)) in sh.scene.lembos().enumerate() {
        counts.lembos += 1;
        match setup::<R>(id as u32, lembo, color, sh.view) {
            Ok(l) => {
                // Each id is set once, by this unit only.
                let _ = sh.lembos[id].set(l);
                ctx.emit(cost, 0, LemboReady { id: id as u32 })?;
            }
            Err(cull) => {
                match cull {
                    Cull::BehindEye => counts.lembos_culled_behind_eye += 1,
                    Cull::Outside => counts.lembos_culled_outside += 1,
                    Cull::Degenerate => counts.lembos_degenerate += 1,
                }
                ctx.work(cost);
            }
        }
    }
    Finished::new(ctx, counts)
}
