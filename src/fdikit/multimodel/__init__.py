"""Multiple-model estimation and diagnosis (Hallouzi 2008): Kalman/EKF building blocks, the IMM filter,
convex-model filters and model-set design."""
