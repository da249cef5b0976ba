//! Poisson surface reconstruction: cotangent Laplacian, deformation gradients, correction, stitching, blending (being written)
