//! A blend query's guiding variants kept beside the model (`variation::variant_cache`): the
//! cached query writes the same bytes as the uncached one, and a corrupt file or one of another
//! model or setting is named in one warning and not used.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// Every file under `dir` (relative path → bytes).
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(p.strip_prefix(root).unwrap().to_path_buf(), std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// The cache files beside `model`, sorted.
fn cached(model: &Path) -> Vec<PathBuf> {
    let dir = PathBuf::from(format!("{}.variants", model.display()));
    let mut v: Vec<PathBuf> = match std::fs::read_dir(&dir) {
        Ok(r) => r.map(|e| e.unwrap().path()).collect(),
        Err(_) => Vec::new(),
    };
    v.sort();
    v
}

/// A small blend query of `model` at 0.3 (between walk and the pre-blend at 0.5) into `out`,
/// with `extra` flags; its stderr, lines sorted.
fn blend(model: &Path, out: &Path, extra: &[&str]) -> String {
    blend_at("0.3", model, out, extra)
}

/// [`blend`] at weight `w`.
fn blend_at(w: &str, model: &Path, out: &Path, extra: &[&str]) -> String {
    let (m, o) = (s(model), s(out));
    let mut args = vec![
        "--model", &m, "--blend", "walk:run", "--weight", w, "-n", "3", "--frame-count", "30",
        "--burn-in", "20", "--thin", "2", "--frame-format", "pc2", "--out", &o,
    ];
    args.extend_from_slice(extra);
    let run = common::ok(env!("CARGO_BIN_EXE_hmc-sample"), &args);
    // The chains run in parallel: their messages in any order.
    let mut lines: Vec<String> = String::from_utf8_lossy(&run.stderr).lines().map(str::to_string).collect();
    lines.sort();
    lines.join("\n")
}

#[test]
fn a_cached_blend_query_writes_the_same_bytes_as_the_uncached_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, model) = common::tiny_model(d);

    // Uncached, then the query that fills the cache, then the one that reads it: the same
    // bytes, and the same messages (no terminal: none on success beyond the sampler's).
    let plain = blend(&model, &d.join("plain"), &["--no-variant-cache"]);
    assert!(cached(&model).is_empty(), "--no-variant-cache wrote {:?}", cached(&model));
    let filled = blend(&model, &d.join("filled"), &[]);
    let kept = cached(&model);
    let names: Vec<String> = kept.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names.len(), 2, "one file per bounding learned weight: {names:?}");
    assert!(names[0].starts_with("blend-0.5-") && names[1].starts_with("walk-"), "{names:?}");
    let read = blend(&model, &d.join("read"), &[]);
    assert_eq!(plain, filled);
    assert_eq!(plain, read);
    let want = files(&d.join("plain"));
    assert!(!want.is_empty());
    assert_eq!(files(&d.join("filled")), want, "the query that fills the cache");
    assert_eq!(files(&d.join("read")), want, "the query that reads it");
    let verbose = blend(&model, &d.join("read-v"), &["-v"]);
    assert_eq!(verbose.matches("variants read from").count(), 2, "{verbose}");
    assert_eq!(cached(&model), kept, "a cache hit writes nothing");
    // Another weight between the same learned weights reads the same files.
    let other = blend_at("0.4", &model, &d.join("other-w"), &["-v"]);
    assert_eq!(other.matches("variants read from").count(), 2, "{other}");

}

#[test]
fn a_corrupt_cache_file_is_named_in_one_line_and_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, model) = common::tiny_model(d);
    let plain = blend(&model, &d.join("plain"), &["--no-variant-cache"]);
    let want = files(&d.join("plain"));
    blend(&model, &d.join("filled"), &[]);
    let walk = cached(&model)[1].clone();
    let mut bytes = std::fs::read(&walk).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&walk, &bytes).unwrap();
    let warned = blend(&model, &d.join("corrupt"), &[]);
    let lines: Vec<&str> = warned.lines().filter(|l| l.contains(&s(&walk))).collect();
    assert_eq!(lines.len(), 1, "{warned}");
    assert!(lines[0].contains("not used, sampled again"), "{warned}");
    assert_eq!(files(&d.join("corrupt")), want, "after a corrupt cache file");
    assert_eq!(blend(&model, &d.join("repaired"), &[]), plain, "the file was replaced");

}

#[test]
fn a_cache_file_of_another_model_or_setting_is_not_used() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (group, model) = common::tiny_model(d);
    blend(&model, &d.join("filled"), &[]);
    let kept = cached(&model);
    let walk = kept[1].clone();

    // Another setting's file under this setting's name: not used.
    blend(&model, &d.join("seed1"), &["--seed", "1"]);
    let seed1: Vec<PathBuf> = cached(&model).into_iter().filter(|p| !kept.contains(p)).collect();
    assert_eq!(seed1.len(), 2, "{seed1:?}");
    let walk1 = seed1.iter().find(|p| p.file_name().unwrap().to_string_lossy().starts_with("walk-")).unwrap();
    std::fs::copy(&walk, walk1).unwrap();
    let warned = blend(&model, &d.join("foreign-setting"), &["--seed", "1"]);
    assert!(warned.contains(&format!("{}: variants of another model, build or setting: not used", walk1.display())), "{warned}");
    assert_eq!(files(&d.join("foreign-setting")), files(&d.join("seed1")));

    // Another model's files beside this model: not used; the output is this model's.
    let other_model = d.join("other.model");
    common::ok(
        env!("CARGO_BIN_EXE_gpdm-train"),
        &["-q", "--group", &s(&group), "--max-iter", "20", "--out", &s(&other_model)],
    );
    let other_plain = blend(&other_model, &d.join("other-plain"), &["--no-variant-cache"]);
    let other_dir = PathBuf::from(format!("{}.variants", other_model.display()));
    std::fs::create_dir_all(&other_dir).unwrap();
    for p in &kept {
        std::fs::copy(p, other_dir.join(p.file_name().unwrap())).unwrap();
    }
    let warned = blend(&other_model, &d.join("other-cached"), &[]);
    assert_eq!(files(&d.join("other-cached")), files(&d.join("other-plain")));
    // The copied files have this model's names: another model's key is another name, so they
    // are never read (nor named); a copy under this model's own names is refused by its key.
    assert_eq!(warned, other_plain, "{warned}");
    let own = cached(&other_model).into_iter().find(|p| !kept.iter().any(|k| k.file_name() == p.file_name()) && p.file_name().unwrap().to_string_lossy().starts_with("walk-")).unwrap();
    std::fs::copy(&walk, &own).unwrap();
    let warned = blend(&other_model, &d.join("other-foreign"), &[]);
    assert!(warned.contains(&format!("{}: variants of another model, build or setting: not used", own.display())), "{warned}");
    assert_eq!(files(&d.join("other-foreign")), files(&d.join("other-plain")));
}
