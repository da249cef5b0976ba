//! OBJ reading and writing: exact round trip, polygons and corner syntaxes,
//! file vertex order preserved, bad input.

use mesh_core::io::obj::parse_obj;
use mesh_core::io::{read_mesh, write_mesh, write_obj};
use mesh_core::shapes::icosphere;
use nalgebra::Vector3;

#[test]
fn round_trip_is_exact_and_ply_obj_agree() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = icosphere(2);
    for (i, v) in m.vertices.iter_mut().enumerate() {
        *v = *v / 3.0 + Vector3::new(1e-12 * i as f64, 0.1, -7.25);
    }
    let obj = dir.path().join("m.obj");
    write_obj(&obj, &m).unwrap();
    assert_eq!(read_mesh(&obj).unwrap(), m);
    let ply = dir.path().join("m.PLY");
    write_mesh(&ply, &m).unwrap();
    assert_eq!(read_mesh(&ply).unwrap(), read_mesh(&obj).unwrap());
}

#[test]
fn polygons_corner_syntaxes_and_relative_indices() {
    let text = "# quad and pentagon, unused vertex 10 first\n\
        mtllib none.mtl\n\
        v 9 9 9\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
        vt 0 0\nvn 0 0 1\n\
        o first\n\
        f 2/1/1 3/1/1 4/1/1 5/1/1\n\
        o second\n\
        v 3 0 0\nv 3.309017 0.9510565 0\nv 2.5 1.5388418 0\nv 1.690983 0.9510565 0\nv 2 0 0\n\
        g pent\n\
        f -5//1 -4//1 -3//1 -2//1 -1//1\n";
    let m = parse_obj(text.as_bytes()).unwrap();
    // File order kept: the unused first vertex stays vertex 0.
    assert_eq!(m.n_vertices(), 10);
    assert_eq!(m.vertices[0], Vector3::new(9.0, 9.0, 9.0));
    assert_eq!(
        m.faces,
        vec![[1, 2, 3], [1, 3, 4], [5, 6, 7], [5, 7, 8], [5, 8, 9]]
    );
    let pent = (25.0 + 10.0 * 5f64.sqrt()).sqrt() / 4.0;
    let a = m.face_areas();
    assert!((a[0] + a[1] - 1.0).abs() < 1e-12);
    assert!((a[2..].iter().sum::<f64>() - pent).abs() < 1e-6);
}

#[test]
fn bad_obj_input_gives_one_line_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[u8], &str); 8] = [
        (b"v 0 0\nf 1 1 1\n", "3 coordinates"),
        (b"v 0 0 x\n", "bad coordinate"),
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "vertex 3"),
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0"),
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 3.1+e2 0 0\n", "'3.1+e2'"),
        (b"# nothing\n", "no vertices"),
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", "out of range"),
        (b"v 0 0 0\nv 1 0 NaN\nv 0 1 0\nf 1 2 3\n", "non-finite"),
    ];
    for (bytes, want) in cases {
        let p = dir.path().join("bad.obj");
        std::fs::write(&p, bytes).unwrap();
        let msg = read_mesh(&p).unwrap_err().to_string();
        assert!(
            msg.contains("bad.obj") && msg.contains(want) && !msg.contains('\n'),
            "{msg}"
        );
    }
    let p = dir.path().join("bin.obj");
    std::fs::write(&p, [0xff, 0xfe, 0x00]).unwrap();
    assert!(read_mesh(&p).unwrap_err().to_string().contains("bin.obj"));
}

/// What MeshLab reads and the geometry leaves no doubt about: a Latin-1 byte
/// in a comment, an empty face, a face repeating a vertex (skipped).
#[test]
fn tolerates_unambiguous_oddities_like_meshlab() {
    let mut bytes = b"# caf\xe9 (Latin-1)\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n".to_vec();
    bytes.extend_from_slice(b"f\nf 1 2\nf 1 2 2\nf 1 2 3\nf 2 4 4 3\n");
    let m = parse_obj(&bytes).unwrap();
    assert_eq!(m.vertices.len(), 4);
    // f 2 4 4 3 fans into (2 4 4) skipped and (2 4 3) kept.
    assert_eq!(m.faces, vec![[0, 1, 2], [1, 3, 2]]);
}
