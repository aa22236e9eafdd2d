"""The offline tools' pieces on recorded tactile data (``tactile estimate``, ``tactile
calibrate``: controller/cli/): video files (video, quiet_decoding), the calibration dataset's
format and its fit (dataset, dataset_fit), the open gel's check (open_gel) and a recording's
grasp support (recording_support)."""
