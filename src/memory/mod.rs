//! The memory system behind the ROPs and the geometry fetch: standalone models that the
//! timed pipeline does not use yet (issue 51 wires them in). A leaf layer: it imports only
//! `error` (and `testkit` in tests).
//!
//! - [`tiles`]: the tiled layout of a surface (8x8-pixel tiles in 32-byte sectors), the
//!   sectors a span or a quad touches, and the per-surface tile table (fast clear,
//!   compression state, hierarchical Z).
//! - [`cache`]: a ROP's colour or depth cache: set-associative, sectored, write-back, LRU.
//! - [`compress`]: lossless depth (plane) and colour (delta) tile codes.
//! - [`trace`]: the request-trace format, DRAMsim3's own, so one file feeds both.
//! - [`dram`]: an event-driven DRAM controller (banks, rows, FR-FCFS, write drain) with
//!   presets for DDR4-2400, GDDR6 and LPDDR5, and its energy per atom and activation.

pub mod cache;
pub mod compress;
pub mod dram;
pub mod tiles;
pub mod trace;
