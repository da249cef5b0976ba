//! The variation stages whose parameters are one struct: each module holds the stage's
//! [`clap::Parser`] + [`serde::Serialize`] `Params` (the command line, and the parameters
//! recorded in the artifact header) and its `run`; `src/bin/<stage>.rs` only parses and runs.

pub mod gpdm_train;
