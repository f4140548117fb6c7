//! The datapath precision of the functional model.
//!
//! Every stage of the extreme method is written once, generic over [`Real`], and
//! instantiated for `f32` (the default, as a hardware unit would be built) and `f64`
//! (to separate the method's own error from rounding). The reference renderer does not use
//! this trait: it is always `f64`.

use crate::cost::counted::Op;
use crate::pipeline::graph::UnitKind;
use num_traits::Float;
use std::fmt::Debug;

/// A floating-point datapath word: `f32` or `f64`.
pub trait Real: Float + Debug + Default + Send + Sync + 'static {
    /// Name used in reports and on the command line.
    const NAME: &'static str;
    /// Whether this word counts its operations ([`crate::cost::counted::Counted`]): code
    /// that would do extra arithmetic for speed (the ROP's shading in lanes, which computes
    /// both sides of a branch) does the formula as written instead.
    const COUNTS_OPERATIONS: bool = false;
    /// Converts from `f64`, rounding to nearest.
    fn of(x: f64) -> Self;
    /// Widens to `f64` exactly.
    fn f64(self) -> f64;
    /// Charges the operations that follow to the unit kind `kind` (a counting datapath,
    /// [`crate::cost::counted::Counted`], keeps per-kind counts; for `f32` and `f64` this is
    /// nothing).
    #[inline(always)]
    fn charge(_kind: UnitKind) {}
    /// Counts `n` operations `op` done beside the datapath words, in fixed point (the
    /// triangle path's edge functions); nothing for `f32` and `f64`.
    #[inline(always)]
    fn count_beside(_op: Op, _n: u64) {}
}

impl Real for f32 {
    const NAME: &'static str = "f32";
    #[inline(always)]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn of(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
    }
}

/// The datapath selected on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Datapath {
    /// IEEE binary32 throughout the extreme method (the default, as hardware).
    #[default]
    F32,
    /// IEEE binary64 throughout the extreme method.
    F64,
}

impl Datapath {
    /// The name used in reports: `f32` or `f64`.
    pub fn name(self) -> &'static str {
        match self {
            Datapath::F32 => f32::NAME,
            Datapath::F64 => f64::NAME,
        }
    }
}
