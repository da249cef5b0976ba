//! What a blend's variations follow (3DV §7): the reference trajectories and contacts of the
//! blend's source, the non-linear mesh blend of two captured motions at w*.
//!
//! Two ways to obtain them ([`BlendGuide`]): `exact` blends the two captures' meshes at w* per
//! query (`group::blend_sequences_at`, deformation gradients and Poisson) and measures the
//! result ([`Reference::of`]); `stored` reads the model alone: the references the model stores
//! of the learned weights of that pair (the two motions at 0 and 1 and every pre-blend between
//! them, `sample::blend_entries`) interpolated linearly in w* between the nearest learned weight
//! on each side ([`Reference::between`]). At a learned weight both are the same (the pre-blends
//! are made by the same blend). The contacts are the same in both: motion `a`'s below w* = 0.5,
//! `b`'s from it on, as `group::blend_sequences_at` assigns them.

use clap::ValueEnum;
use serde::{Deserialize, Serialize};

use crate::contacts::Contacts;
use crate::reference::Reference;
use crate::sample::blend_entries;
use crate::train::VariationModel;

/// Where a blend query's reference trajectories come from (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum BlendGuide {
    /// The blend of the two captures' meshes at w*, made per query (needs the group).
    #[default]
    Exact,
    /// The model's references of the nearest learned weights on each side of w*, interpolated.
    Stored,
}

/// The stored guide of the blend at `w` ∈ [0, 1] of the model's captured motions `a` (w = 0)
/// and `b` (w = 1): the interpolated reference and the contacts (module doc).
pub fn stored(model: &VariationModel, a: usize, b: usize, w: f64) -> Result<(Reference, Option<Contacts>), String> {
    let entries = blend_entries(model, a, b);
    let lo = entries.iter().rev().find(|e| e.0 <= w).unwrap_or(&entries[0]);
    let hi = entries.iter().find(|e| e.0 >= w).unwrap_or(&entries[entries.len() - 1]);
    let t = if hi.0 > lo.0 { (w - lo.0) / (hi.0 - lo.0) } else { 0.0 };
    let (ra, rb) = (&model.sequences[lo.1].reference, &model.sequences[hi.1].reference);
    let reference = Reference::between(ra, rb, t).map_err(|e| {
        format!(
            "blend of '{}' and '{}' at {w}: {e}",
            model.sequences[a].name, model.sequences[b].name
        )
    })?;
    let contacts = if w < 0.5 { &model.sequences[a].contacts } else { &model.sequences[b].contacts };
    Ok((reference, contacts.clone()))
}

/// The largest differences between two references of the same frames: heading (radians),
/// lowest height, leg lowest height and matcher row vertex (metres). None when they do not
/// cover the same frames and vertices.
pub fn difference(x: &Reference, y: &Reference) -> Option<[f64; 4]> {
    let same = x.len() == y.len()
        && x.heading.len() == y.heading.len()
        && x.leg_lowest.len() == y.leg_lowest.len()
        && x.match_rows.len() == y.match_rows.len()
        && x.match_rows.iter().zip(&y.match_rows).all(|(a, b)| a.len() == b.len());
    if !same {
        return None;
    }
    let most = |d: &mut dyn Iterator<Item = f64>| d.fold(0.0, f64::max);
    Some([
        most(&mut x.heading.iter().zip(&y.heading).map(|(a, b)| (a - b).abs())),
        most(&mut x.lowest.iter().zip(&y.lowest).map(|(a, b)| (a - b).abs())),
        most(&mut x.leg_lowest.iter().zip(&y.leg_lowest).flat_map(|(a, b)| [(a[0] - b[0]).abs(), (a[1] - b[1]).abs()])),
        most(&mut x.match_rows.iter().zip(&y.match_rows).flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).norm()))),
    ])
}
