//! Software rasterizer: mesh sequences to PNG frames, contact sheets and GIFs (being written)
