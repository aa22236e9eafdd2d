"""The renderer's appearance against real gel captures: image statistics (stats), their tool
(stats_cli, scripts/gel_stats.py), the fit of a realistic look (fit) and the side-by-side
figure (figure)."""
