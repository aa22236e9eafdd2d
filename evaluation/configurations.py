"""The estimator configurations compared by the benchmark and the speed-accuracy chart: the
paper's, the Mini's default (its profile's ``estimator``), the dense-flow default for gels
without markers, and one-knob variants (flow method and preset, image scale, grey or
per-channel, grid stride, divergence of the raw field or of its NHHD part, temporal filter).
``PAPER`` and ``DEFAULT`` are the labels of the paper's and the default configuration."""

from __future__ import annotations

from dataclasses import replace

from controller.config import sensor_profile
from controller.tactile.settings import EstimatorConfig, estimator_config, sensor_estimator

PAPER = "**paper** (Farneback per-channel w32, 12x9)"
DEFAULT = "**default** (Mini: LK on printed markers, 16x12)"
DENSE = "dense (DIS tuned, gray, 16x12; no-marker default)"


def estimator_variants(quick: bool) -> list[tuple[str, EstimatorConfig]]:
    _, default = sensor_estimator(sensor_profile("gelsight_mini"))
    dense = estimator_config("dense")
    paper = estimator_config("paper")
    fl = dense.flow
    fb = paper.flow.farneback
    plain_dis = replace(
        fl.dis,
        finest_scale=None,
        patch_size=None,
        patch_stride=None,
        gradient_descent_iterations=None,
        variational_refinement_iterations=None,
    )
    configs = [(PAPER, paper), (DEFAULT, default), (DENSE, dense)]
    if quick:
        return configs
    dis = [
        (
            f"DIS {p} gray, scale {s}",
            replace(dense, flow=replace(fl, scale=s, dis=replace(plain_dis, preset=p))),
        )
        for p in ("ultrafast", "fast", "medium")
        for s in (1.0, 0.5)
    ]
    return configs + [
        ("fast (dense without spatial propagation)", estimator_config("fast")),
        ("Farneback w32 gray, 12x9", replace(paper, flow=replace(paper.flow, color="gray"))),
        (
            "Farneback w12 gray, scale 0.5, 1 level",
            replace(
                dense,
                flow=replace(
                    paper.flow,
                    color="gray",
                    scale=0.5,
                    farneback=replace(fb, winsize=12, levels=1, iterations=2, poly_sigma=1.1),
                ),
            ),
        ),
        *dis,
        (
            "DIS ultrafast per-channel",
            replace(dense, flow=replace(fl, color="per_channel", dis=plain_dis)),
        ),
        ("dense, warm start", replace(dense, flow=replace(fl, warm_start=True))),
        ("dense, NHHD-part divergence", replace(dense, divergence_of="curl_free")),
        ("default, grid 32x24 (stride 10)", replace(default, stride_px=10)),
        ("default, grid 12x9 (stride 26.7)", replace(default, stride_px=26.667)),
        ("default, grid 8x6 (stride 40)", replace(default, stride_px=40)),
        ("default, NHHD-part divergence", replace(default, divergence_of="curl_free")),
        ("default, EMA 0.6 (the paper's filter)", replace(default, ema_alpha=0.6)),
    ]
