"""The estimator configurations compared by the benchmark and the speed-accuracy chart: the
paper's, the default (the sensor profiles' ``estimator``), and one-knob variants of the
default (flow method and preset, image scale, grey or per-channel, grid stride, divergence
of the raw field or of its NHHD part, the dipole's grid, temporal filter). The grid stride
is varied through the dipole's grid: with square blocks pooling is exact
(tests/tactile/test_estimator.py), so a flow grid of 8x6 gives the 8x6 dipole exactly.
``PAPER`` and ``DEFAULT`` are the labels of the paper's and the default configuration."""

from __future__ import annotations

from dataclasses import replace

from controller.tactile.settings import DipoleGrid, EstimatorConfig, estimator_config

PAPER = "**paper** (Farneback per-channel w32, 12x9)"
DEFAULT = "**default** (DIS tuned, gray, 16x12, dipole on 4x4 curl-free)"


def estimator_variants(quick: bool) -> list[tuple[str, EstimatorConfig]]:
    default = estimator_config("default")
    paper = estimator_config("paper")
    fl = default.flow
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
    configs = [(PAPER, paper), (DEFAULT, default), ("markers", estimator_config("markers"))]
    if quick:
        return configs

    def dis(**change) -> EstimatorConfig:
        return replace(default, flow=replace(fl, dis=replace(fl.dis, **change)))

    presets = [
        (
            f"DIS {p} gray, scale {s}",
            replace(default, flow=replace(fl, scale=s, dis=replace(plain_dis, preset=p))),
        )
        for p in ("ultrafast", "fast", "medium")
        for s in (1.0, 0.5)
    ]
    return configs + [
        ("Farneback w32 gray, 12x9", replace(paper, flow=replace(paper.flow, color="gray"))),
        (
            "Farneback w12 gray, scale 0.5, 1 level",
            replace(
                default,
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
            "DIS ultrafast per-channel",
            replace(default, flow=replace(fl, color="per_channel", dis=plain_dis)),
        ),
        ("default, DIS spatial propagation", dis(use_spatial_propagation=True)),
        ("default, DIS patches every 4 px", dis(patch_stride=4)),
        ("default, DIS patches every 8 px", dis(patch_stride=8)),
        ("default, warm start", replace(default, flow=replace(fl, warm_start=True))),
        ("default, dipole on 4x3 blocks", replace(default, dipole_grid=DipoleGrid(4, 3))),
        ("default, dipole on 8x6 blocks", replace(default, dipole_grid=DipoleGrid(8, 6))),
        ("default, dipole on the 16x12 grid", replace(default, dipole_grid=None)),
        ("default, raw-field divergence", replace(default, divergence_of="raw")),
        (
            "session 3's default (patches every 4 px, dipole on 8x6)",
            replace(
                default,
                dipole_grid=DipoleGrid(8, 6),
                flow=replace(fl, dis=replace(fl.dis, patch_stride=4)),
            ),
        ),
        ("default, EMA 0.6 (the paper's filter)", replace(default, ema_alpha=0.6)),
    ]
