//! Setup (Martinelli 2006 section 4, Figure 5's first unit): projects a lembo's six reference
//! points, rebuilds the screen-space coefficients of x, y and depth with the paper's linear
//! transform, and culls lembos outside the viewport or behind the eye (one cull test each).
//!
//! Input: the scene's lembos, read from memory in scene order (the unit is the source, so
//! it is never starved until it runs out). Output: [`LemboReady`] per visible lembo to
//! MinMax; the [`ScreenLembo`](crate::raster::setup::ScreenLembo) itself goes to the
//! pipeline's lembo table, as a hardware setup unit writes a primitive's coefficients into
//! a parameter buffer that later stages index.
//!
//! A lembo whose hull reaches far beyond the viewport is split into pieces
//! ([`setup_pieces`]); each piece is a table entry of its own and goes down the pipeline as
//! a lembo does.
//!
//! Cost: `setup.cycles_per_lembo` busy cycles per lembo, culled or not, and as many again
//! per sub-patch a split examines; a further piece of a split lembo is emitted at 1 cycle
//! (it was computed with the split). The result is ready `setup.latency_cycles` later. Not
//! modelled: the memory traffic of fetching the lembos.

use crate::datapath::Real;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::{Finished, PieceId, Shared};
use crate::raster::setup::setup_pieces;
use crate::raster::Counts;

/// A lembo whose screen-space form is in the lembo table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LemboReady {
    /// The lembo piece, whose screen form Setup put in the shared table.
    pub id: PieceId,
}

/// Setup's body: every lembo of the scene in order, projected (and split or clipped) into the
/// shared table.
pub async fn run<R: Real>(mut ctx: Ctx<(), LemboReady>, sh: &Shared<'_, R>) -> Finished {
    let cost = sh.arch.setup.cycles_per_lembo;
    let mut counts = Counts::default();
    let mut pieces = Vec::new();
    // Pieces to the MinMax units, round-robin.
    let mut next_port = 0;
    for (id, (lembo, color)) in sh.scene.lembos().enumerate() {
        counts.lembos += 1;
        match setup_pieces::<R>(
            id as u32,
            lembo,
            color,
            sh.view,
            sh.perspective_tol,
            &mut pieces,
        ) {
            Ok(split) => {
                counts.add_split(split, pieces.len());
                // Each sub-patch examined is set up as a lembo is (six points evaluated,
                // hull tested); the lembo's own cost comes with its first emission.
                let n = pieces.len();
                // Each id is set once, by this unit only.
                let _ = sh.lembos[id].set(std::mem::take(&mut pieces));
                let mut owed = cost * (1 + split.examined as u64);
                for piece in 0..n {
                    let id = PieceId {
                        lembo: id as u32,
                        piece: piece as u32,
                    };
                    ctx.emit(owed.max(1), next_port, LemboReady { id }).await;
                    next_port = ctx.next_port(next_port);
                    owed = 0;
                }
                if n == 0 {
                    ctx.work(owed);
                }
            }
            Err(cull) => {
                counts.add_cull(cull);
                ctx.work(cost);
            }
        }
    }
    Finished::new(ctx, counts)
}
