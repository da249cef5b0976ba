//! The front end both papers share (CVPR 2017 surface motion transfer, 3DV variation synthesis).
//!
//! Data flows one way: capture set -> `segment` (per subject, `mesh_core::segmentation`) and
//! [`align`] (per motion) -> [`part_pca`] (PCA per part, or of the whole body) -> coefficients;
//! [`assemble`] turns per-part meshes decoded from the coefficients back into one mesh, and
//! [`root_placement`] puts it in the world from its root displacements (align's inverse).
//! [`choices`] names the transfer stages' options, so that `plan` can write their command
//! lines without depending on the stages' crate. The feet's clean-up both pipelines share lives
//! here too: [`contact_detector`] finds planted feet, [`footskate`] solves the root shifts that
//! keep them from sliding. `src/bin/<stage>.rs` parses arguments and
//! calls the library.

pub mod align;
pub mod align_stream;
pub mod root_placement;
pub mod motion_stream;
pub mod part_pca;
pub mod streamed_pca;
pub mod assemble;
pub mod choices;
pub mod contact_detector;
pub mod footskate;
pub mod stage;
