//! An event-driven DRAM controller: per channel a read and a write queue, FR-FCFS
//! scheduling over an open-page row buffer per bank, a write drain between two watermarks,
//! and the JEDEC timings between the commands; energy per atom read or written, per
//! activation and per rank-cycle of standby. [`replay`] runs a trace ([`crate::memory::trace`])
//! to [`DramStats`]; [`Dram`] takes requests one at a time and returns their completions.
//!
//! `config.rs` (what a memory is, validated), `timings.rs`, `mapping.rs` (address bits to channel, rank,
//! bank, row, column), `energy.rs` (pJ per event), `channel.rs` (one channel's queues,
//! choice and timing), `acts.rs` (a rank's ACTs: tRRD and tFAW), `controller.rs` (admission, events, completions), `stats.rs`,
//! `presets.rs` (DDR4-2400, GDDR6, LPDDR5, cited), `traces.rs` (the traces it is checked
//! against DRAMsim3 with; `testkit` feature only).

mod acts;
mod channel;
mod config;
mod controller;
#[cfg(test)]
mod dramsim3_check;
mod energy;
mod mapping;
mod presets;
mod stats;
#[cfg(test)]
mod tests;
mod timings;
#[cfg(any(test, feature = "testkit"))]
pub mod traces;

pub use config::DramConfig;
pub use controller::{replay, Completion, Dram, Ticket};
pub use energy::{DramEnergy, IddCurrents};
pub use mapping::{AddressMapping, Location, MapField};
pub use presets::{
    ddr4_2400_x8, for_dramsim3_file, gddr6_16g_x16, gddr6_dramsim3_x128, lpddr5_6400_x16,
};
pub use stats::{DramEnergyStats, DramStats};
pub use timings::DramTimings;
