//! mesh-core: what every surfcap stage shares.
//!
//! Data flows one way through the stages: capture set -> aligned -> parts ->
//! coefficients -> model -> prediction -> surface -> render/report. This crate
//! holds the pieces each of them needs: the triangle mesh and its topology,
//! PLY/OBJ input and output, mesh sequences, the capture-set format, the
//! artifact container that stages pass to each other, rigid motion, and the
//! command-line conventions shared by all stage binaries.

pub mod error;
pub mod mesh;
pub mod topology;
pub mod input;
pub mod io;
pub mod frame_pattern;
pub mod frame_rate;
pub mod sequence;
pub mod capture_set;
pub mod set_check;
pub mod segmentation;
pub mod component_joins;
pub mod artifact;
pub mod part_merge;
pub mod atomic;
pub mod rigid;
pub mod point_tree;
pub mod cli;
pub mod stage;
pub mod clap_docs;
pub mod shapes;
pub mod contacts;
pub mod feet;
pub mod font;

pub use error::{Error, Result};
pub use mesh::TriMesh;
