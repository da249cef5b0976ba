//! The sampled variants of the learned sequences that guide a blend, made once and kept beside
//! the model (3DV §7 blends variants made offline): a blend query at any w* then reads the
//! variants of the learned weights bounding w* instead of sampling them again, and only blends,
//! decodes and cleans up.
//!
//! One file per learned sequence and sampler setting, `<model>.variants/<sequence>-<key>.art`, an
//! artifact (`mesh_core::artifact`) of kind [`CachedVariants::KIND`]: its payload holds the
//! [`VariantKey`] (the model file's SHA-256, the build's, the sequence and every setting the
//! samples depend on) with the variants and their chain statistics; `<key>` is a hash of the
//! key. A file is used only when its key equals the query's, so the same flags give the same
//! bytes with or without the file. A file that cannot be read, is corrupt or holds another
//! key (another model, build or setting) is named in one warning and replaced by the variants
//! sampled again. Files are written atomically; a failed write leaves a warning and the query's
//! output as it is.

use std::path::{Path, PathBuf};

use gpdm::hmc::HmcOptions;
use mesh_core::artifact::{Artifact, Header};
use mesh_core::{Error, Result};
use serde::{Deserialize, Serialize};

use crate::reconstruct::Decoder;
use crate::sample::{matched_variations, sequence_variations_len, ChainStats, HmcStart, Sampler, Variations};
use crate::synthesize::SynthConfig;

/// Everything the sampled variants of one learned sequence depend on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariantKey {
    /// SHA-256 of the model file (lowercase hex).
    pub model_sha256: String,
    /// Identity of the build that samples ([`this_build`]): another build's sampler may draw
    /// other variants.
    pub build: String,
    /// The learned sequence: its index in the model and its name.
    pub sequence: usize,
    pub name: String,
    /// Frames per variant (at the capture's rate).
    pub frames: usize,
    pub sampler: Sampler,
    pub variance_scale: f64,
    /// Variants (`-n`), the seed and the HMC settings (the ancestral sampler falls back to
    /// HMC chains where its draws leave the learned data, so they count for it too).
    pub n: usize,
    pub seed: u64,
    pub hmc_start: HmcStart,
    pub burn_in: usize,
    pub thin: usize,
    pub target_accept: f64,
    pub leapfrog_steps: usize,
    pub initial_step: f64,
}

impl VariantKey {
    /// A 64-bit FNV-1a hash of the key's JSON, as 16 hex digits (the file name's `<key>`).
    fn hash(&self) -> String {
        let json = serde_json::to_string(self).expect("a key serialises");
        let h = json.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
        format!("{h:016x}")
    }
}

/// The payload of a cache file: its key, the variants (`variations[k][part]`, frames × latent
/// dimension) and the statistics of the chains that drew them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CachedVariants {
    pub key: VariantKey,
    pub chains: Vec<ChainStats>,
    pub variations: Variations,
}

impl Artifact for CachedVariants {
    const KIND: &'static str = "variation-variants";
    const VERSION: u32 = 1;

    /// `key.n` variations of the same parts, each `key.frames` rows of finite numbers.
    fn validate(&self) -> std::result::Result<(), String> {
        if self.variations.len() != self.key.n {
            return Err(format!("{} variations, the key says {}", self.variations.len(), self.key.n));
        }
        let parts = self.variations.first().map_or(0, Vec::len);
        for (k, v) in self.variations.iter().enumerate() {
            if v.len() != parts {
                return Err(format!("variation {k} has {} parts, variation 0 {parts}", v.len()));
            }
            if let Some(x) = v.iter().find(|x| x.nrows() != self.key.frames || x.iter().any(|c| !c.is_finite())) {
                return Err(format!("variation {k}: a part of {} frames or not finite", x.nrows()));
            }
        }
        Ok(())
    }
}

/// Where the variants of a model are kept, and the identities their keys hold.
#[derive(Clone, Debug)]
pub struct VariantCache {
    pub dir: PathBuf,
    pub model_sha256: String,
    pub build: String,
}

impl VariantCache {
    /// The cache beside `model` (`<model>.variants/`) of the model whose file has SHA-256
    /// `model_sha256`, sampled by the build `build`.
    pub fn beside(model: &Path, model_sha256: String, build: String) -> VariantCache {
        let mut dir = model.as_os_str().to_owned();
        dir.push(".variants");
        VariantCache { dir: dir.into(), model_sha256, build }
    }

    /// The file of `key`: `<dir>/<sequence name>-<key hash>.art` (the name's characters other than
    /// letters, digits, `.`, `-` and `_` as `_`).
    pub fn path(&self, key: &VariantKey) -> PathBuf {
        let name: String = key
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') { c } else { '_' })
            .collect();
        self.dir.join(format!("{name}-{}.art", key.hash()))
    }

    /// The variants of `key` when its file holds them for `dec`'s model; None when there is no
    /// file, and a warning naming it when it cannot be used.
    fn read(&self, key: &VariantKey, dec: &Decoder) -> Option<CachedVariants> {
        let path = self.path(key);
        if !path.is_file() {
            return None;
        }
        let problem = match CachedVariants::load(&path) {
            Err(e) => e.to_string(),
            Ok(c) if c.key != *key => {
                format!("{}: variants of another model, build or setting", path.display())
            }
            Ok(c) if !fits(&c, dec) => format!("{}: variants of another body", path.display()),
            Ok(c) => return Some(c),
        };
        mesh_core::warn!("{problem}: not used, sampled again");
        None
    }

    /// Keeps `c` in its file (atomically); a failure is a warning.
    fn write(&self, c: &CachedVariants) {
        let path = self.path(&c.key);
        let header = Header::new("hmc-sample", env!("CARGO_PKG_VERSION")).with_seed(c.key.seed);
        if let Err(e) = c.save(&path, &header) {
            mesh_core::warn!("{e}: the variants are not kept");
        }
    }
}

/// This program's identity as a build: its executable's size and modification time (a rebuild
/// changes them; hashing its tens of megabytes would cost a query a fifth of a second).
pub fn this_build() -> Result<String> {
    let exe = std::env::current_exe().map_err(|e| Error::invalid(format!("the path of this program: {e}")))?;
    let meta = std::fs::metadata(&exe).map_err(|e| Error::io(&exe, e))?;
    let modified = meta.modified().map_err(|e| Error::io(&exe, e))?;
    let since = modified.duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
    Ok(format!("{} bytes, modified {}.{:09}", meta.len(), since.as_secs(), since.subsec_nanos()))
}

/// Whether the variants have the model's parts and their latent dimensions.
fn fits(c: &CachedVariants, dec: &Decoder) -> bool {
    let dims: Vec<Option<usize>> =
        dec.model.parts.iter().map(|p| p.gpdm.sequence_latent(c.key.sequence).map(|l| l.ncols())).collect();
    c.variations
        .iter()
        .all(|v| v.len() == dims.len() && v.iter().zip(&dims).all(|(x, d)| *d == Some(x.ncols())))
}

/// The variants of learned sequence `s` for a query of `cfg` (`frames` frames, HMC settings
/// `hmc`) and the statistics of their chains: read from `cache` when it holds them, else
/// sampled ([`sequence_variations_len`], one chain per part; [`matched_variations`] with
/// motion matching, which is never cached) and kept there.
pub fn variants(
    dec: &Decoder,
    s: usize,
    frames: usize,
    cfg: &SynthConfig,
    hmc: &HmcOptions,
    cache: Option<&VariantCache>,
) -> Result<(Variations, Vec<ChainStats>)> {
    if cfg.sampler == Sampler::MotionMatching {
        return matched_variations(dec, s, frames, hmc.n_samples, cfg.seed, &cfg.motion_matching);
    }
    let sample = || sequence_variations_len(dec, s, frames, cfg.sampler, cfg.variance_scale, hmc, 1);
    let Some(cache) = cache else { return sample() };
    let key = VariantKey {
        model_sha256: cache.model_sha256.clone(),
        build: cache.build.clone(),
        sequence: s,
        name: dec.model.sequences.get(s).map_or_else(String::new, |q| q.name.clone()),
        frames,
        sampler: cfg.sampler,
        variance_scale: cfg.variance_scale,
        n: hmc.n_samples,
        seed: hmc.seed,
        hmc_start: cfg.hmc_start,
        burn_in: hmc.burn_in,
        thin: hmc.thin,
        target_accept: hmc.target_accept,
        leapfrog_steps: hmc.leapfrog_steps,
        initial_step: hmc.initial_step,
    };
    if let Some(c) = cache.read(&key, dec) {
        mesh_core::info!("{}: variants read from {}", key.name, cache.path(&key).display());
        replay_notes(&c.chains, cfg.sampler);
        return Ok((c.variations, c.chains));
    }
    let (variations, chains) = sample()?;
    let c = CachedVariants { key, chains, variations };
    cache.write(&c);
    Ok((c.variations, c.chains))
}

/// The messages the sampling of `chains` printed (`sample::sequence_variations_len`), again.
fn replay_notes(chains: &[ChainStats], sampler: Sampler) {
    for c in chains {
        if sampler == Sampler::Hmc && c.started_at_learned {
            mesh_core::warn!(
                "{} part '{}': the mean prediction leaves the learned data (3DV eq. 13's variance above {} of the prior's); its chains start at the learned trajectory",
                c.sequence,
                c.part,
                gpdm::hmc::OFF_DATA_VARIANCE
            );
        }
        if sampler == Sampler::Ancestral && c.hmc_instead {
            mesh_core::info!(
                "{} part '{}': ancestral draws leave the learned data; its variants are HMC chains",
                c.sequence,
                c.part
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> VariantKey {
        VariantKey {
            model_sha256: "ab".repeat(32),
            build: "1 bytes, modified 0.000000000".into(),
            sequence: 2,
            name: "blend-0.5".into(),
            frames: 100,
            sampler: Sampler::Hmc,
            variance_scale: 0.3,
            n: 10,
            seed: 0,
            hmc_start: HmcStart::Mean,
            burn_in: 200,
            thin: 10,
            target_accept: 0.7,
            leapfrog_steps: 20,
            initial_step: 0.01,
        }
    }

    #[test]
    fn every_setting_and_identity_names_another_file_beside_the_model() {
        let cache = VariantCache::beside(Path::new("work/loc.model"), "ab".repeat(32), "b".into());
        let p = cache.path(&key());
        assert_eq!(p.parent(), Some(Path::new("work/loc.model.variants")));
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        assert!(name.starts_with("blend-0.5-") && name.ends_with(".art") && name.len() == "blend-0.5-".len() + 16 + 4, "{name}");
        let others = [
            VariantKey { model_sha256: "cd".repeat(32), ..key() },
            VariantKey { build: "2 bytes, modified 0.000000000".into(), ..key() },
            VariantKey { frames: 101, ..key() },
            VariantKey { sampler: Sampler::Ancestral, ..key() },
            VariantKey { variance_scale: 1.0, ..key() },
            VariantKey { n: 11, ..key() },
            VariantKey { seed: 1, ..key() },
            VariantKey { hmc_start: HmcStart::Ancestral, ..key() },
            VariantKey { burn_in: 50, ..key() },
            VariantKey { thin: 5, ..key() },
            VariantKey { target_accept: 0.8, ..key() },
        ];
        for k in others {
            assert_ne!(cache.path(&k), p, "{k:?}");
        }
        let odd = VariantKey { name: "a/b c".into(), ..key() };
        assert!(cache.path(&odd).file_name().unwrap().to_string_lossy().starts_with("a_b_c-"));
    }

    #[test]
    fn a_payload_of_the_wrong_shape_is_invalid() {
        let x = nalgebra::DMatrix::zeros(100, 5);
        let good = CachedVariants { key: VariantKey { n: 2, ..key() }, chains: Vec::new(), variations: vec![vec![x.clone()]; 2] };
        assert_eq!(good.validate(), Ok(()));
        let fewer = CachedVariants { variations: vec![vec![x.clone()]], ..good.clone() };
        assert!(fewer.validate().unwrap_err().contains("1 variations"));
        let short = CachedVariants { variations: vec![vec![x.clone()], vec![x.rows(0, 99).into_owned()]], ..good.clone() };
        assert!(short.validate().is_err());
        let mut nan = good.clone();
        nan.variations[1][0][(3, 1)] = f64::NAN;
        assert!(nan.validate().is_err());
    }
}
