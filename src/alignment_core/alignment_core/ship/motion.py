"""The ship model for `ship.mode`: paper sinusoids or a spectral sea."""
from __future__ import annotations

from alignment_core.ship.config import ShipConfig
from alignment_core.ship.paper import PaperShipMotion
from alignment_core.validation import ConfigError


def model_class(cfg: ShipConfig) -> type:
    """The class of the ship model for `cfg.mode`: PaperShipMotion or spectral.SpectralShipMotion
    (imported here, not with this module: a launcher imports it before it forks the ship)."""
    if cfg.mode == 'paper':
        return PaperShipMotion
    if cfg.mode == 'spectral':
        from alignment_core.ship.spectral import SpectralShipMotion
        return SpectralShipMotion
    raise ConfigError(f"ship.mode {cfg.mode!r} is not available")


def make_motion(cfg: ShipConfig, seed: int):
    """The ship model for `cfg.mode`."""
    return model_class(cfg)(cfg, seed)
