//! End to end on the `tiny` synthetic capture set (needs the synth assets, as `make test` does):
//! prealign + blend, a short GPDM fit, HMC variations decoded to meshes; same seed gives
//! identical meshes, another seed different ones; variations are neither copies of their source
//! nor degenerate.

mod common;

use mesh_core::capture_set::CaptureSet;
use mesh_core::sequence::MeshSequence;
use variation::group::{build, FrontEnd, GroupSpec};
use variation::prealign::PrealignOptions;
use variation::reconstruct::Assembly;
use variation::sample::{blend_entries, Sampler};
use variation::synthesize::{run, Query, SynthConfig};
use variation::train::{train, TrainConfig};

/// The front end of subject A's `motions`, in memory as `segment` and `align` write them: its
/// segmentation and each motion aligned on the root part's core.
fn front_end(set: &CaptureSet, motions: &[&str]) -> FrontEnd {
    let spec = mesh_core::capture_set::SubjectSpec::load(set.subject_json("A")).unwrap();
    let template = mesh_core::io::read_mesh(set.template_path("A", &spec).unwrap()).unwrap();
    let seg = mesh_core::segmentation::segment(&template, &spec).unwrap();
    let anchor = capture::align::anchor_vertices(capture::align::AlignFrame::Root, Some(&seg)).unwrap();
    let motions = motions
        .iter()
        .map(|m| {
            let seq = MeshSequence::load_dir(set.motion_dir("A", m)).unwrap();
            (m.to_string(), capture::align::align_motion_on(&template, &seq, &anchor).unwrap())
        })
        .collect();
    FrontEnd { segmentation: Some(seg), motions }
}

#[test]
fn tiny_set_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let set_dir = common::tiny_set(dir.path());
    let set = CaptureSet::open(&set_dir).unwrap();
    let front = front_end(&set, &["walk", "run"]);
    let spec = GroupSpec {
        name: "locomotion".into(),
        subject: "A".into(),
        subject_json: None,
        motions: vec!["walk".into(), "run".into(), "no_such_motion".into()],
        reference: None,
        blend_weights: vec![0.5],
        blend_pairs: Vec::new(),
        prealign: PrealignOptions::default(),
        whole_body: false,
        fallback_whole_body: false,
        gait_cycles: false,
    };
    // The tiny clips hold less than one gait cycle: cutting whole cycles leaves the motions
    // whole, with a note, and builds the same group as without the cut.
    let (cut, cut_notes) = build(
        &set,
        &GroupSpec {
            gait_cycles: true,
            ..spec.clone()
        },
        front.clone(),
    )
    .unwrap();
    assert!(cut_notes.iter().any(|n| n.contains("no gait cycle")), "{cut_notes:?}");
    let (group, notes) = build(&set, &spec, front.clone()).unwrap();
    assert_eq!(
        cut.sequences.iter().map(|s| s.map.clone()).collect::<Vec<_>>(),
        group.sequences.iter().map(|s| s.map.clone()).collect::<Vec<_>>()
    );
    assert!(
        notes.iter().any(|n| n.contains("no_such_motion")),
        "{notes:?}"
    );
    assert_eq!(group.sequences.len(), 3);
    let t = group.n_frames();

    // Without annotations, prealign detects contacts from the meshes; they agree with synth's
    // (written from the skeleton's feet) on the time-aligned sequences.
    {
        let json = set.subject_json("A");
        let text = std::fs::read_to_string(&json).unwrap();
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v.as_object_mut().unwrap().remove("contacts");
        std::fs::write(&json, serde_json::to_string(&v).unwrap()).unwrap();
        let (detected, notes) = build(&CaptureSet::open(&set_dir).unwrap(), &spec, front.clone()).unwrap();
        std::fs::write(&json, text).unwrap();
        assert!(
            notes.iter().any(|n| n.contains("contacts detected")),
            "{notes:?}"
        );
        for (a, b) in group.sequences.iter().zip(&detected.sequences).take(2) {
            let (truth, found) = (a.contacts.as_ref().unwrap(), b.contacts.as_ref().unwrap());
            let (p, r) = capture::contact_detector::precision_recall(found, truth);
            eprintln!("{}: detected contacts precision {p:?} recall {r:?}", a.name);
            assert!(
                p.unwrap() > 0.8 && r.unwrap() > 0.5,
                "{}: precision {p:?} recall {r:?}",
                a.name
            );
        }
    }
    assert!(group.sequences.iter().all(|s| s.motion.n_frames() == t));

    let mut tc = TrainConfig::default();
    tc.options.schedule = gpdm::optim::Schedule::Alternate {
        rounds: 1,
        iters: 30,
    };
    let (model, reports) = train(&group, &tc).unwrap();
    assert!(reports
        .iter()
        .all(|r| r.report.final_value < r.report.initial_value));

    // The model accepts the group it was trained on and refuses any other.
    variation::trained_on::check(&model, &group).unwrap();
    let mut renamed = group.clone();
    renamed.name = "jumps".into();
    let mut moved = group.clone();
    moved.template[7].x += 1e-3;
    let mut fewer = group.clone();
    fewer.sequences.pop();
    for (other, fragment) in [(renamed, "group 'locomotion'"), (moved, "another template"), (fewer, "sequences")] {
        let e = variation::trained_on::check(&model, &other).unwrap_err().to_string();
        assert!(e.contains(fragment), "{e}");
    }

    let sc = SynthConfig {
        n: 2,
        blends: vec![0.25],
        seed: 7,
        sample_poses: false,
        assembly: Assembly::Average,
        sampler: Sampler::Hmc,
        motion_matching: Default::default(),
        variance_scale: 1.0,
        burn_in: 30,
        hmc_start: Default::default(),
        thin: 3,
        target_accept: 0.7,
        grounding: true,
        course: true,
        footskate: true,
        footskate_smoothness: variation::footskate::SMOOTHNESS,
        foot_lock: true,
        foot_ease: Default::default(),
        foot_height: true,
        turn_limit: true,
        statistics: true,
        latent_smoothing: 0.0,
        query: None,
        frames: None,
        frame_format: Default::default(),
        blend_guide: Default::default(),
    };
    let out1 = dir.path().join("o1");
    let out2 = dir.path().join("o2");
    let out3 = dir.path().join("o3");
    let r1 = run(&model, Some(&group), &sc, &out1).unwrap();
    let r2 = run(&model, Some(&group), &sc, &out2).unwrap();
    let r3 = run(
        &model,
        Some(&group),
        &SynthConfig {
            seed: 8,
            ..sc.clone()
        },
        &out3,
    )
    .unwrap();
    assert_eq!(r1.sequences.len(), 4); // walk, run, blend-0.5, blend-0.25
    for label in ["walk", "run", "blend-0.5", "blend-0.25"] {
        for k in 0..2 {
            let a = MeshSequence::load_dir(out1.join(label).join(format!("var{k}"))).unwrap();
            let b = MeshSequence::load_dir(out2.join(label).join(format!("var{k}"))).unwrap();
            assert_eq!(a.n_frames(), t);
            assert_eq!(
                a.frames, b.frames,
                "{label} var{k}: same seed, different meshes"
            );
        }
    }
    let a = MeshSequence::load_dir(out1.join("walk/var0")).unwrap();
    let c = MeshSequence::load_dir(out3.join("walk/var0")).unwrap();
    assert_ne!(a.frames, c.frames, "another seed gave the same variation");
    assert!(
        r1.accept_rate.mean > 0.2 && r1.accept_rate.mean < 1.0,
        "{:?}",
        r1.accept_rate
    );
    for s in &r1.sequences {
        for (&d, &e) in s.pose_distance_to_source_m.iter().zip(&s.edge_distortion) {
            assert!(d > 1e-4, "{}: a copy of its source ({d} m)", s.label);
            assert!(d < 0.3, "{}: degenerate ({d} m from the source)", s.label);
            assert!(e.is_finite() && e < 1.0, "{}: edge distortion {e}", s.label);
        }
    }
    // Grounding: feet no deeper below the floor, nor higher above it during contacts, than
    // before (up to the smoothing), and everything measured.
    for s in &r1.sequences {
        assert_eq!(s.penetration_m.len(), 2);
        let sum = |v: &[f64]| v.iter().sum::<f64>();
        assert!(
            sum(&s.penetration_m) + sum(&s.floating_m)
                <= sum(&s.ungrounded_penetration_m) + sum(&s.ungrounded_floating_m) + 2e-3,
            "{}: {:?}",
            s.label,
            (
                &s.penetration_m,
                &s.floating_m,
                &s.ungrounded_penetration_m,
                &s.ungrounded_floating_m
            )
        );
    }
    // Foot-skating clean-up: the tiny set's motions carry contacts, so every variation was
    // cleaned, and its feet slide less on the contacts it pinned than before.
    for s in &r1.sequences {
        let mean = |v: &[Option<f64>]| {
            let v: Vec<f64> = v.iter().map(|x| x.expect("contacts measured")).collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let (after, before) = (mean(&s.contact_sliding_m), mean(&s.raw_contact_sliding_m));
        assert!(
            after < before,
            "{}: sliding {after} after, {before} before",
            s.label
        );
    }
    assert_eq!(r1.accept_rate, r2.accept_rate);
    assert_ne!(r1.accept_rate.mean, r3.accept_rate.mean + 1.0);

    // Queries: one motion at another length, reproducible from (model, query, seed); a blend
    // of the pair given in the other order is guided by the pre-blend at 1 − w.
    let (walk, run_i, pre) = (
        group.index("walk").unwrap(),
        group.index("run").unwrap(),
        group.index("blend-0.5").unwrap(),
    );
    assert_eq!(
        blend_entries(&model, run_i, walk),
        vec![(0.0, run_i), (0.5, pre), (1.0, walk)]
    );
    let query = |q: Query, frames: Option<usize>, out: &std::path::Path| {
        let c = SynthConfig {
            query: Some(q),
            frames,
            sampler: Sampler::Ancestral,
            ..sc.clone()
        };
        run(&model, Some(&group), &c, out).unwrap()
    };
    for frames in [t + 9, 5] {
        let (o4, o5) = (
            dir.path().join(format!("q{frames}a")),
            dir.path().join(format!("q{frames}b")),
        );
        let r = query(Query::Motion("walk".into()), Some(frames), &o4);
        query(Query::Motion("walk".into()), Some(frames), &o5);
        assert_eq!(r.sequences.len(), 1);
        assert_eq!(
            std::fs::read_dir(&o4).unwrap().count(),
            1,
            "only the queried motion"
        );
        for k in 0..2 {
            let a = MeshSequence::load_dir(o4.join("walk").join(format!("var{k}"))).unwrap();
            let b = MeshSequence::load_dir(o5.join("walk").join(format!("var{k}"))).unwrap();
            assert_eq!(a.n_frames(), frames);
            assert_eq!(a.frames, b.frames, "same query and seed, different meshes");
        }
    }
    let o6 = dir.path().join("qb");
    let r = query(
        Query::Blend {
            a: "run".into(),
            b: "walk".into(),
            w: 0.3,
        },
        None,
        &o6,
    );
    assert_eq!(r.sequences[0].label, "run-walk-0.3");
    assert_eq!(
        MeshSequence::load_dir(o6.join("run-walk-0.3/var1"))
            .unwrap()
            .n_frames(),
        t
    );
    let bad = SynthConfig {
        query: Some(Query::Motion("swim".into())),
        ..sc.clone()
    };
    let err = run(&model, Some(&group), &bad, &dir.path().join("qx"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("swim") && err.contains("walk"), "{err}");

    // Strided fit: every second frame trains the dynamics, the variations keep the capture's
    // frame count, and the learned trajectories reconstruct the captured frames.
    let strided = TrainConfig {
        fit_rate: Some(group.fps / 2.0),
        min_fit_frames: None,
        max_fit_frames: None,
        ..tc.clone()
    };
    let (m2, rep2) = train(&group, &strided).unwrap();
    assert_eq!(m2.stride, 2);
    assert_eq!(
        rep2[0].frames,
        3 * variation::frame_stride::kept_count(t, 2)
    );
    assert_eq!(m2.latents(0)[0].nrows(), t);
    let o7 = dir.path().join("s2");
    let r = run(
        &m2,
        Some(&group),
        &SynthConfig {
            sampler: Sampler::Ancestral,
            ..sc.clone()
        },
        &o7,
    )
    .unwrap();
    assert_eq!(r.sequences.len(), 4);
    assert_eq!(
        MeshSequence::load_dir(o7.join("run/var0"))
            .unwrap()
            .n_frames(),
        t
    );
    let (ev, figures) = variation::evaluate::evaluate(&m2, &group, true, 0).unwrap();
    assert!(
        ev.reconstruction_gpdm_m < 0.05,
        "strided reconstruction {} m",
        ev.reconstruction_gpdm_m
    );
    // The latent plots' data: fig. 3 per part, fig. 6 per part (the model has a pair and its
    // pre-blend), fig. 7a, and fig. 5's twenty variations of the first sequence.
    let figures = figures.unwrap();
    let names: Vec<&str> = figures.latent.iter().map(|f| f.0.as_str()).collect();
    let parts = m2.parts.len();
    assert_eq!(names.iter().filter(|n| n.starts_with("fig3-latent-")).count(), parts, "{names:?}");
    assert_eq!(names.iter().filter(|n| n.starts_with("fig6-preblend-")).count(), parts, "{names:?}");
    assert!(names.iter().any(|n| n.starts_with("fig7a-")), "{names:?}");
    assert_eq!(figures.variations.2.len(), 20);
    assert!(ev.plots.is_empty());
}
