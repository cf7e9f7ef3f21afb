"""The ship model for `ship.mode`: paper sinusoids or a spectral sea."""
from __future__ import annotations

from alignment_core.ship.config import ShipConfig
from alignment_core.ship.paper import PaperShipMotion
from alignment_core.validation import ConfigError


def make_motion(cfg: ShipConfig, seed: int):
    """The ship model for `cfg.mode`: PaperShipMotion or spectral.SpectralShipMotion."""
    if cfg.mode == 'paper':
        return PaperShipMotion(cfg, seed)
    if cfg.mode == 'spectral':
        from alignment_core.ship.spectral import SpectralShipMotion
        return SpectralShipMotion(cfg, seed)
    raise ConfigError(f"ship.mode {cfg.mode!r} is not available")
