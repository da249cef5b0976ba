//! A blend query's guide from the model alone (`--blend-guide stored`): the stored references of
//! the nearest learned weights interpolated, against the exact guide measured on the captures'
//! blend at the same weight, on the tiny preset.

mod common;

use std::path::Path;

use variation::blend_guide::{difference, stored};
use variation::group::{blend_sequences_at, Group};
use variation::reference::{Landmarks, Reference};
use variation::train::VariationModel;
use mesh_core::artifact::Artifact;

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// Largest differences allowed between the stored and the exact guide over every frame (and
/// every matcher vertex): heading (radians), lowest height, leg heights and matcher rows
/// (metres); measured on this preset at most 0.0024 rad, 3.2 cm, 4.0 cm and 26 cm between the
/// learned weights. At a learned weight (0, the pre-blend's 0.5, 1) both are measured on the
/// same meshes: only the blend's rigid placement moves the heading.
const BETWEEN: [f64; 4] = [0.005, 0.04, 0.05, 0.3];
const LEARNED: [f64; 4] = [1e-3, 1e-9, 1e-9, 1e-9];

#[test]
fn the_stored_guide_follows_the_exact_blend_and_a_blend_query_needs_the_model_alone() {
    let dir = tempfile::tempdir().unwrap();
    let (group_path, model_path) = common::tiny_model(dir.path());
    let group = Group::load(&group_path).unwrap();
    let model = VariationModel::load(&model_path).unwrap();
    let (a, b) = (group.index("walk").unwrap(), group.index("run").unwrap());
    let landmarks = Landmarks::of(&model.template, &model.faces, &model.parts.iter().map(|p| p.part.clone()).collect::<Vec<_>>(), &model.up);
    let blender = surface::blend::Blender::new(group.template.clone(), group.faces.clone()).unwrap();
    let weights = [0.0, 0.1, 0.25, 0.3, 0.5, 0.6, 0.75, 0.9, 1.0];
    let made = blend_sequences_at(&blender, &group.sequences[a], &group.sequences[b], &weights, &group.up, &group.root_point()).unwrap();
    let mut diffs = Vec::new();
    for (&w, truth) in weights.iter().zip(&made) {
        let exact = Reference::of(&truth.motion.world_frames(), &model.template, &landmarks, &model.up);
        let (guide, contacts) = stored(&model, a, b, w).unwrap();
        assert_eq!(contacts, truth.contacts, "w = {w}: contacts");
        let d = difference(&guide, &exact).expect("the same frames");
        eprintln!("w = {w}: heading {:.2e} rad, lowest {:.2e} m, legs {:.2e} m, matcher rows {:.2e} m", d[0], d[1], d[2], d[3]);
        diffs.push((w, d));
    }
    for (w, d) in diffs {
        let bound = if [0.0, 0.5, 1.0].contains(&w) { LEARNED } else { BETWEEN };
        for k in 0..4 {
            assert!(d[k] <= bound[k], "w = {w}: difference {k} {} > {}", d[k], bound[k]);
        }
    }

    // A blend query from the model alone writes its variations; the exact guide without the
    // captures is refused in one line naming the group.
    let sample = env!("CARGO_BIN_EXE_hmc-sample");
    let out = dir.path().join("blend");
    let m = s(&model_path);
    let o = s(&out);
    common::ok(sample, &["-q", "--model", &m, "--blend", "walk:run", "--weight", "0.3", "-n", "2", "--sampler", "ancestral", "--out", &o]);
    let written = std::fs::read_dir(out.join("walk-run-0.3")).unwrap().count();
    assert_eq!(written, 2);
    let refused = dir.path().join("refused");
    let run = common::stage(sample, &["-q", "--model", &m, "--blend", "walk:run", "--weight", "0.3", "--blend-guide", "exact", "--out", &s(&refused)]);
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr).trim_end().to_string();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--group"), "{err}");
    assert!(!refused.exists());
}
