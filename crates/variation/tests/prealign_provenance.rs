//! `prealign` on the tiny preset: the group's header lists set.json, the subject's
//! subject.json and template, its segmentation and the aligned motions of the group, each with
//! its SHA-256 (computed here independently), and every parameter given.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use mesh_core::artifact::read_header;
use sha2::{Digest, Sha256};

fn sha256(path: &Path) -> String {
    Sha256::digest(std::fs::read(path).unwrap()).iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn prealign_records_every_input_file_and_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let set = common::tiny_set(dir.path());
    let out = dir.path().join("loco.group");
    let front = common::front_end(&set, "A", &["walk", "run"], dir.path());
    let st = Command::new(env!("CARGO_BIN_EXE_prealign"))
        .args(["-q", "--set"])
        .arg(&set)
        .args(&front)
        .args(["--group-name", "loco", "--blend-weights", "0.25,0.75", "--out"])
        .arg(&out)
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let (_, _, header) = read_header(&out).unwrap();
    let mut given: Vec<PathBuf> = vec![set.join("set.json"), set.join("A/subject.json"), set.join("A/walk/000000.ply")];
    given.extend(front[1..].iter().map(PathBuf::from));
    assert_eq!(given.len(), 6, "set.json, subject.json, template, segmentation, two motions");
    for f in &given {
        let rec = header.inputs.iter().find(|r| Path::new(&r.path) == f.as_path());
        let rec = rec.unwrap_or_else(|| panic!("{} not recorded", f.display()));
        assert_eq!(rec.sha256, sha256(f), "{}", f.display());
    }
    assert_eq!(header.params["group_name"], "loco");
    assert_eq!(header.params["motions"], serde_json::json!(front[2..]));
    assert_eq!(header.params["segmentation"], serde_json::json!(front[1]));
    assert_eq!(header.params["blend_weights"], serde_json::json!([0.25, 0.75]));
    assert_eq!(header.params["gait_cycles"], false);
    assert_eq!(header.params["subject_name"], "A", "the subject it resolved to (the set's source)");
    // Every option is recorded under its flag's name, defaults included (the stage's Params).
    assert_eq!(header.params["set"], serde_json::json!(set));
    assert_eq!(header.params["out"], serde_json::json!(out));
    for key in ["subject", "reference", "contact_weight", "export"] {
        assert!(header.params[key].is_null(), "{key}: not given");
    }
    for key in ["whole_body", "fallback_whole_body"] {
        assert_eq!(header.params[key], false, "{key}");
    }
    assert!(header.command_line.is_empty(), "the params describe the run");

    // Invocation independence: the same options in another order and in `--flag=value` form,
    // with flags that change no output, write the same bytes.
    let first = std::fs::read(&out).unwrap();
    let st = Command::new(env!("CARGO_BIN_EXE_prealign"))
        .arg(format!("--out={}", out.display()))
        .args(["--blend-weights=0.25,0.75", "-v", "--threads", "1"])
        .args(&front[2..])
        .args(["--group-name=loco", &format!("--segmentation={}", front[1]), "--set"])
        .arg(&set)
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    assert!(std::fs::read(&out).unwrap() == first, "the group's bytes depend on how the options were written");
}

/// Every option of the variation stages' `Params` is in the JSON record the header stores,
/// under its flag's name.
#[test]
fn variation_stage_params_record_every_option_under_its_flag_name() {
    use crate::recorded_but_part as missing;
    let cases = [
        ("prealign", missing::<variation::stage::prealign::Params>(&["prealign", "--set", "s", "--segmentation", "p.seg", "--group-name", "g", "a.aligned", "b.aligned", "-o", "g.group"])),
        ("gpdm-train", missing::<variation::stage::gpdm_train::Params>(&["gpdm-train", "--group", "g", "-o", "m"])),
        ("hmc-sample", missing::<variation::stage::hmc_sample::Params>(&["hmc-sample", "--model", "m", "--group", "g", "--blend", "walk:run", "--weight", "0.3", "-o", "out"])),
    ];
    for (stage, unrecorded) in cases {
        assert_eq!(unrecorded.unwrap(), Vec::<String>::new(), "{stage}");
    }
    use clap::Parser;
    let p = variation::stage::hmc_sample::Params::try_parse_from(["hmc-sample", "--model", "m", "--group", "g", "--blend", "walk:run", "--weight", "0.3", "-o", "out"]).unwrap();
    let record = serde_json::to_value(&p).unwrap();
    assert_eq!(record["blend"], "walk:run", "as written on the command line");
    assert_eq!(record["blends"], serde_json::json!([0.25, 0.75]), "the default");
    assert_eq!(record["sampler"], "hmc");
}

/// `mesh_core::cli::unrecorded_options` without `part`: `--part` is left out of the Params record
/// on purpose (`part_merge::save_piece` adds it to a piece's header; the whole model's header must
/// not name it, so that merge-parts writes the same bytes as one run).
fn recorded_but_part<P: clap::Parser + serde::Serialize>(args: &[&str]) -> Result<Vec<String>, String> {
    mesh_core::cli::unrecorded_options::<P>(args).map(|v| v.into_iter().filter(|o| o != "part").collect())
}

/// Bad front-end inputs fail in one line naming the problem (and the file where one is at
/// fault), exit 1 and write nothing: no segmentation without a whole-body flag, a motion aligned
/// to another subject's template, a file not named `<motion>.aligned`, a motion given twice.
#[test]
fn prealign_refuses_bad_front_end_inputs_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let set = common::tiny_set(dir.path());
    let a = common::front_end(&set, "A", &["walk"], dir.path());
    let b = common::front_end(&set, "B", &["run"], dir.path());
    let renamed = dir.path().join("walk.motion");
    std::fs::copy(&a[2], &renamed).unwrap();
    let renamed = renamed.to_string_lossy().into_owned();
    let out = dir.path().join("bad.group");
    let cases: [(Vec<&str>, &str, Option<&str>); 4] = [
        (vec![&a[2]], "need --segmentation", None),
        (vec![&a[0], &a[1], &a[2], &b[2]], "aligned to template", Some(&b[2])),
        (vec![&a[0], &a[1], &renamed], "not named <motion>.aligned", Some(&renamed)),
        (vec![&a[0], &a[1], &a[2], &a[2]], "given twice", Some(&a[2])),
    ];
    for (args, want, file) in cases {
        let o = Command::new(env!("CARGO_BIN_EXE_prealign"))
            .args(["-q", "--set"])
            .arg(&set)
            .args(["--group-name", "g"])
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{want}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{want}: {err}");
        assert!(err.contains(want) && file.is_none_or(|f| err.contains(f)), "{want}: {err}");
        assert!(!out.exists(), "{want}: an output was written");
    }
}
