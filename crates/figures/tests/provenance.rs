//! `paper-figure`'s `Params` record every option of each figure under its flag's name (what
//! `Header::with_params` stores), and name the figure drawn.

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
