"""``bag_reindex BAG``: ``ros2 bag reindex`` for this project's rosbag2 MCAP bags, and the repair
run_graph and replay apply to a bag whose recorder died or whose file is damaged.

What was written is kept, what is derived is rebuilt:

* a recording spool left behind (``NAME.recording.mcap``: the recorder was killed before it
  closed the bag) is sorted by log time and written as :class:`~alignment_ros.bag_writer.BagWriter`
  writes a bag (``NAME_0.mcap`` with chunk index and summary); the bag files the recorder was
  writing go (the spool holds all they held, and more);
* a bag file without a valid MCAP summary (cut short, e.g. mid-chunk) is rewritten with every
  complete message it still holds (:class:`~alignment_ros.mcap_salvage.Salvage`), with its
  channels' QoS profiles and type hashes;
* ``metadata.yaml`` is then rebuilt from the files' summaries, as rosbag2's reindex does.

Only for a bag no recorder is writing any more. Schemas are the installed definitions (the
writer's rule), so a type not installed here keeps its name but loses its definition text.
"""
from __future__ import annotations

import argparse
import logging
import os
import shutil
import struct
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import zstandard
from mcap.exceptions import McapError
from mcap.reader import SeekingReader

from alignment_ros.bag import BagReader, _mcap_files
from alignment_ros.bag_metadata import (
    BagError,
    BagMetadata,
    FileInfo,
    TopicInfo,
    from_yaml,
    parse_qos,
    to_yaml,
)
from alignment_ros.bag_writer import MCAP_MAGIC, NO_MESSAGE_TIME, SPOOL_SUFFIX, BagWriter
from alignment_ros.mcap_salvage import Salvage

ZSTD_MAGIC = b'\x28\xb5\x2f\xfd'
WORK_DIR = '.reindex'


@dataclass
class Reindexed:
    """What a reindex found and did."""

    bag: Path
    damage: str | None                  # why the bag needed it (None: it was intact)
    messages: int = 0                   # messages in the bag afterwards
    rewritten: list[str] = field(default_factory=list)   # files written from salvaged records
    salvaged: int = 0                   # complete messages those files kept

    def line(self) -> str:
        """One line saying what happened."""
        if self.damage is None:
            return f'{self.bag}: intact; metadata.yaml rebuilt ({self.messages} messages)'
        return (f'{self.bag}: {self.damage}; reindexed: {self.salvaged} complete messages kept in '
                f'{", ".join(self.rewritten) or "no file"}, {self.messages} in the bag')


# --- reading ---------------------------------------------------------------------------------

def _readable(path: Path) -> bytes:
    """The MCAP bytes of a bag file (a ``.mcap.zstd`` decompressed; a cut one: its prefix)."""
    if not path.name.endswith('.zstd'):
        return path.read_bytes()
    out = bytearray()
    with path.open('rb') as fh:
        reader = zstandard.ZstdDecompressor().stream_reader(fh, read_across_frames=True)
        try:
            while chunk := reader.read(1 << 20):
                out += chunk
        except zstandard.ZstdError:
            pass
    return bytes(out)


def _message_count(path: Path) -> int | None:
    """Messages a bag file's MCAP summary counts; None if it has no valid summary."""
    try:
        if path.name.endswith('.zstd'):
            with tempfile.TemporaryFile() as fh:
                fh.write(_readable(path))
                fh.seek(0)
                return _summary_count(fh)
        with path.open('rb') as fh:
            return _summary_count(fh)
    except (McapError, OSError, ValueError, struct.error, zstandard.ZstdError):
        return None


def file_intact(path: Path) -> bool:
    """Whether a bag file has a valid MCAP summary (else it is read by a linear scan)."""
    return _message_count(Path(path)) is not None


def _summary_count(fh) -> int | None:
    if fh.read(8) != MCAP_MAGIC:
        return None
    fh.seek(0)
    summary = SeekingReader(fh).get_summary()
    if summary is None or summary.statistics is None:
        return None
    return summary.statistics.message_count


def _files(bag: Path) -> list[Path]:
    """The bag files (``NAME_k.mcap[.zstd]`` in natural order), not the recording spool."""
    return [f for f in _mcap_files(bag) if not f.name.endswith(SPOOL_SUFFIX)]


def _bag_dir(path: Path) -> Path:
    path = Path(path)
    if (path / 'bag').is_dir() and not _mcap_files(path):
        path = path / 'bag'    # a run directory of run_graph.sh / replay.sh
    if not path.is_dir():
        raise BagError(f'{path}: not a bag directory')
    return path


def _old_metadata(bag: Path) -> BagMetadata | None:
    try:
        return from_yaml((bag / 'metadata.yaml').read_text())
    except (OSError, BagError):
        return None


def damage(bag: Path) -> str | None:
    """Why the bag needs a reindex (a spool left, metadata.yaml missing or not matching its
    files, a file without a valid MCAP summary), or None if it is intact."""
    bag = _bag_dir(bag)
    spools = sorted(bag.glob('*' + SPOOL_SUFFIX))
    if spools:
        return f'{spools[0].name} left: the recorder did not close the bag'
    files = _files(bag)
    if not files:
        raise BagError(f'{bag}: not a rosbag2 MCAP bag (no .mcap file)')
    counts = {}
    for f in files:
        n = _message_count(f)
        if n is None:
            return f'{f.name} has no valid MCAP summary (cut short?)'
        counts[f.name] = n
    if not (bag / 'metadata.yaml').exists():
        return 'no metadata.yaml'
    meta = _old_metadata(bag)
    if meta is None:
        return 'metadata.yaml unreadable'
    if sorted(meta.relative_file_paths) != sorted(counts):
        return 'metadata.yaml does not list the bag files'
    if meta.message_count != sum(counts.values()):
        return (f'metadata.yaml counts {meta.message_count} messages, the files '
                f'{sum(counts.values())}')
    return None


# --- writing ---------------------------------------------------------------------------------

def _salvage(path: Path) -> Salvage:
    sal = Salvage(_readable(path))
    if bytes(sal.buf[:8]) == MCAP_MAGIC:
        sal.scan(8, len(sal.buf))
    return sal


def _write(sal: Salvage, work: Path, name: str, mode: str, custom_data: dict[str, str] | None
           ) -> list[Path]:
    """Write the salvaged channels and messages as a bag named `name` under `work` (log-time
    order, summary, index: what BagWriter.close writes); return its files."""
    if mode == 'none' and sal.messages and all(d[:4] == ZSTD_MAGIC for _, _, _, d in sal.messages):
        mode = 'message'      # zstd frames, not CDR (the encapsulation header is 00 01 00 00)
    unpack = zstandard.ZstdDecompressor().decompress if mode == 'message' else bytes
    writer = BagWriter(work / name, compression_mode=mode,
                       compression_format='' if mode == 'none' else 'zstd', custom_data=custom_data)
    topic_of: dict[int, str] = {}
    for cid in sorted(sal.channels):
        topic, sid = sal.channels[cid]
        type_name = sal.schemas.get(sid, '')
        if not type_name:
            raise BagError(f'channel {topic} has no schema: cannot rewrite it')
        meta = sal.channel_info.get(cid, ('cdr', {}))[1]
        qos = meta.get('offered_qos_profiles')
        writer.add_topic(topic, type_name, type_hash=meta.get('topic_type_hash') or None,
                         offered_qos=parse_qos(qos) if qos else None)
        topic_of[cid] = topic
    for t_ns, _, cid, data in sorted(sal.messages, key=lambda m: (m[0], m[1])):  # log time, arrival
        writer.write(topic_of[cid], unpack(data), t_ns)
    writer.close()
    assert writer.metadata is not None
    return [work / name / p for p in writer.metadata.relative_file_paths]


def _mode_of(meta: BagMetadata | None, path: Path | None = None) -> str:
    if path is not None and path.name.endswith('.zstd'):
        return 'file'
    mode = (meta.compression_mode if meta else '').lower()
    return mode if mode in ('file', 'message') else 'none'


def _metadata(bag: Path, old: BagMetadata | None) -> BagMetadata:
    """metadata.yaml rebuilt from the bag files' summaries and rosbag2 records."""
    files = _files(bag)
    if not files:
        raise BagError(f'{bag}: no bag file left')
    per_file = [BagReader(f).metadata() for f in files]
    first = per_file[0]
    meta = BagMetadata(compression_format=first.compression_format,
                       compression_mode=first.compression_mode,
                       custom_data=first.custom_data or (old.custom_data if old else None),
                       ros_distro=first.ros_distro or (old.ros_distro if old else '')
                       or BagMetadata().ros_distro,
                       starting_time_ns=NO_MESSAGE_TIME)
    topics: dict[str, TopicInfo] = {}
    end = 0
    for f, m in zip(files, per_file):
        name = f.name[:-len('.zstd')] if f.name.endswith('.zstd') else f.name
        start = m.starting_time_ns if m.message_count else NO_MESSAGE_TIME
        meta.relative_file_paths.append(f.name)
        meta.files.append(FileInfo(name, start, m.duration_ns, m.message_count))
        for t in m.topics:
            if t.name in topics:
                topics[t.name].message_count += t.message_count
            else:
                topics[t.name] = t
        if m.message_count:
            meta.starting_time_ns = min(meta.starting_time_ns, start)
            end = max(end, start + m.duration_ns)
            meta.message_count += m.message_count
    meta.topics = list(topics.values())
    if meta.message_count:
        meta.duration_ns = end - meta.starting_time_ns
    return meta


def reindex(path: Path) -> Reindexed:
    """Repair the bag in place (see the module doc); BagError if it is not a bag."""
    bag = _bag_dir(path)
    result = Reindexed(bag, damage(bag))
    old = _old_metadata(bag)
    spools = sorted(bag.glob('*' + SPOOL_SUFFIX))
    if len(spools) > 1:
        raise BagError(f'{bag}: {len(spools)} recording spools (one bag is one recording)')
    work = bag / WORK_DIR
    shutil.rmtree(work, ignore_errors=True)
    try:
        if spools and old is not None and all(
                (bag / p).is_file() and _message_count(bag / p) is not None
                for p in old.relative_file_paths):
            pass        # the close had finished: only the spool was still to be deleted
        elif spools:
            sal = _salvage(spools[0])
            written = _write(sal, work, bag.name, _mode_of(old), old.custom_data if old else None)
            for f in _files(bag):              # files of a close that was cut: from the spool again
                f.unlink()
            for f in written:
                os.replace(f, bag / f.name)
            result.rewritten = [f.name for f in written]
            result.salvaged = len(sal.messages)
        else:
            for f in _files(bag):
                if _message_count(f) is not None:
                    continue
                sal = _salvage(f)
                written = _write(sal, work, bag.name, _mode_of(old, f),
                                 old.custom_data if old else None)
                os.replace(written[0], f)
                result.rewritten.append(f.name)
                result.salvaged += len(sal.messages)
        meta = _metadata(bag, old)
        tmp = bag / 'metadata.yaml.tmp'
        tmp.write_text(to_yaml(meta))
        os.replace(tmp, bag / 'metadata.yaml')
        for s in spools:
            s.unlink()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    result.messages = meta.message_count
    return result


def repair_if_damaged(path: Path) -> Reindexed | None:
    """Reindex the bag if it needs it (:func:`damage`); None if it was intact."""
    return reindex(path) if damage(path) is not None else None


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``bag_reindex`` (scripts/bag_reindex.sh)."""
    p = argparse.ArgumentParser(prog='bag_reindex', description=__doc__.splitlines()[0])
    p.add_argument('bag_path', type=Path, help='bag directory (or a run directory holding bag/)')
    p.add_argument('-s', '--storage', default='mcap', choices=['mcap'],
                   help='storage identifier (only mcap)')
    args = p.parse_args(argv)
    logging.basicConfig(format='[WARN] %(message)s', level=logging.WARNING, stream=sys.stderr)
    try:
        print(f'bag_reindex: {reindex(args.bag_path).line()}')
    except BagError as exc:
        print(f'bag_reindex: {exc}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
