//! synth: capture sets from real MakeHuman bodies driven by real mocap, with ground truth.
//!
//! Data flow: assets (fetched by `scripts/fetch-assets`) -> [`makehuman`] body, targets, rig
//! -> [`subject`] (shape, topology via [`embedding`], [`skeleton`], [`skinning`] weights) ->
//! [`mocap`] clip -> [`retarget`] -> [`style`] -> forward kinematics -> linear blend skinning
//! -> [`noise`] -> [`capture_set_writer`], with [`truth`] and [`parts`] alongside.

pub mod assets;
pub mod capture_set_writer;
pub mod embedding;
pub mod makehuman;
pub mod mocap;
pub mod noise;
pub mod parts;
pub mod preset;
pub mod retarget;
pub mod skeleton;
pub mod skinning;
pub mod stage;
pub mod style;
pub mod subject;
pub mod truth;
