//! PLY reading and writing: round trips in every encoding, fan
//! triangulation, the fast binary path against ply-rs-bw's generic reader,
//! and bad input (one-line errors naming the file, no panics, no huge
//! allocations).

use std::path::Path;

use mesh_core::io::ply::{encode_ply, parse_ply, parse_ply_generic};
use mesh_core::io::{read_mesh, read_ply, write_ply, write_ply_ascii, write_ply_with};
use mesh_core::io::{PlyEncoding, PlyOptions, PlyPrecision};
use mesh_core::shapes::{capsule_body, icosphere};
use mesh_core::TriMesh;
use nalgebra::Vector3;

/// A mesh whose coordinates need all 53 bits (so f32 storage would show).
fn awkward_mesh() -> TriMesh {
    let mut m = icosphere(2);
    for (i, v) in m.vertices.iter_mut().enumerate() {
        *v = *v * std::f64::consts::PI + Vector3::new(1e-9 * i as f64, -1.0 / 3.0, 1e7);
    }
    m
}

fn all_options() -> Vec<PlyOptions> {
    let mut v = Vec::new();
    for encoding in [
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
        PlyEncoding::Ascii,
    ] {
        for precision in [PlyPrecision::Float, PlyPrecision::Double] {
            v.push(PlyOptions {
                encoding,
                precision,
            });
        }
    }
    v
}

#[test]
fn double_round_trips_are_bit_exact_in_every_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let m = awkward_mesh();
    for opts in all_options()
        .into_iter()
        .filter(|o| o.precision == PlyPrecision::Double)
    {
        let p = dir.path().join("m.ply");
        write_ply_with(&p, &m, opts).unwrap();
        let back = read_mesh(&p).unwrap();
        assert_eq!(back, m, "{opts:?}");
    }
    // The named helpers: binary LE by default, ascii on request.
    let p = dir.path().join("a.ply");
    write_ply(&p, &m).unwrap();
    assert!(std::fs::read(&p)
        .unwrap()
        .starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    assert_eq!(read_ply(&p).unwrap(), m);
    write_ply_ascii(&p, &m).unwrap();
    assert!(std::fs::read(&p)
        .unwrap()
        .starts_with(b"ply\nformat ascii 1.0\n"));
    assert_eq!(read_ply(&p).unwrap(), m);
}

#[test]
fn float_round_trips_equal_the_f32_rounding() {
    let dir = tempfile::tempdir().unwrap();
    let m = awkward_mesh();
    let rounded: Vec<Vector3<f64>> = m
        .vertices
        .iter()
        .map(|v| v.map(|c| c as f32 as f64))
        .collect();
    for opts in all_options()
        .into_iter()
        .filter(|o| o.precision == PlyPrecision::Float)
    {
        let p = dir.path().join("m.ply");
        write_ply_with(&p, &m, opts).unwrap();
        let back = read_ply(&p).unwrap();
        assert_eq!(back.faces, m.faces, "{opts:?}");
        assert_eq!(back.vertices, rounded, "{opts:?}");
    }
}

#[test]
fn fast_binary_path_agrees_with_ply_rs_bw() {
    let (m, _) = capsule_body(5, 12, 0.3, 1.0);
    for opts in all_options() {
        let mut bytes = Vec::new();
        encode_ply(&mut bytes, &m, opts).unwrap();
        assert_eq!(
            parse_ply(&bytes).unwrap(),
            parse_ply_generic(&bytes).unwrap(),
            "{opts:?}"
        );
    }
}

/// A unit square (quad) and a regular pentagon next to it, as polygons.
const POLY_ASCII: &str = "ply
format ascii 1.0
comment polygons of mixed size, extra properties, vertex_index spelling
element vertex 9
property float x
property float y
property float z
property uchar red
element face 2
property uchar flags
property list uchar uint vertex_index
end_header
0 0 0 255
1 0 0 255
1 1 0 255
0 1 0 255
3 0 0 1
3.309017 0.9510565 0 1
2.5 1.5388418 0 1
1.690983 0.9510565 0 1
2 0 0 1
7 4 0 1 2 3
7 5 4 5 6 7 8
";

fn check_polygons(m: &TriMesh) {
    // Fan triangulation: quad (0,1,2,3) -> (0,1,2) (0,2,3); pentagon similarly.
    assert_eq!(
        m.faces,
        vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [4, 7, 8]]
    );
    let areas = m.face_areas();
    assert!((areas[0] + areas[1] - 1.0).abs() < 1e-6);
    // Regular pentagon with unit side: area = sqrt(25 + 10 sqrt 5) / 4.
    let pent = (25.0 + 10.0 * 5f64.sqrt()).sqrt() / 4.0;
    assert!((areas[2..].iter().sum::<f64>() - pent).abs() < 1e-6);
    // All counter-clockwise seen from +z.
    assert!(m.face_normals().iter().all(|n| (n.z - 1.0).abs() < 1e-12));
}

#[test]
fn ascii_polygons_are_fan_triangulated() {
    let m = parse_ply(POLY_ASCII.as_bytes()).unwrap();
    check_polygons(&m);
}

/// The same polygons as binary big-endian with double coordinates, int list
/// counts of type ushort and short indices (the generic reader handles it).
fn poly_binary(le: bool, count_type: &str, index_type: &str) -> Vec<u8> {
    let ascii = parse_ply(POLY_ASCII.as_bytes()).unwrap();
    let pts = ascii.vertices;
    let polys: [&[u32]; 2] = [&[0, 1, 2, 3], &[4, 5, 6, 7, 8]];
    let fmt = if le {
        "binary_little_endian"
    } else {
        "binary_big_endian"
    };
    let mut b = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 9\nproperty double x\nproperty double y\nproperty double z\n\
         property float nx\nelement face 2\nproperty list {count_type} {index_type} vertex_indices\nend_header\n"
    )
    .into_bytes();
    let put = |b: &mut Vec<u8>, bytes: &[u8]| {
        if le {
            b.extend(bytes.iter());
        } else {
            b.extend(bytes.iter().rev());
        }
    };
    for p in &pts {
        for c in p.iter() {
            put(&mut b, &c.to_le_bytes());
        }
        put(&mut b, &0.5f32.to_le_bytes());
    }
    let int = |b: &mut Vec<u8>, ty: &str, v: u32| match ty {
        "uchar" => b.push(v as u8),
        "ushort" | "short" => put(b, &(v as u16).to_le_bytes()),
        _ => put(b, &v.to_le_bytes()),
    };
    for poly in polys {
        int(&mut b, count_type, poly.len() as u32);
        for &i in poly {
            int(&mut b, index_type, i);
        }
    }
    b
}

#[test]
fn binary_polygons_with_any_integer_types_are_fan_triangulated() {
    for le in [true, false] {
        for (ct, it) in [
            ("uchar", "int"),
            ("ushort", "short"),
            ("int", "uint"),
            ("uchar", "ushort"),
        ] {
            let bytes = poly_binary(le, ct, it);
            let fast = parse_ply(&bytes).unwrap();
            check_polygons(&fast);
            assert_eq!(
                fast,
                parse_ply_generic(&bytes).unwrap(),
                "le={le} {ct} {it}"
            );
        }
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Reads `bytes` as a file and returns the error message, checking that it
/// is one line and names the file.
fn read_err(bytes: &[u8]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "bad.ply", bytes);
    let msg = read_mesh(&p).expect_err("bad input must fail").to_string();
    assert!(!msg.contains('\n'), "multi-line error: {msg}");
    assert!(
        msg.contains("bad.ply"),
        "error does not name the file: {msg}"
    );
    msg
}

#[test]
fn malformed_headers_give_one_line_errors() {
    read_err(b"");
    read_err(b"not a ply file\n");
    read_err(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
    read_err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n0\n");
    let m = read_err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n");
    assert!(m.contains("'z'"), "{m}");
    let m = read_err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\nproperty int y\nproperty int z\nend_header\n0 0 0\n");
    assert!(m.contains("float or double"), "{m}");
}

#[test]
fn malformed_ascii_payloads_give_one_line_errors() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    read_err(format!("{head}0 0 0\n1 0 0\n0 one 0\n3 0 1 2\n").as_bytes());
    read_err(format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 1\n").as_bytes());
    let m = read_err(format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").as_bytes());
    assert!(m.contains("vertex 7"), "{m}");
    let m = read_err(format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n").as_bytes());
    assert!(m.contains("-1"), "{m}");
    // Degenerate faces are skipped (as MeshLab does), in both readers.
    for bytes in [
        format!("{head}0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
        format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n"),
    ] {
        let m = parse_ply(bytes.as_bytes()).unwrap();
        assert_eq!((m.vertices.len(), m.faces.len()), (3, 0));
        assert_eq!(parse_ply_generic(bytes.as_bytes()).unwrap(), m);
    }
    let m = read_err(b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    assert!(m.contains("no vertices"), "{m}");
    let m = read_err(format!("{head}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").as_bytes());
    assert!(m.contains("Line 11") && m.contains("'1 nan 0'"), "{m}");
    // 1e999 overflows f32 to infinity: parsed, then rejected as non-finite.
    let m = read_err(format!("{head}0 0 0\n1 1e999 0\n0 1 0\n3 0 1 2\n").as_bytes());
    assert!(m.contains("vertex 1") && m.contains("non-finite"), "{m}");
}

#[test]
fn nan_in_binary_file_is_rejected() {
    let mut m = icosphere(1);
    m.vertices[5].z = f64::NAN;
    let mut bytes = Vec::new();
    encode_ply(&mut bytes, &m, PlyOptions::default()).unwrap();
    let msg = read_err(&bytes);
    assert!(msg.contains("vertex 5"), "{msg}");
    m.vertices[5].z = f64::INFINITY;
    bytes.clear();
    encode_ply(&mut bytes, &m, PlyOptions::default()).unwrap();
    read_err(&bytes);
}

#[test]
fn truncated_binary_files_fail_at_every_cut() {
    let m = icosphere(1);
    for opts in all_options()
        .into_iter()
        .filter(|o| o.encoding != PlyEncoding::Ascii)
    {
        let mut bytes = Vec::new();
        encode_ply(&mut bytes, &m, opts).unwrap();
        for cut in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
            assert!(
                parse_ply(&bytes[..cut]).is_err(),
                "cut at {cut} of {} accepted",
                bytes.len()
            );
            assert!(
                parse_ply_generic(&bytes[..cut]).is_err(),
                "cut at {cut} accepted (generic)"
            );
        }
    }
    let mut bytes = Vec::new();
    encode_ply(&mut bytes, &m, PlyOptions::default()).unwrap();
    let msg = read_err(&bytes[..bytes.len() - 5]);
    assert!(msg.contains("truncated") || msg.contains("end"), "{msg}");
}

#[test]
fn huge_counts_in_a_small_file_fail_fast_without_allocating() {
    for (fmt, count) in [
        ("binary_little_endian", "1000000000000"),
        ("ascii", "1000000000000"),
        ("binary_big_endian", "18446744073709551615"),
    ] {
        let mut bytes = format!(
            "ply\nformat {fmt} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
        )
        .into_bytes();
        bytes.resize(1024, b'1');
        // Rejected from the header alone: a real attempt would abort on allocation.
        let msg = read_err(&bytes);
        assert!(msg.contains("header declares"), "{msg}");
    }
    // A face list count of 2^32 - 1 in a binary file must not allocate 16 GB.
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n"
        .to_vec();
    bytes.extend(std::iter::repeat_n(0u8, 36));
    bytes.extend(u32::MAX.to_le_bytes());
    bytes.extend([0u8; 12]);
    read_err(&bytes);
    assert!(parse_ply_generic(&bytes).is_err());
}

#[test]
fn unknown_extension_and_missing_file_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "mesh.stl", b"solid");
    let msg = read_mesh(&p).unwrap_err().to_string();
    assert!(msg.contains("mesh.stl") && msg.contains(".ply"), "{msg}");
    let msg = read_mesh(dir.path().join("gone.ply"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("gone.ply") && !msg.contains('\n'), "{msg}");
}

#[test]
fn failed_write_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    // The destination is a directory: the rename fails, nothing is left behind.
    let p = dir.path().join("out.ply");
    std::fs::create_dir(&p).unwrap();
    assert!(write_ply(&p, &icosphere(0)).is_err());
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("out.ply")]);
}

/// Load time of a 13k-vertex binary PLY (run with `--ignored --nocapture`;
/// a measurement, not a pass/fail speed goal).
#[test]
#[ignore]
fn measure_13k_vertex_binary_load() {
    let m = mesh_core::shapes::cylinder(100, 130, 0.2, 1.7);
    assert_eq!(m.n_vertices(), 13_000);
    let dir = tempfile::tempdir().unwrap();
    for (name, opts) in [
        ("binary double", PlyOptions::default()),
        (
            "binary float",
            PlyOptions {
                precision: PlyPrecision::Float,
                ..Default::default()
            },
        ),
        (
            "ascii double",
            PlyOptions {
                encoding: PlyEncoding::Ascii,
                ..Default::default()
            },
        ),
    ] {
        let p = dir.path().join("m.ply");
        write_ply_with(&p, &m, opts).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let reps = 50;
        let t = std::time::Instant::now();
        for _ in 0..reps {
            std::hint::black_box(read_ply(&p).unwrap());
        }
        let file = t.elapsed().as_secs_f64() / reps as f64;
        let t = std::time::Instant::now();
        for _ in 0..reps {
            std::hint::black_box(parse_ply_generic(&bytes).unwrap());
        }
        let generic = t.elapsed().as_secs_f64() / reps as f64;
        println!(
            "{name}: read_ply {:.2} ms, ply-rs-bw generic parse {:.2} ms",
            file * 1e3,
            generic * 1e3
        );
    }
}

/// A later frame of a sequence read like its first frame (`read_mesh_like`) is the mesh
/// `read_mesh` reads, whether it shares the first frame's header and faces (only its vertices
/// decoded) or not (ascii, other faces, another vertex count, polygons), and its errors name it
/// as `read_mesh`'s do.
#[test]
fn frames_read_like_the_first_are_the_meshes_read_alone() {
    use mesh_core::io::{read_first_frame, read_mesh_like};
    let dir = tempfile::tempdir().unwrap();
    let first_mesh = awkward_mesh();
    let first_path = dir.path().join("000000.ply");
    write_ply(&first_path, &first_mesh).unwrap();
    let first = read_first_frame(&first_path).unwrap();
    assert_eq!(first.mesh(), &read_mesh(&first_path).unwrap());

    let mut moved = first_mesh.clone();
    for v in moved.vertices.iter_mut() {
        *v = v.yzx() * 0.5 - Vector3::new(0.25, 1e-7, 3.0);
    }
    let mut other_faces = moved.clone();
    other_faces.faces.swap(0, 1);
    let mut candidates = vec![("moved", moved.clone(), PlyOptions::default()), ("other faces", other_faces, PlyOptions::default())];
    for o in all_options() {
        candidates.push(("moved, other encoding", moved.clone(), o));
    }
    candidates.push(("another body", icosphere(1), PlyOptions::default()));
    for (what, mesh, opts) in candidates {
        let path = dir.path().join("000001.ply");
        write_ply_with(&path, &mesh, opts).unwrap();
        assert_eq!(read_mesh_like(&path, &first).unwrap(), read_mesh(&path).unwrap(), "{what} {opts:?}");
    }
    // Polygons and an OBJ frame go the whole way.
    let path = write(dir.path(), "poly.ply", &poly_binary(true, "uchar", "int"));
    assert_eq!(read_mesh_like(&path, &first).unwrap(), read_mesh(&path).unwrap());
    let obj = dir.path().join("000002.obj");
    mesh_core::io::write_obj(&obj, &moved).unwrap();
    assert_eq!(read_mesh_like(&obj, &first).unwrap(), read_mesh(&obj).unwrap());

    // Same header and faces, a non-finite coordinate: refused, naming the file.
    let mut bad = moved.clone();
    bad.vertices[5].y = f64::NAN;
    let mut bytes = Vec::new();
    encode_ply(&mut bytes, &bad, PlyOptions::default()).unwrap();
    let path = write(dir.path(), "000003.ply", &bytes);
    let e = read_mesh_like(&path, &first).unwrap_err().to_string();
    assert_eq!(e, read_mesh(&path).unwrap_err().to_string());
    assert!(e.contains("000003.ply") && e.contains("non-finite"), "{e}");
}
