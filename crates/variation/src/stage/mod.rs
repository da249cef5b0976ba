//! The variation stages: each module holds the stage's [`clap::Parser`] + [`serde::Serialize`]
//! `Params` (the command line, and the parameters recorded in the artifact header) and its
//! `run`; `src/bin/<stage>.rs` only parses and runs.

pub mod gpdm_train;
pub mod hmc_sample;
pub mod prealign;
pub mod variation_eval;
