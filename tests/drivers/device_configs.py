"""Load a device YAML as a script does: ``drivers.registry.select`` then ``drivers.config``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from drivers import registry
from drivers.config import build, load_yaml

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def load_device_config(path: Path | str, backend: str | None = None) -> Any:
    """The config dataclass of the device YAML at ``path`` (``backend`` overrides the file's)."""
    selection = registry.select(load_yaml(path), backend)
    return build(selection.config_class, selection.keys, source=str(path))
