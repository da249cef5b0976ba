//! The export stages: each module holds the stage's [`clap::Parser`] + [`serde::Serialize`]
//! `Params` (the command line, and the parameters a header would record) and its `run`, so that
//! `src/bin/<stage>.rs` only parses and runs.

pub mod html_report;
pub mod mesh_export;
pub mod mesh_import;
