//! A Quake 3 player's `animation.cfg`: the named animations of its legs
//! (`lower.md3`) and torso (`upper.md3`) models.
//!
//! The file holds optional keywords (`sex m`, `headoffset x y z`,
//! `footsteps NAME`, `fixedlegs`, `fixedtorso`), then one line of four
//! numbers per animation: first frame, frame count, looping frames and
//! frames per second. The animations are named by their order, as the game
//! reads them ([`NAMES`]; the comments on the lines are not read). A negative
//! frame count plays the frames backwards; an fps of 0 is read as 1.
//!
//! The file numbers frames as if the torso's animations were followed by the
//! legs': the legs model holds the `BOTH_*` frames and then the `LEGS_*`
//! frames directly, so every `LEGS_*` first frame is lowered by
//! `LEGS_WALKCR.first - TORSO_GESTURE.first`, as the game does.

use std::collections::BTreeMap;
use std::path::Path;

use mesh_core::{Error, Result};

/// The animations of a player, in the order the file lists them. The six
/// after `LEGS_TURN` (Team Arena's) are optional.
pub const NAMES: &[&str] = &[
    "BOTH_DEATH1",
    "BOTH_DEAD1",
    "BOTH_DEATH2",
    "BOTH_DEAD2",
    "BOTH_DEATH3",
    "BOTH_DEAD3",
    "TORSO_GESTURE",
    "TORSO_ATTACK",
    "TORSO_ATTACK2",
    "TORSO_DROP",
    "TORSO_RAISE",
    "TORSO_STAND",
    "TORSO_STAND2",
    "LEGS_WALKCR",
    "LEGS_WALK",
    "LEGS_RUN",
    "LEGS_BACK",
    "LEGS_SWIM",
    "LEGS_JUMP",
    "LEGS_LAND",
    "LEGS_JUMPB",
    "LEGS_LANDB",
    "LEGS_IDLE",
    "LEGS_IDLECR",
    "LEGS_TURN",
    "TORSO_GETFLAG",
    "TORSO_GUARDBASE",
    "TORSO_PATROL",
    "TORSO_FOLLOWME",
    "TORSO_AFFIRMATIVE",
    "TORSO_NEGATIVE",
];

/// How many of [`NAMES`] every file must give.
pub const REQUIRED: usize = 25;

/// Which model's frames an animation indexes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// `lower.md3`.
    Legs,
    /// `upper.md3`.
    Torso,
    /// Both (`BOTH_*`: the same frame numbers in both models).
    Both,
}

/// One named animation, with its first frame in its own model's numbering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Animation {
    pub first: usize,
    pub count: usize,
    /// The last `looping` frames repeat once the animation has played; 0: it
    /// stays on its last frame.
    pub looping: usize,
    pub fps: f64,
    pub reversed: bool,
    pub model: Model,
}

impl Animation {
    /// The frame shown at step `f` (whole frames since the animation
    /// started), as the game's `CG_RunLerpFrame` picks it: the frames in
    /// order, then the looping tail over and over, or the last frame held.
    pub fn frame_at(&self, f: usize) -> usize {
        let f = if f < self.count {
            f
        } else if self.looping > 0 {
            let looping = self.looping.min(self.count);
            (f - self.count) % looping + self.count - looping
        } else {
            self.count - 1
        };
        if self.reversed {
            self.first + self.count - 1 - f
        } else {
            self.first + f
        }
    }

    /// The last frame number this animation shows (for checking it against
    /// its model's frame count).
    pub fn last_frame(&self) -> usize {
        self.first + self.count - 1
    }
}

/// The parsed file.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationConfig {
    /// `m`, `f`, `n` as given (empty when absent).
    pub sex: String,
    pub animations: BTreeMap<&'static str, Animation>,
}

impl AnimationConfig {
    /// The animation named `name` (one of [`NAMES`]).
    pub fn get(&self, name: &str) -> Option<&Animation> {
        self.animations.get(name)
    }
}

fn model_of(name: &str) -> Model {
    if name.starts_with("LEGS_") {
        Model::Legs
    } else if name.starts_with("TORSO_") {
        Model::Torso
    } else {
        Model::Both
    }
}

/// Parses `animation.cfg` text; the error is the problem without the file name.
pub fn parse_animation_cfg(bytes: &[u8]) -> std::result::Result<AnimationConfig, String> {
    let text = String::from_utf8_lossy(bytes);
    let mut sex = String::new();
    let mut rows: Vec<(usize, [i64; 3], f64)> = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let ln = ln + 1;
        let line = line.split("//").next().unwrap_or_default();
        let tokens: Vec<&str> = line.split_whitespace().collect();
        let Some(first) = tokens.first() else { continue };
        if first.starts_with(|c: char| c.is_ascii_digit() || c == '-') {
            if rows.len() == NAMES.len() {
                continue; // lines past the known animations are ignored, as the game does
            }
            if tokens.len() < 4 {
                return Err(format!("line {ln}: an animation needs 4 numbers (first, count, looping, fps)"));
            }
            let mut n = [0i64; 3];
            for (k, t) in tokens[..3].iter().enumerate() {
                n[k] = t
                    .parse()
                    .map_err(|_| format!("line {ln}: bad number '{}'", t.chars().take(40).collect::<String>()))?;
            }
            let fps: f64 = tokens[3]
                .parse()
                .map_err(|_| format!("line {ln}: bad frame rate '{}'", tokens[3].chars().take(40).collect::<String>()))?;
            if !fps.is_finite() || fps < 0.0 {
                return Err(format!("line {ln}: frame rate {fps} is not a non-negative number"));
            }
            rows.push((ln, n, fps));
        } else if rows.is_empty() {
            if first.eq_ignore_ascii_case("sex") {
                sex = tokens.get(1).map_or(String::new(), |s| s.chars().take(8).collect());
            }
            // headoffset, footsteps, fixedlegs, fixedtorso: nothing here depends on them.
        } else {
            return Err(format!("line {ln}: '{}' among the animation lines", first.chars().take(40).collect::<String>()));
        }
    }
    if rows.len() < REQUIRED {
        return Err(format!(
            "{} animation lines, fewer than the {REQUIRED} a player needs (BOTH_DEATH1 ... LEGS_TURN)",
            rows.len()
        ));
    }
    let gesture_first = rows[6].1[0];
    let skip = rows[13].1[0].saturating_sub(gesture_first);
    let mut animations = BTreeMap::new();
    for (k, (ln, [first, count, looping], fps)) in rows.into_iter().enumerate() {
        let name = NAMES[k];
        let model = model_of(name);
        let first = if model == Model::Legs && k < REQUIRED { first.saturating_sub(skip) } else { first };
        let reversed = count < 0;
        let count = count.unsigned_abs();
        if first < 0 || count == 0 || looping < 0 || count > u32::MAX as u64 || first > u32::MAX as i64 {
            return Err(format!(
                "line {ln} ({name}): first frame {first}, {count} frames, {looping} looping: not a playable animation"
            ));
        }
        animations.insert(
            name,
            Animation {
                first: first as usize,
                count: count as usize,
                looping: (looping as u64).min(count) as usize,
                fps: if fps == 0.0 { 1.0 } else { fps },
                reversed,
                model,
            },
        );
    }
    Ok(AnimationConfig { sex, animations })
}

/// Reads `animation.cfg`; errors are one line naming the file.
pub fn read_animation_cfg(path: impl AsRef<Path>) -> Result<AnimationConfig> {
    let path = path.as_ref();
    let bytes = mesh_core::input::read_regular_file(path)?;
    parse_animation_cfg(&bytes).map_err(|m| Error::file(path, m))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 25 lines of a player whose legs animations start at file frame 153
    /// while its torso's start at 90: the legs model numbers them from 90.
    fn config_text() -> String {
        let mut s = String::from("// comment\nsex m\nheadoffset 0 0 0\nfootsteps boot\n\n");
        let rows = [
            (0, 30, 0, 25), (29, 1, 0, 25), (30, 30, 0, 25), (59, 1, 0, 25), (60, 30, 0, 25), (89, 1, 0, 25),
            (90, 40, 0, 13), (130, 6, 0, 15), (136, 6, 0, 15), (142, 5, 0, 20), (147, 4, 0, 20),
            (151, 1, 0, 15), (152, 1, 0, 15),
            (153, 8, 8, 20), (161, 12, 12, 20), (173, 9, 9, 15), (182, 10, 10, 18), (185, 10, 10, 15),
            (202, 8, 0, 15), (211, 8, 0, 20), (219, 9, 0, 15), (228, -6, 0, 20), (234, 10, 4, 10),
            (244, 10, 10, 0), (254, 7, 7, 18),
        ];
        for (a, b, c, d) in rows {
            s += &format!("{a}\t{b}\t{c}\t{d}\t\t// a name the reader ignores\n");
        }
        s
    }

    #[test]
    fn animations_are_named_by_their_order_and_legs_frames_are_renumbered() {
        let cfg = parse_animation_cfg(config_text().as_bytes()).unwrap();
        assert_eq!(cfg.sex, "m");
        let death = cfg.get("BOTH_DEATH1").unwrap();
        assert_eq!((death.first, death.count, death.model), (0, 30, Model::Both));
        let gesture = cfg.get("TORSO_GESTURE").unwrap();
        assert_eq!((gesture.first, gesture.count, gesture.fps, gesture.model), (90, 40, 13.0, Model::Torso));
        // 153 - 90 = 63 frames of the torso's numbering are not in the legs model.
        let walk = cfg.get("LEGS_WALK").unwrap();
        assert_eq!((walk.first, walk.count, walk.looping, walk.model), (161 - 63, 12, 12, Model::Legs));
        assert_eq!(cfg.get("LEGS_WALKCR").unwrap().first, 90);
        assert_eq!(cfg.get("LEGS_IDLECR").unwrap().fps, 1.0, "fps 0 reads as 1");
        assert!(cfg.get("LEGS_LANDB").unwrap().reversed);
        assert!(cfg.get("TORSO_GETFLAG").is_none());
    }

    #[test]
    fn frames_play_in_order_then_loop_the_tail_or_hold_the_last() {
        let cfg = parse_animation_cfg(config_text().as_bytes()).unwrap();
        let walk = cfg.get("LEGS_WALK").unwrap();
        let frames: Vec<usize> = (0..26).map(|f| walk.frame_at(f) - walk.first).collect();
        assert_eq!(frames, [(0..12).collect::<Vec<_>>(), (0..12).collect(), vec![0, 1]].concat());
        // LEGS_IDLE: 10 frames, the last 4 looping.
        let idle = cfg.get("LEGS_IDLE").unwrap();
        let frames: Vec<usize> = (8..16).map(|f| idle.frame_at(f) - idle.first).collect();
        assert_eq!(frames, vec![8, 9, 6, 7, 8, 9, 6, 7]);
        let death = cfg.get("BOTH_DEATH1").unwrap();
        assert_eq!(death.frame_at(100), 29);
        // LEGS_LANDB is played backwards: 6 frames from its last.
        let landb = cfg.get("LEGS_LANDB").unwrap();
        assert_eq!(landb.frame_at(0), landb.first + 5);
        assert_eq!(landb.frame_at(9), landb.first);
    }

    #[test]
    fn a_short_or_malformed_file_is_refused_with_one_line() {
        let text = config_text();
        let short: String = text.lines().take(20).map(|l| format!("{l}\n")).collect();
        let cases = [
            (short, "fewer than the 25"),
            (text.replacen("161\t12", "161\tx", 1), "bad number 'x'"),
            (text.replacen("161\t12\t12\t20", "161\t12", 1), "needs 4 numbers"),
            (text.replacen("254\t7\t7\t18", "254\t7\t7\tnan", 1), "not a non-negative number"),
            (text.replacen("0\t30\t0\t25", "0\t0\t0\t25", 1), "not a playable animation"),
            (text.replacen("202\t8", "1\t8", 1), "not a playable animation"),
            (format!("{text}sex m\n"), "among the animation lines"),
        ];
        for (bad, expected) in cases {
            let err = parse_animation_cfg(bad.as_bytes()).expect_err(expected);
            assert!(err.contains(expected), "'{err}' does not say '{expected}'");
            assert!(!err.contains('\n'));
        }
    }
}
