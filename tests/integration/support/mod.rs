//! What several test modules share: running the binary, golden files, the shipped scenes.

pub mod binary;
pub mod golden;
pub mod scenes;
