//! Frames a viewer cannot accept: a whole-body **turn** between consecutive frames faster than
//! the captures ever turn, and a **tear**, an edge stretched longer than any edge of any
//! captured frame.
//!
//! The turn of frame `t` is the angle of the rotation of the best rigid fit (Procrustes over all
//! vertices) taking frame `t − 1` onto frame `t`; frame 0 does not turn. The captures' rate is
//! the largest such angle over the captured (not pre-blended) sequences of the group, divided
//! by the number of capture frames the prealignment's frame map steps over (a step of two
//! capture frames counts half its angle; a repeated frame is skipped). A variation frame spins
//! when it turns faster than [`SPIN_FACTOR`] times that rate, and tears when its longest edge
//! exceeds [`TEAR_FACTOR`] times the longest edge of any captured frame.
//!
//! A whole-body turn is also what a limb swinging fast does to the fit, and a landing's pitch;
//! what a viewer calls a spin is a turn about the vertical. A frame **spins about the vertical**
//! when the heading of the root part's core (below) changes from the frame before by more than
//! [`SPIN_FACTOR`] times the captures' fastest such change (step-normalised as above).
//!
//! A slow turn passes that bound frame by frame and still takes a body off its course: a
//! variation frame is **off course** when its torso has turned from the variation's first frame
//! by more than [`SPIN_FACTOR`] times the most any captured sequence of the group turns from its
//! own first frame. That angle is the heading about the up axis of the best rigid fit of the root
//! part's core ([`crate::group::root_core`]), frame 0 onto frame `t` (over every vertex, two
//! strides whose legs and arms have swapped fit best turned by up to 180°; a lean is not a turn).

use mesh_core::rigid::procrustes;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::group::Group;

/// A frame spins when it turns faster than this multiple of the captures' fastest turn.
pub const SPIN_FACTOR: f64 = 1.25;
/// A frame tears when an edge is longer than this multiple of the captures' longest edge.
pub const TEAR_FACTOR: f64 = 1.5;

/// Angle (degrees) of the whole-body turn from each frame to the next: `turns[t]` is the turn
/// from frame `t` to frame `t + 1` (one fewer than the frames).
pub fn turn_degrees(frames: &[Vec<Vector3<f64>>]) -> Vec<f64> {
    frames
        .windows(2)
        .map(|w| procrustes(&w[0], &w[1], None).rotation.angle().to_degrees())
        .collect()
}

/// How far (degrees, unsigned) the vertices `core` (every vertex when empty) of each frame have
/// turned about `up` from the first frame: the heading of [`crate::course::headings`], so
/// that a lean into a run is not counted as a turn.
pub fn course_degrees(frames: &[Vec<Vector3<f64>>], core: &[u32], up: &Vector3<f64>) -> Vec<f64> {
    crate::course::headings(frames, core, up).into_iter().map(|h| h.to_degrees().abs()).collect()
}

/// Change of heading (degrees, unsigned) about `up` of the vertices `core` from each frame to
/// the next ([`course_degrees`]' heading): one fewer than the frames.
pub fn heading_turn_degrees(frames: &[Vec<Vector3<f64>>], core: &[u32], up: &Vector3<f64>) -> Vec<f64> {
    crate::course::headings(frames, core, up).windows(2).map(|w| (w[1] - w[0]).to_degrees().abs()).collect()
}

/// Length of the longest edge of each frame (model units, metres).
pub fn longest_edges(frames: &[Vec<Vector3<f64>>], edges: &[[u32; 2]]) -> Vec<f64> {
    frames
        .iter()
        .map(|f| {
            edges
                .iter()
                .map(|&[a, b]| (f[a as usize] - f[b as usize]).norm())
                .fold(0.0, f64::max)
        })
        .collect()
}

/// The captures' own figures, which the variations are held to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CaptureLimits {
    /// Fastest whole-body turn of any captured frame (degrees per frame).
    pub max_turn_deg: f64,
    /// Longest edge of any captured frame (m).
    pub max_edge_m: f64,
    /// The most any captured sequence turns from its first frame (degrees).
    #[serde(default)]
    pub max_course_turn_deg: f64,
    /// Fastest change of heading about the vertical of any captured frame (degrees per frame).
    #[serde(default)]
    pub max_heading_turn_deg: f64,
}

impl CaptureLimits {
    /// The figures of the group's captured sequences (pre-blends left out; module doc).
    pub fn of_group(group: &Group) -> CaptureLimits {
        let edges = crate::metrics::edges(&group.faces);
        let core = crate::group::root_core(&group.parts, group.template.len());
        let mut limits = CaptureLimits { max_turn_deg: 0.0, max_edge_m: 0.0, max_course_turn_deg: 0.0, max_heading_turn_deg: 0.0 };
        for s in group.sequences.iter().filter(|s| s.blend.is_none()) {
            let frames = s.motion.world_frames();
            let headings = heading_turn_degrees(&frames, &core, &group.up);
            for (t, (turn, heading)) in turn_degrees(&frames).into_iter().zip(headings).enumerate() {
                let step = match (s.map.get(t), s.map.get(t + 1)) {
                    (Some(&a), Some(&b)) => b.saturating_sub(a),
                    _ => 1,
                };
                if step > 0 {
                    limits.max_turn_deg = limits.max_turn_deg.max(turn / step as f64);
                    limits.max_heading_turn_deg = limits.max_heading_turn_deg.max(heading / step as f64);
                }
            }
            let longest = longest_edges(&frames, &edges).into_iter().fold(0.0, f64::max);
            limits.max_edge_m = limits.max_edge_m.max(longest);
            let course = course_degrees(&frames, &core, &group.up).into_iter().fold(0.0, f64::max);
            limits.max_course_turn_deg = limits.max_course_turn_deg.max(course);
        }
        limits
    }

    /// Turns faster than this spin (degrees per frame).
    pub fn spin_bound_deg(&self) -> f64 {
        SPIN_FACTOR * self.max_turn_deg
    }

    /// Heading changes faster than this spin about the vertical (degrees per frame).
    pub fn heading_spin_bound_deg(&self) -> f64 {
        SPIN_FACTOR * self.max_heading_turn_deg
    }

    /// Edges longer than this tear (m).
    pub fn tear_bound_m(&self) -> f64 {
        TEAR_FACTOR * self.max_edge_m
    }

    /// Frames turned further than this from the first are off course (degrees).
    pub fn course_bound_deg(&self) -> f64 {
        SPIN_FACTOR * self.max_course_turn_deg
    }
}

/// One variation's spins and tears against [`CaptureLimits`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TurnsAndTears {
    /// Frames that turn faster than the spin bound (a frame `t ≥ 1` turns from `t − 1`).
    pub spinning_frames: Vec<usize>,
    /// Frames whose heading changes faster than the heading bound: spins about the vertical.
    #[serde(default)]
    pub heading_spinning_frames: Vec<usize>,
    /// Frames holding an edge longer than the tear bound.
    pub torn_frames: Vec<usize>,
    /// Frames turned from the first further than the course bound.
    #[serde(default)]
    pub off_course_frames: Vec<usize>,
    /// The most the variation turns from its first frame (degrees).
    #[serde(default)]
    pub max_course_turn_deg: f64,
    /// Fastest turn of the variation (degrees per frame) and its longest edge (m).
    pub max_turn_deg: f64,
    pub max_edge_m: f64,
    /// Fastest change of heading of the variation (degrees per frame).
    #[serde(default)]
    pub max_heading_turn_deg: f64,
    /// Steps between frames the turn limit slowed ([`crate::turn_limit`]; 0 without it).
    #[serde(default)]
    pub slowed_steps: usize,
}

impl TurnsAndTears {
    /// The spins and tears of `frames` (`edges`: the mesh's unique edges; `core`: the vertices
    /// the course is measured on, [`course_degrees`], about `up`).
    pub fn of(frames: &[Vec<Vector3<f64>>], edges: &[[u32; 2]], core: &[u32], up: &Vector3<f64>, limits: &CaptureLimits) -> Self {
        let turns = turn_degrees(frames);
        let longest = longest_edges(frames, edges);
        let course = course_degrees(frames, core, up);
        let headings = heading_turn_degrees(frames, core, up);
        TurnsAndTears {
            heading_spinning_frames: (0..headings.len()).filter(|&t| headings[t] > limits.heading_spin_bound_deg()).map(|t| t + 1).collect(),
            max_heading_turn_deg: headings.iter().copied().fold(0.0, f64::max),
            off_course_frames: (0..course.len()).filter(|&t| course[t] > limits.course_bound_deg()).collect(),
            max_course_turn_deg: course.iter().copied().fold(0.0, f64::max),
            spinning_frames: (0..turns.len())
                .filter(|&t| turns[t] > limits.spin_bound_deg())
                .map(|t| t + 1)
                .collect(),
            torn_frames: (0..longest.len())
                .filter(|&t| longest[t] > limits.tear_bound_m())
                .collect(),
            max_turn_deg: turns.iter().copied().fold(0.0, f64::max),
            max_edge_m: longest.iter().copied().fold(0.0, f64::max),
            slowed_steps: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    /// A small irregular point cloud (no symmetry, so the fit's rotation is unique).
    fn body() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.1, 0.0),
            Vector3::new(0.2, 1.3, 0.1),
            Vector3::new(0.1, 0.2, 0.7),
            Vector3::new(0.5, 0.4, 0.3),
        ]
    }

    fn turned(deg: f64) -> Vec<Vector3<f64>> {
        let r = Rotation3::from_axis_angle(&Vector3::y_axis(), deg.to_radians());
        body().iter().map(|p| r * p + Vector3::new(3.0, 0.0, 1.0)).collect()
    }

    #[test]
    fn a_body_turned_about_its_up_axis_turns_by_that_angle_whatever_its_travel() {
        let frames = vec![turned(0.0), turned(10.0), turned(35.0), turned(-140.0)];
        let turns = turn_degrees(&frames);
        for (got, want) in turns.iter().zip([10.0, 25.0, 175.0]) {
            assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        }
    }

    #[test]
    fn frames_past_the_bounds_are_named_and_frames_within_them_are_not() {
        let limits = CaptureLimits { max_turn_deg: 8.0, max_edge_m: 1.0, max_course_turn_deg: 20.0, max_heading_turn_deg: 8.0 };
        let mut frames = vec![turned(0.0), turned(9.0), turned(30.0), turned(31.0)];
        // Frame 3 also has a stretched point: its edge 0-1 grows past 1.5 m.
        frames[3][1] += Vector3::new(0.0, 0.0, 2.0);
        let edges = [[0, 1], [1, 2]];
        let r = TurnsAndTears::of(&frames, &edges, &[], &Vector3::y(), &limits);
        // 9° is within 1.25 × 8° = 10°; 21° is not; frame 3 turns by its tear's fit.
        assert!(r.spinning_frames.contains(&2) && !r.spinning_frames.contains(&1));
        assert_eq!(r.torn_frames, vec![3]);
        // 30° and 31° from the first frame are past 1.25 × 20° = 25°; 9° is not.
        assert_eq!(r.off_course_frames, vec![2, 3]);
        assert!((r.max_edge_m - longest_edges(&frames, &edges)[3]).abs() < 1e-12);
    }

    fn pitched(deg: f64) -> Vec<Vector3<f64>> {
        let r = Rotation3::from_axis_angle(&Vector3::x_axis(), deg.to_radians());
        body().iter().map(|p| r * p).collect()
    }

    /// A body turned about the vertical spins about it at the turn's rate; one pitched forward
    /// (a landing's crouch) turns as a whole body and does not change its heading.
    #[test]
    fn a_turn_about_the_vertical_changes_the_heading_and_a_pitch_does_not() {
        let limits = CaptureLimits { max_turn_deg: 4.0, max_edge_m: 10.0, max_course_turn_deg: 90.0, max_heading_turn_deg: 4.0 };
        let turning: Vec<_> = [0.0, 3.0, 12.0, 13.0].iter().map(|&d| turned(d)).collect();
        let heading = heading_turn_degrees(&turning, &[], &Vector3::y());
        for (got, want) in heading.iter().zip([3.0, 9.0, 1.0]) {
            assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        }
        let r = TurnsAndTears::of(&turning, &[[0, 1]], &[], &Vector3::y(), &limits);
        assert_eq!((r.spinning_frames.clone(), r.heading_spinning_frames.clone()), (vec![2], vec![2]));
        let pitching: Vec<_> = [0.0, 3.0, 12.0, 13.0].iter().map(|&d| pitched(d)).collect();
        let r = TurnsAndTears::of(&pitching, &[[0, 1]], &[], &Vector3::y(), &limits);
        assert_eq!(r.spinning_frames, vec![2]);
        assert!(r.heading_spinning_frames.is_empty() && r.max_heading_turn_deg < 1e-9, "{r:?}");
    }

    #[test]
    fn a_slow_steady_turn_spins_nowhere_but_goes_off_course() {
        // 6° a frame for 20 frames: under an 8°/frame capture rate at every step, 114° from the
        // start by the end, against captures that turn at most 15° from their first frame.
        let limits = CaptureLimits { max_turn_deg: 8.0, max_edge_m: 10.0, max_course_turn_deg: 15.0, max_heading_turn_deg: 8.0 };
        let frames: Vec<_> = (0..20).map(|t| turned(6.0 * t as f64)).collect();
        let r = TurnsAndTears::of(&frames, &[[0, 1]], &[], &Vector3::y(), &limits);
        assert!(r.spinning_frames.is_empty(), "{:?}", r.spinning_frames);
        // 18.75° is the bound: frames 4 (24°) on are off course.
        assert_eq!(r.off_course_frames, (4..20).collect::<Vec<_>>());
        assert!((r.max_course_turn_deg - 114.0).abs() < 1e-9);
    }
}
