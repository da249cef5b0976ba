//! surfcap's PLY/OBJ readers against MeshLab's on third-party test meshes: Debian's
//! `assimp-testmodels` and pymeshlab's sample meshes, fetched by `scripts/fetch-assets`.
//! `fixtures/third-party-meshes.json` records what pymeshlab loads from each file
//! (`scripts/compare/meshlab_counts.py`); surfcap must load the same vertex and face counts, and
//! refuse what MeshLab refuses. Two files are refused on purpose where MeshLab guesses
//! (docs/RELIABILITY.md, "Tolerance"): they must fail with the documented message.

use std::path::PathBuf;

/// Files MeshLab reads by guessing, which surfcap refuses: (file, fragment of the error).
const REFUSED_ON_PURPOSE: [(&str, &str); 2] = [
    ("assimp/invalid/malformed.obj", "face index 0 (OBJ indices start at 1)"),
    ("assimp/OBJ/number_formats.obj", "bad coordinate '3.1+e2'"),
];

fn third_party_dir() -> PathBuf {
    let cache = match std::env::var_os("SURFCAP_CACHE") {
        Some(c) => PathBuf::from(c),
        None => PathBuf::from(std::env::var_os("HOME").expect("HOME or SURFCAP_CACHE")).join(".cache/surfcap"),
    };
    let dir = cache.join("assets/third-party");
    assert!(dir.is_dir(), "{}: missing: run scripts/fetch-assets", dir.display());
    dir
}

#[test]
fn reads_what_meshlab_reads() {
    let dir = third_party_dir();
    let fixture = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/third-party-meshes.json");
    let table: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(fixture).unwrap()).unwrap();
    let meshes = table["meshes"].as_object().unwrap();
    assert!(meshes.len() >= 40, "{} meshes in the table", meshes.len());
    let mut checked = 0;
    for (rel, want) in meshes {
        let path = dir.join(rel);
        assert!(path.is_file(), "{}: in the table but not fetched", path.display());
        let got = mesh_core::io::read_mesh(&path);
        if let Some((_, fragment)) = REFUSED_ON_PURPOSE.iter().find(|(f, _)| f == rel) {
            let e = got.expect_err(rel).to_string();
            assert!(e.contains(fragment), "{rel}: error {e:?} lacks {fragment:?}");
        } else if want.get("refused").is_some() {
            assert!(got.is_err(), "{rel}: MeshLab refuses it, surfcap read it");
        } else {
            let m = got.unwrap_or_else(|e| panic!("{rel}: MeshLab reads it, surfcap: {e}"));
            let (v, f) = (want["vertices"].as_u64().unwrap() as usize, want["faces"].as_u64().unwrap() as usize);
            assert_eq!((m.vertices.len(), m.faces.len()), (v, f), "{rel}: (vertices, faces) vs MeshLab's");
        }
        checked += 1;
    }
    assert_eq!(checked, meshes.len());
}
