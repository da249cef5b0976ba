//! Gaussian Process Dynamical Model and Hybrid Monte Carlo sampling (being written)
