//! Gaussian-process regression numerics: kernels, marginal likelihood, conjugate gradients, Bayesian linear regression, DTW, PCA (being written)
