//! The discoid passes in the functional model (Piranda et al. 2006 section 3, DESIGN.md §4):
//! [`table`] (what the blend units know of every discoid, a fragment evaluated),
//! [`target`] (the ROP's per-pixel state, its work on a fragment in each pass, the blend in
//! primitive order, the resolve and its holes), [`passes`] (the three passes over a scene).
//! The timed ROP units (`pipeline::units::rop`) do the same work through [`target`].
//! This file only declares and re-exports.

pub mod passes;
pub mod table;
pub mod target;

pub use passes::{
    check_scene, render_discoids, render_discoids_functional, render_discoids_in, DiscoidFrame,
};
pub use table::{evaluate, DiscoidFragment, DiscoidTable, Evaluated, PlanarDiscoids};
pub use target::{
    accumulation_keeps, count_holes, depth_pass_wins, process, resolve, DiscoidTarget,
    KeptFragment, Pass, HOLE_REACH,
};
