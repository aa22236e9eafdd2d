"""The episode tools behind ``tactile replay`` (controller/cli/replay.py, docs/EPISODES.md
"Tools"), on top of the reader (``controller.episode``): an episode's streams as arrays
(episode_streams), its summary, chart (episode_chart, trial_chart), re-estimation, the
LeRobot v3.0 export (lerobot_*, image_stats) and the Rerun export (rerun_export)."""
