//! export: results people can open.
//!
//! - [`frames`]: a mesh sequence as one OBJ or PLY file per frame, and back.
//! - OBJ + PC2 point cache: [`mesh_core::io::pc2`] (Blender's Mesh Cache
//!   modifier, 3ds Max), written beside a template OBJ, and back.
//! - [`glb`]: a glTF 2.0 binary with the animation as morph targets whose
//!   weights are sampled one-hot per frame (validator-clean by default;
//!   frame stride and int16 quantisation on request).
//! - [`md3`]: Quake 3 MD3 models (vertex-animated surfaces and tags), read
//!   for the animated-character benchmark.
//! - [`rate`]: the frame rate a sequence folder plays at (its rate file, its
//!   capture's `subject.json`, or `--fps`).
//! - [`report`]: the static `OUT/index.html` page of a pipeline run, with
//!   [`viewer`] the embedded three.js player of source / transfer / truth,
//!   [`transfer_summary`] the pose error per motion (table and SVG plot) and
//!   [`variation_summary`] the variation tables.
//!
//! Everything written goes through [`mesh_core::atomic`], so an output is
//! either complete or absent.

pub mod base64;
pub mod frames;
pub mod glb;
pub mod html;
pub mod md3;
pub mod rate;
pub mod report;
pub mod stage;
pub mod transfer_summary;
pub mod usd;
pub mod variation_summary;
pub mod viewer;
