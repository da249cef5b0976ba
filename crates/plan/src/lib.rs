//! The pipelines' task graph (`plan`): from a capture set and the pipelines' options, every
//! stage invocation of `make transfer` (CVPR) and `make variation` (3DV) with its inputs, the
//! directories it creates and the file that marks it complete; written as a make fragment
//! ([`make_fragment`]) or as Slurm job arrays over task tables ([`slurm`], [`task_table`]).
//! Every stage flag the plan writes is named through that stage's `Params` ([`flag`]), so a
//! renamed field fails to compile here.

pub mod collect;
pub mod flag;
pub mod front_end;
pub mod json_text;
pub mod make_fragment;
pub mod options;
pub mod per_part;
pub mod resources;
pub mod slurm;
pub mod stage;
pub mod subjects;
pub mod step_line;
pub mod task;
pub mod task_table;
pub mod transfer;
pub mod variation;
