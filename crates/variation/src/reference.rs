//! Reference trajectories: what the post-processes of a sampled variation read of its source
//! sequence, computed once from the source's meshes and stored in the trained model, so that a
//! query of a training sequence needs the model alone.
//!
//! Per source frame `t` ([`Reference`]): the heading `h_s(t)` of the root part's core about the
//! up axis (the course step, [`crate::course::keep`]); the height of the body's lowest point
//! (grounding, [`crate::grounding::ground_on`], and the floor, their minimum over the frames);
//! the height of each leg's lowest point (the foot heights, [`crate::foot_height::lift`], and the
//! contacts completed at the clip's ends, [`crate::foot_lock::close_clip_ends`]); and the
//! matcher's rows, the subsampled vertices of the frame rigidly aligned to the template (the DTW
//! correspondence, [`crate::grounding::MatchSource`]). The contacts are the sequence's own
//! (`train::SequenceInfo::contacts`). The vertices all of these are measured on ([`Landmarks`])
//! follow from the template, its faces, parts and up axis, which the model holds.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::grounding::{self, MatchSource};
use crate::group::{root_core, PartDef};

/// The vertices the post-processes measure on, from the body alone.
#[derive(Clone, Debug)]
pub struct Landmarks {
    /// The root part's core (`group::root_core`): headings are measured on it.
    pub core: Vec<u32>,
    /// Sole vertices of both feet ([`crate::group::soles`]; empty where none are found).
    pub soles: Vec<Vec<u32>>,
    /// The two soles when both are found.
    pub feet: Option<[Vec<u32>; 2]>,
    /// [`mesh_core::feet::leg_weights`] of the two leg parts (None without both feet and both
    /// leg parts); their vertices are the legs.
    pub leg_weights: Option<[Vec<(u32, f64)>; 2]>,
}

impl Landmarks {
    /// The landmarks of a body: template vertices and faces, its parts, up axis.
    pub fn of(template: &[Vector3<f64>], faces: &[[u32; 3]], parts: &[PartDef], up: &Vector3<f64>) -> Landmarks {
        let soles = crate::group::soles(parts, template, up, mesh_core::feet::SOLE_TOLERANCE);
        let feet: Option<[Vec<u32>; 2]> = match soles.as_slice() {
            [l, r] if !l.is_empty() && !r.is_empty() => Some([l.clone(), r.clone()]),
            _ => None,
        };
        let leg_weights = feet.as_ref().and_then(|f| match crate::foot_lock::leg_parts(parts).as_slice() {
            [l, r] => Some([0, 1].map(|k| mesh_core::feet::leg_weights(&[l, r][k].vertices, &f[k], template, faces, up))),
            _ => None,
        });
        Landmarks { core: root_core(parts, template.len()), soles, feet, leg_weights }
    }

    /// Each leg's vertices (None without leg weights).
    pub fn legs(&self) -> Option<[Vec<u32>; 2]> {
        self.leg_weights.as_ref().map(|w| [0, 1].map(|f| w[f].iter().map(|p| p.0).collect()))
    }
}

/// The reference trajectories of one source sequence (module doc), one entry per source frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// Heading of the root part's core from the first frame (radians, unwrapped;
    /// [`crate::course::headings`]).
    pub heading: Vec<f64>,
    /// Height along up of the body's lowest vertex ([`grounding::lowest`] of every vertex).
    pub lowest: Vec<f64>,
    /// Height along up of each leg's lowest vertex; empty when the body has no two legs
    /// ([`Landmarks::leg_weights`]).
    pub leg_lowest: Vec<[f64; 2]>,
    /// The DTW matcher's rows: [`grounding::match_vertices`] of the frame after its rigid
    /// alignment to the template.
    pub match_rows: Vec<Vec<Vector3<f64>>>,
}

impl Reference {
    /// The reference of the source frames `frames` (world coordinates, template topology).
    pub fn of(
        frames: &[Vec<Vector3<f64>>],
        template: &[Vector3<f64>],
        landmarks: &Landmarks,
        up: &Vector3<f64>,
    ) -> Reference {
        let leg_lowest = match landmarks.legs() {
            Some(legs) => {
                let [l, r] = legs.map(|leg| grounding::lowest(frames, &leg, up));
                l.into_iter().zip(r).map(|(a, b)| [a, b]).collect()
            }
            None => Vec::new(),
        };
        Reference {
            heading: crate::course::headings(frames, &landmarks.core, up),
            lowest: grounding::lowest(frames, &[], up),
            leg_lowest,
            match_rows: MatchSource::new(frames, template).into_rows(),
        }
    }

    /// The reference `(1 - t) x + t y` of two references of the same frames and vertices,
    /// every trajectory interpolated linearly frame by frame (the matcher's rows vertex by
    /// vertex); an error naming what differs when they do not match.
    pub fn between(x: &Reference, y: &Reference, t: f64) -> std::result::Result<Reference, String> {
        if x.heading.len() != y.heading.len()
            || x.lowest.len() != y.lowest.len()
            || x.leg_lowest.len() != y.leg_lowest.len()
            || x.match_rows.len() != y.match_rows.len()
        {
            return Err(format!("references of {} and {} frames cannot be interpolated", x.len(), y.len()));
        }
        if x.match_rows.iter().zip(&y.match_rows).any(|(a, b)| a.len() != b.len()) {
            return Err("references of different matcher rows cannot be interpolated".to_string());
        }
        let mix = |a: f64, b: f64| a + t * (b - a);
        Ok(Reference {
            heading: x.heading.iter().zip(&y.heading).map(|(&a, &b)| mix(a, b)).collect(),
            lowest: x.lowest.iter().zip(&y.lowest).map(|(&a, &b)| mix(a, b)).collect(),
            leg_lowest: x.leg_lowest.iter().zip(&y.leg_lowest).map(|(a, b)| [mix(a[0], b[0]), mix(a[1], b[1])]).collect(),
            match_rows: x
                .match_rows
                .iter()
                .zip(&y.match_rows)
                .map(|(ra, rb)| ra.iter().zip(rb).map(|(p, q)| p + (q - p) * t).collect())
                .collect(),
        })
    }

    /// Source frames covered.
    pub fn len(&self) -> usize {
        self.lowest.len()
    }

    /// No frames.
    pub fn is_empty(&self) -> bool {
        self.lowest.is_empty()
    }

    /// The lowest height over every frame: the source's floor.
    pub fn floor(&self) -> f64 {
        self.lowest.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Per frame, each leg's lowest height above `floor` (empty without legs).
    pub fn legs_above(&self, floor: f64) -> Vec<[f64; 2]> {
        self.leg_lowest.iter().map(|h| [h[0] - floor, h[1] - floor]).collect()
    }

    /// The lowest heights of leg `f` (empty without legs).
    pub fn leg(&self, f: usize) -> Vec<f64> {
        self.leg_lowest.iter().map(|h| h[f]).collect()
    }

    /// The DTW matcher over these rows.
    pub fn matcher(&self, template: &[Vector3<f64>]) -> MatchSource {
        MatchSource::from_rows(template, self.match_rows.clone())
    }

    /// Checks the reference against `frames` source frames of a template of `n_vertices`
    /// vertices, with or without legs: every trajectory has one entry per frame and the
    /// matcher's rows their vertex count; every value is finite. The problem, or Ok.
    pub fn check(&self, frames: usize, n_vertices: usize, legs: bool) -> std::result::Result<(), String> {
        let row = grounding::match_vertices(n_vertices).len();
        let leg_frames = if legs { frames } else { 0 };
        if self.heading.len() != frames || self.lowest.len() != frames || self.match_rows.len() != frames {
            return Err(format!(
                "reference trajectories of {} headings, {} heights and {} matcher rows for {frames} frames",
                self.heading.len(),
                self.lowest.len(),
                self.match_rows.len()
            ));
        }
        if self.leg_lowest.len() != leg_frames {
            return Err(format!("{} leg heights for {leg_frames} frames", self.leg_lowest.len()));
        }
        if let Some(t) = self.match_rows.iter().position(|r| r.len() != row) {
            return Err(format!("matcher row {t} of {} vertices, expected {row}", self.match_rows[t].len()));
        }
        let finite = self.heading.iter().chain(&self.lowest).chain(self.leg_lowest.iter().flatten()).all(|v| v.is_finite())
            && self.match_rows.iter().flatten().all(|p| p.iter().all(|v| v.is_finite()));
        if !finite {
            return Err("a reference trajectory holds a value that is not finite".to_string());
        }
        Ok(())
    }
}
