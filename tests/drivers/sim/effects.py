"""Every image effect of the renderer switched on at once, for the renderer tests."""

from drivers.sim.render.image_effects import ImageEffects

ALL = ImageEffects(
    noise_grey=3.0,
    drift_gain_per_level=(0.04, -0.03, 0.02),
    drift_gradient_grey_per_level=6.0,
    blur_sigma_px=0.8,
    motion_blur_samples=3,
    marker_dropout_fraction=0.2,
    occlusion_count=2,
)
