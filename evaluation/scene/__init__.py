"""Measurements of the simulated insertion scene itself (what its torques and contacts look
like to the machine), by running the product's trials and reading the scene's truth."""
