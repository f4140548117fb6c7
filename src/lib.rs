//! lembo-sim (crate doc written below in full once the pipeline exists).
pub mod camera;
pub mod datapath;
pub mod lembo;
pub mod rop;
pub mod error;
pub mod scene;
pub mod reference;
pub mod raster;
