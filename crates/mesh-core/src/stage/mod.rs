//! The stages that need nothing beyond mesh-core: each module holds the stage's
//! [`clap::Parser`] + [`serde::Serialize`] `Params` and its `run`; `src/bin/<stage>.rs` only
//! parses and runs. Neither writes an artifact, so no header records their `Params`.

pub mod check_set;
pub mod inspect;

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::{check_set, inspect};
    use crate::cli::{unrecorded_options as missing, AlreadyReported};

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        assert_eq!(missing::<check_set::Params>(&["check-set", "set"]).unwrap(), Vec::<String>::new());
        assert_eq!(missing::<inspect::Params>(&["inspect", "a.model", "b.model"]).unwrap(), Vec::<String>::new());
    }

    /// Both print one line per problem themselves, so their error adds no further message.
    #[test]
    fn bad_input_fails_without_a_further_message() {
        let dir = tempfile::tempdir().unwrap();
        let (set, file) = (dir.path().to_str().unwrap(), dir.path().join("none.model"));
        let errors = [
            check_set::run(&check_set::Params::try_parse_from(["check-set", "-q", set]).unwrap()),
            inspect::run(&inspect::Params::try_parse_from(["inspect", "-q", file.to_str().unwrap()]).unwrap()),
        ];
        for e in errors {
            let e = e.unwrap_err();
            assert!(e.downcast_ref::<AlreadyReported>().is_some(), "{e}");
        }
    }
}
