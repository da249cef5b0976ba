//! The `render` stage: sequence folders in, PNG frames, a contact sheet and
//! an animated GIF out. `main` only parses [`Params`] and calls [`run`].

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::cli::CommonArgs;
use rayon::prelude::*;
use serde::Serialize;

use crate::anim::{GifBuilder, GifPalette};
use crate::camera::{Axis, ProjectionKind, View};
use crate::colour::{self, Rgb};
use crate::contact::{ContactSheet, Row};
use crate::font;
use crate::image::RgbImage;
use crate::scene::{Layer, Renderer, Shading, Style};
use crate::sequence::{bounding_box, SeqView};
use mesh_core::sequence::{FrameRange, MeshSequence};

/// Draw mesh sequences, overlaid in distinct colours, to PNG frames, a contact sheet and a GIF
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "render",
    version,
    after_help = "e.g.: render data/set/A/walk work/transfer/walk --labels source,transfer --camera three-quarter --out work/render/walk"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Sequence folders of NNNNNN.ply / NNNNNN.obj frames, drawn overlaid, one colour each
    #[arg(required = true, value_name = "SEQ_DIR")]
    pub seq_dirs: Vec<PathBuf>,
    /// Output folder: frames/NNNNNN.png (numbered from 0), contact.png, anim.gif
    #[arg(short, long)]
    pub out: PathBuf,
    /// View: front, side, three-quarter, or AZIMUTH,ELEVATION in degrees (azimuth 90 = subject's left)
    #[arg(long, default_value = "three-quarter", value_parser = parse_view)]
    pub camera: View,
    /// Perspective projection with this vertical field of view in degrees [default: orthographic]
    #[arg(long, value_name = "DEG")]
    pub perspective: Option<f64>,
    /// The subjects' up axis (+y, -y, +x, -x, +z, -z); they face +z (-y when up is +z)
    #[arg(long, default_value = "+y", value_parser = parse_axis)]
    pub up: Axis,
    /// Image size: N (square) or WxH
    #[arg(long, default_value = "512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Frames to draw, START:END (END excluded; either may be omitted)
    #[arg(long, value_name = "A:B")]
    pub frames: Option<FrameRange>,
    /// Draw every N-th frame (frames, GIF)
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub stride: u32,
    /// Columns (evenly spaced frames) of the contact sheet; 0 = no contact sheet
    #[arg(long, default_value_t = 8, value_name = "N")]
    pub contact_columns: usize,
    /// One contact-sheet row per sequence instead of one row of all sequences overlaid
    #[arg(long)]
    pub separate_rows: bool,
    /// GIF frame rate in frames per second (of the drawn frames)
    #[arg(long, default_value_t = 25.0, value_name = "FPS")]
    pub gif_fps: f64,
    /// Sequence labels, comma-separated: a legend on frames and GIF, row labels on the contact sheet
    #[arg(long, value_delimiter = ',', value_name = "A,B,...")]
    pub labels: Option<Vec<String>>,
    /// Sequence colours, comma-separated palette names or #rrggbb [default: blue,orange,green,...]
    #[arg(long, value_delimiter = ',', value_parser = parse_colour, value_name = "C,C,...")]
    pub colours: Option<Vec<Rgb>>,
    /// Colour vertices by body part from this subject.json's curves (every sequence must fit it)
    #[arg(long, value_name = "SUBJECT_JSON")]
    pub subject: Option<PathBuf>,
    /// Flat shading (one normal per face) instead of smooth (Gouraud) shading
    #[arg(long)]
    pub flat: bool,
    /// No anti-aliasing (default: 2x2 supersampling)
    #[arg(long)]
    pub no_aa: bool,
    /// Light-grey background instead of white
    #[arg(long)]
    pub grey: bool,
    /// No ground grid
    #[arg(long)]
    pub no_floor: bool,
    /// Do not write frames/
    #[arg(long)]
    pub no_frames: bool,
    /// Do not write anim.gif
    #[arg(long)]
    pub no_gif: bool,
    /// Camera follows the first sequence across the ground (keeps travelling motions large in
    /// frame); with --separate-rows, every sequence is followed on its own
    #[arg(long)]
    pub follow: bool,
}

fn parse_view(s: &str) -> Result<View, String> {
    View::parse(s).ok_or_else(|| {
        "expected front, side, three-quarter or AZIMUTH,ELEVATION (|elevation| <= 90)".into()
    })
}
fn parse_axis(s: &str) -> Result<Axis, String> {
    Axis::parse(s).ok_or_else(|| "expected +x, -x, +y, -y, +z or -z".into())
}
fn parse_colour(s: &str) -> Result<Rgb, String> {
    colour::parse(s).ok_or_else(|| format!("unknown colour {s:?} (a palette name or #rrggbb)"))
}
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let p = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (8..=4096).contains(v))
    };
    let r = match s.split_once(['x', 'X']) {
        Some((w, h)) => p(w).zip(p(h)),
        None => p(s).map(|v| (v, v)),
    };
    r.ok_or_else(|| "expected N or WxH with each side in 8..=4096".into())
}
/// Moves every frame of every sequence so that the first sequence's centroid
/// stays above the origin of the ground plane (the plane orthogonal to `up`):
/// the camera then follows the subject while the relative placement of the
/// overlaid sequences, and all vertical motion, is kept.
pub fn follow_first(seqs: &mut [MeshSequence], up: &nalgebra::Vector3<f64>) {
    let Some(first) = seqs.first() else { return };
    let offsets: Vec<nalgebra::Vector3<f64>> = first
        .frames
        .iter()
        .map(|f| {
            let c = f.iter().sum::<nalgebra::Vector3<f64>>() / f.len().max(1) as f64;
            c - up * up.dot(&c)
        })
        .collect();
    let Some(&last) = offsets.last() else { return };
    for s in seqs.iter_mut() {
        for (i, frame) in s.frames.iter_mut().enumerate() {
            let o = offsets.get(i).copied().unwrap_or(last);
            for p in frame.iter_mut() {
                *p -= o;
            }
        }
    }
}

/// [`follow_first`] for the overlaid sequences, or with `each` (one contact-sheet row per
/// sequence) every sequence followed on its own.
pub fn follow(seqs: &mut [MeshSequence], up: &nalgebra::Vector3<f64>, each: bool) {
    if each {
        for seq in seqs.iter_mut() {
            follow_first(std::slice::from_mut(seq), up);
        }
    } else {
        follow_first(seqs, up);
    }
}

/// Runs the stage (after `args.common.init()`).
pub fn run(args: &Params) -> anyhow::Result<()> {
    check(args)?;
    let n_seq = args.seq_dirs.len();
    // Everything is read and checked before anything is written.
    let mut seqs: Vec<MeshSequence> = args
        .seq_dirs
        .iter()
        .map(MeshSequence::load_dir)
        .collect::<Result<_, _>>()?;
    if args.follow {
        follow(&mut seqs, &args.up.vector(), args.separate_rows);
    }
    let lens: Vec<usize> = seqs.iter().map(|s| s.frames.len()).collect();
    let longest = *lens.iter().max().unwrap_or(&0);
    if lens.iter().any(|&l| l != longest) {
        mesh_core::warn!(
            "sequences differ in length ({lens:?} frames): shorter ones hold their last frame"
        );
    }
    let range = match &args.frames {
        Some(r) if r.start >= longest => {
            bail!("--frames {}: the sequences have {longest} frames", r.start)
        }
        Some(r) => r.start..r.end.unwrap_or(usize::MAX).min(longest),
        None => 0..longest,
    };
    let part_colours = part_colours(args, &seqs)?;
    let colours: Vec<Rgb> = match &args.colours {
        Some(c) => c.clone(),
        None => (0..n_seq).map(colour::palette).collect(),
    };
    let views: Vec<SeqView> = seqs
        .iter()
        .zip(&part_colours)
        .map(|(s, pc)| match pc {
            Some(c) => SeqView::from(s).with_vertex_colours(c),
            None => SeqView::from(s),
        })
        .collect();
    let style = style(args);
    let projection = match args.perspective {
        Some(fov_y_deg) => ProjectionKind::Perspective { fov_y_deg },
        None => ProjectionKind::Orthographic,
    };
    let (w, h) = args.size;
    let bbox = bounding_box(&views, range.clone());
    let renderer = Renderer::new(&bbox, &args.camera, &args.up, projection, w, h, style);
    let legend: Vec<(String, Rgb)> = args
        .labels
        .iter()
        .flatten()
        .cloned()
        .zip(colours.iter().copied())
        .collect();
    let draw = |f: usize| -> RgbImage {
        let layers: Vec<Layer> = views
            .iter()
            .zip(&colours)
            .filter_map(|(v, &c)| {
                Some(Layer {
                    vertices: v.frame_clamped(f)?,
                    faces: v.faces,
                    colour: c,
                    vertex_colours: v.vertex_colours,
                })
            })
            .collect();
        let mut img = renderer.render(&layers);
        draw_legend(&mut img, &legend);
        img
    };

    let out = &args.out;
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output folder", out.display()))?;
    let chosen: Vec<usize> = range.clone().step_by(args.stride as usize).collect();
    write_frames_and_gif(args, &chosen, &draw)?;
    if args.contact_columns > 0 {
        let names: Vec<String> = match &args.labels {
            Some(l) => l.clone(),
            None => args.seq_dirs.iter().map(|d| short_name(d)).collect(),
        };
        let rows: Vec<Row> = if args.separate_rows || n_seq == 1 {
            views
                .iter()
                .zip(&colours)
                .zip(&names)
                .map(|((v, &c), n)| Row {
                    label: n.clone(),
                    sequences: vec![(c, *v)],
                })
                .collect()
        } else {
            vec![Row {
                label: names.join("\n"),
                sequences: colours.iter().copied().zip(views.iter().copied()).collect(),
            }]
        };
        let mut sheet = ContactSheet::new(rows);
        sheet.n_columns = args.contact_columns;
        sheet.cell_width = (w / 2).max(64);
        sheet.cell_height = (h / 2).max(64);
        sheet.frames = range.clone();
        sheet.view = args.camera;
        sheet.up = args.up;
        sheet.projection = projection;
        sheet.style = style;
        sheet.render().write_png(&out.join("contact.png"))?;
    }
    mesh_core::info!(
        "drew {} frames of {n_seq} sequence(s) into {}",
        chosen.len(),
        out.display()
    );
    Ok(())
}

/// The flags' own checks: one label and colour per sequence, a positive GIF rate, a field of
/// view between 1 and 170 degrees.
fn check(args: &Params) -> anyhow::Result<()> {
    let n_seq = args.seq_dirs.len();
    if let Some(l) = &args.labels {
        if l.len() != n_seq {
            bail!("--labels: {} labels for {n_seq} sequences", l.len());
        }
    }
    if let Some(c) = &args.colours {
        if c.len() != n_seq {
            bail!("--colours: {} colours for {n_seq} sequences", c.len());
        }
    }
    if !(args.gif_fps.is_finite() && args.gif_fps > 0.0) {
        bail!("--gif-fps must be a positive number");
    }
    if let Some(f) = args.perspective {
        if !(f.is_finite() && f > 1.0 && f < 170.0) {
            bail!("--perspective: field of view must be between 1 and 170 degrees");
        }
    }
    Ok(())
}

/// With `--subject`, every sequence's vertex colours by body part; else none.
fn part_colours(args: &Params, seqs: &[MeshSequence]) -> anyhow::Result<Vec<Option<Vec<Rgb>>>> {
    let Some(path) = &args.subject else {
        return Ok(vec![None; seqs.len()]);
    };
    let spec = crate::parts::read_subject(path)?;
    seqs.iter()
        .zip(&args.seq_dirs)
        .map(|(s, dir)| {
            crate::parts::part_colours(&spec, path, &s.frames[0], &s.faces)
                .map(Some)
                .with_context(|| format!("{}: with --subject", dir.display()))
        })
        .collect()
}

/// The drawing style the flags ask for.
fn style(args: &Params) -> Style {
    Style {
        shading: if args.flat { Shading::Flat } else { Shading::Gouraud },
        supersample: if args.no_aa { 1 } else { 2 },
        background: if args.grey { colour::LIGHT_GREY } else { colour::WHITE },
        floor: !args.no_floor,
        ..Style::default()
    }
}

/// The `chosen` frames drawn by `draw` into `<out>/frames/NNNNNN.png` and `<out>/anim.gif`
/// (unless `--no-frames` / `--no-gif`), 64 at a time.
fn write_frames_and_gif(args: &Params, chosen: &[usize], draw: &(dyn Fn(usize) -> RgbImage + Sync)) -> anyhow::Result<()> {
    let out = &args.out;
    let (w, h) = args.size;
    let want_frames = !args.no_frames;
    let want_gif = !args.no_gif;
    let mut gif = if want_gif {
        let picks: Vec<usize> = (0..8).map(|k| chosen[k * (chosen.len() - 1) / 7]).collect();
        let samples: Vec<RgbImage> = picks.par_iter().map(|&f| draw(f)).collect();
        let refs: Vec<&RgbImage> = samples.iter().collect();
        Some(
            GifBuilder::new(w, h, args.gif_fps, GifPalette::learn(&refs))
                .map_err(|e| anyhow::anyhow!("{}: {e}", out.join("anim.gif").display()))?,
        )
    } else {
        None
    };
    if want_frames || want_gif {
        let frames_dir = out.join("frames");
        let bar = mesh_core::cli::progress_bar(chosen.len() as u64, "render", &args.common);
        // Chunks bound memory; frames within a chunk render in parallel, in any order,
        // each independently, so the output does not depend on the thread count.
        for (c, chunk) in chosen.chunks(64).enumerate() {
            let images: Vec<RgbImage> = chunk.par_iter().map(|&f| draw(f)).collect();
            if want_frames {
                images.par_iter().enumerate().try_for_each(|(k, img)| {
                    img.write_png(&frames_dir.join(format!("{:06}.png", c * 64 + k)))
                })?;
            }
            if let Some(g) = gif.as_mut() {
                for img in &images {
                    g.push(img)
                        .map_err(|e| anyhow::anyhow!("{}: {e}", out.join("anim.gif").display()))?;
                }
            }
            bar.inc(chunk.len() as u64);
        }
        bar.finish_and_clear();
        if want_frames {
            remove_stale_frames(&frames_dir, chosen.len())?;
        }
    }
    if let Some(g) = gif {
        let path = out.join("anim.gif");
        let bytes = g
            .finish()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        mesh_core::atomic::write_bytes_atomic(&path, &bytes)?;
    }
    Ok(())
}

/// Removes `NNNNNN.png` files numbered `n` or above left in `dir` by an
/// earlier, longer run, so `frames/` holds exactly this run's frames.
fn remove_stale_frames(dir: &std::path::Path, n: usize) -> anyhow::Result<()> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?;
    for entry in entries {
        let path = entry
            .with_context(|| format!("{}: cannot list", dir.display()))?
            .path();
        let stale = path.extension().is_some_and(|e| e == "png")
            && path
                .file_stem()
                .and_then(|s| s.to_str())
                .filter(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|s| s.parse::<usize>().ok())
                .is_some_and(|k| k >= n);
        if stale {
            std::fs::remove_file(&path)
                .with_context(|| format!("{}: cannot remove stale frame", path.display()))?;
        }
    }
    Ok(())
}

/// A folder's last component (for default row labels).
fn short_name(p: &std::path::Path) -> String {
    p.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

/// Sequence names in their colours, top-left.
fn draw_legend(img: &mut RgbImage, legend: &[(String, Rgb)]) {
    let s = (img.height / 256).max(1);
    for (k, (text, c)) in legend.iter().enumerate() {
        let y = (4 + k as u32 * (font::GLYPH_H + 3)) * s;
        font::draw_text(img, 4 * s as i64, y as i64, text, s, *c);
    }
}

#[cfg(test)]
mod follow_tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn follow_removes_ground_travel_but_keeps_height_and_relative_offsets() {
        let tri = vec![[0u32, 1, 2]];
        let frame = |x: f64, y: f64| vec![Vector3::new(x, y, 0.0), Vector3::new(x + 1.0, y, 0.0), Vector3::new(x, y + 1.0, 0.0)];
        let a = MeshSequence::new(tri.clone(), vec![frame(0.0, 0.0), frame(5.0, 2.0)]);
        let b = MeshSequence::new(tri, vec![frame(1.0, 0.0), frame(6.0, 0.0)]);
        let mut seqs = vec![a, b];
        follow_first(&mut seqs, &Vector3::y());
        let c = |f: &Vec<Vector3<f64>>| f.iter().sum::<Vector3<f64>>() / 3.0;
        assert!((c(&seqs[0].frames[0]).x - c(&seqs[0].frames[1]).x).abs() < 1e-12);
        assert!((c(&seqs[0].frames[1]).y - (2.0 + 1.0 / 3.0)).abs() < 1e-12, "height kept");
        assert!((c(&seqs[1].frames[1]).x - c(&seqs[0].frames[1]).x - 1.0).abs() < 1e-12, "relative offset kept");
    }

    #[test]
    fn with_one_row_per_sequence_each_sequence_is_followed_on_its_own() {
        let tri = vec![[0u32, 1, 2]];
        let frame = |x: f64, z: f64| vec![Vector3::new(x, 0.0, z), Vector3::new(x + 1.0, 0.0, z), Vector3::new(x, 1.0, z)];
        let a = MeshSequence::new(tri.clone(), vec![frame(0.0, 0.0), frame(5.0, 0.0)]);
        let b = MeshSequence::new(tri, vec![frame(0.0, 3.0), frame(-4.0, 9.0)]);
        let mut seqs = vec![a, b];
        follow(&mut seqs, &Vector3::y(), true);
        let c = |f: &Vec<Vector3<f64>>| f.iter().sum::<Vector3<f64>>() / 3.0;
        for s in &seqs {
            for f in &s.frames {
                let g = c(f);
                assert!(g.x.abs() < 1e-12 && g.z.abs() < 1e-12, "{g:?}");
            }
        }
    }
}

#[cfg(test)]
mod params_tests {
    use super::*;

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        let argv = ["render", "a", "b", "--out", "r", "--camera", "30,10", "--size", "64x48", "--colours", "red,#00ff00"];
        assert_eq!(mesh_core::cli::unrecorded_options::<Params>(&argv).unwrap(), Vec::<String>::new());
        let r = serde_json::to_value(Params::try_parse_from(argv).unwrap()).unwrap();
        assert_eq!(r["size"], serde_json::json!([64, 48]));
        assert_eq!(r["camera"], serde_json::json!({"azimuth_deg": 30.0, "elevation_deg": 10.0}));
    }
}
