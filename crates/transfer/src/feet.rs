//! Planted feet of a transfer: the foot-skating clean-up CVPR §6 mentions, applied to the placed
//! target frames. A transfer travels as its source's root does, scaled by the height ratio `r`,
//! and the target's legs need not step exactly that far, so its soles slide where the source's
//! do not. The clean-up shifts each placed frame horizontally by `d(t)`, solved by
//! [`capture::footskate`] (the objective is stated there) with one velocity term per foot `f`
//! down in two consecutive frames `t − 1` and `t`: the shift moves by `r Δs_f(t) − Δp_f(t)`
//! (`p_f`, `s_f` the target's and the source's sole centroids, horizontal parts), so the
//! target's sole moves as the source's does, scaled.
//!
//! Matching the source's sole motion rather than pinning the sole at an anchor keeps what the
//! source really does on the floor: a planted foot (Δs ≈ 0) is pinned, a foot that pivots or
//! shuffles (a spin, a get-up) moves as the source's does, so the correction does not
//! accumulate into drift. The ridge `μ` = [`RETURN`] makes it a local correction that returns
//! to zero away from contacts (smoothness `λ` = [`SMOOTHNESS`]). Without `μ` a pinned foot
//! carries every error of the transferred leg into the root and the body drifts (placed error
//! 6.9 -> 14.0 cm on the holdout benchmark); with it the placement is unchanged (holdout 6.91
//! -> 6.90 cm, demo 7.59 -> 7.63) and the sliding comes within 1.15x of the truth's on 7 of 9
//! benchmark motions (4 without the clean-up; docs/studies/04-placement.md). The source's
//! contacts are detected on its own meshes ([`capture::contact_detector`]), never on the
//! target's, whose sliding soles are what is being corrected.
//!
//! The shift moves whole frames, so each frame's shape, and its pose error after a per-frame
//! rigid fit, is unchanged.
//!
//! The same contacts put the transfer's feet on the target's floor ("foot height"). A
//! transferred leg need not reach the floor where the source's does: its pose is regressed,
//! and its root height is the source's scaled by `r`. Moving the whole body would trade the
//! feet's error for the body's (on the tiny preset the placed error rose from 7.2 to 11.5 cm on
//! a jump whose body height was right and whose feet floated 5 cm). So each leg is deformed
//! instead, hip seam fixed, every leg vertex `v` moved by `w(v) e_f(t)` along up with the leg
//! weights of [`mesh_core::feet::leg_weights`] (1 on the sole, 0 at the seam), where the drop
//! `e_f` of leg `f` solves
//!
//! `min_e  Σ_{t: foot f down} (l_f(t) + e(t) − floor)² + λ Σ_t (e(t−1) − 2 e(t) + e(t+1))²
//!        + μ Σ_t e(t)²`
//!
//! (`l_f` the lowest point of leg `f` along up, `floor` the template's lowest leg point, the
//! floor the template stands on), so a planted foot stands on the floor and a lifted one eases
//! back to its regressed height.
//!
//! That holds where the body's height is the source's, scaled (`--placement scaled-source`).
//! Where the root's height is regressed (`regressed`, `blended`), it drifts, and the legs would
//! stretch by the drift (holdout cartwheel: pose error 2.7 -> 9.9 cm, the body floating 9 cm).
//! There the whole body is first lowered by a drop `h(t)` of the same objective, with `l(t)` the
//! lower of the two legs' lowest points and the frames where either foot is down (a vertical
//! shift of the frame, which leaves its pose unchanged); the legs then take what is left.

use capture::align::{AlignedMotion, CaptureInfo};
use capture::contact_detector::{self, Rule};
use capture::footskate::Problem;
use capture::part_pca::PcaModel;
use capture::choices::Placement;
use gp::band::{BandCholesky, SymmetricBand};
use mesh_core::rigid::RigidMotion;
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};

use capture::root_placement::place;

/// The two soles (left, right) of a subject's template, from its PCA model's leg parts
/// ([`mesh_core::feet::soles`]); None without two non-empty soles.
pub fn soles(pca: &PcaModel, up: &Vector3<f64>) -> Option<[Vec<u32>; 2]> {
    let parts: Vec<(&str, &[u32])> = pca
        .parts
        .iter()
        .map(|p| (p.name.as_str(), p.vertices.as_slice()))
        .collect();
    let found = mesh_core::feet::soles(&parts, &pca.template_vertices(), up, mesh_core::feet::SOLE_TOLERANCE);
    match <[Vec<u32>; 2]>::try_from(found) {
        Ok(s) if s.iter().all(|v| !v.is_empty()) => Some(s),
        _ => None,
    }
}

/// Default weight `λ` of the correction's second differences (per frame², against weight 1 per
/// contact residual), as the variation's clean-up.
pub const SMOOTHNESS: f64 = 1.0;

/// Weight `μ` of the shifts themselves (module doc), against weight 1 per contact residual: a
/// shift is pulled back toward zero over a few frames once no contact asks for it, so errors
/// of the transferred legs do not accumulate into drift.
pub const RETURN: f64 = 0.1;

/// Weight `μ` of the foot-height drops themselves (module doc), against weight 1 per planted
/// frame: it leaves a planted sole 1 % of its distance off the floor and brings a lifted
/// foot's drop back toward zero within about 8 frames.
pub const HEIGHT_RETURN: f64 = 0.01;

/// What [`solve`]'s moves do: the number of frames with a planted foot, the largest horizontal root
/// shift, and how far a planted sole was moved onto the floor (median over planted frames, m).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Planted {
    pub planted_frames: usize,
    /// The largest horizontal shift of a frame (foot skating).
    pub max_shift_m: f64,
    /// The largest vertical shift of a frame (foot height under a regressed root height).
    pub max_body_drop_m: f64,
    pub median_foot_move_m: f64,
}

/// The horizontal shifts `d(t)` of the module doc: `target` and `source` the two subjects' sole
/// tracks (same frame count as `contacts`), `ratio` the scale `r`.
pub fn corrections(
    target: &[Vec<Vector3<f64>>; 2],
    source: &[Vec<Vector3<f64>>; 2],
    contacts: &[[bool; 2]],
    ratio: f64,
    up: &Vector3<f64>,
    smoothness: f64,
    notes: &mut Vec<String>,
) -> Result<Vec<Vector3<f64>>> {
    let n = contacts.len();
    mesh_core::feet::check_smoothness(smoothness)?;
    if target.iter().chain(source).any(|f| f.len() != n) {
        return Err(Error::invalid(format!(
            "foot-skating clean-up: {n} contact frames but sole tracks of other lengths"
        )));
    }
    let horizontal = |p: Vector3<f64>| p - up * up.dot(&p);
    let pairs: Vec<(usize, usize)> = (1..n)
        .flat_map(|t| (0..2).map(move |f| (t, f)))
        .filter(|&(t, f)| contacts[t - 1][f] && contacts[t][f])
        .collect();
    if pairs.is_empty() {
        return Ok(vec![Vector3::zeros(); n]);
    }
    // One velocity term per pair: the shift moves by g = horizontal(r Δs − Δp).
    let mut problem = Problem::<3>::new(n, smoothness, RETURN)?;
    for &(t, f) in &pairs {
        let g = horizontal(
            (source[f][t] - source[f][t - 1]) * ratio - (target[f][t] - target[f][t - 1]),
        );
        problem.add_velocity(t, g.into());
    }
    let d = problem.solve(notes)?;
    Ok(std::iter::once(Vector3::zeros())
        .chain(d[1..].iter().map(|&d| horizontal(Vector3::from(d))))
        .collect())
}

/// The vertices of the two legs (left, right) of a subject's template: its `leg*` parts or,
/// without them, the template's two sides ([`mesh_core::feet::soles`] with no height limit).
/// The lowest point of a leg is its foot's in any pose, whichever part of the foot touched the
/// floor in the template.
pub fn legs(pca: &PcaModel, up: &Vector3<f64>) -> [Vec<u32>; 2] {
    let parts: Vec<(&str, &[u32])> = pca.parts.iter().map(|p| (p.name.as_str(), p.vertices.as_slice())).collect();
    let mut found = mesh_core::feet::soles(&parts, &pca.template_vertices(), up, f64::INFINITY).into_iter();
    [found.next().unwrap_or_default(), found.next().unwrap_or_default()]
}

/// Per frame, the lowest point along `up` of each of the two `legs` (left, right) of `frames`.
pub fn lowest_points(frames: &[Vec<Vector3<f64>>], legs: &[Vec<u32>; 2], up: &Vector3<f64>) -> [Vec<f64>; 2] {
    legs.clone().map(|s| {
        frames
            .iter()
            .map(|f| s.iter().map(|&v| f[v as usize].dot(up)).fold(f64::INFINITY, f64::min))
            .collect()
    })
}

/// The drops `e(t)` of one leg's sole (module doc) that put the leg's lowest point `lowest`
/// (per frame, from [`lowest_points`]) on `floor` wherever `planted`, with smoothness `λ`,
/// returning to zero away from the contacts. All zero without contacts.
pub fn leg_drops(
    lowest: &[f64],
    planted: &[bool],
    floor: f64,
    smoothness: f64,
    notes: &mut Vec<String>,
) -> Result<Vec<f64>> {
    let n = planted.len();
    mesh_core::feet::check_smoothness(smoothness)?;
    if lowest.len() != n {
        return Err(Error::invalid(format!(
            "foot height: {n} contact frames but a leg track of {} frames",
            lowest.len()
        )));
    }
    if !(0..n).any(|t| planted[t] && lowest[t].is_finite()) {
        return Ok(vec![0.0; n]);
    }
    let mut a = SymmetricBand::zeros(n, 2);
    (0..n).for_each(|t| a.add(t, t, HEIGHT_RETURN));
    let mut b = DMatrix::<f64>::zeros(n, 1);
    for t in (0..n).filter(|&t| planted[t] && lowest[t].is_finite()) {
        a.add(t, t, 1.0);
        b[(t, 0)] += floor - lowest[t];
    }
    let w = [1.0, -2.0, 1.0];
    for t in 1..n.saturating_sub(1) {
        for (u, wu) in w.iter().enumerate() {
            for (v, wv) in w.iter().enumerate().take(u + 1) {
                a.add(t + u - 1, t + v - 1, smoothness * wu * wv);
            }
        }
    }
    let chol = BandCholesky::new(&a, "foot-height normal equations", notes)
        .map_err(|e| Error::invalid(format!("foot height: {e}")))?;
    let x = chol.solve(&b);
    Ok((0..n).map(|t| x[(t, 0)]).collect())
}

/// The median of `values` (reordered); 0 when empty.
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let m = values.len() / 2;
    if values.len() % 2 == 1 {
        values[m]
    } else {
        0.5 * (values[m - 1] + values[m])
    }
}

/// The source's soles as placed in the world and the contacts detected on them.
pub struct SourceContacts {
    /// Per frame, the placed sole vertices: the left sole's, then the right's.
    pub world: Vec<Vec<Vector3<f64>>>,
    /// Indices into `world`'s frames of the left and the right sole.
    pub soles: [Vec<u32>; 2],
    pub contacts: Vec<[bool; 2]>,
}

/// The vertices of a source's two soles ([`soles`]), as read from each of its frames.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceSoles {
    /// The left sole's vertices, then the right's.
    picked: Vec<u32>,
    /// How many of `picked` are the left sole's.
    left: usize,
}

impl SourceSoles {
    /// None when the source has no two leg parts.
    pub fn of(source_pca: &PcaModel, up: &Vector3<f64>) -> Option<SourceSoles> {
        let body_soles = soles(source_pca, up)?;
        Some(SourceSoles { left: body_soles[0].len(), picked: body_soles.concat() })
    }

    /// The sole vertices of `frame`; None when the frame has fewer vertices than a sole names.
    pub fn pick(&self, frame: &[Vector3<f64>]) -> Option<Vec<Vector3<f64>>> {
        self.picked.iter().map(|&v| frame.get(v as usize).copied()).collect()
    }

    /// The contacts detected on the sole vertices `sole_frames` (per frame, [`SourceSoles::pick`]
    /// of the unplaced frame) placed by `poses` ([`contact_detector::detect`], which reads the
    /// sole vertices only); None without a frame rate.
    pub fn contacts(&self, sole_frames: &[Vec<Vector3<f64>>], poses: &[RigidMotion], capture: &CaptureInfo) -> Option<SourceContacts> {
        if !(capture.fps > 0.0) {
            return None;
        }
        let up = Vector3::from(capture.up);
        let world = place(poses, sole_frames);
        let soles = [(0..self.left as u32).collect(), (self.left as u32..self.picked.len() as u32).collect()];
        let contacts = contact_detector::detect(&world, &soles, &up, capture.fps, &Rule::default())?;
        Some(SourceContacts { world, soles, contacts })
    }
}

/// The source's contacts, detected on its own placed soles ([`SourceSoles::contacts`]); None
/// when it has no two leg parts or no frame rate.
pub fn source_contacts(source_pca: &PcaModel, motion: &AlignedMotion) -> Option<SourceContacts> {
    let soles = SourceSoles::of(source_pca, &Vector3::from(motion.capture.up))?;
    let Some(sole_frames) = motion.frames.iter().map(|f| soles.pick(f)).collect::<Option<Vec<_>>>() else {
        mesh_core::info!("a sole vertex is beyond the source motion's vertices: no contacts");
        return None;
    };
    soles.contacts(&sole_frames, &motion.poses, &motion.capture)
}

/// What a transfer's feet are measured and cleaned with on a target: its soles ([`soles`]),
/// its legs ([`legs`]) and its floor, the height along up of its template's lowest leg point.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetFeet {
    pub soles: [Vec<u32>; 2],
    pub legs: [Vec<u32>; 2],
    pub floor: f64,
}

impl TargetFeet {
    /// None without two non-empty soles.
    pub fn of(target_pca: &PcaModel, up: &Vector3<f64>) -> Option<TargetFeet> {
        let soles = soles(target_pca, up)?;
        let legs = legs(target_pca, up);
        let template = target_pca.template_vertices();
        let floor = legs.iter().flatten().map(|&v| template[v as usize].dot(up)).fold(f64::INFINITY, f64::min);
        Some(TargetFeet { soles, legs, floor })
    }
}

/// The feet clean-ups [`solve`] prepares: the horizontal foot-skating shift and the vertical leg
/// deformation onto the floor (module doc), with smoothness `λ`; `faces` the target's (its
/// legs' seams with the torso).
#[derive(Clone, Copy, Debug)]
pub struct CleanUp<'a> {
    pub footskate: bool,
    pub foot_height: bool,
    pub smoothness: f64,
    pub faces: &'a [[u32; 3]],
}

/// Relative width of the band of a leg's lowest vertices [`FeetRecord`] keeps: a frame's shift
/// moves every vertex alike, so it reorders their heights by rounding only (a few machine
/// epsilons of the coordinates and the shift), far inside this band.
const LOWEST_BAND: f64 = 1e-9;

/// What the clean-ups read of a placed transfer (module doc), recorded a block of frames at a
/// time so that the frames need not be held: per frame, the centroid of each sole, and the
/// vertices of each leg low enough to be its lowest point once the frame is shifted (those
/// within [`LOWEST_BAND`] of the lowest, usually one).
#[derive(Clone, Debug, Default)]
pub struct FeetRecord {
    soles: [Vec<Vector3<f64>>; 2],
    /// `[leg][frame]`: the candidate vertices and the largest coordinate sum `|p|₁` of the leg.
    lowest: [Vec<(Vec<Vector3<f64>>, f64)>; 2],
}

impl FeetRecord {
    /// Records the placed, unshifted `frames` (the next ones of the motion).
    pub fn push(&mut self, frames: &[Vec<Vector3<f64>>], target: &TargetFeet, up: &Vector3<f64>) {
        for (all, new) in self.soles.iter_mut().zip(mesh_core::feet::feet_tracks(frames, &target.soles)) {
            all.extend(new);
        }
        for (record, leg) in self.lowest.iter_mut().zip(&target.legs) {
            record.extend(frames.iter().map(|f| {
                let lowest = leg.iter().map(|&v| f[v as usize].dot(up)).fold(f64::INFINITY, f64::min);
                let size = leg.iter().map(|&v| f[v as usize].abs().sum()).fold(0.0, f64::max);
                let band = LOWEST_BAND * (1.0 + size);
                let low = leg.iter().map(|&v| f[v as usize]).filter(|p| p.dot(up) <= lowest + band).collect();
                (low, size)
            }));
        }
    }

    /// Frames recorded.
    pub fn len(&self) -> usize {
        self.soles[0].len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Per frame, the lowest point along `up` of each leg once frame `t` is shifted by
    /// `shifts[t]` ([`lowest_points`] of the shifted frames, to the bit). Fails if a shift is so
    /// large that its rounding could reorder heights beyond the recorded band.
    fn lowest(&self, shifts: Option<&[Vector3<f64>]>, up: &Vector3<f64>) -> Result<[Vec<f64>; 2]> {
        let mut out: [Vec<f64>; 2] = Default::default();
        for (heights, record) in out.iter_mut().zip(&self.lowest) {
            for (t, (low, size)) in record.iter().enumerate() {
                let d = shifts.map_or_else(Vector3::zeros, |s| s[t]);
                if 16.0 * f64::EPSILON * (size + d.abs().sum()) > LOWEST_BAND * (1.0 + size) {
                    return Err(Error::invalid(format!("foot height: frame {t} shifted by {:.3e} m, beyond what the clean-up can place", d.norm())));
                }
                let shifted = |p: &Vector3<f64>| if shifts.is_some() { p + d } else { *p };
                heights.push(low.iter().map(|p| shifted(p).dot(up)).fold(f64::INFINITY, f64::min));
            }
        }
        Ok(out)
    }
}

/// The moves of the feet clean-ups for every frame of a transfer ([`solve`]), applied a frame
/// at a time ([`FeetMoves::apply`]).
#[derive(Clone, Debug, Default)]
pub struct FeetMoves {
    up: Vector3<f64>,
    /// The shift of each frame: horizontal (foot skating), plus the body's drop where the root
    /// height is regressed (foot height).
    shifts: Option<Vec<Vector3<f64>>>,
    /// Per leg (left, right), the drop of each frame and the leg vertices' weights (foot height).
    drops: Vec<(Vec<f64>, Vec<(u32, f64)>)>,
}

impl FeetMoves {
    /// Frame `t` of the transfer, placed, moved: shifted, then each leg dropped.
    pub fn apply(&self, t: usize, frame: &mut [Vector3<f64>]) {
        if let Some(d) = self.shifts.as_ref().and_then(|s| s.get(t)) {
            frame.iter_mut().for_each(|p| *p += d);
        }
        for (drops, weights) in &self.drops {
            if let Some(e) = drops.get(t) {
                for &(v, w) in weights {
                    frame[v as usize] += self.up * (e * w);
                }
            }
        }
    }
}

/// The clean-ups of a transfer (module doc) solved from its `record` (every frame placed; the
/// target `ratio` times the source's size) and the source's contacts: the moves to apply to each
/// frame and what they do. No moves when neither clean-up is asked for.
pub fn solve(
    record: &FeetRecord,
    source: &SourceContacts,
    target: &TargetFeet,
    target_pca: &PcaModel,
    ratio: f64,
    up: &Vector3<f64>,
    clean_up: &CleanUp,
    placement: Placement,
) -> Result<(FeetMoves, Planted)> {
    mesh_core::feet::check_smoothness(clean_up.smoothness)?;
    let contacts = &source.contacts;
    if record.len() != contacts.len() {
        return Err(Error::invalid(format!("feet clean-up: {} frames for {} source frames", record.len(), contacts.len())));
    }
    let mut notes = Vec::new();
    let mut planted = Planted { planted_frames: contacts.iter().filter(|c| c[0] || c[1]).count(), ..Planted::default() };
    let mut moves = FeetMoves { up: *up, ..FeetMoves::default() };
    if clean_up.footskate {
        let shifts = corrections(
            &record.soles,
            &mesh_core::feet::feet_tracks(&source.world, &source.soles),
            contacts,
            ratio,
            up,
            clean_up.smoothness,
            &mut notes,
        )?;
        planted.max_shift_m = shifts.iter().map(|d| d.norm()).fold(0.0, f64::max);
        moves.shifts = Some(shifts);
    }
    if clean_up.foot_height && placement != Placement::ScaledSource {
        let lowest = record.lowest(moves.shifts.as_deref(), up)?;
        let lower: Vec<f64> = lowest[0].iter().zip(&lowest[1]).map(|(l, r)| l.min(*r)).collect();
        let down: Vec<bool> = contacts.iter().map(|c| c[0] || c[1]).collect();
        let drops = leg_drops(&lower, &down, target.floor, clean_up.smoothness, &mut notes)?;
        planted.max_body_drop_m = drops.iter().map(|e| e.abs()).fold(0.0, f64::max);
        let mut shifts = moves.shifts.take().unwrap_or_else(|| vec![Vector3::zeros(); contacts.len()]);
        shifts.iter_mut().zip(&drops).for_each(|(d, e)| *d += up * *e);
        moves.shifts = Some(shifts);
    }
    if clean_up.foot_height {
        let lowest = record.lowest(moves.shifts.as_deref(), up)?;
        let template = target_pca.template_vertices();
        let mut moved = Vec::new();
        for side in 0..2 {
            let down: Vec<bool> = contacts.iter().map(|c| c[side]).collect();
            let drops = leg_drops(&lowest[side], &down, target.floor, clean_up.smoothness, &mut notes)?;
            let weights = mesh_core::feet::leg_weights(&target.legs[side], &target.soles[side], &template, clean_up.faces, up);
            moved.extend(down.iter().zip(&drops).filter(|(d, _)| **d).map(|(_, e)| e.abs()));
            moves.drops.push((drops, weights));
        }
        planted.median_foot_move_m = median(&mut moved);
    }
    for note in notes {
        mesh_core::info!("{note}");
    }
    Ok((moves, planted))
}

#[cfg(test)]
mod tests {
    use super::*;

    const UP: Vector3<f64> = Vector3::new(0.0, 1.0, 0.0);
    const RATIO: f64 = 1.2;

    /// Sole tracks of 40 frames: the source's left sole stands at x = 0.3 in frames 5-24 and
    /// moves at 2 cm/frame along x (and bobs in height) elsewhere; its right sole shuffles at
    /// 0.5 cm/frame along z in frames 10-29. The target's soles are the source's scaled by
    /// `RATIO`, plus `slide(t)` on the left sole.
    fn tracks(slide: impl Fn(usize) -> Vector3<f64>) -> ([Vec<Vector3<f64>>; 2], [Vec<Vector3<f64>>; 2], Vec<[bool; 2]>) {
        let left = |t: usize| {
            let x = if (5..25).contains(&t) { 0.3 } else if t < 5 { 0.3 - 0.02 * (5 - t) as f64 } else { 0.3 + 0.02 * (t - 24) as f64 };
            Vector3::new(x, if (5..25).contains(&t) { 0.0 } else { 0.05 }, 0.1)
        };
        let right = |t: usize| Vector3::new(0.5, 0.0, -0.1 + 0.005 * t as f64);
        let source: [Vec<Vector3<f64>>; 2] = [(0..40).map(left).collect(), (0..40).map(right).collect()];
        let target = [
            (0..40).map(|t| left(t) * RATIO + slide(t)).collect(),
            (0..40).map(|t| right(t) * RATIO).collect(),
        ];
        let contacts = (0..40).map(|t| [(5..25).contains(&t), (10..30).contains(&t)]).collect();
        (target, source, contacts)
    }

    fn shifted(track: &[Vector3<f64>], d: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        track.iter().zip(d).map(|(p, d)| p + d).collect()
    }

    /// Mean horizontal speed of `track` over the frames `range` (both ends in it).
    fn slide(track: &[Vector3<f64>], range: std::ops::Range<usize>) -> f64 {
        let h = |p: Vector3<f64>| p - UP * UP.dot(&p);
        let n = range.len() - 1;
        range.clone().skip(1).map(|t| h(track[t] - track[t - 1]).norm()).sum::<f64>() / n as f64
    }

    #[test]
    fn a_transfer_whose_soles_follow_the_scaled_source_is_left_alone() {
        // Planted, shuffling and swinging soles, a constant offset between the subjects: every
        // contact residual is zero, so is the correction.
        let (target, source, contacts) = tracks(|_| Vector3::new(0.7, 0.0, -0.2));
        let d = corrections(&target, &source, &contacts, RATIO, &UP, SMOOTHNESS, &mut Vec::new()).unwrap();
        assert!(d.iter().all(|d| d.norm() < 1e-12), "{d:?}");
    }

    /// A slip of the target's left sole, 3 cm over frames 12-17 and back by frame 22, while
    /// the source's stands, and a vertical bob.
    fn slip(t: usize) -> Vector3<f64> {
        let x = match t {
            12..=17 => 0.03 * (t - 11) as f64 / 6.0,
            18..=22 => 0.03 * (23 - t) as f64 / 6.0,
            _ => 0.0,
        };
        Vector3::new(x, 0.005 * (t % 3) as f64, 0.0)
    }

    #[test]
    fn a_sole_slipping_where_the_source_stands_is_pinned_and_a_shuffle_kept() {
        // The clean-up takes part of the slip out (measured: 29 %; the return weight keeps
        // it from pinning harder), moves nothing vertically, keeps the first frame, and the
        // right sole (down in frames 10-29, shuffling as the source's does) keeps shuffling at
        // the scaled source's speed, 0.6 cm/frame.
        let (target, source, contacts) = tracks(slip);
        let d = corrections(&target, &source, &contacts, RATIO, &UP, SMOOTHNESS, &mut Vec::new()).unwrap();
        assert_eq!(d[0], Vector3::zeros());
        assert!(d.iter().all(|d| d.y.abs() < 1e-12));
        let (before, after) = (slide(&target[0], 5..25), slide(&shifted(&target[0], &d), 5..25));
        assert!(after < 0.8 * before, "{before} -> {after}");
        let shuffle = slide(&shifted(&target[1], &d), 25..30);
        assert!((shuffle - 0.006).abs() < 5e-4, "{shuffle}");
    }

    #[test]
    fn a_persistent_slide_is_not_turned_into_drift() {
        // A slide that lasts the whole 20-frame contact (1.5 cm/frame) would need a shift that
        // persists; the clean-up takes out part of it and, once the contact ends at frame 25,
        // decays to a tenth of its peak within 8 frames instead of carrying on as drift.
        let (target, source, mut contacts) = tracks(|t| Vector3::new(0.015 * t.min(24) as f64, 0.0, 0.0));
        contacts.iter_mut().for_each(|c| c[1] = false);
        let d = corrections(&target, &source, &contacts, RATIO, &UP, SMOOTHNESS, &mut Vec::new()).unwrap();
        let peak = d.iter().map(|d| d.norm()).fold(0.0, f64::max);
        let (before, after) = (slide(&target[0], 5..25), slide(&shifted(&target[0], &d), 5..25));
        assert!(after < before && peak > 0.01, "{before} -> {after}, peak {peak}");
        assert!(d[33..].iter().all(|d| d.norm() < 0.1 * peak), "{:?}", &d[33..]);
    }

    #[test]
    fn no_contacts_no_shift_and_bad_smoothness_refused() {
        let (target, source, _) = tracks(|t| Vector3::new(0.01 * t as f64, 0.0, 0.0));
        let none = vec![[false; 2]; 40];
        let d = corrections(&target, &source, &none, RATIO, &UP, SMOOTHNESS, &mut Vec::new()).unwrap();
        assert!(d.iter().all(|d| *d == Vector3::zeros()));
        let e = corrections(&target, &source, &none, RATIO, &UP, -1.0, &mut Vec::new()).unwrap_err();
        assert!(e.to_string().contains("smoothness"), "{e}");
        let e = corrections(&target, &source, &none[..39], RATIO, &UP, SMOOTHNESS, &mut Vec::new()).unwrap_err();
        assert!(e.to_string().contains("39"), "{e}");
    }

    /// A leg whose lowest point floats 3 cm above a floor at 0.1 m where its foot is down
    /// (frames 5-24) and is 15 cm up elsewhere.
    fn floating() -> (Vec<f64>, Vec<bool>) {
        let down: Vec<bool> = (0..40).map(|t| (5..25).contains(&t)).collect();
        (down.iter().map(|&d| if d { 0.13 } else { 0.25 }).collect(), down)
    }

    #[test]
    fn a_floating_planted_foot_is_brought_down_onto_the_floor_and_eased_back_in_the_air() {
        // Through the contact the drop is -3 cm within 1 mm (the foot ends on the floor); it
        // fades back toward zero once the foot is up, by less than 1 cm per frame, and is under
        // a tenth of its size 8 frames after the contact.
        let (lowest, down) = floating();
        let e = leg_drops(&lowest, &down, 0.1, SMOOTHNESS, &mut Vec::new()).unwrap();
        assert!(e[8..22].iter().all(|e| (e + 0.03).abs() < 0.001), "{e:?}");
        assert!(e.windows(2).all(|w| (w[1] - w[0]).abs() < 0.01), "{e:?}");
        assert!(e[33..].iter().all(|e| e.abs() < 0.003), "{e:?}");
    }

    #[test]
    fn a_sinking_foot_is_raised_and_no_contact_means_no_move() {
        let (mut lowest, down) = floating();
        lowest.iter_mut().for_each(|l| *l -= 0.05);
        let e = leg_drops(&lowest, &down, 0.1, SMOOTHNESS, &mut Vec::new()).unwrap();
        assert!(e[8..22].iter().all(|e| (e - 0.02).abs() < 0.001), "{e:?}");
        let none = vec![false; 40];
        assert!(leg_drops(&lowest, &none, 0.1, SMOOTHNESS, &mut Vec::new()).unwrap().iter().all(|e| *e == 0.0));
        let e = leg_drops(&lowest, &down[..39], 0.1, SMOOTHNESS, &mut Vec::new()).unwrap_err();
        assert!(e.to_string().contains("39"), "{e}");
        assert!(leg_drops(&lowest, &down, 0.1, f64::NAN, &mut Vec::new()).is_err());
    }
}
