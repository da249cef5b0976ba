//! The variation stages: each module holds the stage's [`clap::Parser`] + [`serde::Serialize`]
//! `Params` (the command line, and the parameters recorded in the artifact header) and its
//! `run`; `src/bin/<stage>.rs` only parses and runs.

pub mod gpdm_train;
pub mod hmc_sample;
pub mod prealign;

/// Two motion names written `A:B` (`hmc-sample --blend`, `prealign --blend-pairs`).
fn parse_pair(s: &str) -> Result<(String, String), String> {
    match s.split_once(':') {
        Some((a, b)) if !a.is_empty() && !b.is_empty() => Ok((a.into(), b.into())),
        _ => Err(format!("'{s}' is not two motion names A:B")),
    }
}
