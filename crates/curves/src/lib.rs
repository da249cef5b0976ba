//! Part curves proposed for a template that has none ([`limb_loops`]),
//! written into a copy of `subject.json` by the `propose-curves` stage, with a picture of
//! the loops and parts for checking them ([`check_image`]).

pub mod agreement;
pub mod body_graph;
pub mod check_image;
pub mod extremities;
pub mod limb_loops;
pub mod stage;
