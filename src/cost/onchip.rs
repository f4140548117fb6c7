//! The operations of on-chip tessellation (the `onchip` triangle source), counted as the
//! hardware would perform them (DESIGN.md §12): the functional model evaluates the
//! tessellation's vertices in `f64` on the host where TriangleSetup reads them, so these
//! units' operations are not taken by a counting run but from what each lembo asks of
//! them.
//!
//! - **Tessellator**, per lembo: each of its (n + 1)(n + 2)/2 domain points by two
//!   fixed-point increments (u, v), and each of its n² triangles' three vertex indices by
//!   three fixed-point adds and a row-end compare: `IntAdd` 2 per point and 4 per triangle.
//! - **DomainEval**, per domain point: w = 1 − u − v (2 adds), the six quadratic basis
//!   functions (w(2w − 1), u(2u − 1), v(2v − 1), 4uw, 4vw, 4uv: 12 multiplies, 3 adds),
//!   the weighted sums of the six points and of the six normals (36 multiplies, 30 adds),
//!   and the normal's normalisation (a dot product, a square root, a reciprocal and three
//!   multiplies: 6 multiplies, 2 adds, 1 square root, 1 divide). In all 54 multiplies, 37
//!   adds, a square root and a divide, in the datapath's precision.

use super::counted::OpTable;
use crate::datapath::Op;
use crate::graph::UnitKind;
use crate::raster::triangle::TriangleSource;

/// A DomainEval's operations per domain point, as [`Op`] and count.
pub const DOMAIN_EVAL_PER_POINT: [(Op, u64); 4] =
    [(Op::Mul, 54), (Op::Add, 37), (Op::Sqrt, 1), (Op::Div, 1)];

/// A Tessellator's fixed-point adds per domain point and per triangle.
pub const TESSELLATOR_PER_POINT: u64 = 2;
/// See [`TESSELLATOR_PER_POINT`].
pub const TESSELLATOR_PER_TRIANGLE: u64 = 4;

/// Adds to `ops` what the Tessellators and DomainEvals do to tessellate every chunk (lembo)
/// of `source` on chip.
pub fn tessellation_ops(source: &dyn TriangleSource, ops: &mut OpTable) {
    let lembos = source.chunks() as u64;
    let points = lembos * source.vertices_per_chunk();
    let triangles = lembos * source.per_chunk();
    ops.add(
        UnitKind::Tessellator,
        Op::IntAdd,
        points * TESSELLATOR_PER_POINT + triangles * TESSELLATOR_PER_TRIANGLE,
    );
    for (op, n) in DOMAIN_EVAL_PER_POINT {
        ops.add(UnitKind::DomainEval, op, points * n);
    }
}
