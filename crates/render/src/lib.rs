//! Software rasterizer: mesh sequences to PNG frames, contact sheets and GIFs.
//!
//! This is how everyone looks at surfcap results: one or several mesh
//! sequences drawn overlaid, each in its own colour (as in the variation
//! paper's overlapped figures), with a camera fixed over the whole animation.
//!
//! - [`camera`]: bounding box, view presets, orthographic/perspective framing.
//! - [`lighting`]: Lambert head + fill + ambient lighting.
//! - [`raster`]: z-buffered triangle and line rasterization.
//! - [`scene`]: layers, style, floor grid, [`scene::Renderer`].
//! - [`font`]: built-in 5x7 bitmap font for labels.
//! - [`image`]: RGB images and PNG encoding.
//! - [`contact`]: contact sheets (rows of sequences x evenly spaced frames).
//! - [`anim`]: animated GIF with one global palette.
//! - [`parts`]: per-vertex body-part colours from a subject's curves.
//! - [`sequence`]: borrowed views of mesh sequences and loading folders of frames.
//! - [`stage`]: the `render` command line.

pub mod anim;
pub mod camera;
pub mod colour;
pub mod contact;
pub mod font;
pub mod image;
pub mod lighting;
pub mod parts;
pub mod raster;
pub mod scene;
pub mod sequence;
pub mod stage;

pub use camera::{Aabb, Axis, Camera, ProjectionKind, View};
pub use colour::Rgb;
pub use image::RgbImage;
pub use scene::{Layer, Renderer, Shading, Style};
