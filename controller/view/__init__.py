"""The live view and the live stream of a run, fed by the episode writer's listeners
(``controller.episode.writer.Listener``), so the control loop never waits for them.

* ``snapshot``: ``ViewSnapshot``, what the view draws for one tactile frame;
* ``feed``: ``ViewFeed``, the episode writer's listener that builds the snapshots;
* ``view_drawing``: drawing a snapshot on a pygame Surface (imports pygame);
* ``window``: ``LiveView``, the view's own process, its keys and screenshots;
* ``live_stream``: ``FoxgloveLiveStream``, the episode's streams served over Foxglove's
  WebSocket protocol (foxglove-sdk).

Nothing in the run path imports this package: a run without a view never loads pygame.
"""
