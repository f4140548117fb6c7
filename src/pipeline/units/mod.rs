//! The units of Figure 5, one file per box. Each file holds the unit's body, an `async fn
//! run` that takes its [`Ctx`](super::runtime::Ctx) and its own context, calls the functional
//! model and adds only time, and its [`Unit`] declaration: its kind, the items it reads and
//! writes, and how its context is taken from a run. None reaches into the runtime beyond
//! `Ctx`.
//!
//! Every file of this directory is one unit, listed by the build script (`build.rs`): it
//! becomes a module here and its `impl<R: Real> Unit<R> for Type` an entry of [`bodies`].
//! Adding a unit is its kind in [`crate::graph`] (and the boundaries that reach it), its
//! configuration section in `config/sections.rs` and its file here; no list names it.

use super::unit::{Elaborate, ErasedUnit, Unit};
use crate::datapath::Real;

include!(concat!(env!("OUT_DIR"), "/units.rs"));

/// Each unit file (`module: Type`, from `each_unit!`) declared a module, and its unit's body
/// listed by `entries`, in file-name order.
macro_rules! declare {
    ($($module:ident: $unit:ident,)*) => {
        $(pub mod $module;)*

        fn entries<R: Real>() -> Vec<Box<dyn Elaborate<R>>> {
            vec![$(entry::<R, $module::$unit>()),*]
        }
    };
}

each_unit!(declare);

/// Every unit with a body, as the builder elaborates them (in file-name order: the builder
/// finds each by its kind); a kind of the graph missing here is refused by the builder's
/// check before a run starts.
pub fn bodies<R: Real>() -> Vec<Box<dyn Elaborate<R>>> {
    entries::<R>()
}

/// A unit's body, type-erased for the builder.
fn entry<R: Real, U: Unit<R>>() -> Box<dyn Elaborate<R>> {
    Box::new(ErasedUnit::<U>::new())
}
