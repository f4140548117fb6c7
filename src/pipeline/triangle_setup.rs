//! TriangleSetup (the triangle path, DESIGN §5): projects a triangle's three vertices,
//! snaps them to 16.8 fixed point, sets up the integer edge functions and the
//! perspective-correct attribute planes, and culls (one test per triangle).
//!
//! Input: the triangles (the tessellated scene), in their source's order (the unit is the
//! source: the Tessellator's output is read from memory, so the unit is never starved until
//! it runs out). Output: each set-up triangle, round-robin to the triangle rasterizers.
//!
//! Cost: `triangle_setup.cycles_per_triangle` busy cycles per triangle, culled or not; the
//! result is ready `triangle_setup.latency_cycles` later. Not modelled: vertex fetch and
//! the post-transform vertex cache (each triangle's three vertices are transformed here).

use super::actor::{ActorError, Ctx};
use super::{Finished, Shared};
use crate::datapath::Real;
use crate::raster::triangle::{count_cull, setup, ScreenTriangle};
use crate::raster::Counts;
use std::sync::Arc;

pub fn run<R: Real>(
    mut ctx: Ctx<(), Arc<ScreenTriangle<R>>>,
    sh: &Shared<R>,
) -> Result<Finished, ActorError> {
    let cost = sh.arch.triangle_setup.cycles_per_triangle;
    let source = sh
        .triangles
        .expect("the triangle path is elaborated with a triangle source");
    let mut counts = Counts::default();
    let mut triangles = Vec::new();
    let mut next = 0;
    for c in 0..source.chunks() {
        source.chunk(c, &mut triangles);
        for (k, t) in triangles.iter().enumerate() {
            counts.triangles += 1;
            let id = source.id(c, k);
            match setup::<R>(id, &t.positions, &t.normals, t.color, sh.view) {
                Ok(st) => {
                    ctx.emit(cost, next, Arc::new(st))?;
                    next = (next + 1) % ctx.outputs();
                }
                Err(cull) => {
                    count_cull(cull, &mut counts);
                    ctx.work(cost);
                }
            }
        }
    }
    Finished::new(ctx, counts)
}
