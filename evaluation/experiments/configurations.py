"""The estimator configurations compared by the benchmark and the speed-accuracy chart: the
paper's, the sensors' ``default`` (the Mini's profile's ``estimator``: grid Lucas-Kanade per
colour channel; the DIGIT's too), ``default_grey`` (on the luminance) and one-knob variants
of ``default`` (warm start, iterations, smoothness, the dipole's grid), and the DIS family
around ``dis_half`` (a faster configuration for marker gels: flow preset, image scale, grey
or per-channel, patch stride, variational refinement, divergence of the raw field or of its
NHHD part, the dipole's grid, temporal filter) and cheaper Farneback settings. The grid
stride is varied through the dipole's grid: with square blocks pooling is exact
(tests/controller/tactile/test_estimator.py), so a flow grid of 8x6 gives the 8x6 dipole
exactly. ``PAPER`` and ``DEFAULT`` are the labels of the paper's and the Mini's default
configuration."""

from __future__ import annotations

from dataclasses import replace

from controller.tactile.settings import DipoleGrid, EstimatorConfig, estimator_config
from core.sensor_profile import sensor_profile

PAPER = "**paper** (Farneback per-channel w32, 12x9)"
DEFAULT = "**default** (both sensors': grid LK per channel, 16x12, grasp-centred dipole)"
GREY = "default_grey (grid LK on the luminance: faster, for marker gels)"
DIS_HALF = "dis_half (DIS tuned, gray, half resolution)"


def estimator_variants(
    quick: bool, fallback_variants: bool = True
) -> list[tuple[str, EstimatorConfig]]:
    """The compared configurations, (label, configuration); ``quick``: the first five.
    ``fallback_variants``: include the default's dipole-grid variants, which differ from it
    only without open-gel frames (the fallback path): the benchmark times that path; the
    speed-accuracy chart's datasets all have open frames, where they are the default."""
    default = estimator_config(sensor_profile("gelsight_mini").estimator)
    paper = estimator_config("paper")
    dis_half = estimator_config("dis_half")
    fl = dis_half.flow
    fb = paper.flow.farneback
    plain_dis = replace(
        fl.dis,
        finest_scale=None,
        patch_size=None,
        patch_stride=None,
        gradient_descent_iterations=None,
        variational_refinement_iterations=None,
        use_spatial_propagation=None,
    )
    configs = [
        (PAPER, paper),
        (DEFAULT, default),
        (GREY, estimator_config("default_grey")),
        (DIS_HALF, dis_half),
        ("markers", estimator_config("markers")),
    ]
    if quick:
        return configs
    lk = default.flow

    def grid_lk(**change) -> EstimatorConfig:
        return replace(default, flow=replace(lk, grid_lk=replace(lk.grid_lk, **change)))

    def dis(**change) -> EstimatorConfig:
        return replace(dis_half, flow=replace(fl, dis=replace(fl.dis, **change)))

    presets = [
        (
            f"DIS {p} gray, scale {s}",
            replace(dis_half, flow=replace(fl, scale=s, dis=replace(plain_dis, preset=p))),
        )
        for p in ("ultrafast", "fast", "medium")
        for s in (1.0, 0.5)
    ]
    refined = replace(plain_dis, preset="ultrafast", variational_refinement_iterations=5)
    return configs + [
        ("default, cold start", replace(default, flow=replace(lk, warm_start=False))),
        ("default, one Gauss-Newton step", grid_lk(iterations=1)),
        ("default, smoothness 0.1", grid_lk(smoothness=0.1)),
        ("default, smoothness 1", grid_lk(smoothness=1.0)),
        *(
            [
                ("default, dipole on 8x6 blocks", replace(default, dipole_grid=DipoleGrid(8, 6))),
                ("default, dipole on the 16x12 grid", replace(default, dipole_grid=None)),
            ]
            if fallback_variants
            else []
        ),
        ("Farneback w32 gray, 12x9", replace(paper, flow=replace(paper.flow, color="gray"))),
        (
            "Farneback w12 gray, scale 0.5, 1 level",
            replace(
                dis_half,
                flow=replace(
                    paper.flow,
                    color="gray",
                    scale=0.5,
                    farneback=replace(fb, winsize=12, levels=1, iterations=2, poly_sigma=1.1),
                ),
            ),
        ),
        *presets,
        (
            "DIS ultrafast gray, scale 1.0, variational refinement",
            replace(dis_half, flow=replace(fl, scale=1.0, dis=refined)),
        ),
        (
            "DIS ultrafast per-channel",
            replace(dis_half, flow=replace(fl, color="per_channel", dis=plain_dis)),
        ),
        ("dis_half, DIS spatial propagation", dis(use_spatial_propagation=True)),
        ("dis_half, DIS patches every 4 px", dis(patch_stride=4)),
        ("dis_half, DIS patches every 8 px", dis(patch_stride=8)),
        ("dis_half, dipole on 8x6 blocks", replace(dis_half, dipole_grid=DipoleGrid(8, 6))),
        ("dis_half, raw-field divergence", replace(dis_half, divergence_of="raw")),
        ("dis_half, EMA 0.6 (the paper's filter)", replace(dis_half, ema_alpha=0.6)),
    ]
