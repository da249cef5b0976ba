//! Part colouring from curves on a capsule with known rings.

use std::path::Path;

use mesh_core::capture_set::SubjectSpec;
use mesh_core::shapes;
use render::colour;
use render::parts::{part_colours, part_palette};

#[test]
fn regions_between_and_beyond_loops_get_band_and_part_colours() {
    // Capsule rings bottom to top; "arm" loops: near = ring 12, far = ring 16.
    let (m, lay) = shapes::capsule_body(20, 12, 0.2, 2.0);
    let near = lay.ring(12);
    // The far loop given sparsely (every third vertex): joined by shortest paths.
    let far: Vec<u32> = lay.ring(16).into_iter().step_by(3).collect();
    let json = format!(
        r#"{{"fps": 25, "parts": {{"torso": null, "arm": "torso"}}, "curves": {{"arm": [{near:?}, {far:?}]}}}}"#
    );
    let spec: SubjectSpec = serde_json::from_str(&json).unwrap();
    let c = part_colours(&spec, Path::new("subject.json"), &m.vertices, &m.faces).unwrap();
    let pal = part_palette(&spec);
    let (arm, torso) = (pal["arm"], pal["torso"]);
    let band = colour::mix(arm, torso, 0.5);
    assert_ne!(arm, torso);
    let ring_colour = |k: usize| {
        let r = lay.ring(k);
        let c0 = c[r[0] as usize];
        assert!(
            r.iter().all(|&v| c[v as usize] == c0),
            "ring {k} not uniform"
        );
        c0
    };
    for k in 0..12 {
        assert_eq!(ring_colour(k), torso, "ring {k}");
    }
    for k in 12..=16 {
        assert_eq!(ring_colour(k), band, "ring {k}");
    }
    for k in 17..lay.n_rings() {
        assert_eq!(ring_colour(k), arm, "ring {k}");
    }
    assert_eq!(c[lay.bottom_pole() as usize], torso);
    assert_eq!(c[lay.top_pole() as usize], arm);
}

/// Loops that share vertices do not cut the mesh into a part and its band: the colours refuse
/// them as the `segment` stage does, so a picture never shows parts the pipeline does not use.
#[test]
fn loops_that_share_vertices_are_refused_as_the_segment_stage_refuses_them() {
    // The far loop runs along ring 16 for half the circumference and along
    // the near loop (ring 12) for the other half: shared vertices.
    let (m, lay) = shapes::capsule_body(20, 12, 0.2, 2.0);
    let near = lay.ring(12);
    let far: Vec<u32> = (0..12).map(|s| if s < 6 { lay.ring(16)[s] } else { lay.ring(12)[s] }).collect();
    let json = format!(
        r#"{{"fps": 25, "parts": {{"torso": null, "arm": "torso"}}, "curves": {{"arm": [{near:?}, {far:?}]}}}}"#
    );
    let spec: SubjectSpec = serde_json::from_str(&json).unwrap();
    let e = part_colours(&spec, Path::new("subject.json"), &m.vertices, &m.faces).unwrap_err().to_string();
    let mesh = mesh_core::TriMesh { vertices: m.vertices.clone(), faces: m.faces.clone() };
    let stage = mesh_core::segmentation::segment(&mesh, &spec).unwrap_err().to_string();
    assert_eq!(e, format!("subject.json: {stage}"));
}

#[test]
fn bad_curves_are_reported_against_the_subject_file() {
    let (m, _) = shapes::capsule_body(4, 8, 0.2, 1.0);
    let spec: SubjectSpec = serde_json::from_str(
        r#"{"fps": 25, "parts": {"torso": null, "arm": "torso"}, "curves": {"arm": [[0, 1, 2]]}}"#,
    )
    .unwrap();
    let e = part_colours(&spec, Path::new("s/subject.json"), &m.vertices, &m.faces)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("s/subject.json: ") && e.contains("2 curves"),
        "{e}"
    );
    let spec: SubjectSpec =
        serde_json::from_str(r#"{"fps": 25, "parts": {"a": "b", "b": "a"}, "curves": {}}"#)
            .unwrap();
    assert!(part_colours(&spec, Path::new("s.json"), &m.vertices, &m.faces).is_err());
}
