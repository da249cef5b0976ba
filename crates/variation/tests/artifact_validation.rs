//! The variation artifacts rewritten with a valid checksum but broken contents (indices past the
//! template, sequences of other lengths, GPDMs that do not match the model's sequences): each is
//! refused on load with its problem named, never a panic later.

use capture::align::align_motion;
use gpdm::model::{Gpdm, GpdmConfig};
use mesh_core::artifact::{Artifact, Header};
use mesh_core::rigid::RigidMotion;
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::cylinder;
use nalgebra::{DMatrix, Vector3};
use variation::group::{Group, GroupSequence, PartDef};
use variation::part_data::DisplacementScale;
use variation::reference::{Landmarks, Reference};
use variation::train::{PartModel, SequenceInfo, VariationModel};

const FRAMES: usize = 6;

fn parts(n: u32) -> Vec<PartDef> {
    vec![
        PartDef { name: "torso".into(), parent: None, vertices: (0..n / 2 + 8).collect() },
        PartDef { name: "leg_l".into(), parent: Some(0), vertices: (n / 2..n).collect() },
    ]
}

fn group() -> Group {
    let t = cylinder(8, 10, 0.1, 1.0);
    let frames = (0..FRAMES)
        .map(|i| t.vertices.iter().map(|v| v + Vector3::new(0.01 * i as f64 * v.y, 0.0, 0.0)).collect())
        .collect();
    let motion = align_motion(&t, &MeshSequence::new(t.faces.clone(), frames)).unwrap();
    let seq = |name: &str| GroupSequence {
        name: name.into(),
        blend: None,
        blend_of: None,
        motion: motion.clone(),
        contacts: Some(vec![[true, false]; FRAMES]),
        map: (0..FRAMES).collect(),
    };
    Group {
        name: "g".into(),
        subject: "A".into(),
        fps: 25.0,
        up: Vector3::y(),
        template: t.vertices.clone(),
        faces: t.faces.clone(),
        parts: parts(t.n_vertices() as u32),
        reference: "walk".into(),
        sequences: vec![seq("walk"), seq("run")],
        pair: Some((0, 1)),
    }
}

fn model() -> VariationModel {
    let g = group();
    let landmarks = Landmarks::of(&g.template, &g.faces, &g.parts, &g.up);
    let part = |p: &PartDef| {
        let seqs: Vec<DMatrix<f64>> = (0..2)
            .map(|s| DMatrix::from_fn(FRAMES, 3 * p.vertices.len(), |i, c| ((i * 7 + c + s) as f64 * 0.3).sin()))
            .collect();
        PartModel {
            part: p.clone(),
            reference: p.vertices.iter().map(|&v| g.template[v as usize]).collect(),
            gpdm: Gpdm::new(&seqs, GpdmConfig::default()).unwrap(),
        }
    };
    VariationModel {
        group: "g".into(),
        subject: "A".into(),
        fps: 25.0,
        up: Vector3::y(),
        template: g.template.clone(),
        faces: g.faces.clone(),
        parts: g.parts.iter().map(part).collect(),
        scale: DisplacementScale { translation: 1.0, rotation: 1.0 },
        sequences: ["walk", "run"]
            .iter()
            .map(|n| SequenceInfo {
                name: (*n).into(),
                blend: None,
                blend_of: None,
                start_pose: RigidMotion::identity(),
                contacts: None,
                reference: Reference::of(&g.sequences[0].motion.world_frames(), &g.template, &landmarks, &g.up),
            })
            .collect(),
        pair: Some((0, 1)),
        stride: 1,
        frames: FRAMES,
        capture_limits: variation::turns_and_tears::CaptureLimits::of_group(&g),
    }
}

/// Saves `value` (the writer does not validate) and loads it back: the error names the file.
fn refused<T: Artifact>(value: &T, want: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.art");
    value.save(&path, &Header::new("test", "0")).unwrap();
    let e = T::load(&path).err().expect("load accepted a bad payload").to_string();
    assert!(e.starts_with(&path.display().to_string()) && e.contains(want), "{e} (wanted '{want}')");
}

#[test]
fn a_group_is_validated_after_decoding() {
    let good = group();
    assert_eq!(good.validate(), Ok(()));
    let mut bad = good.clone();
    bad.parts[1].vertices.push(500);
    refused(&bad, "vertex index 500");
    let mut bad = good.clone();
    bad.parts[1].parent = Some(1);
    refused(&bad, "parent");
    let mut bad = good.clone();
    bad.faces[3][2] = 80;
    refused(&bad, "face");
    let mut bad = good.clone();
    bad.sequences[1].map.pop();
    refused(&bad, "sequence 'run'");
    let mut bad = good.clone();
    bad.sequences[0].motion.frames[2].pop();
    refused(&bad, "frame 2");
    let mut bad = good.clone();
    bad.reference = "jump".into();
    refused(&bad, "reference 'jump'");
    let mut bad = good.clone();
    bad.pair = Some((0, 2));
    refused(&bad, "blend pair (0, 2)");
    // A pre-blend names the two captured motions it blends.
    let mut blended = good.clone();
    let mut pre = blended.sequences[0].clone();
    (pre.name, pre.blend, pre.blend_of) = ("blend-0.5".into(), Some(0.5), Some((0, 1)));
    blended.sequences.push(pre);
    assert_eq!(blended.validate(), Ok(()));
    let mut bad = blended.clone();
    bad.sequences[2].blend_of = None;
    refused(&bad, "sequence 2: blend weight Some(0.5)");
    let mut bad = blended.clone();
    bad.sequences[2].blend_of = Some((0, 2));
    refused(&bad, "sequence 2");
    let mut bad = blended.clone();
    bad.sequences[1].blend_of = Some((0, 2));
    refused(&bad, "sequence 1");
}

#[test]
fn a_variation_model_is_validated_after_decoding() {
    let good = model();
    assert_eq!(good.validate(), Ok(()));
    let mut bad = good.clone();
    bad.parts[1].reference.pop();
    refused(&bad, "part 'leg_l'");
    let mut bad = good.clone();
    bad.sequences.pop();
    bad.pair = None;
    refused(&bad, "latent trajectories");
    let mut bad = good.clone();
    bad.parts[0].gpdm.seq_lens[0] += 1;
    refused(&bad, "part 'torso'");
    let mut bad = good.clone();
    bad.parts[0].gpdm.beta[3] = -1.0;
    refused(&bad, "hyperparameters");
    let mut bad = good.clone();
    bad.stride = 0;
    refused(&bad, "stride 0");
    let mut bad = good.clone();
    bad.capture_limits.max_turn_deg = f64::NAN;
    refused(&bad, "capture limits");
    let mut bad = good.clone();
    bad.up = Vector3::new(0.0, 2.0, 0.0);
    refused(&bad, "up axis");
    let mut bad = good.clone();
    bad.sequences[1].blend = Some(0.5);
    refused(&bad, "sequence 1: blend weight Some(0.5) of sequences None");
}
