//! The export stages' `Params` records hold every option under its flag's name (html-report's
//! too, though it writes no artifact).

use clap::Parser;
use mesh_core::cli::unrecorded_options as missing;

#[test]
fn export_stage_params_record_every_option_under_its_flag_name() {
    let cases = [
        ("mesh-export", missing::<export::stage::mesh_export::Params>(&["mesh-export", "in", "-o", "x.glb"])),
        ("mesh-import", missing::<export::stage::mesh_import::Params>(&["mesh-import", "in", "-o", "out", "--pattern", "walk.%04d.obj"])),
        ("html-report", missing::<export::stage::html_report::Params>(&["html-report", "-o", "out", "--view", "source=set/A/walk"])),
    ];
    for (stage, unrecorded) in cases {
        assert_eq!(unrecorded.unwrap(), Vec::<String>::new(), "{stage}");
    }
    let p = export::stage::mesh_import::Params::try_parse_from(["mesh-import", "in", "-o", "out", "--pattern", "walk.%04d.obj"]).unwrap();
    assert_eq!(serde_json::to_value(&p).unwrap()["pattern"], "walk.%04d.obj", "as written");
    let p = export::stage::mesh_export::Params::try_parse_from(["mesh-export", "in", "-o", "x.glb"]).unwrap();
    assert_eq!(serde_json::to_value(&p).unwrap()["frame_format"], "obj", "the default, by its command-line name");
}
