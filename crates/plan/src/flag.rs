//! Stage flags named through the stages' own `Params`, so that the command lines the plan
//! writes follow the stages: `flag!(Align, segmentation)` is `"--segmentation"` and does not
//! compile unless `align`'s `Params` has a field `segmentation`; `flag!(PcaFit | GpdmTrain,
//! out)` checks both stages. A field's flag is its name in kebab case (clap's derive default);
//! [`stage_flags_are_their_field_names`](tests) checks that every stage named here keeps to
//! it, so the spelling the plan writes is the one the stage parses.

pub use capture::stage::align::Params as Align;
pub use capture::stage::pca_fit::Params as PcaFit;
pub use capture::stage::segment::Params as Segment;
pub use curves::stage::Params as ProposeCurves;
pub use figures::paper_figure::Params as PaperFigure;
pub use figures::paper_figure::{
    ConfidenceArgs as ConfidenceFigure, CorrectionArgs as CorrectionFigure, CostArgs as CostMatrixFigure,
};
pub use merge_parts::Params as MergeParts;
pub use render::stage::Params as Render;
pub use transfer::stage::dtw_densify::Params as DtwDensify;
pub use transfer::stage::gpr_predict::Params as GprPredict;
pub use transfer::stage::gpr_train::Params as GprTrain;
pub use figures::learning_curves::Params as LearningCurves;
pub use transfer::stage::transfer_eval::Params as TransferEval;
pub use variation::stage::gpdm_train::Params as GpdmTrain;
pub use variation::stage::hmc_sample::Params as HmcSample;
pub use variation::stage::prealign::Params as Prealign;
pub use figures::variation_eval::Params as VariationEval;

/// `--field-name` of a field of one or more stages' `Params` (checked at compile time); a
/// field of a flattened group is named by its path, `flag!(HmcSample, common.seed)` (one stage).
macro_rules! flag {
    ($params:ty, $($field:ident).+) => {{
        let _: fn(&$params) = |p| {
            let _ = &p.$($field).+;
        };
        $crate::flag::long(stringify!($($field).+))
    }};
    ($($params:ty)|+, $field:ident) => {{
        $(let _: fn(&$params) = |p| {
            let _ = &p.$field;
        };)+
        $crate::flag::long(stringify!($field))
    }};
}
pub(crate) use flag;

/// The long flag of a `Params` field (the last name of a path such as `common . seed`): its
/// name in kebab case.
pub fn long(field: &str) -> String {
    let name = field.rsplit('.').next().unwrap_or(field).trim();
    format!("--{}", name.replace('_', "-"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Every long flag of `C` (and of its subcommands) is its argument's id in kebab case.
    fn check<C: CommandFactory>(errors: &mut Vec<String>) {
        fn walk(cmd: &clap::Command, errors: &mut Vec<String>) {
            for a in cmd.get_arguments() {
                if let Some(l) = a.get_long() {
                    let want = long(a.get_id().as_str());
                    if format!("--{l}") != want && !matches!(l, "help" | "version") {
                        errors.push(format!("{}: --{l} is field `{}` (want {want})", cmd.get_name(), a.get_id()));
                    }
                }
            }
            for s in cmd.get_subcommands() {
                walk(s, errors);
            }
        }
        walk(&C::command(), errors);
    }

    #[test]
    fn stage_flags_are_their_field_names() {
        let mut errors = Vec::new();
        check::<Align>(&mut errors);
        check::<PcaFit>(&mut errors);
        check::<Segment>(&mut errors);
        check::<ProposeCurves>(&mut errors);
        check::<PaperFigure>(&mut errors);
        check::<MergeParts>(&mut errors);
        check::<Render>(&mut errors);
        check::<DtwDensify>(&mut errors);
        check::<GprPredict>(&mut errors);
        check::<GprTrain>(&mut errors);
        check::<LearningCurves>(&mut errors);
        check::<TransferEval>(&mut errors);
        check::<GpdmTrain>(&mut errors);
        check::<HmcSample>(&mut errors);
        check::<Prealign>(&mut errors);
        check::<VariationEval>(&mut errors);
        assert!(errors.is_empty(), "{}", errors.join("\n"));
    }

    #[test]
    fn a_flag_is_the_fields_name_in_kebab_case() {
        assert_eq!(flag!(GprPredict, target_template), "--target-template");
        assert_eq!(flag!(PcaFit | GpdmTrain, out), "--out");
        assert_eq!(flag!(HmcSample, common.seed), "--seed");
    }
}
