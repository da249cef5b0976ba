//! The named motions every player can perform, built from its
//! `animation.cfg` animations as the game plays them: a track of clips for
//! the legs and one for the torso, sampled at a fixed frame rate.
//!
//! A clip plays once (then holds its last frame), a number of cycles of its
//! looping frames, or for a time. A motion lasts as long as its leading
//! track; the other track keeps playing meanwhile (looping, or held on its
//! last frame). Since every player plays the same named animations, the
//! same instant *as a fraction of the motion* shows the same moment of the
//! movement (the same step of a walk cycle, the same stage of a fall): the
//! key-poses of a training pair are taken at equal fractions ([`keyposes`]).

use crate::animation_cfg::Animation;
use crate::character::{Character, FramePosition};

/// How long a clip plays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Play {
    /// Every frame once.
    Once,
    /// The non-looping frames, then this many cycles of the looping ones.
    Cycles(u32),
    /// This many seconds (looping or holding the last frame).
    Seconds(f64),
}

/// One animation of a track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    pub animation: &'static str,
    pub play: Play,
}

/// Which track sets the motion's length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lead {
    Legs,
    Torso,
}

/// A named motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionSpec {
    pub name: &'static str,
    /// What it shows, for the docs and `--help`.
    pub about: &'static str,
    pub legs: &'static [Clip],
    pub torso: &'static [Clip],
    pub lead: Lead,
}

const fn clip(animation: &'static str, play: Play) -> Clip {
    Clip { animation, play }
}
const STAND: &[Clip] = &[clip("TORSO_STAND", Play::Seconds(1.0))];
const IDLE: &[Clip] = &[clip("LEGS_IDLE", Play::Seconds(1.0))];
const DEATH1: &[Clip] = &[clip("BOTH_DEATH1", Play::Once), clip("BOTH_DEAD1", Play::Seconds(0.4))];
const DEATH2: &[Clip] = &[clip("BOTH_DEATH2", Play::Once), clip("BOTH_DEAD2", Play::Seconds(0.4))];
const DEATH3: &[Clip] = &[clip("BOTH_DEATH3", Play::Once), clip("BOTH_DEAD3", Play::Seconds(0.4))];

/// Every motion the builder knows, by name.
pub const MOTIONS: &[MotionSpec] = &[
    MotionSpec { name: "walk", about: "four walk cycles", legs: &[clip("LEGS_WALK", Play::Cycles(4))], torso: STAND, lead: Lead::Legs },
    MotionSpec { name: "run", about: "four run cycles", legs: &[clip("LEGS_RUN", Play::Cycles(4))], torso: STAND, lead: Lead::Legs },
    MotionSpec { name: "back", about: "four cycles of walking backwards", legs: &[clip("LEGS_BACK", Play::Cycles(4))], torso: STAND, lead: Lead::Legs },
    MotionSpec { name: "crouch", about: "four cycles of a crouched walk", legs: &[clip("LEGS_WALKCR", Play::Cycles(4))], torso: STAND, lead: Lead::Legs },
    MotionSpec { name: "crouched", about: "two seconds of the crouched idle", legs: &[clip("LEGS_IDLECR", Play::Seconds(2.0))], torso: STAND, lead: Lead::Legs },
    MotionSpec {
        name: "jump",
        about: "a jump, its landing and a second standing",
        legs: &[clip("LEGS_JUMP", Play::Once), clip("LEGS_LAND", Play::Once), clip("LEGS_IDLE", Play::Seconds(0.4))],
        torso: STAND,
        lead: Lead::Legs,
    },
    MotionSpec { name: "gesture", about: "the torso's taunt gesture, standing", legs: IDLE, torso: &[clip("TORSO_GESTURE", Play::Once)], lead: Lead::Torso },
    MotionSpec { name: "death1", about: "the first death fall, then lying still", legs: DEATH1, torso: DEATH1, lead: Lead::Legs },
    MotionSpec { name: "death2", about: "the second death fall, then lying still", legs: DEATH2, torso: DEATH2, lead: Lead::Legs },
    MotionSpec { name: "death3", about: "the third death fall, then lying still", legs: DEATH3, torso: DEATH3, lead: Lead::Legs },
];

/// The motion named `name`.
pub fn motion(name: &str) -> Option<&'static MotionSpec> {
    MOTIONS.iter().find(|m| m.name == name)
}

/// Seconds a clip of `anim` plays.
pub fn clip_seconds(anim: &Animation, play: Play) -> f64 {
    match play {
        Play::Once => anim.count as f64 / anim.fps,
        Play::Cycles(n) if anim.looping > 0 => {
            (anim.count - anim.looping + n as usize * anim.looping) as f64 / anim.fps
        }
        Play::Cycles(_) => anim.count as f64 / anim.fps,
        Play::Seconds(s) => s,
    }
}

/// A track resolved against one character: its animations and when each starts.
struct Track {
    clips: Vec<(Animation, f64)>,
    seconds: f64,
}

impl Track {
    fn new(character: &Character, clips: &[Clip]) -> std::result::Result<Track, String> {
        let mut out = Vec::with_capacity(clips.len());
        let mut start = 0.0;
        for c in clips {
            let anim = character.animation(c.animation)?;
            out.push((anim, start));
            start += clip_seconds(&anim, c.play);
        }
        Ok(Track { clips: out, seconds: start })
    }

    /// Where the track is at `time` seconds: within the last clip that has
    /// started (the last clip runs on past its end).
    fn at(&self, time: f64) -> FramePosition {
        let (anim, start) = self
            .clips
            .iter()
            .rev()
            .find(|(_, start)| *start <= time)
            .unwrap_or(&self.clips[0]);
        let steps = ((time - start) * anim.fps).max(0.0);
        let f = steps.floor();
        let whole = f as usize;
        FramePosition { a: anim.frame_at(whole), b: anim.frame_at(whole + 1), t: steps - f }
    }
}

/// The frames of `motion` performed by `character` at `fps` frames per
/// second: per frame the legs' and the torso's positions. A motion has at
/// least two frames.
pub fn sample(
    character: &Character,
    motion: &MotionSpec,
    fps: f64,
) -> std::result::Result<Vec<(FramePosition, FramePosition)>, String> {
    let legs = Track::new(character, motion.legs)?;
    let torso = Track::new(character, motion.torso)?;
    let seconds = match motion.lead {
        Lead::Legs => legs.seconds,
        Lead::Torso => torso.seconds,
    };
    let n = ((seconds * fps).round() as usize).max(2);
    Ok((0..n)
        .map(|i| {
            let time = i as f64 / fps;
            (legs.at(time), torso.at(time))
        })
        .collect())
}

/// `count` key-poses `[source_frame, target_frame]` of a pair of motions of
/// `n_source` and `n_target` frames: the centres of `count` equal slices of
/// each.
pub fn keyposes(n_source: usize, n_target: usize, count: usize) -> Vec<[usize; 2]> {
    let at = |n: usize, k: usize| (((k as f64 + 0.5) * n as f64 / count as f64) as usize).min(n - 1);
    (0..count).map(|k| [at(n_source, k), at(n_target, k)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animation_cfg::Model;

    fn anim(count: usize, looping: usize, fps: f64) -> Animation {
        Animation { first: 10, count, looping, fps, reversed: false, model: Model::Legs }
    }

    #[test]
    fn clip_lengths_follow_the_frame_counts_and_rates() {
        assert_eq!(clip_seconds(&anim(30, 0, 25.0), Play::Once), 1.2);
        assert_eq!(clip_seconds(&anim(12, 12, 20.0), Play::Cycles(4)), 2.4);
        // Two lead-in frames, then three cycles of four looping frames.
        assert_eq!(clip_seconds(&anim(6, 4, 10.0), Play::Cycles(3)), 1.4);
        assert_eq!(clip_seconds(&anim(6, 0, 10.0), Play::Cycles(3)), 0.6);
        assert_eq!(clip_seconds(&anim(6, 0, 10.0), Play::Seconds(0.25)), 0.25);
    }

    #[test]
    fn a_track_interpolates_between_frames_and_moves_to_the_next_clip() {
        let track = Track { clips: vec![(anim(4, 4, 10.0), 0.0), (Animation { first: 50, ..anim(2, 0, 5.0) }, 0.8)], seconds: 1.2 };
        let p = track.at(0.25);
        assert_eq!((p.a, p.b), (12, 13));
        assert!((p.t - 0.5).abs() < 1e-9);
        // Just before the end of the first cycle: frame 3 blending into frame 0 again.
        let p = track.at(0.39);
        assert_eq!((p.a, p.b), (13, 10));
        let p = track.at(0.9);
        assert_eq!((p.a, p.b), (50, 51));
        // Past its end the last clip holds its last frame.
        let p = track.at(5.0);
        assert_eq!((p.a, p.b), (51, 51));
    }

    #[test]
    fn keyposes_sit_at_equal_fractions_of_both_motions() {
        assert_eq!(keyposes(50, 100, 5), vec![[5, 10], [15, 30], [25, 50], [35, 70], [45, 90]]);
        let k = keyposes(3, 7, 5);
        assert!(k.iter().all(|[s, t]| *s < 3 && *t < 7));
        assert!(k.windows(2).all(|w| w[0][0] <= w[1][0] && w[0][1] < w[1][1]));
    }

    #[test]
    fn motion_names_are_unique_plain_names() {
        for (i, m) in MOTIONS.iter().enumerate() {
            assert!(m.name.chars().all(|c| c.is_ascii_alphanumeric()), "{}", m.name);
            assert!(MOTIONS[i + 1..].iter().all(|o| o.name != m.name), "{}", m.name);
            assert_eq!(motion(m.name), Some(m));
        }
    }
}
