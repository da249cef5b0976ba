//! characters: a capture-set benchmark from real animated humans made by other people, the
//! player models of the game OpenArena (Quake 3 MD3 format, fetched by `scripts/fetch-assets`).
//!
//! - [`animation_cfg`]: a player's `animation.cfg`, its named animations;
//! - [`character`]: legs, torso and head models assembled at their tags into one mesh per
//!   frame, in the capture set's axes and metres;
//! - [`motions`]: the named motions (walk, run, jump, death, ...) as tracks of animations
//!   sampled at a frame rate, and the key-poses of a pair;
//! - [`set_writer`]: a capture set of two characters with key-poses and the target's own
//!   performances of the test motions as a reference;
//! - [`stage`]: the `characters` stage.
//!
//! The MD3 reader itself is `export::md3`, beside the other readers of other tools' files.

pub mod animation_cfg;
pub mod character;
pub mod motions;
pub mod set_writer;
pub mod stage;
