//! `paper-figure`'s, `learning-curves`' and `variation-eval`'s `Params` record every option under its flag's name
//! (what `Header::with_params` stores), and `paper-figure` names the figure drawn.

use clap::Parser;
use figures::paper_figure::Params;

#[test]
fn every_figure_records_every_option_under_its_flag_name() {
    let cases: [&[&str]; 3] = [
        &["paper-figure", "cost-matrix", "--set", "set", "--motion", "walk", "--source-pca", "s", "--target-pca", "t", "a", "b", "-o", "f.png"],
        &[
            "paper-figure", "correction", "--model", "m", "--source-pca", "s", "--target-pca", "t", "--segmentation", "seg",
            "--target-training", "x", "a.aligned", "-o", "f.png",
        ],
        &["paper-figure", "confidence", "--confidence", "c.json", "-o", "f.png"],
    ];
    for args in cases {
        let unrecorded = mesh_core::cli::unrecorded_options::<Params>(args).unwrap();
        assert!(unrecorded.is_empty(), "{}: {unrecorded:?} not recorded", args[1]);
    }
    let p = Params::try_parse_from(["paper-figure", "confidence", "--confidence", "c.json", "-o", "f.png"]).unwrap();
    assert_eq!(serde_json::to_value(&p).unwrap()["figure"], "confidence");
}

#[test]
fn learning_curves_and_variation_eval_record_every_option_under_its_flag_name() {
    let args = [
        "learning-curves", "--source-pca", "s", "--target-pca", "t", "--source-whole", "sw", "--target-whole", "tw", "--pair", "a", "b", "c",
        "-o", "lc",
    ];
    let unrecorded = mesh_core::cli::unrecorded_options::<figures::learning_curves::Params>(&args).unwrap();
    assert!(unrecorded.is_empty(), "learning-curves: {unrecorded:?} not recorded");
    let args = ["variation-eval", "--model", "m", "--group", "g", "--plots", "p", "-o", "e.json"];
    let unrecorded = mesh_core::cli::unrecorded_options::<figures::variation_eval::Params>(&args).unwrap();
    assert!(unrecorded.is_empty(), "variation-eval: {unrecorded:?} not recorded");
}
