"""What a recording did, for its --stats file and its closing line, and the expected counts it
waits for (the recorder's end: recorder.py)."""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from alignment_ros.bag import BagWriter
from alignment_ros.record_progress import ProgressPublisher

if TYPE_CHECKING:
    from alignment_ros.recorder import Recorder


def read_expected(path: Path) -> dict[str, int] | None:
    """The expected counts ({topic: count}) once the file exists (written atomically), else None."""
    try:
        text = path.read_text()
    except FileNotFoundError:
        return None
    return {str(k): int(v) for k, v in json.loads(text).items()}


def recording_stats(args: argparse.Namespace, rec: Recorder, writer: BagWriter, reason: str,
           expected: dict[str, int] | None, reached: ProgressPublisher | None) -> dict[str, Any]:
    """What the recording did (the --stats file)."""
    span = (rec.last_rx - rec.first_rx) if rec.first_rx is not None and rec.last_rx is not None else 0.0
    total = sum(rec.counts.values())
    return {
        'bag': str(args.output),
        'files': writer.metadata.relative_file_paths if writer.metadata else [],
        'topics': rec.counts,
        'total': total,
        'end_reason': reason,
        'expected': expected,
        'missing': rec.missing(expected or {}),
        'taken_directly': rec.taken_directly,
        'last_stamp_ns': rec.last_stamp_ns,
        'publishers': rec.publishers(),
        'executor': args.executor,
        'progress_published': reached.published if reached is not None else 0,
        'receive_span_s': span,
        'first_message_unix_s': rec.first_rx_unix,
        'receive_rate_msg_s': total / span if span > 0 else None,
        'cpu_s': time.process_time(),
        'cpu_ready_s': rec.first_rx_cpu_s,
        'reorder': {'peak_bytes': writer.reorder.peak_bytes,
                    'peak_messages': writer.reorder.peak_messages, 'late': writer.reorder.late},
    }


def report(args: argparse.Namespace, stats: dict[str, Any]) -> None:
    """The stats file and the closing line."""
    if args.stats:
        args.stats.parent.mkdir(parents=True, exist_ok=True)
        args.stats.write_text(json.dumps(stats, indent=2) + '\n')
    print(f'recorder done ({stats["end_reason"]}): {stats["total"]} messages in {args.output}',
          flush=True)
