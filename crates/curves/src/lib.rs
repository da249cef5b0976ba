//! Part curves proposed for a template that has none ([`limb_loops`]),
//! written into a copy of `subject.json` by the `propose-curves` stage.

pub mod agreement;
pub mod geodesic;
pub mod limb_loops;
pub mod stage;
