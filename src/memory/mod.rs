//! The memory system behind the ROPs (issue 51): standalone models that the timed pipeline
//! does not use yet. A leaf layer: it imports only `error` and `testkit`.
//!
//! - [`tiles`]: the tiled layout of a surface (8x8-pixel tiles in 32-byte sectors), the
//!   sectors a span or a quad touches, and the per-surface tile table (fast clear,
//!   compression state, hierarchical Z).
//! - [`cache`]: a ROP's colour or depth cache: set-associative, sectored, write-back, LRU.
//! - [`compress`]: lossless depth (plane) and colour (delta) tile codes.

pub mod cache;
pub mod compress;
pub mod tiles;
