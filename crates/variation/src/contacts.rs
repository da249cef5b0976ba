//! Feet-contact annotations (`mesh_core::contacts`, shared with the transfer's evaluation).

pub use mesh_core::contacts::*;
