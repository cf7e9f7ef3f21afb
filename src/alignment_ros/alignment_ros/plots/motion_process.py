"""The ship-motion figure of some bags, drawn in a process of its own (plots.read_and_draw):

    python -m alignment_ros.plots.motion_process PNG BAG [BAG ...]

prints the PNG's path when drawn, nothing when the bags hold none of its topics; on an error, its
line on stderr and exit status 1."""
from __future__ import annotations

import logging
import sys
from pathlib import Path

from . import MOTION_TOPICS, motion
from .series import read


def main(argv: list[str]) -> int:
    png, *bags = argv
    logging.getLogger('alignment_ros').setLevel(logging.ERROR)    # the bag's warnings: the caller's to give
    try:
        path = motion.motion(read([Path(b) for b in bags], MOTION_TOPICS), Path(png))
    except Exception as e:     # noqa: BLE001 (the caller raises it)
        print(f'{type(e).__name__}: {e}', file=sys.stderr)
        return 1
    if path is not None:
        print(path)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
