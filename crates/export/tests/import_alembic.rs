//! `mesh-import` on an Alembic file: Blender's cube (`fixtures/alembic/cube.abc`) read into a
//! folder of PLY frames with its rate in `rate.json`; a PolyMesh picked with `--object`; a cut
//! file and a wrong name refused with one line naming the file.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mesh_core::sequence::{read_rate, MeshSequence};

fn import(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mesh-import")).args(args).output().unwrap()
}

fn cube() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/alembic/cube.abc")
}

#[test]
fn blenders_cube_becomes_a_folder_of_frames_at_its_rate() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cube");
    let st = import(&[cube().as_os_str(), "--out".as_ref(), out.as_os_str(), "-v".as_ref()]);
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(st.status.success(), "{err}");
    assert!(err.contains("PolyMesh /Cube/CubeShape: 3 frames of 8 vertices, 12 triangles, 25 fps"), "{err}");
    let seq = MeshSequence::load_dir(&out).unwrap();
    assert_eq!((seq.n_frames(), seq.n_vertices(), seq.n_faces()), (3, 8, 12));
    assert_eq!(read_rate(&out).unwrap(), Some(25.0));
    // Blender's frame 3, vertex 6 (1.8387611, 2.8575764, 2.0618238) in +Z up, turned +Y up.
    let want = nalgebra::Vector3::new(1.8387611, 2.0618238, -2.8575764);
    assert!((seq.frames[2][6] - want).amax() < 1e-6, "{}", seq.frames[2][6]);

    let named = dir.path().join("named");
    for object in ["CubeShape", "/Cube/CubeShape", "Cube"] {
        let st = import(&[cube().as_os_str(), "--object".as_ref(), object.as_ref(), "-o".as_ref(), named.as_os_str()]);
        assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
        assert_eq!(MeshSequence::load_dir(&named).unwrap().frames, seq.frames);
    }
}

#[test]
fn cut_files_and_wrong_names_are_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cut = dir.path().join("cut.abc");
    std::fs::write(&cut, &std::fs::read(cube()).unwrap()[..2000]).unwrap();
    for (args, says) in [
        (vec![cut.as_os_str()], format!("mesh-import: {}: ", cut.display())),
        (
            vec![cube().as_os_str(), "--object".as_ref(), "Suzanne".as_ref()],
            "no PolyMesh at or below 'Suzanne' (the file has /Cube/CubeShape)".to_string(),
        ),
        (
            vec![dir.path().join("walk.pc2").as_os_str(), "--object".as_ref(), "x".as_ref()],
            "--object picks a PolyMesh of an .abc input".to_string(),
        ),
    ] {
        let mut args = args;
        args.extend(["--out".as_ref(), out.as_os_str()]);
        let st = import(&args);
        let err = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(1), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(&says), "{err}");
    }
    assert!(!out.exists());
}
