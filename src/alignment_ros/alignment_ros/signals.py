"""SIGINT/SIGTERM as a flag a main loop polls (no heavy imports: the recorder and the player start
in well under a second)."""
from __future__ import annotations

import signal


def stop_on_signals() -> dict[str, bool]:
    """SIGINT/SIGTERM set the returned dict's 'signal' flag (for a main loop to poll)."""
    stop = {'signal': False}

    def on_signal(signum: int, frame: object) -> None:
        stop['signal'] = True
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    return stop
