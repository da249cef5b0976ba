//! Where the foot sliding of written variations comes from: every frame pair that the
//! independent height rule ([`variation::metrics::foot_sliding`]) counts is classed by the
//! contacts the clean-ups used (the source's, transferred along the DTW): both frames planted,
//! one (a contact's start or end), or none (a swing foot passing low over the floor).
//!
//! Every swing pair faster than 2 cm/frame is listed with its frames and the nearest transferred
//! contact of that foot. Also prints the lowest vertex of each variation, and with BASE (another
//! hmc-sample --out of the same model and seed) how far the clean-ups moved it.
//!
//! Usage: slide_sources GROUP MODEL DIR [BASE] (DIR = hmc-sample --out). With
//! `--blends 0.25,0.75`, also the variations of the group's first two motions blended at those
//! weights (`blend-W`, as `hmc-sample --blends` writes them), against the same blended sources
//! and contacts as hmc-sample builds.

use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;
use variation::footskate::transfer_contacts;
use variation::group::Group;
use variation::train::VariationModel;

/// Height of the lowest vertex of sole `so` in frame `f` along `up`.
fn sole_low(f: &[Vector3<f64>], so: &[u32], up: &Vector3<f64>) -> f64 {
    so.iter().map(|&i| f[i as usize].dot(up)).fold(f64::INFINITY, f64::min)
}

/// Centroid of sole `so` in frame `f`.
fn sole_centre(f: &[Vector3<f64>], so: &[u32]) -> Vector3<f64> {
    so.iter().map(|&i| f[i as usize]).sum::<Vector3<f64>>() / so.len() as f64
}

/// Classes every frame pair of written variations that the foot-sliding metric counts by the
/// transferred contacts (both planted, one, none) and lists the fast swing pairs.
#[derive(Parser)]
struct Cli {
    /// The group file (prealign's output).
    group: String,
    /// The variation model (gpdm-train's output).
    model: String,
    /// The variations: hmc-sample's --out folder.
    dir: String,
    /// Another hmc-sample --out of the same model and seed: prints how far the clean-ups moved
    /// each variation's lowest vertex.
    base: Option<String>,
    /// Blend weights, comma-separated: also the variations of the group's first two motions
    /// blended at these weights (`blend-W`, as `hmc-sample --blends` writes them) [default: none].
    #[arg(long, value_delimiter = ',', value_name = "W,...")]
    blends: Vec<f64>,
    /// Prints each foot's height above the sole floor, horizontal speed and transferred contact
    /// over each variation's last N frames, and the source's at the matched frame.
    #[arg(long, default_value_t = 0, value_name = "N")]
    tail: usize,
}

fn main() -> mesh_core::Result<()> {
    let cli = Cli::parse();
    let group = Group::load(&cli.group)?;
    let model = VariationModel::load(&cli.model)?;
    let parts: Vec<_> = model.parts.iter().map(|p| p.part.clone()).collect();
    let soles = variation::group::soles(&parts, &model.template, &model.up, mesh_core::feet::SOLE_TOLERANCE);
    let up = model.up;
    let weights = cli.blends.clone();
    let mut sequences = group.sequences.clone();
    if let ([a, b, ..], false) = (&group.sequences[..], weights.is_empty()) {
        let blender = surface::blend::Blender::new(group.template.clone(), group.faces.clone())?;
        let blended = variation::group::blend_sequences_at(&blender, a, b, &weights, &group.up, &group.root_point())?;
        for (mut s, w) in blended.into_iter().zip(&weights) {
            s.name = variation::group::blend_name(*w);
            sequences.push(s);
        }
    }
    for s in &sequences {
        let source = s.motion.world_frames();
        let Some(c) = &s.contacts else { continue };
        let mut k = 0;
        loop {
            let dir = std::path::Path::new(&cli.dir).join(&s.name).join(format!("var{k}"));
            if !dir.exists() {
                break;
            }
            let v = MeshSequence::load_dir(&dir)?.frames;
            let m = variation::grounding::correspondence(&v, &source, &model.template);
            let tc = transfer_contacts(c, &m);
            let ground = soles
                .iter()
                .flat_map(|so| v.iter().flat_map(move |f| so.iter().map(move |&i| f[i as usize].dot(&up))))
                .fold(f64::INFINITY, f64::min);
            // classes: both planted, one, none
            let mut sum = [0.0f64; 3];
            let mut cnt = [0usize; 3];
            for (foot, so) in soles.iter().enumerate() {
                let low = |f: &Vec<Vector3<f64>>| sole_low(f, so, &up);
                let centre = |f: &Vec<Vector3<f64>>| sole_centre(f, so);
                for t in 0..v.len() - 1 {
                    if low(&v[t]) - ground <= 0.02 && low(&v[t + 1]) - ground <= 0.02 {
                        let d = centre(&v[t + 1]) - centre(&v[t]);
                        let d = (d - up * d.dot(&up)).norm();
                        let cls = match (tc[t][foot], tc[t + 1][foot]) {
                            (true, true) => 0,
                            (false, false) => 2,
                            _ => 1,
                        };
                        sum[cls] += d;
                        cnt[cls] += 1;
                        if cls == 2 && d > 0.02 {
                            let near = (0..tc.len())
                                .filter(|&u| tc[u][foot])
                                .map(|u| u as i64 - t as i64)
                                .min_by_key(|k| k.abs());
                            println!(
                                "  swing pair: foot {foot}, frames {t}-{}, {d:.3} m/frame, soles {:.3} / {:.3} m above the floor; nearest contact of that foot: {}",
                                t + 1,
                                low(&v[t]) - ground,
                                low(&v[t + 1]) - ground,
                                near.map_or("none".to_string(), |k| format!("{k:+} frames"))
                            );
                        }
                    }
                }
            }
            let (mut lo, mut lv, mut lt) = (f64::INFINITY, 0usize, 0usize);
            for (t, f) in v.iter().enumerate() {
                for (i, p) in f.iter().enumerate() {
                    if p.dot(&up) < lo {
                        (lo, lv, lt) = (p.dot(&up), i, t);
                    }
                }
            }
            let src_lo = source.iter().flat_map(|f| f.iter().map(|p| p.dot(&up))).fold(f64::INFINITY, f64::min);
            println!("  lowest vertex {lv} at frame {lt}: {:.3} m below the source's lowest point; sole floor {:.3}; in a sole: {}", src_lo - lo, src_lo - ground, soles.iter().any(|s| s.contains(&(lv as u32))));
            if let Some(b) = &cli.base {
                let base = MeshSequence::load_dir(std::path::Path::new(b).join(&s.name).join(format!("var{k}")))?.frames;
                let d = (v[lt][lv] - base[lt][lv]).dot(&up);
                let legs: Vec<_> = parts.iter().filter(|p| p.name.starts_with("leg")).map(|p| (p.name.clone(), p.vertices.contains(&(lv as u32)))).collect();
                println!("  vs base: vertex moved {d:.3} up; template height {:.3}; legs {legs:?}; base lowest {:.3}", model.template[lv].dot(&up), base[lt][lv].dot(&up));
            }
            // With --tail n: each foot's height above the sole floor, horizontal speed and
            // transferred contact over the last n frames, and the source's at the matched frame.
            let tail = cli.tail;
            // Each sole's floor in the source (its lowest height over the source's frames).
            let source_floor: Vec<f64> = soles
                .iter()
                .map(|so| source.iter().map(|f| sole_low(f, so, &up)).fold(f64::INFINITY, f64::min))
                .collect();
            for t in v.len().saturating_sub(tail)..v.len() {
                let per_foot: Vec<String> = soles
                    .iter()
                    .enumerate()
                    .map(|(foot, so)| {
                        let d = if t > 0 { sole_centre(&v[t], so) - sole_centre(&v[t - 1], so) } else { Vector3::zeros() };
                        let speed = (d - up * d.dot(&up)).norm();
                        // The source at the matched frame: its sole's height above its own floor.
                        let j = (m[t].round() as usize).min(source.len() - 1);
                        format!(
                            "foot {foot} {:.3} m, {speed:.3} m/frame{} (source frame {j}: {:.3} m{})",
                            sole_low(&v[t], so, &up) - ground,
                            if tc[t][foot] { ", contact" } else { "" },
                            sole_low(&source[j], so, &up) - source_floor[foot],
                            if c[j][foot] { ", contact" } else { "" }
                        )
                    })
                    .collect();
                println!("  frame {t}: {}", per_foot.join("; "));
            }
            let tot: usize = cnt.iter().sum();
            let all: f64 = sum.iter().sum();
            println!(
                "{} var{k}: height-rule pairs {tot}, mean {:.3} m/frame; planted {} ({:.3}), boundary {} ({:.3}), swing {} ({:.3}); transferred contact frames {}",
                s.name,
                if tot > 0 { all / tot as f64 } else { f64::NAN },
                cnt[0], if cnt[0] > 0 { sum[0] / cnt[0] as f64 } else { 0.0 },
                cnt[1], if cnt[1] > 0 { sum[1] / cnt[1] as f64 } else { 0.0 },
                cnt[2], if cnt[2] > 0 { sum[2] / cnt[2] as f64 } else { 0.0 },
                tc.iter().map(|c| c[0] as usize + c[1] as usize).sum::<usize>()
            );
            k += 1;
        }
    }
    Ok(())
}
