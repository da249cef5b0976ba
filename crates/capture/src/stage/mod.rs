//! The front end's stages: each module holds the stage's [`clap::Parser`] + [`serde::Serialize`]
//! `Params` (the command line, and the parameters recorded in the artifact header) and its
//! `run`, so that `src/bin/<stage>.rs` only parses and runs.

pub mod align;
pub mod pca_fit;
pub mod segment;
