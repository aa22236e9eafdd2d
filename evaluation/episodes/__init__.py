"""The episode tools (``tactile replay``, docs/EPISODES.md "Tools"): an episode file's
summary, chart, re-estimation, LeRobot v3.0 export and repair, on top of the product's reader
(``controller.episode``)."""
