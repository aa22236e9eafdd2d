"""Episodes: one MCAP file per run (docs/EPISODES.md).

Product code at the edge: the run path (``controller.run``) hooks the writer in as a loop
observer and a tap on the wrench source; the state machine never imports it.

* ``topics``: every topic, its schema, encoding, frame and units (the format's contract);
* ``reader``: ``read_episode(path) -> Episode`` (finished, cut or damaged files alike;
  ``scan`` reads the records past damage);
* ``repair``: ``repair(path, out) -> RepairReport`` (finishes a killed run's file; import it
  from ``controller.episode.repair``);
* ``writer``, ``recorder``, ``session``: the writing side (``EpisodeRecording``).
"""

from controller.episode.reader import (
    Episode,
    EpisodeError,
    EpisodeMessage,
    decode_image,
    grid_arrays,
    read_episode,
)
from controller.episode.topics import TOPICS, Topic

__all__ = [
    "TOPICS",
    "Episode",
    "EpisodeError",
    "EpisodeMessage",
    "Topic",
    "decode_image",
    "grid_arrays",
    "read_episode",
]
