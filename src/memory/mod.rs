//! The memory system below the ROPs and the geometry fetch (issue 51): standalone models
//! the timed pipeline does not use yet. A leaf layer: it imports only `error` (and
//! `testkit` in tests).
//!
//! - [`trace`]: the request-trace format, DRAMsim3's own, so one file feeds both.
//! - [`dram`]: an event-driven DRAM controller (banks, rows, FR-FCFS, write drain) with
//!   presets for DDR4-2400, GDDR6 and LPDDR5, and its energy per atom and activation.

pub mod dram;
pub mod trace;
