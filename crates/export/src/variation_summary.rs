//! The report's view of a `variation.json` (`{group: {train, eval, samples}}`, written by
//! `plan collect variation`): the tables of docs/RESULTS.md ("Variation") instead of the
//! nested JSON.
//!
//! - Figures, one column per group (`<table class="variation-figures">`): 3DV fig. 4 (mean
//!   per-vertex reconstruction of the training meshes, GPDM against PCA of the same
//!   dimension), fig. 7b per blend weight (latent interpolation against the non-linear blend,
//!   guided against unguided), the mean prediction of 3DV eqs. 8-10 per sequence, and the HMC
//!   acceptance rate (mean and range over the chains).
//! - Per sequence, ranges over its variations (`<table class="variation-sequences">`): pose
//!   distance to the source, to the nearest source frame, timing offset, edge distortion,
//!   foot sliding on the carried-over contacts and by the height rule (raw → after the
//!   clean-up), floor penetration after grounding (raw), the mean distance between
//!   variations, the diversity measures, and the frames that spin or tear (summed over the
//!   variations, against the captures' fastest turn and longest edge, which the figures
//!   table gives per group); the source's value in brackets.
//! - Training, one row per group (`<table class="variation-training">`): parts, frames per
//!   part, seconds, objective evaluations and why the optimiser stopped.
//!
//! A value list with missing entries (`null`: no contact pair, say) ranges over the others;
//! `-` when none is left.

use serde_json::Value;

use crate::html::escape;

/// Whether `v` looks like a `variation.json`: a non-empty object of groups, each an object
/// with at least one of `train`, `eval`, `samples`.
pub fn is_variation_table(v: &Value) -> bool {
    v.as_object().is_some_and(|m| {
        !m.is_empty()
            && m.values().all(|g| {
                g.as_object().is_some_and(|o| ["train", "eval", "samples"].iter().any(|k| o.contains_key(*k)))
            })
    })
}

/// The finite numbers of a list (or a single number), scaled.
fn numbers(v: Option<&Value>, scale: f64) -> Vec<f64> {
    match v {
        Some(Value::Array(a)) => a.iter().filter_map(Value::as_f64).filter(|x| x.is_finite()).map(|x| x * scale).collect(),
        Some(x) => x.as_f64().filter(|x| x.is_finite()).map(|x| vec![x * scale]).unwrap_or_default(),
        None => Vec::new(),
    }
}

/// `min-max` with `decimals` decimals (one value when both print alike), `-` for none.
pub fn range_text(values: &[f64], decimals: usize) -> String {
    if values.is_empty() {
        return "-".into();
    }
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (a, b) = (format!("{lo:.decimals$}"), format!("{hi:.decimals$}"));
    if a == b {
        a
    } else {
        format!("{a}-{b}")
    }
}

fn one(v: Option<&Value>, scale: f64, decimals: usize) -> String {
    range_text(&numbers(v, scale), decimals)
}

fn cell(text: &str) -> String {
    format!("<td>{}</td>", escape(text))
}

fn figures(groups: &[(&String, &Value)]) -> String {
    let mut s = String::from("<table class=\"variation-figures\"><thead><tr><th></th>");
    for (g, _) in groups {
        s += &format!("<th>{}</th>", escape(g));
    }
    s += "</tr></thead><tbody>";
    let row = |label: &str, f: &dyn Fn(&Value) -> String| {
        let mut r = format!("<tr><th>{}</th>", escape(label));
        for (_, v) in groups {
            r += &cell(&f(v));
        }
        r + "</tr>"
    };
    s += &row("fig. 4: training-mesh reconstruction, GPDM vs PCA of the same dimension (mean per vertex)", &|v| {
        let e = &v["eval"];
        match (e["reconstruction_gpdm_m"].as_f64(), e["reconstruction_pca_m"].as_f64()) {
            (Some(g), Some(p)) => format!("{:.2} vs {:.2} mm", 1e3 * g, 1e3 * p),
            _ => "-".into(),
        }
    });
    // Blend weights of every group, in first-seen order.
    let mut weights: Vec<f64> = Vec::new();
    for (_, v) in groups {
        for b in v["eval"]["latent_blend"].as_array().into_iter().flatten() {
            if let Some(w) = b["w"].as_f64() {
                if !weights.contains(&w) {
                    weights.push(w);
                }
            }
        }
    }
    for w in weights {
        let label = format!("fig. 7b: latent interpolation vs the non-linear blend as truth, guided vs unguided, w = {w}");
        s += &row(&label, &|v| {
            let b = v["eval"]["latent_blend"].as_array().into_iter().flatten().find(|b| b["w"].as_f64() == Some(w));
            match b.map(|b| (b["guided_m"].as_f64(), b["unguided_m"].as_f64())) {
                Some((Some(g), Some(u))) => format!("{:.2} vs {:.2} mm", 1e3 * g, 1e3 * u),
                _ => "-".into(),
            }
        });
    }
    s += &row("mean prediction (3DV eqs. 8-10) from the first latent point vs the data", &|v| {
        let parts: Vec<String> = v["eval"]["mean_prediction"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|m| Some(format!("{} {:.1}", m["sequence"].as_str()?, 1e3 * m["error_m"].as_f64()?)))
            .collect();
        if parts.is_empty() {
            "-".into()
        } else {
            parts.join(", ") + " mm"
        }
    });
    s += &row(
        "captures' fastest turn (about the vertical), longest edge and largest turn from the start (a variation frame spins, tears, goes off course past 1.25×, 1.5×, 1.25×)",
        &|v| {
            let c = &v["samples"]["capture_limits"];
            let course = c["max_course_turn_deg"].as_f64().map_or(String::new(), |d| format!(", {d:.1}°"));
            let heading = c["max_heading_turn_deg"].as_f64().map_or(String::new(), |d| format!(" ({d:.1}°)"));
            match (c["max_turn_deg"].as_f64(), c["max_edge_m"].as_f64()) {
                (Some(t), Some(e)) => format!("{t:.1}°{heading}/frame, {:.1} mm{course}", 1e3 * e),
                _ => "-".into(),
            }
        },
    );
    s += &row("HMC acceptance (target 0.7), mean (range over chains)", &|v| {
        let a = &v["samples"]["accept_rate"];
        match (a["mean"].as_f64(), a["min"].as_f64(), a["max"].as_f64()) {
            (Some(m), Some(lo), Some(hi)) => format!("{m:.2} ({})", range_text(&[lo, hi], 2)),
            _ => "-".into(),
        }
    });
    s + "</tbody></table>"
}

/// `raw → after (source)` for two value lists and the source's value, `decimals` decimals.
fn before_after(seq: &Value, raw: &str, after: &str, source: &str, scale: f64, decimals: usize) -> String {
    format!(
        "{} → {} ({})",
        one(seq.get(raw), scale, decimals),
        one(seq.get(after), scale, decimals),
        one(seq.get(source), scale, decimals)
    )
}

/// Column heads of the per-sequence table, in order.
pub const SEQUENCE_COLUMNS: [&str; 14] = [
    "group",
    "sequence (frames)",
    "pose distance to source, mm",
    "to nearest source frame, mm",
    "timing offset, frames",
    "pace / ground covered, of the source's",
    "edge distortion (source)",
    "sliding on contacts, m/frame, raw → after (source)",
    "sliding by height rule, m/frame, raw → after (source)",
    "floor penetration, grounded (raw), mm",
    "distance between variations, m",
    "coverage",
    "diversity global / local, mm",
    "frames spinning (about the vertical) / torn / off course, of all; steps slowed by the turn limit",
];

/// `spinning (about the vertical) / torn / off course, of all` frames summed over a sequence's
/// variations, and the steps the turn limit slowed where it slowed any (`-` without the measure).
fn spins_and_tears(seq: &Value) -> String {
    let Some(vars) = seq["turns_and_tears"].as_array().filter(|a| !a.is_empty()) else {
        return "-".into();
    };
    let count = |k: &str| -> usize { vars.iter().map(|v| v[k].as_array().map_or(0, Vec::len)).sum() };
    let all = seq["frames"].as_u64().map_or(String::new(), |f| format!(", of {}", f as usize * vars.len()));
    let slowed: u64 = vars.iter().filter_map(|v| v["slowed_steps"].as_u64()).sum();
    let slowed = if slowed > 0 { format!("; {slowed} slowed") } else { String::new() };
    format!(
        "{} ({} about the vertical) / {} / {}{all}{slowed}",
        count("spinning_frames"),
        count("heading_spinning_frames"),
        count("torn_frames"),
        count("off_course_frames")
    )
}

fn sequences(groups: &[(&String, &Value)]) -> String {
    let mut s = String::from("<table class=\"variation-sequences\"><thead><tr>");
    for c in SEQUENCE_COLUMNS {
        s += &format!("<th>{}</th>", escape(c));
    }
    s += "</tr></thead><tbody>";
    for (g, v) in groups {
        for q in v["samples"]["sequences"].as_array().into_iter().flatten() {
            let label = q["label"].as_str().unwrap_or("?");
            let frames = q["frames"].as_u64().map(|f| format!(" ({f})")).unwrap_or_default();
            let d = &q["diversity"];
            let cells = [
                g.to_string(),
                format!("{label}{frames}"),
                one(q.get("pose_distance_to_source_m"), 1e3, 0),
                one(q.get("manifold_distance_m"), 1e3, 0),
                one(q.get("timing_offset_frames"), 1.0, 1),
                format!("{} / {}", one(q.get("pose_speed_ratio"), 1.0, 2), one(q.get("travel_ratio"), 1.0, 2)),
                format!("{} ({})", one(q.get("edge_distortion"), 1.0, 2), one(q.get("source_edge_distortion"), 1.0, 2)),
                before_after(q, "raw_contact_sliding_m", "contact_sliding_m", "source_contact_sliding_m", 1.0, 3),
                before_after(q, "raw_foot_sliding_m", "foot_sliding_m", "source_foot_sliding_m", 1.0, 3),
                format!("{} ({})", one(q.get("penetration_m"), 1e3, 0), one(q.get("ungrounded_penetration_m"), 1e3, 0)),
                one(q["pairwise_distance_m"].get("mean"), 1.0, 2),
                one(d.get("coverage"), 1.0, 2),
                format!("{} / {}", one(d.get("global_m"), 1e3, 0), one(d.get("local_m"), 1e3, 0)),
                spins_and_tears(q),
            ];
            s += "<tr>";
            for c in &cells {
                s += &cell(c);
            }
            s += "</tr>";
        }
    }
    s + "</tbody></table>"
}

fn training(groups: &[(&String, &Value)]) -> String {
    let mut s = String::from(
        "<table class=\"variation-training\"><thead><tr><th>group</th><th>parts</th><th>frames per part</th>\
         <th>frame stride</th><th>seconds per part</th><th>objective evaluations</th><th>stopped by</th></tr></thead><tbody>",
    );
    for (g, v) in groups {
        let parts: Vec<&Value> = v["train"]["parts"].as_array().into_iter().flatten().collect();
        let col = |k: &str| -> Vec<f64> { parts.iter().filter_map(|p| p[k].as_f64()).collect() };
        let mut exits: Vec<String> = Vec::new();
        for p in &parts {
            for e in p["exits"].as_array().into_iter().flatten().filter_map(Value::as_str) {
                if !exits.iter().any(|x| x == e) {
                    exits.push(e.to_string());
                }
            }
        }
        let names: Vec<&str> = parts.iter().filter_map(|p| p["part"].as_str()).collect();
        let cells = [
            g.to_string(),
            if names.is_empty() { "-".into() } else { names.join(", ") },
            range_text(&col("frames"), 0),
            one(v["train"].get("stride"), 1.0, 0),
            range_text(&col("seconds"), 2),
            range_text(&col("evaluations"), 0),
            if exits.is_empty() { "-".into() } else { exits.join(", ") },
        ];
        s += "<tr>";
        for c in &cells {
            s += &cell(c);
        }
        s += "</tr>";
    }
    s + "</tbody></table>"
}

/// The variation section's content, or `None` when `v` is not a `variation.json`.
pub fn section_html(v: &Value) -> Option<String> {
    if !is_variation_table(v) {
        return None;
    }
    let groups: Vec<(&String, &Value)> = v.as_object()?.iter().collect();
    let mut notes = String::new();
    for (g, v) in &groups {
        for n in v["samples"]["notes"].as_array().into_iter().flatten().filter_map(Value::as_str) {
            notes += &format!("<li>{}: {}</li>", escape(g), escape(n));
        }
    }
    if !notes.is_empty() {
        notes = format!("<ul class=\"notes\">{notes}</ul>");
    }
    Some(format!(
        "<h3>Figures (3DV)</h3>{}<h3>Per sequence (ranges over its variations; the source's value in brackets)</h3>{}\
         <h3>Training</h3>{}{notes}",
        figures(&groups),
        sequences(&groups),
        training(&groups)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_skip_missing_values() {
        assert_eq!(range_text(&[], 2), "-");
        assert_eq!(range_text(&[0.1234, 0.1236], 3), "0.123-0.124");
        assert_eq!(range_text(&[0.1231, 0.1232], 3), "0.123");
        let v = serde_json::json!([null, 0.5, null, 0.25]);
        assert_eq!(one(Some(&v), 1e3, 0), "250-500");
        assert_eq!(one(Some(&serde_json::json!([null])), 1.0, 1), "-");
    }

    #[test]
    fn tables_from_a_small_variation_json() {
        let v = serde_json::json!({"walkrun": {
            "train": {"stride": 1, "parts": [
                {"part": "torso", "frames": 75, "seconds": 0.5, "evaluations": 100, "exits": ["ValueTolerance"]},
                {"part": "leg_l", "frames": 75, "seconds": 1.5, "evaluations": 300, "exits": ["GradientTolerance"]}]},
            "eval": {"reconstruction_gpdm_m": 0.00132, "reconstruction_pca_m": 0.00332,
                     "latent_blend": [{"w": 0.25, "guided_m": 0.00179, "unguided_m": 0.00206}],
                     "mean_prediction": [{"sequence": "walk", "error_m": 0.0089}]},
            "samples": {"accept_rate": {"mean": 0.7, "min": 0.54, "max": 0.82}, "notes": [],
                "capture_limits": {"max_turn_deg": 6.96, "max_edge_m": 0.0412, "max_course_turn_deg": 12.04, "max_heading_turn_deg": 3.14},
                "sequences": [{"label": "walk", "frames": 25, "pose_distance_to_source_m": [0.094, 0.124],
                    "raw_contact_sliding_m": [0.061, 0.079], "contact_sliding_m": [0.0, 1e-17],
                    "source_contact_sliding_m": 0.005, "pairwise_distance_m": {"mean": 0.4},
                    "diversity": {"coverage": 0.5, "global_m": 0.1, "local_m": 0.05},
                    "turns_and_tears": [{"spinning_frames": [3, 4], "heading_spinning_frames": [3], "torn_frames": [4], "off_course_frames": [20, 21]},
                                        {"spinning_frames": [9], "torn_frames": [], "slowed_steps": 2}]}]}}});
        assert!(is_variation_table(&v));
        let h = section_html(&v).unwrap();
        for needle in [
            "<td>1.32 vs 3.32 mm</td>",
            "w = 0.25</th><td>1.79 vs 2.06 mm</td>",
            "<td>walk 8.9 mm</td>",
            "<td>0.70 (0.54-0.82)</td>",
            "<td>walk (25)</td><td>94-124</td>",
            "<td>0.061-0.079 → 0.000 (0.005)</td>",
            "<td>0.40</td><td>0.50</td><td>100 / 50</td><td>3 (1 about the vertical) / 1 / 2, of 50; 2 slowed</td>",
            "goes off course past 1.25×, 1.5×, 1.25×)</th><td>7.0° (3.1°)/frame, 41.2 mm, 12.0°</td>",
            "<td>torso, leg_l</td><td>75</td><td>1</td><td>0.50-1.50</td><td>100-300</td><td>ValueTolerance, GradientTolerance</td>",
        ] {
            assert!(h.contains(needle), "{needle} not in {h}");
        }
        assert!(!is_variation_table(&serde_json::json!({"hmc_acceptance": 0.7})));
    }
}
