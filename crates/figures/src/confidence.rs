//! The per-frame confidence figure: nearest distance and variance ratio per part beside the
//! pose error.

use std::path::Path;

use mesh_core::{Error, Result};

use crate::plot::{png_bytes, register_font};

/// Default `--threshold` of the confidence figure: a frame is shaded as
/// extrapolating when some body part's normalised nearest distance reaches
/// 1, i.e. the part is as far from its nearest training pose as a typical
/// training pose is from the mean pose (`transfer::confidence`).
pub const DEFAULT_EXTRAPOLATION_THRESHOLD: f64 = 1.0;

/// Name of the non-body-part entry of [`transfer::confidence::Confidence`].
pub const DISPLACEMENT: &str = "displacement";

/// Colour of the extrapolating frames' background.
pub const EXTRAPOLATING_COLOUR: [u8; 3] = [255, 221, 170];

/// Reads a `gpr-predict --confidence` JSON file and checks it: at least one
/// frame, every listed part present in both maps, every non-null series
/// `frames` long and finite. Errors name the file.
pub fn load_confidence(path: &Path) -> Result<transfer::confidence::Confidence> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let c: transfer::confidence::Confidence = serde_json::from_str(&text).map_err(|e| {
        Error::file(path, format!("not a confidence file (gpr-predict --confidence): {e}"))
    })?;
    if c.frames == 0 {
        return Err(Error::file(path, "0 frames"));
    }
    if c.parts.is_empty() {
        return Err(Error::file(path, "no parts"));
    }
    for (field, map) in [("variance_ratio", &c.variance_ratio), ("nearest_distance", &c.nearest_distance)] {
        for p in &c.parts {
            let Some(series) = map.get(p) else {
                return Err(Error::file(path, format!("{field} has no entry for part '{p}'")));
            };
            if let Some(v) = series {
                if v.len() != c.frames {
                    return Err(Error::file(
                        path,
                        format!("{field} of '{p}' has {} values for {} frames", v.len(), c.frames),
                    ));
                }
                if let Some(f) = v.iter().position(|x| !x.is_finite()) {
                    return Err(Error::file(path, format!("{field} of '{p}' is not finite at frame {f}")));
                }
            }
        }
    }
    Ok(c)
}

/// Reads an `transfer-eval` record and checks that its per-frame pose errors
/// cover the `frames` frames of `confidence_path`. Errors name the file.
pub fn load_eval(path: &Path, frames: usize, confidence_path: &Path) -> Result<transfer::evaluate::EvalRecord> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let r: transfer::evaluate::EvalRecord = serde_json::from_str(&text)
        .map_err(|e| Error::file(path, format!("not an evaluate record: {e}")))?;
    if r.frame_pose_m.len() != frames {
        return Err(Error::file(
            path,
            format!(
                "frame_pose_m has {} frames but {} has {frames}: not the same motion",
                r.frame_pose_m.len(),
                confidence_path.display()
            ),
        ));
    }
    if let Some(f) = r.frame_pose_m.iter().position(|x| !x.is_finite()) {
        return Err(Error::file(path, format!("frame_pose_m is not finite at frame {f}")));
    }
    Ok(r)
}

/// Per frame, the largest normalised nearest distance over the body parts
/// (the displacement left out: the pose error of `transfer-eval` is measured after
/// a rigid alignment, which the displacement does not change). `None` when no
/// body part has distances (the affine baseline).
pub fn max_part_distance(c: &transfer::confidence::Confidence) -> Option<Vec<f64>> {
    let series: Vec<&Vec<f64>> = c
        .parts
        .iter()
        .filter(|p| p.as_str() != DISPLACEMENT)
        .filter_map(|p| c.nearest_distance.get(p).and_then(|s| s.as_ref()))
        .collect();
    (!series.is_empty())
        .then(|| (0..c.frames).map(|f| series.iter().map(|s| s[f]).fold(f64::MIN, f64::max)).collect())
}

/// Pearson correlation of `a` and `b` (same length); `None` with fewer than 3
/// points or when either is constant.
pub fn pearson(a: &[f64], b: &[f64]) -> Option<f64> {
    let n = a.len().min(b.len());
    if n < 3 {
        return None;
    }
    let (ma, mb) = (a[..n].iter().sum::<f64>() / n as f64, b[..n].iter().sum::<f64>() / n as f64);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a[..n].iter().zip(&b[..n]) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    (saa > 0.0 && sbb > 0.0).then(|| sab / (saa * sbb).sqrt())
}

/// One entry of the confidence figure: a body part or the displacement.
#[derive(Clone, Debug)]
pub struct ConfidenceSeries {
    pub name: String,
    pub nearest: Option<Vec<f64>>,
    pub variance: Option<Vec<f64>>,
}

/// The per-frame confidence figure (`paper-figure confidence`): panel 1 the
/// normalised nearest distance of every part, panel 2 the variance ratio,
/// panel 3 (with an `transfer-eval` record) the pose error in cm; frames where
/// [`max_part_distance`] reaches `threshold` are shaded in every panel.
#[derive(Clone, Debug)]
pub struct ConfidenceFigure {
    pub title: String,
    /// Second title line (the correlation, the count of shaded frames).
    pub caption: String,
    pub frames: usize,
    pub series: Vec<ConfidenceSeries>,
    /// Per-frame max over the body parts of the nearest distance.
    pub max_distance: Option<Vec<f64>>,
    /// Per-frame pose RMS error (m).
    pub error_m: Option<Vec<f64>>,
    pub threshold: f64,
    /// Pearson correlation of `max_distance` and `error_m`.
    pub correlation: Option<f64>,
}

/// Width of the legend column right of each panel (pixels).
const LEGEND_W: u32 = 190;
/// Height of one panel and of the title block (pixels).
const PANEL_H: u32 = 240;
const TITLE_H: u32 = 58;

/// Size of the confidence figure for `frames` frames, with or without the
/// error panel: about 6 pixels per frame within 760..1800 wide, 240 pixels
/// per panel plus the title.
pub fn confidence_figure_size(frames: usize, with_error: bool) -> (u32, u32) {
    let w = ((frames * 6) as u32 + 120 + LEGEND_W).clamp(760, 1800);
    (w, TITLE_H + PANEL_H * if with_error { 3 } else { 2 })
}

/// Runs of consecutive frames where `v >= threshold`, as `[first, last]`.
pub fn runs_at_or_above(v: &[f64], threshold: f64) -> Vec<[usize; 2]> {
    let mut out: Vec<[usize; 2]> = Vec::new();
    for (f, x) in v.iter().enumerate() {
        if *x >= threshold {
            match out.last_mut() {
                Some(r) if r[1] + 1 == f => r[1] = f,
                _ => out.push([f, f]),
            }
        }
    }
    out
}

const PART_COLOURS: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [188, 189, 34],
];

impl ConfidenceFigure {
    /// The figure of a checked confidence (see [`load_confidence`]) and
    /// optionally its checked evaluate record ([`load_eval`]).
    pub fn new(
        c: &transfer::confidence::Confidence,
        eval: Option<&transfer::evaluate::EvalRecord>,
        title: Option<String>,
        threshold: f64,
    ) -> Self {
        let series = c
            .parts
            .iter()
            .map(|p| ConfidenceSeries {
                name: p.clone(),
                nearest: c.nearest_distance.get(p).cloned().flatten(),
                variance: c.variance_ratio.get(p).cloned().flatten(),
            })
            .collect();
        let max_distance = max_part_distance(c);
        let error_m = eval.map(|r| r.frame_pose_m.clone());
        let correlation = match (&max_distance, &error_m) {
            (Some(d), Some(e)) => pearson(d, e),
            _ => None,
        };
        let shaded: usize = max_distance
            .as_ref()
            .map_or(0, |d| d.iter().filter(|x| **x >= threshold).count());
        let mut caption = format!(
            "shaded: {shaded} of {} frames where a body part's nearest distance is ≥ {threshold}",
            c.frames
        );
        if error_m.is_some() {
            caption.push_str(&match correlation {
                Some(r) => format!("; Pearson r(max part distance, pose error) = {r:.2}"),
                None => "; Pearson r undefined (a constant series)".into(),
            });
        }
        let title = title.unwrap_or_else(|| match eval {
            Some(r) => format!("{} {}, {}: per-frame confidence and pose error", r.direction, r.motion, r.method),
            None => "per-frame confidence".into(),
        });
        ConfidenceFigure {
            title,
            caption,
            frames: c.frames,
            series,
            max_distance,
            error_m,
            threshold,
            correlation,
        }
    }

    pub fn size(&self) -> (u32, u32) {
        confidence_figure_size(self.frames, self.error_m.is_some())
    }

    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), String> {
        use plotters::prelude::*;
        let e = |x: &dyn std::fmt::Debug| format!("{x:?}");
        let rgb = |c: [u8; 3]| RGBColor(c[0], c[1], c[2]);
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let (w, _) = root.dim_in_pixel();
        let (head, body) = root.split_vertically(TITLE_H);
        head.draw(&Text::new(self.title.clone(), (14, 8), ("sans-serif", 19).into_font().color(&BLACK)))
            .map_err(|x| e(&x))?;
        head.draw(&Text::new(
            self.caption.clone(),
            (14, 34),
            ("sans-serif", 14).into_font().color(&RGBColor(60, 60, 60)),
        ))
        .map_err(|x| e(&x))?;
        let n_panels = if self.error_m.is_some() { 3 } else { 2 };
        let panels = body.split_evenly((n_panels, 1));
        let runs = self
            .max_distance
            .as_ref()
            .map(|d| runs_at_or_above(d, self.threshold))
            .unwrap_or_default();
        let colour_of = |k: usize, name: &str| {
            if name == DISPLACEMENT {
                RGBColor(110, 110, 110)
            } else {
                rgb(PART_COLOURS[k % PART_COLOURS.len()])
            }
        };
        let x_range = -0.5..(self.frames as f64 - 0.5).max(0.5);
        for (p, area) in panels.iter().enumerate() {
            let (plot, legend) = area.split_horizontally(w - LEGEND_W);
            // (panel title, y label, y max, per-series values)
            let (name, y_desc, values): (&str, &str, Vec<(usize, &str, &Vec<f64>)>) = match p {
                0 => (
                    "nearest distance to the training inputs (0 = a training pose, 1 = typical spread)",
                    "nearest distance",
                    self.series
                        .iter()
                        .enumerate()
                        .filter_map(|(k, s)| s.nearest.as_ref().map(|v| (k, s.name.as_str(), v)))
                        .collect(),
                ),
                1 => (
                    "GP predictive variance / prior variance",
                    "variance ratio",
                    self.series
                        .iter()
                        .enumerate()
                        .filter_map(|(k, s)| s.variance.as_ref().map(|v| (k, s.name.as_str(), v)))
                        .collect(),
                ),
                _ => (
                    "pose error (evaluate, after rigid alignment per frame)",
                    "RMS error (cm)",
                    vec![],
                ),
            };
            let err_cm: Vec<f64> = self.error_m.iter().flatten().map(|x| x * 100.0).collect();
            let top = match p {
                0 => values
                    .iter()
                    .flat_map(|v| v.2.iter())
                    .fold(self.threshold, |a, &b| a.max(b))
                    * 1.1,
                1 => 1.05,
                _ => err_cm.iter().fold(0.0f64, |a, &b| a.max(b)).max(1e-3) * 1.1,
            };
            let mut chart = ChartBuilder::on(&plot)
                .caption(name, ("sans-serif", 14))
                .margin_left(10)
                .margin_right(6)
                .margin_top(4)
                .margin_bottom(2)
                .x_label_area_size(34)
                .y_label_area_size(62)
                .build_cartesian_2d(x_range.clone(), 0.0..top)
                .map_err(|x| e(&x))?;
            chart
                .draw_series(runs.iter().map(|r| {
                    Rectangle::new(
                        [(r[0] as f64 - 0.5, 0.0), (r[1] as f64 + 0.5, top)],
                        rgb(EXTRAPOLATING_COLOUR).filled(),
                    )
                }))
                .map_err(|x| e(&x))?;
            chart
                .configure_mesh()
                .light_line_style(RGBColor(238, 238, 238))
                .x_label_formatter(&|x| format!("{x:.0}"))
                .x_desc(if p + 1 == n_panels { "frame" } else { "" })
                .y_desc(y_desc)
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|x| e(&x))?;
            let mut entries: Vec<(String, RGBColor, bool)> = Vec::new();
            for (k, label, v) in &values {
                let c = colour_of(*k, label);
                let pts = v.iter().enumerate().map(|(f, y)| (f as f64, *y));
                if *label == DISPLACEMENT {
                    chart
                        .draw_series(DashedLineSeries::new(pts, 6, 4, c.stroke_width(2)))
                        .map_err(|x| e(&x))?;
                } else {
                    chart.draw_series(LineSeries::new(pts, c.stroke_width(2))).map_err(|x| e(&x))?;
                }
                entries.push((label.to_string(), c, *label == DISPLACEMENT));
            }
            if p == 0 {
                let t = self.threshold;
                chart
                    .draw_series(DashedLineSeries::new(
                        [(x_range.start, t), (x_range.end, t)],
                        8,
                        5,
                        BLACK.stroke_width(1),
                    ))
                    .map_err(|x| e(&x))?;
            }
            if p == 2 {
                let c = RGBColor(170, 20, 20);
                let pts: Vec<(f64, f64)> = err_cm.iter().enumerate().map(|(f, y)| (f as f64, *y)).collect();
                chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2))).map_err(|x| e(&x))?;
                if self.frames <= 200 {
                    chart
                        .draw_series(pts.iter().map(|q| Circle::new(*q, 2, c.filled())))
                        .map_err(|x| e(&x))?;
                }
                entries.push(("pose RMS error".into(), c, false));
            }
            if values.is_empty() && p < 2 {
                let (px, py) = chart.backend_coord(&(x_range.start, top * 0.5));
                plot.draw(&Text::new(
                    "none (no GP: the key-pose affine baseline)".to_string(),
                    (px + 20, py),
                    ("sans-serif", 14).into_font().color(&RGBColor(90, 90, 90)),
                ))
                .map_err(|x| e(&x))?;
            }
            // Legend column.
            let font = ("sans-serif", 13).into_font().color(&BLACK);
            let mut y = 28i32;
            for (label, c, dashed) in &entries {
                if *dashed {
                    legend
                        .draw(&PathElement::new(vec![(8, y + 7), (16, y + 7)], c.stroke_width(2)))
                        .map_err(|x| e(&x))?;
                    legend
                        .draw(&PathElement::new(vec![(21, y + 7), (30, y + 7)], c.stroke_width(2)))
                        .map_err(|x| e(&x))?;
                } else {
                    legend
                        .draw(&PathElement::new(vec![(8, y + 7), (30, y + 7)], c.stroke_width(3)))
                        .map_err(|x| e(&x))?;
                }
                legend.draw(&Text::new(label.clone(), (36, y), font.clone())).map_err(|x| e(&x))?;
                y += 19;
            }
            if p == 0 {
                legend
                    .draw(&PathElement::new(vec![(8, y + 7), (30, y + 7)], BLACK.stroke_width(1)))
                    .map_err(|x| e(&x))?;
                legend
                    .draw(&Text::new(format!("threshold {}", self.threshold), (36, y), font.clone()))
                    .map_err(|x| e(&x))?;
                y += 19;
            }
            if !runs.is_empty() {
                legend
                    .draw(&Rectangle::new([(8, y + 1), (30, y + 13)], rgb(EXTRAPOLATING_COLOUR).filled()))
                    .map_err(|x| e(&x))?;
                legend
                    .draw(&Text::new("extrapolating".to_string(), (36, y), font.clone()))
                    .map_err(|x| e(&x))?;
            }
        }
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }

    /// Writes the PNG at `png` (and, with `svg`, the SVG), each atomically.
    pub fn write(&self, png: &Path, svg: Option<&Path>) -> Result<()> {
        use plotters::prelude::*;
        register_font();
        if self.frames == 0 {
            return Err(Error::file(png, "no frames to draw"));
        }
        let (w, h) = self.size();
        let mut pixels = vec![0u8; (w * h * 3) as usize];
        self.draw(BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area())
            .map_err(|m| Error::file(png, format!("cannot draw the figure: {m}")))?;
        let bytes = png_bytes(png, &pixels, w, h)?;
        let text = match svg {
            Some(svg) => {
                let mut text = String::new();
                self.draw(SVGBackend::with_string(&mut text, (w, h)).into_drawing_area())
                    .map_err(|m| Error::file(svg, format!("cannot draw the figure: {m}")))?;
                Some(text)
            }
            None => None,
        };
        mesh_core::atomic::write_bytes_atomic(png, &bytes)?;
        if let (Some(svg), Some(text)) = (svg, text) {
            mesh_core::atomic::write_bytes_atomic(svg, text.as_bytes())?;
        }
        Ok(())
    }
}
