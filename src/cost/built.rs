//! Units priced as they would be built (DESIGN.md §12): where the model computes
//! differently from hardware for exactness, its image stays as it is and its counts follow
//! the hardware, operations charged per hardware event ([`Event`]) that the counting run
//! tallies. One formula per event, kept here and nowhere else.
//!
//! **TriangleRasterizer** (replaced: the model finds each row's covered columns in closed
//! form and works out every fragment from the three full edge functions, three divides for
//! its barycentrics and six for its perspective-correct attributes). Hardware walks the
//! bounding box hierarchically and steps everything by increments (Pineda's edge
//! functions): setup hands it the edge functions and their steps, and the attribute planes.
//! The walk visits the box's coarse tiles (`raster::triangle::COARSE_TILE_PX`) and the
//! quads of the tiles it does not reject; the planes (window depth z, 1/w, normal/w and
//! position/w: [`PLANES`]) move with the edges, one add a move.
//!
//! | event | edge functions (32-bit fixed point) | planes and attributes (datapath) |
//! |---|---|---|
//! | a tile | step to it (3 adds), its trivial-reject corner (3 adds), sign tests (3 compares, on the adder) | step to it (8 adds) |
//! | a quad tested | step to it (3 adds), the other three pixels (9 adds), 12 fill-rule compares | step to it (8 adds) |
//! | a quad covered | | `reciprocal: "quad"`: one reciprocal of 1/w (a divide) |
//! | a fragment | | its lane's plane values (8 adds); `"quad"`: a Newton step from the quad's reciprocal, w (2 - w (1/w)) (2 multiplies, an add), `"pixel"`: a reciprocal (a divide); the six attributes times w (6 multiplies) |
//! | a sample (multisampled: the fragments are samples) | | its window depth (an add); the pixel's attributes are worked out once, at its centre, by the ROP that shades it, and counted there as executed |
//!
//! Uncovered lanes of a covered quad are gated: they spend nothing beyond the coverage test.
//!
//! **TriangleSetup** (executed counts kept, the planes added): the model's setup projects,
//! clips, snaps and builds the integer edge functions as hardware would (counted as
//! executed), but sets up no attribute plane, since its rasterizer divides per pixel. Per
//! set-up triangle handed to the rasterizer, hardware adds: the reciprocal of the doubled
//! area (a divide); per plane ([`PLANES`]) the vertex differences (2 adds), dA/dx and dA/dy
//! (3 multiplies and an add each, the second difference's product and the area's
//! reciprocal) and the value at the walk's origin (2 multiplies, 2 adds) and the quad's
//! diagonal lane offset (an add): 8 multiplies and 7 adds; for the walk, the three edge
//! functions at its first tile (2 multiplies and 2 adds each), each edge's trivial-reject
//! corner offset and diagonal lane offset (2 adds), and the origin's offset from vertex 0
//! (2 adds). Steps by a tile or a quad are the per-pixel steps shifted (tile and quad sides
//! are powers of two): wiring.

use super::counted::OpTable;
use crate::config::Reciprocal;
use crate::datapath::{Event, Op, OPS};
use crate::graph::UnitKind;

/// Attribute planes the triangle path interpolates: window depth, 1/w, normal/w (3) and
/// position/w (3).
pub const PLANES: u64 = 8;

/// Operation counts in [`OPS`] order from the classes a formula uses.
fn ops(add: u64, mul: u64, div: u64, int_add: u64, int_mul: u64) -> [u64; OPS.len()] {
    let mut out = [0; OPS.len()];
    out[Op::Add as usize] = add;
    out[Op::Mul as usize] = mul;
    out[Op::Div as usize] = div;
    out[Op::IntAdd as usize] = int_add;
    out[Op::IntMul as usize] = int_mul;
    out
}

/// What the rasterizer does per `event` (the module's table).
pub fn rasterizer_per(event: Event, reciprocal: Reciprocal) -> [u64; OPS.len()] {
    let quad = reciprocal == Reciprocal::Quad;
    match event {
        Event::Triangle => ops(0, 0, 0, 0, 0),
        Event::Tile => ops(PLANES, 0, 0, 9, 0),
        Event::QuadTested => ops(PLANES, 0, 0, 24, 0),
        Event::QuadCovered => ops(0, 0, quad as u64, 0, 0),
        Event::Fragment if quad => ops(PLANES + 1, 2 + 6, 0, 0, 0),
        Event::Fragment => ops(PLANES, 6, 1, 0, 0),
        // The sample's window depth, stepped with the edges; the pixel's attributes are the
        // shading ROP's, once a pixel, counted as executed there.
        Event::Sample => ops(1, 0, 0, 0, 0),
    }
}

/// What setup adds per set-up triangle to what the model executes (the module's text).
pub fn setup_per_triangle() -> [u64; OPS.len()] {
    ops(7 * PLANES, 8 * PLANES, 1, 6 + 6 + 2, 6)
}

/// One vertex's work in the triangle setup, as the model executes it for each corner of
/// each triangle (`raster::triangle::setup`): its two depth-plane distances (8 multiplies,
/// 6 adds, 2 compares), its projection (24 multiplies, 15 adds, a reciprocal), its 1/w
/// and the six attributes over w (a reciprocal, 6 multiplies) and its 16.8 snap (2
/// roundings). A post-transform vertex cache hit, or a corner whose vertex the domain
/// evaluator already set up for its patch, does none of it.
pub fn setup_per_vertex() -> [u64; OPS.len()] {
    let mut out = ops(21, 38, 2, 0, 0);
    out[Op::Cmp as usize] = 2;
    out[Op::Round as usize] = 2;
    out
}

/// `counted` with the units priced as built: the triangle rasterizer's operations from
/// the walk's events, the triangle setup's executed ones plus its planes and steps per
/// triangle it set up, less one vertex's work ([`setup_per_vertex`]) for each of the
/// `reused` triangle corners whose transformed vertex was reused. Kinds and events the run
/// did not touch stay 0.
pub fn as_built(counted: &OpTable, reciprocal: Reciprocal, reused: u64) -> OpTable {
    let mut out = *counted;
    let mut raster = [0; OPS.len()];
    for event in crate::datapath::EVENTS {
        let n = counted.events(event);
        for (total, per) in raster.iter_mut().zip(rasterizer_per(event, reciprocal)) {
            *total += n * per;
        }
    }
    out.set(UnitKind::TriangleRasterizer, raster);
    let triangles = counted.events(Event::Triangle);
    let mut setup = counted.of(UnitKind::TriangleSetup);
    for (total, per) in setup.iter_mut().zip(setup_per_triangle()) {
        *total += triangles * per;
    }
    // A corner culled before its projection (behind a depth plane) executed less than a
    // vertex's work: never take away more than was executed.
    for (total, per) in setup.iter_mut().zip(setup_per_vertex()) {
        *total = total.saturating_sub(reused * per);
    }
    out.set(UnitKind::TriangleSetup, setup);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-worked account: 2 triangles, 3 tiles, 5 quads tested, 4 covered, 6 fragments,
    /// on top of 10 executed setup adds and 99 executed rasterizer multiplies (replaced).
    #[test]
    fn the_account_is_the_events_times_the_table() {
        let mut t = OpTable::default();
        t.add(UnitKind::TriangleSetup, Op::Add, 10);
        t.add(UnitKind::TriangleRasterizer, Op::Mul, 99);
        for (e, n) in [
            (Event::Triangle, 2),
            (Event::Tile, 3),
            (Event::QuadTested, 5),
            (Event::QuadCovered, 4),
            (Event::Fragment, 6),
        ] {
            t.add_events(e, n);
        }
        let q = as_built(&t, Reciprocal::Quad, 0);
        // Adds: 8 a tile, 8 a quad tested, 9 a fragment; multiplies 8 a fragment; a divide
        // a covered quad; 9 fixed-point adds a tile and 24 a quad tested.
        assert_eq!(
            q.of(UnitKind::TriangleRasterizer),
            [
                3 * 8 + 5 * 8 + 6 * 9,
                6 * 8,
                4,
                0,
                0,
                0,
                0,
                3 * 9 + 5 * 24,
                0
            ]
        );
        let p = as_built(&t, Reciprocal::Pixel, 0);
        assert_eq!(
            p.of(UnitKind::TriangleRasterizer),
            [
                3 * 8 + 5 * 8 + 6 * 8,
                6 * 6,
                6,
                0,
                0,
                0,
                0,
                3 * 9 + 5 * 24,
                0
            ]
        );
        assert_eq!(
            q.of(UnitKind::TriangleSetup),
            [10 + 2 * 56, 2 * 64, 2, 0, 0, 0, 0, 2 * 14, 2 * 6]
        );
        assert_eq!(q.events(Event::Fragment), 6);
        // Nothing else moves.
        assert_eq!(q.of(UnitKind::Rop), t.of(UnitKind::Rop));
        // A reused vertex takes one vertex's work from setup, never below 0.
        let mut setup = t;
        setup.add(UnitKind::TriangleSetup, Op::Mul, 38);
        let r = as_built(&setup, Reciprocal::Quad, 1);
        let mut want = q.of(UnitKind::TriangleSetup);
        want[Op::Add as usize] -= 21;
        for op in [Op::Div, Op::Cmp, Op::Round] {
            want[op as usize] = 0;
        }
        assert_eq!(r.of(UnitKind::TriangleSetup), want);
    }

    /// A run without triangles (the lembo path) keeps its table.
    #[test]
    fn a_run_without_triangles_is_unchanged() {
        let mut t = OpTable::default();
        t.add(UnitKind::Segmenter, Op::Mul, 7);
        assert_eq!(as_built(&t, Reciprocal::Quad, 0), t);
    }
}
