//! The `characters` stage: capture sets from real animated game characters
//! (OpenArena's Quake 3 players, fetched by `scripts/fetch-assets`), one per
//! source:target pair. `src/bin/characters.rs` only parses [`Params`] and
//! calls [`run`].

use std::path::{Path, PathBuf};

use clap::Parser;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::character::Character;
use crate::set_writer::{write_set, SetPlan};

/// The motions each pair trains on and tests on by default (every motion is in [`crate::motions::MOTIONS`]).
pub const TRAIN: &[&str] = &["walk", "run", "jump", "death1"];
pub const TEST: &[&str] = &["back", "crouch"];
/// Where the players came from (recorded in each `set.json`).
pub const PROVENANCE: &str = "OpenArena 0.8.5 player models (Debian openarena-data and \
    openarena-081-players 0.8.5split-14, GPL-2+): lower.md3, upper.md3, head.md3, animation.cfg";

/// Build capture sets from real animated game characters (Quake 3 MD3 players), one per pair
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "characters",
    version,
    after_help = "e.g.: characters --out out/characters         # sarge-sorceress and major-liz\n\
                  e.g.: characters --characters smarine:assassin --fps 30 --out out/characters\n\
                  (needs scripts/fetch-assets first)"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// A pair of players SOURCE:TARGET (folder names under --assets); repeat for more sets
    #[arg(long, value_name = "SOURCE:TARGET", default_values_t = ["sarge:sorceress".to_string(), "major:liz".to_string()])]
    pub characters: Vec<String>,
    /// Training motions of every pair, from: walk, run, back, crouch, crouched, jump, gesture, death1, death2, death3
    #[arg(long, value_delimiter = ',', value_name = "A,B,...", default_values_t = TRAIN.iter().map(|m| m.to_string()))]
    pub train: Vec<String>,
    /// Test motions of every pair; the target's own performance of each is written as its reference
    #[arg(long, value_delimiter = ',', value_name = "A,B,...", default_values_t = TEST.iter().map(|m| m.to_string()))]
    pub test: Vec<String>,
    /// Frame rate of every motion written
    #[arg(long, value_name = "F", default_value_t = 25.0)]
    pub fps: f64,
    /// Folder of player folders (<name>/{lower,upper,head}.md3, animation.cfg)
    /// [default: $SURFCAP_CACHE/assets/openarena, else ~/.cache/surfcap/assets/openarena]
    #[arg(long)]
    pub assets: Option<PathBuf>,
    /// Output folder: one capture set per pair, OUT/<SOURCE>-<TARGET>
    #[arg(short, long)]
    pub out: PathBuf,
}

/// The players' folder: `--assets`, else the one `scripts/fetch-assets` fills.
fn assets_dir(p: &Params) -> anyhow::Result<PathBuf> {
    if let Some(dir) = &p.assets {
        return Ok(dir.clone());
    }
    let cache = match std::env::var_os("SURFCAP_CACHE") {
        Some(c) if !c.is_empty() => PathBuf::from(c),
        _ => match std::env::var_os("HOME") {
            Some(h) => Path::new(&h).join(".cache/surfcap"),
            None => anyhow::bail!("neither SURFCAP_CACHE nor HOME is set: give --assets"),
        },
    };
    let dir = cache.join("assets/openarena");
    if !dir.join(".complete-v1").is_file() {
        anyhow::bail!("{}: characters missing or incomplete: run scripts/fetch-assets first", dir.display());
    }
    Ok(dir)
}

/// A `SOURCE:TARGET` pair of plain names.
fn parse_pair(text: &str) -> anyhow::Result<(String, String)> {
    let plain = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    match text.split_once(':') {
        Some((a, b)) if plain(a) && plain(b) && a != b => Ok((a.to_string(), b.to_string())),
        _ => anyhow::bail!("--characters {text}: expected SOURCE:TARGET, two different player names"),
    }
}

/// Writes one capture set per pair.
pub fn run(p: &Params) -> anyhow::Result<()> {
    if !(p.fps.is_finite() && p.fps > 0.0) {
        anyhow::bail!("--fps {}: expected a positive number of frames per second", p.fps);
    }
    let train: Vec<&str> = p.train.iter().map(String::as_str).collect();
    let test: Vec<&str> = p.test.iter().map(String::as_str).collect();
    if let Some(m) = train.iter().find(|m| test.contains(m)) {
        anyhow::bail!("--train and --test both name '{m}': a motion is either trained on or tested on");
    }
    let pairs = p.characters.iter().map(|c| parse_pair(c)).collect::<anyhow::Result<Vec<_>>>()?;
    let assets = assets_dir(p)?;
    let mut loaded: std::collections::BTreeMap<String, Character> = Default::default();
    for (a, b) in &pairs {
        for name in [a, b] {
            if !loaded.contains_key(name) {
                loaded.insert(name.clone(), Character::load(&assets.join(name))?);
            }
        }
    }
    for (a, b) in &pairs {
        let plan = SetPlan {
            source: &loaded[a],
            target: &loaded[b],
            train: &train,
            test: &test,
            fps: p.fps,
            provenance: PROVENANCE,
        };
        let out = p.out.join(format!("{a}-{b}"));
        let s = write_set(&plan, &out)?;
        mesh_core::info!(
            "wrote {}: {} {} vertices in {} pieces, {:.2} m; {} {} vertices in {} pieces, {:.2} m",
            out.display(),
            s[0].name,
            s[0].vertices,
            s[0].components,
            s[0].height_m,
            s[1].name,
            s[1].vertices,
            s[1].components,
            s[1].height_m
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        let argv = ["characters", "--out", "sets"];
        assert_eq!(mesh_core::cli::unrecorded_options::<Params>(&argv).unwrap(), Vec::<String>::new());
    }

    #[test]
    fn the_help_names_every_motion() {
        use clap::CommandFactory;
        let help = Params::command().render_long_help().to_string();
        for m in crate::motions::MOTIONS {
            assert!(help.contains(&format!(" {},", m.name)) || help.contains(&format!(" {}\n", m.name)), "{}", m.name);
        }
    }

    #[test]
    fn a_motion_is_trained_on_or_tested_on_not_both() {
        let p = Params::try_parse_from(["characters", "--train", "walk,back", "--out", "/nonexistent"]).unwrap();
        let e = run(&p).unwrap_err().to_string();
        assert!(e.contains("'back'"), "{e}");
    }

    #[test]
    fn pairs_are_two_different_plain_names() {
        assert_eq!(parse_pair("sarge:sorceress").unwrap(), ("sarge".into(), "sorceress".into()));
        for bad in ["sarge", "sarge:sarge", ":liz", "a/b:c", "a:b:c"] {
            assert!(parse_pair(bad).is_err(), "{bad}");
        }
    }
}
