"""The renderer's appearance against real gel captures: image statistics (stats), their tool
(stats_cli, python -m evaluation gel_stats), the fit of a realistic look (fit) and the side-by-side
figure (figure)."""
