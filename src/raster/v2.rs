//! Two-component vectors in the (u, v) domain, in datapath precision.

use crate::datapath::Real;

/// A (u, v) pair.
pub type V2<R> = [R; 2];

/// The dot product.
#[inline(always)]
pub fn dot<R: Real>(a: V2<R>, b: V2<R>) -> R {
    a[0] * b[0] + a[1] * b[1]
}

/// The Euclidean length, without overflow (`hypot`).
#[inline(always)]
pub fn norm<R: Real>(a: V2<R>) -> R {
    a[0].length(a[1])
}

/// The vector turned a quarter turn clockwise (the walk direction for a gradient: the
/// region where Y grows stays on the left).
#[inline(always)]
pub fn rot_cw<R: Real>(a: V2<R>) -> V2<R> {
    [a[1], -a[0]]
}
