//! A short fuzz run in the test suite: every seed is accepted by its reader,
//! 20,000 mutated inputs raise no panic and no hang, and every kept
//! regression input (`crates/fuzz/regressions/`) stays fixed.

use std::time::Duration;

#[test]
fn seeds_are_valid_inputs_of_their_readers() {
    for (target, bytes) in fuzz::seed_corpus() {
        let ok = match target {
            fuzz::Target::Ply => mesh_core::io::ply::parse_ply(&bytes).is_ok(),
            fuzz::Target::Obj => mesh_core::io::obj::parse_obj(&bytes).is_ok(),
            fuzz::Target::Pc2 => mesh_core::io::pc2::parse_pc2(&bytes).is_ok(),
            fuzz::Target::Alembic => mesh_core::io::alembic::parse_alembic(&bytes, None).is_ok(),
            fuzz::Target::Md3 => export::md3::parse_md3(&bytes).is_ok(),
            fuzz::Target::AnimationCfg => characters::animation_cfg::parse_animation_cfg(&bytes).is_ok(),
            fuzz::Target::SetJson => mesh_core::capture_set::SetSpec::parse(&bytes).is_ok(),
            fuzz::Target::SubjectJson => mesh_core::capture_set::SubjectSpec::parse(&bytes).is_ok(),
            fuzz::Target::Artifact => {
                use mesh_core::artifact::Artifact;
                mesh_core::segmentation::Segmentation::decode(&bytes).is_ok()
                    || <capture::part_pca::PcaModel as Artifact>::decode(&bytes).is_ok()
                    || capture::align::AlignedMotion::decode(&bytes).is_ok()
                    || transfer::densify::Correspondences::decode(&bytes).is_ok()
                    || mesh_core::part_merge::Piece::<capture::part_pca::PcaModel>::decode(&bytes).is_ok()
                    || variation::variant_cache::CachedVariants::decode(&bytes).is_ok()
            }
        };
        assert!(ok, "seed for {target:?} rejected by its own reader");
    }
}

#[test]
fn twenty_thousand_mutated_inputs_raise_no_panic_and_no_hang() {
    let dir = tempfile::tempdir().unwrap();
    let seeds = fuzz::seed_corpus();
    let r = fuzz::fuzz(1, &seeds, 20_000, Duration::from_secs(600), Some(dir.path()));
    eprintln!("{r:?}");
    assert_eq!(r.inputs, 20_000);
    assert_eq!((r.panics, r.hangs), (0, 0), "kept: {:?}", r.kept);
    assert!(r.per_target.len() == 9, "{:?}", r.per_target);
}

#[test]
fn kept_regression_inputs_stay_fixed() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            continue;
        }
        assert_eq!(fuzz::replay(&p), Some(true), "{} panics again", p.display());
    }
}
