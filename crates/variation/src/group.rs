//! A movement group ready for modelling: the subject's template and body parts (`segment`'s),
//! its motions as `align` aligned them ([`FrontEnd`]) and time-warped onto a reference motion ([`crate::prealign`]), plus the
//! pre-blended sequences `Y_w = blend(Y_1, Y_2, w)` for `w ∈ W` (paper §7), made with the
//! non-linear mesh interpolation `surface::blend::Blender` on the aligned frames. A group may
//! hold any number of motions and pre-blend any pairs of them (by default the first two); the
//! first pair is the group's blend pair (its pre-blends are named `blend-<w>`, those of the
//! other pairs `blend-<A>-<B>-<w>`).
//!
//! Every sequence's displacements are those of its root point (`capture::align`'s definition,
//! the root point the centroid of the root part's core, [`Group::root_point`]), computed from
//! its world poses after re-timing and blending ([`root_displacements`]): a turn or lean of the
//! torso then moves the torso and not, by its lever arm, a point wherever the template stands.
//!
//! A blend's world poses ([`blend_poses`]) interpolate the two motions' poses expressed in
//! their own ground frame (start position on the ground, start heading about the up axis):
//! translations linearly, rotations along the geodesic; the result is placed at the first
//! motion's ground frame and its displacements recomputed. (Blending the body-frame
//! displacement 6-vectors instead, then integrating, made a walk/run blend climb into the air:
//! the run's forward lean tilts its body-frame translations.) Its contacts are the nearer
//! endpoint's (`w < 0.5`: the first).

use mesh_core::artifact::Artifact;
use mesh_core::capture_set::{CaptureSet, SubjectSpec};
use mesh_core::rigid::{relative_in_body_frame, so3_exp, so3_log, RigidMotion};
use mesh_core::segmentation::Segmentation;
use mesh_core::{Error, Result};
use nalgebra::{Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};
use capture::align::{check_topology, AlignedMotion};

use crate::contacts::{self, Contacts};
use crate::gait;
use crate::prealign::{apply, apply_contacts, warp, PrealignOptions, Warp};

/// One body part (transfer paper §4 segmentation, overlap bands included).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartDef {
    pub name: String,
    /// Index of the parent part (None for the root, the torso, which is part 0).
    pub parent: Option<usize>,
    /// Template vertex indices.
    pub vertices: Vec<u32>,
}

/// One time-aligned training sequence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroupSequence {
    /// Motion name, or `blend-<w>` for a pre-blended sequence.
    pub name: String,
    /// For a pre-blended sequence, its weight `w` between the two motions of `blend_of`.
    pub blend: Option<f64>,
    /// For a pre-blended sequence, the indices of the motions it blends (w = 0, w = 1).
    pub blend_of: Option<(usize, usize)>,
    pub motion: AlignedMotion,
    pub contacts: Option<Contacts>,
    /// Motion frame used for each reference frame (for the reference: its kept frames; for
    /// blends: the identity).
    pub map: Vec<usize>,
}

/// A prealigned movement group.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Group {
    pub name: String,
    pub subject: String,
    pub fps: f64,
    /// Unit up axis of the subject.
    pub up: Vector3<f64>,
    pub template: Vec<Vector3<f64>>,
    pub faces: Vec<[u32; 3]>,
    pub parts: Vec<PartDef>,
    /// Name of the reference motion.
    pub reference: String,
    pub sequences: Vec<GroupSequence>,
    /// Indices of the blend pair `(Y_1, Y_2)` (w = 0 and w = 1): the first pair pre-blended,
    /// by default the first two motions; None with a single motion.
    pub pair: Option<(usize, usize)>,
}

impl Artifact for Group {
    const KIND: &'static str = "variation-group";
    const VERSION: u32 = 4;

    /// A valid body ([`check_body`]); at least one sequence, each a valid aligned motion of
    /// the template's vertex count, all of one frame count, with contacts and a frame map of
    /// that length and a blend weight in [0, 1] between two captured motions; the reference and
    /// the blend pair among them.
    fn validate(&self) -> std::result::Result<(), String> {
        check_body(&self.template, &self.faces, &self.up, self.fps, &self.parts)?;
        let n = self.n_frames();
        if self.sequences.is_empty() || n == 0 {
            return Err("no sequences".into());
        }
        for s in &self.sequences {
            let what = |e: String| format!("sequence '{}': {e}", s.name);
            s.motion.validate().map_err(what)?;
            let vertices = s.motion.frames[0].len();
            if vertices != self.template.len() {
                return Err(what(format!("{vertices} vertices, the template has {}", self.template.len())));
            }
            if s.motion.n_frames() != n || s.map.len() != n || s.contacts.as_ref().is_some_and(|c| c.len() != n) {
                return Err(what(format!("frames, frame map or contacts differ from the group's {n} frames")));
            }
            if s.blend.is_some_and(|w| !(0.0..=1.0).contains(&w)) {
                return Err(what(format!("blend weight {:?} outside [0, 1]", s.blend)));
            }
        }
        if self.index(&self.reference).is_none() {
            return Err(format!("reference '{}' is not one of the sequences", self.reference));
        }
        let blends: Vec<(Option<f64>, Option<(usize, usize)>)> =
            self.sequences.iter().map(|s| (s.blend, s.blend_of)).collect();
        check_blends(&blends)?;
        check_pair(self.pair, self.sequences.len())
    }
}

/// The body both variation artifacts carry: a non-empty finite template, faces inside it, a
/// unit up axis, a finite frame rate >= 0, parts whose vertices lie in the template with part 0
/// the root and every other part's parent an earlier part. The error is the problem.
pub fn check_body(
    template: &[Vector3<f64>],
    faces: &[[u32; 3]],
    up: &Vector3<f64>,
    fps: f64,
    parts: &[PartDef],
) -> std::result::Result<(), String> {
    let n = template.len();
    if n == 0 || !template.iter().all(|v| v.iter().all(|c| c.is_finite())) {
        return Err(format!("a template of {n} vertices, or one with a non-finite coordinate"));
    }
    if let Some(f) = faces.iter().find(|f| f.iter().any(|&v| v as usize >= n)) {
        return Err(format!("face {f:?} indexes past the template's {n} vertices"));
    }
    if !((up.norm() - 1.0).abs() < 1e-6) || !(fps.is_finite() && fps >= 0.0) {
        return Err(format!("up axis {up:?} not a unit vector or frame rate {fps} not a finite number >= 0"));
    }
    if parts.is_empty() {
        return Err("no parts".into());
    }
    for (k, p) in parts.iter().enumerate() {
        if let Some(&v) = p.vertices.iter().find(|&&v| v as usize >= n) {
            return Err(format!("part '{}': vertex index {v} past the template's {n} vertices", p.name));
        }
        let parent_ok = match p.parent {
            None => k == 0,
            Some(q) => k > 0 && q < k,
        };
        if !parent_ok {
            return Err(format!("part '{}' (part {k}) has parent {:?}: part 0 is the root, others name an earlier part", p.name, p.parent));
        }
    }
    Ok(())
}

/// Per sequence `(blend weight, blended pair)`: both set (a pre-blend, of two distinct
/// sequences that are not pre-blends) or neither. The error names the first offender.
pub fn check_blends(seqs: &[(Option<f64>, Option<(usize, usize)>)]) -> std::result::Result<(), String> {
    for (i, &(w, of)) in seqs.iter().enumerate() {
        match (w, of) {
            (None, None) => {}
            (Some(_), Some((a, b)))
                if a != b && seqs.get(a).is_some_and(|s| s.0.is_none()) && seqs.get(b).is_some_and(|s| s.0.is_none()) => {}
            _ => return Err(format!("sequence {i}: blend weight {w:?} of sequences {of:?} (a pre-blend needs both, of two captured motions)")),
        }
    }
    Ok(())
}

/// A blend pair of two distinct sequence indices below `n`, or none.
pub fn check_pair(pair: Option<(usize, usize)>, n: usize) -> std::result::Result<(), String> {
    match pair {
        Some((a, b)) if a >= n || b >= n || a == b => Err(format!("blend pair ({a}, {b}) for {n} sequences")),
        _ => Ok(()),
    }
}

impl Group {
    /// Index of the sequence named `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.sequences.iter().position(|s| s.name == name)
    }
    /// Frames per sequence (all equal after prealignment).
    pub fn n_frames(&self) -> usize {
        self.sequences.first().map_or(0, |s| s.motion.n_frames())
    }
    /// The template point whose motion the displacements are: the centroid of the root part's
    /// core ([`root_core`]).
    pub fn root_point(&self) -> Vector3<f64> {
        capture::align::root_point(&self.template, &root_core(&self.parts, self.template.len()))
    }
}

/// Displacements `D_i = Q_{i-1}⁻¹ Q_i` (`D_0 = 0`) of the root poses `Q_i = P_i ∘ T(root)` of
/// world poses `P_i` (`capture::align`).
pub fn root_displacements(poses: &[RigidMotion], root: &Vector3<f64>) -> Vec<[f64; 6]> {
    let roots = capture::align::root_poses(poses, root);
    let mut d = vec![[0.0; 6]];
    for w in roots.windows(2) {
        let v = relative_in_body_frame(&w[0], &w[1]).to_6vec();
        d.push(std::array::from_fn(|k| v[k]));
    }
    d.truncate(poses.len());
    d
}

/// Name of the pre-blended sequence at weight `w` of the group's blend pair.
pub fn blend_name(w: f64) -> String {
    format!("blend-{w}")
}

/// Name of the pre-blended sequence at weight `w` of motions `a` and `b` (not the group's
/// blend pair).
pub fn pair_blend_name(a: &str, b: &str, w: f64) -> String {
    format!("blend-{a}-{b}-{w}")
}

/// What [`build`] needs.
#[derive(Clone, Debug)]
pub struct GroupSpec {
    pub name: String,
    pub subject: String,
    /// The subject's description in place of the set's `subject.json` (e.g. the one
    /// `propose-curves` wrote for a set without curves).
    pub subject_json: Option<std::path::PathBuf>,
    /// Motions of the group, in order; those the front end did not align are skipped (reported
    /// by [`build`]).
    pub motions: Vec<String>,
    /// Reference motion (default: the first present).
    pub reference: Option<String>,
    /// Blend weights `W` (each in (0, 1)) of every pre-blended pair.
    pub blend_weights: Vec<f64>,
    /// Pairs of motions to pre-blend at every weight, the first being the group's blend pair;
    /// empty: the first two present motions. A pair naming a missing motion is skipped (noted).
    pub blend_pairs: Vec<(String, String)>,
    pub prealign: PrealignOptions,
    /// Model the whole body as one part instead of the subject's segmentation.
    pub whole_body: bool,
    /// Without a segmentation, model the whole body (reported in the notes) instead of failing.
    pub fallback_whole_body: bool,
    /// Cut every motion to the same number of whole gait cycles before the DTW ([`crate::gait`]).
    pub gait_cycles: bool,
}

/// What the front end made of the group's subject: its segmentation (`segment`; None: none
/// given) and its motions aligned to its template (`align`), by name.
#[derive(Clone, Debug, Default)]
pub struct FrontEnd {
    pub segmentation: Option<Segmentation>,
    pub motions: Vec<(String, AlignedMotion)>,
}

/// Prealigns and blends the group's motions of `front`. Returns the group and notes (skipped
/// motions, whole-body fallback).
pub fn build(set: &CaptureSet, spec: &GroupSpec, front: FrontEnd) -> Result<(Group, Vec<String>)> {
    let subject_json = spec.subject_json.clone().unwrap_or_else(|| set.subject_json(&spec.subject));
    let subject_spec = SubjectSpec::load(&subject_json)?;
    let template = &mesh_core::io::read_mesh(set.template_path(&spec.subject, &subject_spec)?)?;
    let (present, reference, mut notes) = group_motions(spec, &front)?;
    let pairs = blend_pairs(spec, &present, &mut notes)?;
    let parts = body_parts(spec, template, front.segmentation.as_ref(), &mut notes)?;
    let up = subject_spec.up_vector().unwrap_or(Vector3::y());
    let body = Body {
        template,
        // Soles of the two leg parts, left first, for motions without contact annotations.
        soles: soles(&parts, &template.vertices, &up, mesh_core::feet::SOLE_TOLERANCE),
        has_legs: parts.iter().filter(|p| p.name.starts_with("leg")).count() == 2,
        up,
    };
    let root = capture::align::root_point(&template.vertices, &root_core(&parts, template.n_vertices()));
    // Steps: taking each motion, warping each, then each blend.
    let bar = mesh_core::cli::stage_progress(
        (2 * present.len() + pairs.len() * spec.blend_weights.len()) as u64,
        "motions read, warped; blends",
    );
    let mut motions = front.motions;
    let mut loaded = Vec::new();
    for m in &present {
        bar.inc(1);
        let k = motions.iter().position(|(n, _)| n == m).expect("present motions are the front end's");
        let aligned = motions.swap_remove(k).1;
        loaded.push(motion_contacts(&subject_spec, &subject_json, &body, m, aligned, &mut notes)?);
    }
    let r = present.iter().position(|m| *m == reference).expect("checked");
    let (windows, cut_cycles) = gait_windows(spec, &loaded, &mut notes)?;
    let ref_frames = loaded[r].1.frames[windows[r].0..windows[r].0 + windows[r].1].to_vec();
    let ref_contacts = slice_contacts(&loaded[r].2, windows[r]);
    let mut sequences = Vec::new();
    for (q, (name, motion, c)) in loaded.into_iter().enumerate() {
        bar.inc(1);
        let (w0, len) = windows[q];
        let map: Vec<usize> = if q == r {
            (w0..w0 + len).collect()
        } else {
            warp_onto_reference(spec, &name, &motion, &c, len, cut_cycles, &ref_frames, ref_contacts.as_ref())?
        };
        let contacts = c.as_ref().map(|c| apply_contacts(c, &map));
        sequences.push(GroupSequence {
            name,
            blend: None,
            blend_of: None,
            motion: apply(&motion, &map, &root),
            contacts,
            map,
        });
    }
    let pair = pairs.first().copied();
    let mut group = Group {
        name: spec.name.clone(),
        subject: spec.subject.clone(),
        fps: subject_spec.fps,
        up,
        template: template.vertices.clone(),
        faces: template.faces.clone(),
        parts,
        reference,
        sequences,
        pair,
    };
    add_blends(&mut group, spec, &pairs, &root, &bar)?;
    bar.finish_and_clear();
    Ok((group, notes))
}

/// The group's motions the front end aligned (the others noted as skipped), its reference
/// motion, and the notes so far; checks the reference and the blend weights.
fn group_motions(spec: &GroupSpec, front: &FrontEnd) -> Result<(Vec<String>, String, Vec<String>)> {
    let (present, skipped): (Vec<String>, Vec<String>) = spec
        .motions
        .iter()
        .cloned()
        .partition(|m| front.motions.iter().any(|(n, _)| n == m));
    if present.is_empty() {
        return Err(Error::invalid(format!(
            "group '{}': none of the motions {:?} exists for subject {}",
            spec.name, spec.motions, spec.subject
        )));
    }
    let reference = spec.reference.clone().unwrap_or_else(|| present[0].clone());
    if !present.contains(&reference) {
        return Err(Error::invalid(format!(
            "group '{}': reference motion '{reference}' is not in the group",
            spec.name
        )));
    }
    for &w in &spec.blend_weights {
        if !(w > 0.0 && w < 1.0) {
            return Err(Error::invalid(format!(
                "blend weight {w} must lie strictly between 0 and 1"
            )));
        }
    }
    let notes = skipped
        .iter()
        .map(|m| format!("motion '{m}' was not aligned: skipped"))
        .collect();
    Ok((present, reference, notes))
}

/// The body's parts: the subject's segmentation, or the whole body as one part (asked for, or,
/// with `fallback_whole_body`, without a segmentation: noted).
fn body_parts(
    spec: &GroupSpec,
    template: &mesh_core::TriMesh,
    segmentation: Option<&Segmentation>,
    notes: &mut Vec<String>,
) -> Result<Vec<PartDef>> {
    let whole = capture::part_pca::whole_body(template.n_vertices());
    let seg = match segmentation {
        _ if spec.whole_body => &whole,
        Some(s) if s.n_vertices != template.n_vertices() => {
            return Err(Error::invalid(format!(
                "the segmentation is of {} vertices, the template has {}",
                s.n_vertices,
                template.n_vertices()
            )))
        }
        Some(s) => s,
        None if spec.fallback_whole_body => {
            notes.push("no segmentation of the subject: modelling the whole body as one part".into());
            &whole
        }
        None => {
            return Err(Error::invalid(
                "the group's body parts need the subject's segmentation (from `segment`), or model the whole body",
            ))
        }
    };
    Ok(seg
        .parts
        .iter()
        .map(|p| PartDef {
            name: p.name.clone(),
            parent: p
                .parent
                .as_ref()
                .and_then(|q| seg.parts.iter().position(|x| &x.name == q)),
            vertices: p.vertices.clone(),
        })
        .collect())
}

/// What taking a motion into the group needs of its body.
struct Body<'a> {
    template: &'a mesh_core::TriMesh,
    soles: Vec<Vec<u32>>,
    /// Two leg parts: contacts can be detected on the soles.
    has_legs: bool,
    up: Vector3<f64>,
}

/// Motion `m`, aligned to the body's template, with its contacts: the subject's annotations, or
/// detected on its soles in world coordinates (noted).
fn motion_contacts(
    subject_spec: &SubjectSpec,
    subject_json: &std::path::Path,
    body: &Body,
    m: &str,
    aligned: AlignedMotion,
    notes: &mut Vec<String>,
) -> Result<(String, AlignedMotion, Option<Contacts>)> {
    check_topology(body.template, aligned.frames[0].len(), &aligned.faces)
        .map_err(|e| Error::invalid(format!("motion '{m}': {e}")))?;
    let mut c = contacts::from_subject(subject_spec, m, aligned.n_frames())
        .map_err(|e| Error::file(subject_json, e.to_string()))?;
    if c.is_none() && body.has_legs {
        c = capture::contact_detector::detect(
            &aligned.world_frames(),
            &body.soles,
            &body.up,
            subject_spec.fps,
            &capture::contact_detector::Rule::default(),
        );
        if c.is_some() {
            notes.push(format!(
                "motion '{m}' has no contact annotations: contacts detected from its meshes"
            ));
        }
    }
    Ok((m.to_string(), aligned, c))
}

/// The window `(start, length)` kept of each motion: everything, or (`gait_cycles`) the same
/// whole number of gait cycles of each; and whether cycles were cut. A motion without a
/// repeating gait leaves every motion whole (noted).
fn gait_windows(
    spec: &GroupSpec,
    loaded: &[(String, AlignedMotion, Option<Contacts>)],
    notes: &mut Vec<String>,
) -> Result<(Vec<(usize, usize)>, bool)> {
    let mut windows: Vec<(usize, usize)> = loaded.iter().map(|l| (0, l.1.n_frames())).collect();
    let periods: Option<Vec<usize>> = match spec.gait_cycles {
        false => None,
        true => loaded
            .iter()
            .map(|(m, a, _)| {
                let p = gait::period(&a.frames, &gait::GaitOptions::default());
                if p.is_none() {
                    notes.push(format!(
                        "motion '{m}': no gait cycle found (its poses do not repeat): the group's motions are used whole"
                    ));
                }
                p
            })
            .collect(),
    };
    let Some(periods) = periods else {
        return Ok((windows, false));
    };
    let lp: Vec<(usize, usize)> = loaded
        .iter()
        .zip(&periods)
        .map(|(l, &p)| (l.1.n_frames(), p))
        .collect();
    let k = gait::common_cycles(&lp)?;
    for (w, &p) in windows.iter_mut().zip(&periods) {
        w.1 = k * p;
    }
    for ((m, _, _), p) in loaded.iter().zip(&periods) {
        mesh_core::info!("{m}: gait period {p} frames, {k} cycle(s) kept");
    }
    Ok((windows, true))
}

/// Contacts of the window `(start, length)`.
fn slice_contacts(c: &Option<Contacts>, (s, n): (usize, usize)) -> Option<Contacts> {
    c.as_ref().map(|c| c[s..s + n].to_vec())
}

/// The frames of `motion` (`len` of them) that the DTW puts on the reference's frames. With
/// whole gait cycles (`cut_cycles`) every start of the window is tried and the cheapest DTW kept,
/// with one contact weight λ for all (that of the first window).
#[allow(clippy::too_many_arguments)]
fn warp_onto_reference(
    spec: &GroupSpec,
    name: &str,
    motion: &AlignedMotion,
    c: &Option<Contacts>,
    len: usize,
    cut_cycles: bool,
    ref_frames: &[Vec<Vector3<f64>>],
    ref_contacts: Option<&Contacts>,
) -> Result<Vec<usize>> {
    let starts = if cut_cycles { 0..=motion.n_frames() - len } else { 0..=0 };
    let mut opts = spec.prealign.clone();
    let mut best: Option<(usize, Warp)> = None;
    for s in starts {
        let wp = warp(
            &motion.frames[s..s + len],
            slice_contacts(c, (s, len)).as_ref(),
            ref_frames,
            ref_contacts,
            &opts,
        )
        .map_err(|e| Error::invalid(format!("{name}: {e}")))?;
        opts.contact_weight = Some(wp.contact_weight);
        if best.as_ref().is_none_or(|b| wp.mean_cost < b.1.mean_cost) {
            best = Some((s, wp));
        }
    }
    let (s, wp) = best.expect("at least one window");
    mesh_core::info!(
        "{name}: frames {s}..{} warped onto the reference (mean DTW cost {:.1} mm)",
        s + len,
        wp.mean_cost * 1e3
    );
    Ok(wp.map.iter().map(|&i| s + i).collect())
}

/// The blends of each pair at each weight, appended to the group's sequences (none for a group
/// of one motion: the caller warns).
fn add_blends(
    group: &mut Group,
    spec: &GroupSpec,
    pairs: &[(usize, usize)],
    root: &Vector3<f64>,
    bar: &mesh_core::cli::ProgressBar,
) -> Result<()> {
    if spec.blend_weights.is_empty() || pairs.is_empty() {
        return Ok(());
    }
    let blender = surface::blend::Blender::new(group.template.clone(), group.faces.clone())?;
    for (i, &(a, b)) in pairs.iter().enumerate() {
        for &w in &spec.blend_weights {
            bar.inc(1);
            let mut s = blend_sequences(&blender, &group.sequences[a], &group.sequences[b], w, &group.up, root)?;
            s.blend_of = Some((a, b));
            if i > 0 {
                s.name = pair_blend_name(&group.sequences[a].name, &group.sequences[b].name, w);
            }
            group.sequences.push(s);
        }
    }
    Ok(())
}

/// The vertices a body's rigid pose is fitted on: the root part's core, its vertices in no
/// other part (the torso without the bands it shares with the limbs; `capture::align`'s
/// `AlignFrame::Root`). A fit on every vertex lets the limbs decide the heading: a template in
/// another pose than the frame then turns it by tens of degrees from one frame to the next.
/// Empty (every vertex) when the core has fewer than 3 vertices.
pub fn root_core(parts: &[PartDef], n_vertices: usize) -> Vec<u32> {
    let Some(root) = parts.iter().find(|p| p.parent.is_none()) else {
        return Vec::new();
    };
    let children = parts.iter().filter(|p| p.parent.is_some()).map(|p| p.vertices.as_slice());
    let core = capture::align::root_core(&root.vertices, children, n_vertices);
    if core.len() < 3 {
        Vec::new()
    } else {
        core
    }
}

/// Sole vertices of the two legs ([`mesh_core::feet::soles`] on the parts named `leg*`).
pub fn soles(
    parts: &[PartDef],
    template: &[Vector3<f64>],
    up: &Vector3<f64>,
    tol: f64,
) -> Vec<Vec<u32>> {
    let legs: Vec<(&str, &[u32])> = parts
        .iter()
        .map(|p| (p.name.as_str(), p.vertices.as_slice()))
        .collect();
    mesh_core::feet::soles(&legs, template, up, tol)
}

/// The pairs of [`GroupSpec::blend_pairs`] as indices into `present` (the motions found, in
/// group order): pairs naming a motion of the group that is missing are skipped with a note;
/// a name outside the group, a motion paired with itself or a pair given twice is an error.
fn blend_pairs(
    spec: &GroupSpec,
    present: &[String],
    notes: &mut Vec<String>,
) -> Result<Vec<(usize, usize)>> {
    if spec.blend_pairs.is_empty() {
        return Ok(if present.len() >= 2 { vec![(0, 1)] } else { Vec::new() });
    }
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    for (a, b) in &spec.blend_pairs {
        let what = format!("group '{}': blend pair '{a}:{b}'", spec.name);
        if let Some(m) = [a, b].into_iter().find(|m| !spec.motions.contains(m)) {
            return Err(Error::invalid(format!("{what}: '{m}' is not one of the group's motions")));
        }
        if a == b {
            return Err(Error::invalid(format!("{what}: a motion blended with itself")));
        }
        let (Some(i), Some(j)) = (present.iter().position(|m| m == a), present.iter().position(|m| m == b)) else {
            notes.push(format!("{what} skipped: a motion is missing"));
            continue;
        };
        if pairs.iter().any(|&(p, q)| (p, q) == (i, j) || (p, q) == (j, i)) {
            return Err(Error::invalid(format!("{what} is listed twice")));
        }
        pairs.push((i, j));
    }
    Ok(pairs)
}

/// The pre-blended sequence `Y_w` of two time-aligned sequences (module doc; displacements of
/// the template point `root`); its `blend_of` is left to the caller, which knows their indices.
pub fn blend_sequences(
    blender: &surface::blend::Blender,
    a: &GroupSequence,
    b: &GroupSequence,
    w: f64,
    up: &Vector3<f64>,
    root: &Vector3<f64>,
) -> Result<GroupSequence> {
    let mut out = blend_sequences_at(blender, a, b, &[w], up, root)?;
    Ok(out.remove(0))
}

/// [`blend_sequences`] at several weights: each frame pair is polar-decomposed once and
/// interpolated at every weight (the same frames as separate calls, at a fraction of the cost).
pub fn blend_sequences_at(
    blender: &surface::blend::Blender,
    a: &GroupSequence,
    b: &GroupSequence,
    weights: &[f64],
    up: &Vector3<f64>,
    root: &Vector3<f64>,
) -> Result<Vec<GroupSequence>> {
    use rayon::prelude::*;
    let n = a.motion.n_frames();
    if b.motion.n_frames() != n {
        return Err(Error::invalid(format!(
            "blend: {} and {} have different lengths",
            a.name, b.name
        )));
    }
    // by_frame[t][i]: frame t at weights[i].
    let by_frame = (0..n)
        .into_par_iter()
        .map(|t| {
            let da = blender.decompose(&a.motion.frames[t])?;
            let db = blender.decompose(&b.motion.frames[t])?;
            weights
                .iter()
                .map(|&w| blender.interpolate(&da, &db, w))
                .collect::<Result<Vec<_>>>()
        })
        .collect::<Result<Vec<_>>>()?;
    let mut by_weight: Vec<Vec<Vec<Vector3<f64>>>> =
        weights.iter().map(|_| Vec::with_capacity(n)).collect();
    for frame in by_frame {
        for (seq, x) in by_weight.iter_mut().zip(frame) {
            seq.push(x);
        }
    }
    Ok(weights
        .iter()
        .zip(by_weight)
        .map(|(&w, frames)| {
            let poses = blend_poses(&a.motion.poses, &b.motion.poses, w, up);
            let disp = root_displacements(&poses, root);
            let contacts = if w < 0.5 {
                a.contacts.clone()
            } else {
                b.contacts.clone()
            };
            GroupSequence {
                name: blend_name(w),
                blend: Some(w),
                blend_of: None,
                motion: AlignedMotion {
                    faces: a.motion.faces.clone(),
                    frames,
                    poses,
                    displacements: disp,
                    anchor: a.motion.anchor.clone(),
                    capture: a.motion.capture.clone(),
                },
                contacts,
                map: (0..n).collect(),
            }
        })
        .collect())
}

/// The ground frame of a world pose: its position dropped onto the ground plane through the
/// origin (normal `up`) and its heading, the rotation about `up` closest to the pose's.
pub fn ground_frame(pose: &RigidMotion, up: &Vector3<f64>) -> RigidMotion {
    let up = up.normalize();
    // A template direction orthogonal to up, and where the pose sends it, both made horizontal.
    let e = if up.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::z()
    };
    let h = |v: Vector3<f64>| v - up * v.dot(&up);
    let (e0, e1) = (h(e), h(pose.rotation * e));
    let angle = if e1.norm() < 1e-9 {
        0.0
    } else {
        e0.cross(&e1).dot(&up).atan2(e0.dot(&e1))
    };
    RigidMotion::new(
        Rotation3::from_axis_angle(&Unit::new_normalize(up), angle),
        h(pose.translation),
    )
}

/// World poses of the blend at weight `w` of two time-aligned pose sequences (module doc).
pub fn blend_poses(
    a: &[RigidMotion],
    b: &[RigidMotion],
    w: f64,
    up: &Vector3<f64>,
) -> Vec<RigidMotion> {
    let (ga, gb) = match (a.first(), b.first()) {
        (Some(pa), Some(pb)) => (ground_frame(pa, up), ground_frame(pb, up)),
        _ => return Vec::new(),
    };
    let (ia, ib) = (ga.inverse(), gb.inverse());
    a.iter()
        .zip(b)
        .map(|(pa, pb)| {
            let (qa, qb) = (ia.compose(pa), ib.compose(pb));
            let r = qa.rotation * so3_exp(&(so3_log(&(qa.rotation.inverse() * qb.rotation)) * w));
            let t = qa.translation * (1.0 - w) + qb.translation * w;
            ga.compose(&RigidMotion::new(r, t))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(yaw: f64, tilt: f64, t: [f64; 3]) -> RigidMotion {
        RigidMotion::new(
            Rotation3::from_axis_angle(&Vector3::y_axis(), yaw)
                * Rotation3::from_axis_angle(&Vector3::x_axis(), tilt),
            Vector3::from(t),
        )
    }

    #[test]
    fn blend_poses_keep_endpoints_and_height() {
        let up = Vector3::y();
        // Upright walker heading +x from (1, 0.9, 2); leaning runner elsewhere, another heading.
        let a: Vec<_> = (0..5)
            .map(|i| pose(0.0, 0.0, [1.0 + 0.1 * i as f64, 0.9, 2.0]))
            .collect();
        let b: Vec<_> = (0..5)
            .map(|i| {
                let d = Rotation3::from_axis_angle(&Vector3::y_axis(), 1.0) * Vector3::x();
                let p = Vector3::new(-3.0, 0.8, 0.5) + d * (0.3 * i as f64);
                pose(1.0, 0.3, [p.x, p.y, p.z])
            })
            .collect();
        let w0 = blend_poses(&a, &b, 0.0, &up);
        for (p, q) in w0.iter().zip(&a) {
            assert!((p.translation - q.translation).norm() < 1e-12);
            assert!(p.rotation.angle_to(&q.rotation) < 1e-12);
        }
        // w = 1: b's motion moved onto a's start; its height, lean and speed are b's.
        let w1 = blend_poses(&a, &b, 1.0, &up);
        for (i, p) in w1.iter().enumerate() {
            assert!((p.translation.y - 0.8).abs() < 1e-12, "{}", p.translation.y);
            let travelled = (p.translation - w1[0].translation).norm();
            assert!((travelled - 0.3 * i as f64).abs() < 1e-12);
            // Travel along a's heading (+x), lean kept.
            assert!((p.translation.z - 2.0).abs() < 1e-12);
            assert!((p.rotation.angle_to(&pose(0.0, 0.3, [0.0; 3]).rotation)) < 1e-12);
        }
        // Half way: height and speed in between.
        let wh = blend_poses(&a, &b, 0.5, &up);
        assert!((wh[4].translation.y - 0.85).abs() < 1e-12);
        assert!(((wh[4].translation - wh[0].translation).norm() - 0.8).abs() < 1e-12);
    }
}
