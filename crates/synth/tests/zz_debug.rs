use synth::preset;
use synth::subject::{BodyAssets, Subject, Topology};
#[test]
fn debug_loops() {
    let b = BodyAssets::load(&synth::assets::asset_dir().unwrap()).unwrap();
    let s = Subject::build(&b, &preset::subject_b(Topology::Obj("notoes_collapse5pc.obj".into()), 25.0)).unwrap();
    let bi = s.skeleton.index("LeftArm").unwrap();
    let bone = &s.skeleton.bones[bi];
    let len = (bone.tail - bone.head).norm();
    let d = bone.direction();
    // edges lengths near arm
    let mut el = vec![];
    for f in &s.faces { for k in 0..3 { let (a, c) = (f[k] as usize, f[(k+1)%3] as usize); if (s.rest[a]-bone.head).dot(&d) > 0.0 && s.rest[a].x > 0.2 { el.push((s.rest[a]-s.rest[c]).norm()); } } }
    el.sort_by(f64::total_cmp);
    eprintln!("bone len {len} median edge {}", el[el.len()/2]);
    for f in [0.15, 0.22, 0.3, 0.45, 0.6] {
        let c = bone.head + (bone.tail - bone.head) * f;
        let r = synth::parts::debug_ring(&s, &c, &d, "LeftArm");
        eprintln!("f {f}: {:?}", r.map(|l| l.iter().map(|&i| ((s.rest[i as usize]-bone.head).dot(&d)/len * 100.0).round()).collect::<Vec<_>>()));
    }
}
