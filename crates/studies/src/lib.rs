//! Modules shared by the study binaries (`src/bin/`): each binary is one research program whose
//! measurements a study in docs/studies reports.

pub mod gp_support;
pub mod gpdm_problem;
pub mod limb_bend;
pub mod study_pairs;
/// The gpdm tests' and benchmarks' synthetic capture.
#[path = "../../gpdm/tests/common/synthetic.rs"]
pub mod synthetic;
/// The gp benchmark's synthetic training pairs.
#[path = "../../gp/benches/synthetic_pairs.rs"]
pub mod synthetic_pairs;
