//! The transfer stages: each module holds the stage's [`clap::Parser`] + [`serde::Serialize`]
//! `Params` (the command line, and the parameters recorded in the artifact header) and its
//! `run`; `src/bin/<stage>.rs` only parses and runs.

pub mod dtw_densify;
pub mod gpr_predict;
pub mod gpr_train;
pub mod representation_error;
pub mod surface_quality;
pub mod transfer_eval;
