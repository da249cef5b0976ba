//! Contact sheets: a grid of rows (one sequence, or a group of overlaid
//! sequences such as "source / transfer / truth") by columns (evenly spaced
//! frames), with optional row labels and frame numbers in the built-in font.

use rayon::prelude::*;

use crate::camera::{Axis, ProjectionKind, View};
use crate::colour::{self, Rgb};
use crate::font;
use crate::image::RgbImage;
use crate::scene::{Layer, Renderer, Style};
use crate::sequence::{bounding_box, SeqView};

/// One row: a label and the sequences drawn overlaid in each cell.
///
/// A label may have several lines (`\n`); when it has exactly one line per
/// sequence and more than one sequence, each line is drawn in its
/// sequence's colour (a legend).
#[derive(Clone, Debug)]
pub struct Row<'a> {
    pub label: String,
    pub sequences: Vec<(Rgb, SeqView<'a>)>,
}

/// How many times the median row's size a row may be and still set the sheet's scale.
pub const CLIP_FACTOR: f64 = 3.0;

/// A contact sheet description; [`ContactSheet::render`] draws it.
#[derive(Clone, Debug)]
pub struct ContactSheet<'a> {
    pub rows: Vec<Row<'a>>,
    /// Number of evenly spaced frames (columns); fewer if the sequences are shorter.
    pub n_columns: usize,
    /// Size of one cell in pixels.
    pub cell_width: u32,
    pub cell_height: u32,
    /// Frames considered: `frames.start..frames.end` (clamped to the longest sequence).
    pub frames: std::ops::Range<usize>,
    pub view: View,
    pub up: Axis,
    pub projection: ProjectionKind,
    pub style: Style,
    /// Draw row labels (left) and frame numbers (top).
    pub labels: bool,
    /// Integer scale of the 5x7 font.
    pub font_scale: u32,
}

impl<'a> ContactSheet<'a> {
    /// Defaults: 8 columns, 192x192 cells, all frames, front orthographic view,
    /// labels on.
    pub fn new(rows: Vec<Row<'a>>) -> Self {
        ContactSheet {
            rows,
            n_columns: 8,
            cell_width: 192,
            cell_height: 192,
            frames: 0..usize::MAX,
            view: View::FRONT,
            up: Axis::PLUS_Y,
            projection: ProjectionKind::Orthographic,
            style: Style::default(),
            labels: true,
            font_scale: 2,
        }
    }

    /// The frame index shown in each column: `n` evenly spaced frames from
    /// the first to the last of the range (rounded to the nearest frame).
    pub fn column_frames(&self) -> Vec<usize> {
        let longest = self
            .rows
            .iter()
            .flat_map(|r| r.sequences.iter().map(|s| s.1.n_frames()))
            .max()
            .unwrap_or(0);
        let end = self.frames.end.min(longest);
        let start = self.frames.start.min(end);
        let len = end - start;
        let n = self.n_columns.min(len);
        match n {
            0 => Vec::new(),
            1 => vec![start],
            _ => (0..n)
                .map(|j| start + ((j * (len - 1)) as f64 / (n - 1) as f64).round() as usize)
                .collect(),
        }
    }

    /// The rows the camera frames: every row whose bounding box (over the frame range) is at
    /// most [`CLIP_FACTOR`] times the median row's diagonal; a row beyond (a method whose output
    /// explodes) is drawn clipped by the cells at the others' scale, and marked.
    pub fn framed_rows(&self) -> Vec<bool> {
        let diag: Vec<f64> = self
            .rows
            .iter()
            .map(|r| {
                let views: Vec<SeqView> = r.sequences.iter().map(|s| s.1).collect();
                let b = bounding_box(&views, self.frames.clone());
                if b.is_empty() { 0.0 } else { (b.max - b.min).norm() }
            })
            .collect();
        let mut sorted = diag.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        diag.iter().map(|&d| !(d > CLIP_FACTOR * median)).collect()
    }

    /// Draws the sheet. One camera frames every frame of the range of every
    /// sequence in every row ([`ContactSheet::framed_rows`]), so cells are directly comparable.
    pub fn render(&self) -> RgbImage {
        let cols = self.column_frames();
        let framed = self.framed_rows();
        let labels: Vec<String> = self
            .rows
            .iter()
            .zip(&framed)
            .map(|(r, &f)| if f { r.label.clone() } else { format!("{}\n(clipped)", r.label) })
            .collect();
        let s = self.font_scale.max(1);
        let line_h = (font::GLYPH_H + 3) * s;
        let pad = 4 * s;
        let label_w = if self.labels {
            let w = labels
                .iter()
                .flat_map(|l| l.lines().map(|l| font::text_width(l, s)))
                .max()
                .unwrap_or(0);
            if w > 0 {
                w + 2 * pad
            } else {
                0
            }
        } else {
            0
        };
        let header_h = if self.labels && !cols.is_empty() {
            line_h + pad
        } else {
            0
        };
        let width = label_w + self.cell_width * cols.len().max(1) as u32;
        let height = header_h + self.cell_height * self.rows.len().max(1) as u32;
        let mut sheet = RgbImage::new(width, height, self.style.background);

        let all: Vec<SeqView> = self
            .rows
            .iter()
            .zip(&framed)
            .filter(|(_, &f)| f)
            .flat_map(|(r, _)| r.sequences.iter().map(|s| s.1))
            .collect();
        let bbox = bounding_box(&all, self.frames.clone());
        let renderer = Renderer::new(
            &bbox,
            &self.view,
            &self.up,
            self.projection,
            self.cell_width,
            self.cell_height,
            self.style,
        );

        if header_h > 0 {
            for (c, f) in cols.iter().enumerate() {
                let text = f.to_string();
                let x = label_w as i64
                    + c as i64 * self.cell_width as i64
                    + (self.cell_width as i64 - font::text_width(&text, s) as i64) / 2;
                font::draw_text(&mut sheet, x, pad as i64, &text, s, colour::TEXT);
            }
        }
        // Cells render in parallel; each is independent, so the sheet does not
        // depend on the thread count.
        let jobs: Vec<(usize, usize)> = (0..self.rows.len())
            .flat_map(|r| (0..cols.len()).map(move |c| (r, c)))
            .collect();
        let cells: Vec<RgbImage> = jobs
            .par_iter()
            .map(|&(r, c)| {
                let layers: Vec<Layer> = self.rows[r]
                    .sequences
                    .iter()
                    .filter_map(|(col, seq)| {
                        Some(Layer {
                            vertices: seq.frame_clamped(cols[c])?,
                            faces: seq.faces,
                            colour: *col,
                            vertex_colours: seq.vertex_colours,
                        })
                    })
                    .collect();
                renderer.render(&layers)
            })
            .collect();
        for (&(r, c), cell) in jobs.iter().zip(&cells) {
            let y0 = header_h as i64 + r as i64 * self.cell_height as i64;
            sheet.blit(cell, label_w as i64 + c as i64 * self.cell_width as i64, y0);
        }
        for (r, row) in self.rows.iter().enumerate() {
            let y0 = header_h as i64 + r as i64 * self.cell_height as i64;
            if label_w > 0 {
                let lines: Vec<&str> = labels[r].lines().collect();
                let legend = lines.len() == row.sequences.len() && lines.len() > 1;
                let block = lines.len() as i64 * line_h as i64;
                let top = y0 + (self.cell_height as i64 - block) / 2;
                for (k, line) in lines.iter().enumerate() {
                    let c = if legend {
                        row.sequences[k].0
                    } else {
                        colour::TEXT
                    };
                    font::draw_text(
                        &mut sheet,
                        pad as i64,
                        top + k as i64 * line_h as i64,
                        line,
                        s,
                        c,
                    );
                }
            }
        }
        sheet
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn tri_frames(n: usize) -> (Vec<[u32; 3]>, Vec<Vec<Vector3<f64>>>) {
        let frames = (0..n)
            .map(|i| {
                let x = i as f64 * 0.1;
                vec![
                    Vector3::new(x, 0.0, 0.0),
                    Vector3::new(x + 1.0, 0.0, 0.0),
                    Vector3::new(x, 1.0, 0.0),
                ]
            })
            .collect();
        (vec![[0, 1, 2]], frames)
    }

    #[test]
    fn columns_are_evenly_spaced_and_include_both_ends() {
        let (f, fr) = tri_frames(11);
        let mut sheet = ContactSheet::new(vec![Row {
            label: "A".into(),
            sequences: vec![(colour::palette(0), SeqView::new(&f, &fr))],
        }]);
        sheet.n_columns = 6;
        assert_eq!(sheet.column_frames(), vec![0, 2, 4, 6, 8, 10]);
        sheet.n_columns = 50;
        assert_eq!(sheet.column_frames().len(), 11);
        sheet.frames = 3..7;
        sheet.n_columns = 2;
        assert_eq!(sheet.column_frames(), vec![3, 6]);
    }

    #[test]
    fn sheet_size_follows_rows_columns_and_labels() {
        let (f, fr) = tri_frames(5);
        let v = SeqView::new(&f, &fr);
        let rows = vec![
            Row {
                label: "source".into(),
                sequences: vec![(colour::palette(0), v)],
            },
            Row {
                label: "transfer\ntruth".into(),
                sequences: vec![(colour::palette(1), v), (colour::palette(2), v)],
            },
        ];
        let mut sheet = ContactSheet::new(rows);
        sheet.n_columns = 3;
        sheet.cell_width = 40;
        sheet.cell_height = 30;
        sheet.style.supersample = 1;
        let img = sheet.render();
        let s = sheet.font_scale;
        let label_w = font::text_width("transfer", s) + 8 * s;
        assert_eq!(img.width, label_w + 3 * 40);
        assert_eq!(img.height, (font::GLYPH_H + 3) * s + 4 * s + 2 * 30);
        sheet.labels = false;
        let img = sheet.render();
        assert_eq!((img.width, img.height), (120, 60));
        // Each cell shows the triangle: some non-background pixels in every cell.
        for r in 0..2 {
            for c in 0..3 {
                let hit = (0..30)
                    .any(|y| (0..40).any(|x| img.get(c * 40 + x, r * 30 + y) != colour::WHITE));
                assert!(hit, "cell {r},{c} is empty");
            }
        }
    }

    /// A row a hundred times the others' size (an exploding method) does not set the scale: the
    /// other rows are drawn as large as without it, and it is marked clipped.
    #[test]
    fn an_exploding_row_is_clipped_and_the_others_keep_their_scale() {
        let (f, fr) = tri_frames(5);
        let big: Vec<Vec<Vector3<f64>>> = fr.iter().map(|v| v.iter().map(|p| p * 100.0).collect()).collect();
        let (small, huge) = (SeqView::new(&f, &fr), SeqView::new(&f, &big));
        let row = |label: &str, v| Row { label: label.into(), sequences: vec![(colour::palette(0), v)] };
        let sheet_of = |rows| {
            let mut sheet = ContactSheet::new(rows);
            sheet.n_columns = 2;
            sheet.cell_width = 40;
            sheet.cell_height = 40;
            sheet.labels = false;
            sheet.style.supersample = 1;
            sheet
        };
        let with = sheet_of(vec![row("a", small), row("b", small), row("exploding", huge)]);
        assert_eq!(with.framed_rows(), vec![true, true, false]);
        let without = sheet_of(vec![row("a", small), row("b", small)]);
        assert_eq!(without.framed_rows(), vec![true, true]);
        let (img, reference) = (with.render(), without.render());
        for y in 0..80 {
            for x in 0..80 {
                assert_eq!(img.get(x, y), reference.get(x, y), "pixel {x},{y} of the first two rows");
            }
        }
    }
}
