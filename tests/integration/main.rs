//! The integration tests, one test binary (as nexosim keeps them): each module below was a
//! test binary of its own, each built and linked against the whole crate again, so that a
//! fresh `cargo test --release` spent most of its time building. A module is one area (its
//! `//!` says what it checks); `support` holds what several of them share. A test's name
//! starts with its module's, so one area runs alone with
//! `cargo test --release --test integration cycles_golden::`.

mod support;

mod atomic;
mod cli;
mod cost;
mod creases;
mod culling;
mod cycles_golden;
mod datapath;
mod design_point;
mod discoid;
mod docs;
mod dram_check;
mod extreme_method;
mod extremes;
mod fuzz;
mod html;
mod knobs;
mod layers;
mod memory_model;
mod multisample;
mod near_plane;
mod perspective;
mod scope;
mod see_through;
mod sweep;
mod threads;
mod timed;
mod triangle;
