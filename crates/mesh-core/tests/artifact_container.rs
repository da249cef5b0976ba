//! The artifact container: round trip, determinism, byte layout, and one
//! distinct one-line error per kind of bad file.

use std::collections::BTreeMap;
use std::path::Path;

use mesh_core::artifact::{
    read_artifact, read_header, sha256_file, write_artifact, Artifact, Header, MAGIC,
};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Model {
    name: String,
    values: Vec<f64>,
    faces: Vec<[u32; 3]>,
    parts: BTreeMap<String, Vec<u64>>,
}

impl Artifact for Model {
    const KIND: &'static str = "test-model";
    const VERSION: u32 = 3;
}

fn model() -> Model {
    let mut parts = BTreeMap::new();
    parts.insert("torso".to_string(), vec![0, 1, 2, u64::MAX]);
    parts.insert("arm_l".to_string(), vec![]);
    Model {
        name: "walk ünïcode".to_string(),
        values: vec![0.1, -2.5e-300, f64::MAX, 1.0 / 3.0, -0.0],
        faces: vec![[0, 1, 2], [2, 1, 70000]],
        parts,
    }
}

fn header(dir: &Path) -> Header {
    let input = dir.join("input.txt");
    std::fs::write(&input, b"abc").unwrap();
    Header::new("test-stage", "0.1.0")
        .with_command_line(["/some/build/dir/test-stage", "--seed", "7", "in.ply"])
        .with_params(&serde_json::json!({"m": 20, "kernel": "nn"}))
        .unwrap()
        .with_seed(7)
        .with_input(&input)
        .unwrap()
}

/// Writes a valid artifact and returns its bytes.
fn good_file(dir: &Path) -> (std::path::PathBuf, Vec<u8>) {
    let path = dir.join("good.art");
    model().save(&path, &header(dir)).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    (path, bytes)
}

fn err_of<T: std::fmt::Debug>(r: mesh_core::Result<T>) -> String {
    let msg = r.expect_err("expected an error").to_string();
    assert!(!msg.contains('\n'), "error is not one line: {msg:?}");
    msg
}

#[test]
fn command_line_is_kept_without_params_and_dropped_with_them() {
    let h = Header::new("test-stage", "0.1.0").with_command_line(["/build/test-stage", "-v", "x"]);
    assert_eq!(h.command_line, ["test-stage", "-v", "x"], "program name reduced to its file name");
    let h = h.with_params(&serde_json::json!({"m": 20})).unwrap();
    assert!(h.command_line.is_empty());
    assert_eq!(h.params, serde_json::json!({"m": 20}));
}

#[test]
fn round_trip_preserves_header_and_payload() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = good_file(dir.path());
    let (h, m) = Model::load_with_header(&path).unwrap();
    assert_eq!(m, model());
    assert_eq!(h, header(dir.path()));
    assert!(h.command_line.is_empty(), "params replace the command line");
    assert_eq!(
        h.inputs[0].sha256,
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    let (kind, version, h2) = read_header(&path).unwrap();
    assert_eq!((kind.as_str(), version), ("test-model", 3));
    assert_eq!(h2, h);
    // The free functions agree with the trait.
    let (_, m2): (Header, Model) = read_artifact(&path, "test-model", 3).unwrap();
    assert_eq!(m2, model());
}

#[test]
fn sha256_file_matches_known_vectors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("empty");
    std::fs::write(&p, b"").unwrap();
    assert_eq!(
        sha256_file(&p).unwrap(),
        "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
    );
    // Larger than the 64 KiB read buffer: compare with a one-shot digest.
    let big: Vec<u8> = (0..200_000u32).map(|i| (i * 7 % 251) as u8).collect();
    std::fs::write(&p, &big).unwrap();
    let expect: String = Sha256::digest(&big)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(sha256_file(&p).unwrap(), expect);
}

#[test]
fn same_input_gives_byte_identical_files() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.art");
    let b = dir.path().join("b.art");
    model().save(&a, &header(dir.path())).unwrap();
    model().save(&b, &header(dir.path())).unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn byte_layout_matches_the_documentation() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes) = good_file(dir.path());
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap()) as usize;
    assert_eq!(&bytes[..8], b"SURFCAP\0");
    assert_eq!(MAGIC, *b"SURFCAP\0");
    assert_eq!(u32_at(8), 1, "container version");
    let klen = u32_at(12) as usize;
    assert_eq!(&bytes[16..16 + klen], b"test-model");
    let mut o = 16 + klen;
    assert_eq!(u32_at(o), 3, "kind version");
    o += 4;
    let hlen = u64_at(o);
    o += 8;
    let h: serde_json::Value = serde_json::from_slice(&bytes[o..o + hlen]).unwrap();
    assert_eq!(h["producer"]["stage"], "test-stage");
    assert_eq!(h["seed"], 7);
    assert_eq!(h["params"]["m"], 20);
    o += hlen;
    let plen = u64_at(o);
    o += 8;
    let expect = bincode::serde::encode_to_vec(model(), bincode::config::standard()).unwrap();
    assert_eq!(&bytes[o..o + plen], &expect[..]);
    o += plen;
    assert_eq!(bytes.len(), o + 32);
    assert_eq!(&bytes[o..], Sha256::digest(&bytes[..o]).as_slice());
}

#[test]
fn wrong_kind_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = good_file(dir.path());
    let msg = err_of(read_artifact::<Model>(&path, "pca-model", 3));
    assert_eq!(
        msg,
        format!(
            "{}: expected artifact kind 'pca-model', found 'test-model'",
            path.display()
        )
    );
}

#[test]
fn wrong_kind_version_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = good_file(dir.path());
    let msg = err_of(read_artifact::<Model>(&path, "test-model", 4));
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    assert!(
        msg.contains("version 3 is not supported") && msg.contains("reads version 4"),
        "{msg}"
    );
}

#[test]
fn any_flipped_byte_after_the_lengths_is_a_checksum_mismatch() {
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = good_file(dir.path());
    let klen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let hstart = 16 + klen + 4 + 8;
    let hlen = u64::from_le_bytes(bytes[hstart - 8..hstart].try_into().unwrap()) as usize;
    let pstart = hstart + hlen + 8;
    // Bytes in the kind, the header JSON, the payload and the checksum itself.
    for at in [
        16,
        16 + klen,
        hstart + 3,
        hstart + hlen / 2,
        pstart,
        bytes.len() - 40,
        bytes.len() - 1,
    ] {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        std::fs::write(&path, &bad).unwrap();
        let msg = err_of(Model::load(&path));
        assert_eq!(
            msg,
            format!("{}: checksum mismatch (file corrupt)", path.display()),
            "byte {at}"
        );
        assert!(
            read_header(&path).is_err(),
            "read_header must verify the checksum too"
        );
    }
}

#[test]
fn every_truncation_is_reported_as_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = good_file(dir.path());
    for cut in 0..bytes.len() {
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let msg = err_of(Model::load(&path));
        assert!(msg.contains("truncated"), "cut at {cut}: {msg}");
        assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    }
}

#[test]
fn wrong_magic_container_version_and_trailing_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = good_file(dir.path());

    std::fs::write(&path, b"ply\nformat binary_little_endian 1.0\n").unwrap();
    assert!(err_of(Model::load(&path)).ends_with("not a surfcap artifact (wrong magic bytes)"));

    let mut v2 = bytes.clone();
    v2[8] = 2;
    std::fs::write(&path, &v2).unwrap();
    assert!(err_of(Model::load(&path)).contains("container version 2 is not supported"));

    let mut long = bytes.clone();
    long.extend_from_slice(b"xx");
    std::fs::write(&path, &long).unwrap();
    assert!(err_of(Model::load(&path)).contains("2 unexpected bytes after the checksum"));

    let missing = dir.path().join("missing.art");
    let msg = err_of(Model::load(&missing));
    assert!(msg.starts_with(&missing.display().to_string()), "{msg}");
}

#[test]
fn payload_of_another_type_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.art");
    // Same kind and version but a payload that is not a `Model`.
    write_artifact(&path, "test-model", 3, &Header::new("s", "0"), &(1u8, 2u8)).unwrap();
    let msg = err_of(Model::load(&path));
    assert!(
        msg.contains("'test-model' payload does not decode"),
        "{msg}"
    );
}

/// A payload whose serialisation fails, to make a write fail midway.
struct Unserialisable;
impl Serialize for Unserialisable {
    fn serialize<S: serde::Serializer>(&self, _: S) -> Result<S::Ok, S::Error> {
        Err(serde::ser::Error::custom("cannot serialise"))
    }
}

#[test]
fn failed_writes_leave_no_partial_or_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = good_file(dir.path());
    let before: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();

    // Encoding fails: the existing artifact stays intact.
    let msg = err_of(write_artifact(
        &path,
        "test-model",
        3,
        &Header::default(),
        &Unserialisable,
    ));
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    assert_eq!(std::fs::read(&path).unwrap(), bytes);

    // The rename fails (the destination is a non-empty directory).
    let blocker = dir.path().join("blocked.art");
    std::fs::create_dir(&blocker).unwrap();
    std::fs::write(blocker.join("keep"), b"").unwrap();
    assert!(model().save(&blocker, &Header::default()).is_err());

    let mut after: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    after.retain(|n| n != "blocked.art");
    let mut before = before;
    before.sort();
    after.sort();
    assert_eq!(before, after, "temporary files left behind");
}

/// Index lists are stored as one-byte varints but bincode claims their
/// in-memory size against the decode limit: a payload of many small integers
/// and many empty inner vectors must still load.
#[test]
fn compact_integer_payloads_decode() {
    use mesh_core::artifact::{read_artifact, write_artifact, Header};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ints.bin");
    let payload: (Vec<u32>, Vec<usize>, Vec<Vec<u32>>, Vec<[u32; 3]>) =
        ((0..50_000).map(|i| i % 100).collect(), vec![3; 50_000], vec![Vec::new(); 20_000], vec![[1, 2, 3]; 30_000]);
    write_artifact(&path, "ints", 1, &Header::new("test", "0"), &payload).unwrap();
    let (_, back): (Header, (Vec<u32>, Vec<usize>, Vec<Vec<u32>>, Vec<[u32; 3]>)) = read_artifact(&path, "ints", 1).unwrap();
    assert_eq!(back, payload);
}

/// `load_hashed` gives the payload `load` gives and the file's SHA-256 as `sha256_file`
/// computes it, and fails as `load` does on a corrupt file.
#[test]
fn load_hashed_gives_the_file_hash_of_sha256_file() {
    let dir = tempfile::tempdir().unwrap();
    let (path, mut bytes) = good_file(dir.path());
    let (payload, sha) = Model::load_hashed(&path).unwrap();
    assert_eq!(payload, Model::load(&path).unwrap());
    assert_eq!(sha, sha256_file(&path).unwrap());
    let last = bytes.len() - 40;
    bytes[last] ^= 1;
    std::fs::write(&path, &bytes).unwrap();
    assert!(err_of(Model::load_hashed(&path)).contains("checksum mismatch"));
}

/// `read_artifact` and the hash of `sha256_file`, as `read_artifact_seeded` returns them.
fn read_whole(path: &Path, kind: &str, version: u32) -> Result<(Header, Model, String), String> {
    let (h, m) = read_artifact::<Model>(path, kind, version).map_err(|e| e.to_string())?;
    Ok((h, m, sha256_file(path).unwrap()))
}

/// The one-pass reader gives what the whole-file reader gives, value, header and hash, or the
/// same error, on the good file, every truncation, a flipped byte anywhere, a payload of
/// another type, wrong kind and version, and trailing bytes in the payload or after the
/// checksum.
#[test]
fn seeded_reading_in_one_pass_agrees_with_whole_file_reading() {
    use mesh_core::artifact::read_artifact_seeded;
    use std::marker::PhantomData;
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = good_file(dir.path());
    let streamed = |kind: &str, version: u32| {
        read_artifact_seeded(&path, kind, version, PhantomData::<Model>).map_err(|e| {
            let msg = e.to_string();
            assert!(!msg.contains('\n'), "{msg}");
            msg
        })
    };
    let good = streamed("test-model", 3).unwrap();
    assert_eq!(good.1, model());
    assert_eq!(Ok(good), read_whole(&path, "test-model", 3));
    assert!(streamed("other-kind", 3).unwrap_err().contains("expected artifact kind 'other-kind'"));
    assert_eq!(streamed("test-model", 4), read_whole(&path, "test-model", 4));
    let mut cases: Vec<Vec<u8>> = (0..bytes.len()).map(|cut| bytes[..cut].to_vec()).collect();
    for at in 0..bytes.len() {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        cases.push(bad);
    }
    let mut long = bytes.clone();
    long.extend_from_slice(b"xx");
    cases.push(long);
    for (i, case) in cases.iter().enumerate() {
        std::fs::write(&path, case).unwrap();
        assert_eq!(streamed("test-model", 3), read_whole(&path, "test-model", 3), "case {i}");
    }
    let other = dir.path().join("other.art");
    let payloads: [&dyn Fn(&Path); 2] = [
        &|p| write_artifact(p, "test-model", 3, &Header::new("s", "0"), &(1u8, 2u8)).unwrap(),
        // A `Model` followed by more bytes in the payload.
        &|p| write_artifact(p, "test-model", 3, &Header::new("s", "0"), &(model(), 7u64)).unwrap(),
    ];
    for write in payloads {
        write(&other);
        let got = read_artifact_seeded(&other, "test-model", 3, PhantomData::<Model>).map_err(|e| e.to_string());
        assert!(got.as_ref().unwrap_err().contains("payload does not decode"), "{got:?}");
        assert_eq!(got, read_whole(&other, "test-model", 3));
    }
}

/// A payload written piece by piece, field by field and element by element, is the file
/// `save` writes for the whole value; a wrong announced length or a failing piece leaves
/// neither the output nor a temporary file, and the piece's own error is returned.
#[test]
fn streamed_writing_gives_the_saved_file() {
    use mesh_core::artifact::{encoded_len, encoded_seq_len, write_artifact_streamed};
    let dir = tempfile::tempdir().unwrap();
    let (_, want) = good_file(dir.path());
    let m = model();
    let len = encoded_len(&m.name).unwrap()
        + encoded_seq_len(m.values.len())
        + m.values.iter().map(|v| encoded_len(v).unwrap()).sum::<u64>()
        + encoded_len(&m.faces).unwrap()
        + encoded_len(&m.parts).unwrap();
    let fill = |w: &mut mesh_core::artifact::PayloadWriter<'_>| {
        w.encode(&m.name)?;
        w.seq_len(m.values.len())?;
        for v in &m.values {
            w.encode(v)?;
        }
        w.encode(&m.faces)?;
        w.encode(&m.parts)
    };
    let out_dir = dir.path().join("out");
    let out = out_dir.join("streamed.art");
    write_artifact_streamed(&out, Model::KIND, Model::VERSION, &header(dir.path()), len, fill).unwrap();
    assert!(std::fs::read(&out).unwrap() == want, "streamed bytes differ from the saved file");
    std::fs::remove_file(&out).unwrap();

    let err = err_of(write_artifact_streamed(&out, Model::KIND, Model::VERSION, &header(dir.path()), len + 1, fill));
    assert!(err.contains("not the") && err.contains("announced"), "{err}");
    let err = err_of(write_artifact_streamed(&out, Model::KIND, Model::VERSION, &header(dir.path()), len, |w| {
        w.encode(&m.name)?;
        Err(mesh_core::Error::file("frame.ply", "truncated"))
    }));
    assert_eq!(err, "frame.ply: truncated");
    assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 0, "output or temporary left behind");
}
