//! Small synthetic inputs shared by the unit tests.

use capture::align::AlignedMotion;
use mesh_core::rigid::{so3_exp, RigidMotion};
use mesh_core::segmentation::{Part, Segmentation};
use nalgebra::Vector3;

/// A capsule "torso" (rings below 8) with a "limb" (rings 4 and up) bending
/// by a different angle in each of 8 frames, as an aligned motion.
pub fn bending_capsule() -> (mesh_core::TriMesh, Segmentation, AlignedMotion) {
    let (mesh, l) = mesh_core::shapes::capsule_body(12, 8, 0.2, 2.0);
    let n = mesh.n_vertices();
    let ring = |r: usize| l.ring(l.body_ring(r))[0] as usize;
    let part = |name: &str, parent: Option<&str>, keep: &dyn Fn(usize) -> bool| {
        let vertices: Vec<u32> = (0..n as u32).filter(|&v| keep(v as usize)).collect();
        let mut local = vec![u32::MAX; n];
        vertices
            .iter()
            .enumerate()
            .for_each(|(i, &v)| local[v as usize] = i as u32);
        let faces = mesh
            .faces
            .iter()
            .filter(|f| f.iter().all(|&v| local[v as usize] != u32::MAX))
            .map(|f| f.map(|v| local[v as usize]))
            .collect();
        Part {
            name: name.into(),
            parent: parent.map(Into::into),
            vertices,
            faces,
            overlap: Vec::new(),
            loops: Vec::new(),
        }
    };
    let seg = Segmentation {
        n_vertices: n,
        parts: vec![
            part("torso", None, &|v| v < ring(8)),
            part("limb", Some("torso"), &|v| v >= ring(4)),
        ],
    };
    let frames: Vec<Vec<Vector3<f64>>> = (0..8)
        .map(|i| {
            let r = so3_exp(&Vector3::new(0.0, 0.0, 0.15 * i as f64 - 0.5));
            let c = Vector3::new(0.0, 1.0, 0.0);
            mesh.vertices
                .iter()
                .map(|v| if v.y > 1.0 { r * (v - c) + c } else { *v })
                .collect()
        })
        .collect();
    let motion = AlignedMotion {
        faces: mesh.faces.clone(),
        poses: vec![RigidMotion::identity(); frames.len()],
        displacements: vec![[0.0; 6]; frames.len()],
        anchor: Vec::new(),
        frames,
        capture: Default::default(),
    };
    (mesh, seg, motion)
}
