//! The report's view of a transfer `results.json` (one record per direction, motion, method,
//! placement and training): the pose error per motion as a table of the layout of
//! docs/RESULTS.md ("Every method": rows direction and motion, one column per method, RMS in
//! cm, a pooled row), the same numbers as an inline SVG bar chart, the floor offset and the
//! foot sliding as tables of the same layout (all a run without truth has), and the records
//! without their per-frame arrays.
//!
//! A method's column is its name, with `-keyposes` appended for records trained on the
//! key-poses only. Pose error does not depend on the placement, so each (motion, column) takes
//! the record with the most common placement of the file (the pipelines' default), or the
//! first one there is. The pooled row is the RMS over every frame of the motions:
//! `sqrt(Σ frames·rms² / Σ frames)`.

use serde_json::Value;

use crate::html::{escape, json_to_html};

/// One cell of the pose-error table: a motion's error under one method.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// `direction motion`, e.g. `A->B punch`.
    pub row: String,
    /// Method, e.g. `gpr-nn+correct+stitch` or `gpr-nn-keyposes`.
    pub column: String,
    /// RMS per-vertex pose error in centimetres.
    pub cm: f64,
    pub frames: u64,
}

/// The pose-error table of a results list: rows and columns in first-seen order, cells.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseTable {
    pub rows: Vec<String>,
    pub columns: Vec<String>,
    pub cells: Vec<Cell>,
}

impl PoseTable {
    /// The cell of `row` and `column`, if that motion was run with that method.
    pub fn get(&self, row: &str, column: &str) -> Option<&Cell> {
        self.cells.iter().find(|c| c.row == row && c.column == column)
    }

    /// RMS over every frame of a column's motions (cm).
    pub fn pooled(&self, column: &str) -> Option<f64> {
        let (mut sum, mut n) = (0.0, 0u64);
        for c in self.cells.iter().filter(|c| c.column == column) {
            sum += c.cm * c.cm * c.frames as f64;
            n += c.frames;
        }
        (n > 0).then(|| (sum / n as f64).sqrt())
    }
}

fn text<'a>(r: &'a Value, key: &str) -> &'a str {
    r.get(key).and_then(Value::as_str).unwrap_or("")
}

/// Reads the pose-error table from a `results.json` value; `None` when it is not a list of
/// transfer records (objects with `direction`, `motion`, `method` and `rms_pose_m`).
pub fn pose_table(results: &Value) -> Option<PoseTable> {
    measure_table(results, "rms_pose_m")
}

/// The table of any per-record measure in metres (`rms_pose_m`, `floor_offset_m`,
/// `foot_sliding_m`), in cm; `None` when no record has it.
pub fn measure_table(results: &Value, key: &str) -> Option<PoseTable> {
    let records = results.as_array()?;
    let usable: Vec<&Value> = records
        .iter()
        .filter(|r| {
            r.get(key).and_then(Value::as_f64).is_some_and(f64::is_finite)
                && ["direction", "motion", "method"].iter().all(|k| r.get(*k).is_some_and(Value::is_string))
        })
        .collect();
    if usable.is_empty() {
        return None;
    }
    // The most common placement (first seen wins a tie).
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for r in &usable {
        let p = text(r, "placement");
        match counts.iter_mut().find(|(q, _)| *q == p) {
            Some(slot) => slot.1 += 1,
            None => counts.push((p, 1)),
        }
    }
    let usual = counts.iter().fold(("", 0), |best, &c| if c.1 > best.1 { c } else { best }).0;
    let mut table = PoseTable::default();
    let mut chosen_usual: Vec<bool> = Vec::new();
    for r in usable {
        let row = format!("{} {}", text(r, "direction"), text(r, "motion"));
        let mut column = text(r, "method").to_string();
        if text(r, "training") == "keyposes" {
            column += "-keyposes";
        }
        let cell = Cell {
            row: row.clone(),
            column: column.clone(),
            cm: 100.0 * r[key].as_f64().unwrap_or(f64::NAN),
            frames: r.get("frames").and_then(Value::as_u64).unwrap_or(0),
        };
        let is_usual = text(r, "placement") == usual;
        match table.cells.iter().position(|c| c.row == row && c.column == column) {
            Some(i) if is_usual && !chosen_usual[i] => {
                table.cells[i] = cell;
                chosen_usual[i] = true;
            }
            Some(_) => {}
            None => {
                table.cells.push(cell);
                chosen_usual.push(is_usual);
            }
        }
        if !table.rows.contains(&row) {
            table.rows.push(row);
        }
        if !table.columns.contains(&column) {
            table.columns.push(column);
        }
    }
    Some(table)
}

/// The table as HTML (`<table class="pose-error">`, one decimal, `-` where a motion lacks a
/// method), with the pooled row.
pub fn pose_table_html(t: &PoseTable) -> String {
    table_html(t, "pose-error")
}

/// A measure's table as HTML of class `class`, one decimal, with the pooled (RMS) row.
pub fn table_html(t: &PoseTable, class: &str) -> String {
    let mut s = format!("<table class=\"{class}\"><thead><tr><th>direction, motion (frames)</th>");
    for c in &t.columns {
        s += &format!("<th>{}</th>", escape(c));
    }
    s += "</tr></thead><tbody>";
    for row in &t.rows {
        let frames = t.cells.iter().find(|c| &c.row == row).map_or(0, |c| c.frames);
        s += &format!("<tr><th>{} ({frames})</th>", escape(row));
        for col in &t.columns {
            match t.get(row, col) {
                Some(c) => s += &format!("<td>{:.1}</td>", c.cm),
                None => s += "<td>-</td>",
            }
        }
        s += "</tr>";
    }
    s += "<tr class=\"pooled\"><th>pooled</th>";
    for col in &t.columns {
        match t.pooled(col) {
            Some(v) => s += &format!("<td>{v:.1}</td>"),
            None => s += "<td>-</td>",
        }
    }
    s + "</tr></tbody></table>"
}

/// Colours of the plot's series (method columns), in column order.
pub const SERIES_COLOURS: [&str; 10] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

/// A "nice" axis step (1, 2 or 5 times a power of ten) giving about `ticks` intervals up to `max`.
fn nice_step(max: f64, ticks: f64) -> f64 {
    let raw = (max / ticks).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * p).find(|s| *s >= raw).unwrap_or(10.0 * p)
}

/// The per-motion pose error as an inline SVG bar chart (`<svg class="error-plot">`): one
/// group of bars per motion, one bar per method, heights linear in cm from 0. Each bar is a
/// `<rect class="bar">` carrying `data-row`, `data-column` and `data-cm` (the value it
/// draws) and a `<title>` tooltip.
pub fn pose_plot_svg(t: &PoseTable) -> String {
    const BAR: f64 = 12.0;
    const GAP: f64 = 18.0;
    const LEFT: f64 = 48.0;
    const TOP: f64 = 14.0;
    const PLOT_H: f64 = 220.0;
    const LABEL_H: f64 = 34.0;
    let n_cols = t.columns.len().max(1) as f64;
    let group_w = n_cols * BAR + GAP;
    let plot_w = t.rows.len().max(1) as f64 * group_w;
    let max = t.cells.iter().map(|c| c.cm).filter(|v| v.is_finite()).fold(0.0, f64::max);
    let step = nice_step(max.max(1e-6), 5.0);
    let top_value = (max / step).ceil().max(1.0) * step;
    let y = |v: f64| TOP + PLOT_H * (1.0 - v / top_value);
    let legend_h = 16.0 * t.columns.len() as f64;
    let width = LEFT + plot_w + 10.0;
    let height = TOP + PLOT_H + LABEL_H + legend_h + 8.0;
    let mut s = format!(
        "<svg class=\"error-plot\" width=\"{width:.0}\" height=\"{height:.0}\" \
         viewBox=\"0 0 {width:.0} {height:.0}\" font-family=\"sans-serif\" font-size=\"11\" role=\"img\">\
         <title>Pose RMS error per motion and method, cm</title>"
    );
    // Axis, ticks and grid.
    let mut v = 0.0;
    while v <= top_value + 1e-9 {
        s += &format!(
            "<line x1=\"{LEFT}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            LEFT + plot_w,
            LEFT - 4.0,
            y(v) + 4.0,
            trim_number(v),
            y = y(v)
        );
        v += step;
    }
    s += &format!(
        "<line x1=\"{LEFT}\" x2=\"{LEFT}\" y1=\"{TOP}\" y2=\"{:.1}\" stroke=\"#444\"/>\
         <text transform=\"translate(12 {:.1}) rotate(-90)\" text-anchor=\"middle\">pose RMS, cm</text>",
        TOP + PLOT_H,
        TOP + PLOT_H / 2.0
    );
    for (i, row) in t.rows.iter().enumerate() {
        let x0 = LEFT + GAP / 2.0 + i as f64 * group_w;
        for (j, col) in t.columns.iter().enumerate() {
            let Some(c) = t.get(row, col) else { continue };
            if !c.cm.is_finite() {
                continue;
            }
            let top = y(c.cm);
            s += &format!(
                "<rect class=\"bar\" x=\"{:.1}\" y=\"{top:.3}\" width=\"{:.1}\" height=\"{:.3}\" fill=\"{}\" \
                 data-row=\"{}\" data-column=\"{}\" data-cm=\"{}\"><title>{}, {}: {:.1} cm</title></rect>",
                x0 + j as f64 * BAR,
                BAR - 1.0,
                TOP + PLOT_H - top,
                SERIES_COLOURS[j % SERIES_COLOURS.len()],
                escape(row),
                escape(col),
                c.cm,
                escape(row),
                escape(col),
                c.cm
            );
        }
        s += &format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            x0 + n_cols * BAR / 2.0,
            TOP + PLOT_H + 16.0,
            escape(row)
        );
    }
    for (j, col) in t.columns.iter().enumerate() {
        let ly = TOP + PLOT_H + LABEL_H + 16.0 * j as f64;
        s += &format!(
            "<rect x=\"{LEFT}\" y=\"{ly:.1}\" width=\"10\" height=\"10\" fill=\"{}\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            SERIES_COLOURS[j % SERIES_COLOURS.len()],
            LEFT + 16.0,
            ly + 9.0,
            escape(col)
        );
    }
    s + "</svg>"
}

/// An axis label without trailing zeros (`0.5`, `2`, `10`).
fn trim_number(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The records as one table without the array-valued fields (per-frame errors), which the
/// table and plot above summarise.
pub fn records_html(results: &Value) -> String {
    let Some(records) = results.as_array() else { return json_to_html(results) };
    let slim: Vec<Value> = records
        .iter()
        .map(|r| match r {
            Value::Object(m) => {
                Value::Object(m.iter().filter(|(_, v)| !v.is_array()).map(|(k, v)| (k.clone(), v.clone())).collect())
            }
            other => other.clone(),
        })
        .collect();
    json_to_html(&Value::Array(slim))
}

/// One direction's cross-validated estimate (m): pooled, and per training motion where the
/// records carry it (`cv_motions`).
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub direction: String,
    pub rms_pose_m: f64,
    pub motions: Vec<(String, f64)>,
}

/// Per direction, in order of first appearance, the cross-validated estimate its records
/// carry (`cv_rms_pose_m`, `cv_motions`).
pub fn cross_validation_estimates(results: &Value) -> Vec<Estimate> {
    let mut out: Vec<Estimate> = Vec::new();
    for r in results.as_array().into_iter().flatten() {
        let (Some(d), Some(cv)) = (r["direction"].as_str(), r["cv_rms_pose_m"].as_f64()) else { continue };
        if !out.iter().any(|e| e.direction == d) {
            let motions = r["cv_motions"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|m| Some((m["motion"].as_str()?.to_string(), m["rms_pose_m"].as_f64()?)))
                .collect();
            out.push(Estimate { direction: d.to_string(), rms_pose_m: cv, motions });
        }
    }
    out
}

/// An estimate as the report shows it: `A->B 4.3 cm (walk 3.2, run 5.6, ...)`, escaped.
fn estimate_html(e: &Estimate) -> String {
    let motions: Vec<String> = e.motions.iter().map(|(m, v)| format!("{} {:.1}", escape(m), v * 100.0)).collect();
    let detail = if motions.is_empty() { String::new() } else { format!(" ({})", motions.join(", ")) };
    format!("{} {:.1} cm{detail}", escape(&e.direction), e.rms_pose_m * 100.0)
}

/// The whole transfer section's content: the pose-error table and plot where the run had
/// truth (else a line saying so), the floor offset and foot sliding tables, then the records;
/// `None` when `results` holds no transfer record.
pub fn section_html(results: &Value) -> Option<String> {
    let pose = pose_table(results);
    let floor = measure_table(results, "floor_offset_m");
    let sliding = measure_table(results, "foot_sliding_m");
    if pose.is_none() && floor.is_none() && sliding.is_none() {
        return None;
    }
    let mut s = match &pose {
        Some(t) => format!(
            "<h3>Pose error per motion (RMS per vertex, cm)</h3>{}<figure class=\"plot\">{}</figure>",
            pose_table_html(t),
            pose_plot_svg(t)
        ),
        None => "<p class=\"no-truth\">No ground truth of these motions: no pose error. What a transfer \
                 shows without it follows, measured where the source stands on a foot.</p>"
            .to_string(),
    };
    let estimates = cross_validation_estimates(results);
    if !estimates.is_empty() {
        let items: Vec<String> = estimates.iter().map(estimate_html).collect();
        s += &format!(
            "<p class=\"cv-estimate\">Pose error to expect on a new motion, estimated from the training \
             motions alone (cross-validated, gpr-nn; in brackets each training motion's, held out): {}.</p>",
            items.join("; ")
        );
    }
    if let Some(t) = floor {
        s += "<h3>Floor offset (median height of the standing leg's lowest point above the target's floor \
              where the source stands on a foot, cm; pooled: RMS)</h3>";
        s += &table_html(&t, "floor-offset");
    }
    if let Some(t) = sliding {
        s += "<h3>Foot sliding on contacts (cm per frame; pooled: RMS)</h3>";
        s += &table_html(&t, "foot-sliding");
    }
    Some(s + &format!("<h3>Every record</h3>{}", records_html(results)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(dir: &str, motion: &str, method: &str, placement: &str, training: &str, rms: f64, frames: u64) -> Value {
        serde_json::json!({"direction": dir, "motion": motion, "method": method, "placement": placement,
            "training": training, "rms_pose_m": rms, "frames": frames, "frame_pose_m": [rms, rms]})
    }

    #[test]
    fn one_cell_per_motion_and_method_at_the_usual_placement() {
        let v = Value::Array(vec![
            rec("A->B", "punch", "gpr-nn", "blended", "dense", 0.09, 10),
            rec("A->B", "punch", "gpr-nn", "scaled-source", "dense", 0.05, 10),
            rec("A->B", "punch", "gpr-nn", "scaled-source", "keyposes", 0.08, 10),
            rec("A->B", "punch", "gpr-se", "scaled-source", "dense", 0.06, 10),
            rec("B->A", "dance", "gpr-nn", "scaled-source", "dense", 0.02, 30),
        ]);
        let t = pose_table(&v).unwrap();
        assert_eq!(t.rows, ["A->B punch", "B->A dance"]);
        assert_eq!(t.columns, ["gpr-nn", "gpr-nn-keyposes", "gpr-se"]);
        assert!((t.get("A->B punch", "gpr-nn").unwrap().cm - 5.0).abs() < 1e-12, "the scaled-source record");
        assert!(t.get("B->A dance", "gpr-se").is_none());
        // sqrt((25*10 + 4*30) / 40) = sqrt(9.25)
        assert!((t.pooled("gpr-nn").unwrap() - 9.25f64.sqrt()).abs() < 1e-12);
        let html = pose_table_html(&t);
        assert!(html.contains("<td>5.0</td>") && html.contains("<td>-</td>") && html.contains("<td>3.0</td>"), "{html}");
        let svg = pose_plot_svg(&t);
        assert_eq!(svg.matches("class=\"bar\"").count(), 4, "{svg}");
        assert!(!records_html(&v).contains("frame_pose_m"));
    }

    #[test]
    fn bars_are_linear_from_zero() {
        let v = Value::Array(vec![
            rec("A->B", "walk", "a", "", "", 0.02, 5),
            rec("A->B", "walk", "b", "", "", 0.06, 5),
        ]);
        let svg = pose_plot_svg(&pose_table(&v).unwrap());
        let heights: Vec<f64> = svg
            .split("class=\"bar\"")
            .skip(1)
            .map(|s| s.split("height=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap())
            .collect();
        assert!((heights[1] / heights[0] - 3.0).abs() < 1e-3, "{heights:?}");
    }

    #[test]
    fn not_transfer_records() {
        assert!(pose_table(&serde_json::json!({"a": 1})).is_none());
        assert!(pose_table(&serde_json::json!([{"x": 1}])).is_none());
        assert_eq!(nice_step(13.0, 5.0), 5.0);
        assert_eq!(nice_step(0.9, 5.0), 0.2);
    }

    /// The cross-validated estimate of each direction, once per direction, shown in the
    /// section as cm with each training motion's; without the per-motion errors the pooled one
    /// alone; none without it.
    #[test]
    fn the_estimate_from_the_training_motions_is_shown_once_per_direction() {
        let mut a = rec("A->B", "punch", "gpr-nn", "scaled-source", "dense", 0.05, 10);
        let mut b = rec("A->B", "kick", "gpr-nn", "scaled-source", "dense", 0.06, 10);
        let motions = serde_json::json!([{"motion": "walk", "frames": 9, "rms_pose_m": 0.032}, {"motion": "dance<1>", "frames": 4, "rms_pose_m": 1.2}]);
        for r in [&mut a, &mut b] {
            r["cv_rms_pose_m"] = serde_json::json!(0.0571);
            r["cv_motions"] = motions.clone();
        }
        let mut c = rec("B->A", "dance", "gpr-nn", "scaled-source", "dense", 0.02, 30);
        let v = Value::Array(vec![a.clone(), b, c.clone()]);
        let want = Estimate { direction: "A->B".into(), rms_pose_m: 0.0571, motions: vec![("walk".into(), 0.032), ("dance<1>".into(), 1.2)] };
        assert_eq!(cross_validation_estimates(&v), vec![want]);
        let html = section_html(&v).unwrap();
        assert!(html.contains("A-&gt;B 5.7 cm (walk 3.2, dance&lt;1&gt; 120.0)") && html.matches("cv-estimate").count() == 1, "{html}");
        assert!(!section_html(&Value::Array(vec![c.clone()])).unwrap().contains("cv-estimate"));
        c["cv_rms_pose_m"] = serde_json::json!(0.03);
        assert!(section_html(&Value::Array(vec![c])).unwrap().contains("B-&gt;A 3.0 cm.</p>"));
    }
}
