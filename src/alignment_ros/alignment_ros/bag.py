"""rosbag2 MCAP bags: the reader, and the public names of writing (:mod:`bag_writer`).

Bags are rosbag2 Jazzy MCAP bags (``metadata.yaml`` + ``NAME_0.mcap`` [``NAME_1.mcap`` ...],
``ros2`` profile, ``ros2msg`` schemas with the installed definitions, RIHS01 type hashes,
``cdr`` encoding, messages in log-time order), so ``ros2 bag``, Foxglove and PlotJuggler open
them. :class:`BagReader` reads this project's bags and any rosbag2 MCAP bag: split
(``relative_file_paths``), compressed (``compression_mode`` FILE: ``.mcap.zstd`` files;
MESSAGE: zstd message payloads; zstd/lz4 chunks), without metadata.yaml (the files' summaries
and ``rosbag2`` metadata records), or truncated. This module does not import rclpy.

Log time
--------
rosbag2 stores the *receive* time as each message's log time. Our graph runs on simulation
time, and a wall-clock receive time would make bags of the same scenario and seed differ, so
the recorder stores **simulation time** instead:

1. the message's own stamp when its first field is a ``std_msgs/Header`` (``header.stamp``);
2. the clock value itself for ``rosgraph_msgs/Clock`` (any type whose first field is a
   ``builtin_interfaces/Time``);
3. otherwise (e.g. ``std_msgs/Float64MultiArray``) the latest simulation time the recorder
   knows: the largest ``/clock`` value received so far (with ``--use-sim-time`` and no
   ``/clock`` recorded: the recorder node's ROS clock), or, before that, the largest stamp
   seen on any topic (0 if nothing was seen yet).

Both stamp kinds sit at the same place in the CDR bytes (right after the 4-byte encapsulation
header: ``int32 sec``, ``uint32 nanosec``), so :func:`stamp_reader` reads them with one
``struct.unpack_from`` and no deserialisation. Because log time is a stamp, messages arrive out
of log-time order; the writer puts them in order through a bounded reorder buffer (see
:mod:`bag_writer`).
"""
from __future__ import annotations

import heapq
import logging
import re
import struct
import tempfile
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, NamedTuple

import zstandard
from mcap.exceptions import McapError
from mcap.reader import SeekingReader

from alignment_ros import msg_definitions
from alignment_ros.bag_metadata import STREAM_QOS, BagError, BagMetadata, TopicInfo, from_yaml, parse_qos
from alignment_ros.bag_writer import MCAP_MAGIC, NO_MESSAGE_TIME, SPOOL_SUFFIX, BagWriter
from alignment_ros.mcap_salvage import Salvage

__all__ = ['STREAM_QOS', 'BagError', 'BagMessage', 'BagReader', 'BagWriter', 'read_bag',
           'stamp_reader', 'topic_counts']

log = logging.getLogger(__name__)


class BagMessage(NamedTuple):
    """One stored message: topic, ROS type name (pkg/msg/Type), log time (ns), CDR bytes."""

    topic: str
    type_name: str
    t_ns: int
    data: bytes


# --- log time -------------------------------------------------------------------------------

def _cdr_time_ns(data: bytes | memoryview) -> int:
    """Stamp (ns) of a CDR message whose first field is a Header or a Time."""
    fmt = '<iI' if data[1] == 1 else '>iI'  # encapsulation byte 1: 1 = little endian
    sec, nanosec = struct.unpack_from(fmt, data, 4)
    return sec * 1_000_000_000 + nanosec


def stamp_reader(type_name: str) -> Callable[[bytes | memoryview], int] | None:
    """Return a function reading the stamp (ns) from CDR bytes, or None if the type has none
    (its installed .msg's first field is neither a ``std_msgs/Header`` nor a
    ``builtin_interfaces/Time``, or no .msg is installed)."""
    return _cdr_time_ns if msg_definitions.has_stamp(type_name) else None


# --- which files ----------------------------------------------------------------------------

def _natural(p: Path) -> tuple:
    return tuple(int(s) if s.isdigit() else s for s in re.split(r'(\d+)', p.name))


def _mcap_files(path: Path) -> list[Path]:
    return sorted([*path.glob('*.mcap'), *path.glob('*.mcap.zstd')], key=_natural)


def _bag_files(path: Path) -> tuple[list[Path], BagMetadata | None]:
    """The bag's files and its metadata.yaml (None if absent); BagError if not a bag."""
    if not path.exists():
        raise BagError(f'{path}: no such bag (path does not exist)')
    if path.is_file():
        if not path.name.endswith(('.mcap', '.mcap.zstd')):
            raise BagError(f'{path}: not a rosbag2 bag (expected a bag directory or a .mcap file)')
        return [path], None
    meta_file = path / 'metadata.yaml'
    meta = None
    if meta_file.is_file():
        try:
            meta = from_yaml(meta_file.read_text())
        except BagError as exc:
            log.warning('%s: %s; using the .mcap files found', path, exc)
        if meta is not None and meta.storage_identifier != 'mcap':
            raise BagError(f'{path}: storage {meta.storage_identifier!r} is not supported (only mcap)')
    if meta is not None:
        files = [path / p for p in meta.relative_file_paths]
        missing = [f for f in files if not f.is_file()]
        if missing:
            log.warning('%s: files listed in metadata.yaml are missing: %s', path, missing)
        files = [f for f in files if f.is_file()] or _mcap_files(path)
    else:
        spools = sorted(path.glob('*' + SPOOL_SUFFIX))
        files = spools or _mcap_files(path)
        if files:
            log.warning('%s: no metadata.yaml (%s); reading %s', path,
                        'recording not finalised' if spools else 'recording not closed cleanly?',
                        ', '.join(f.name for f in files))
    if not files:
        raise BagError(f'{path}: not a rosbag2 MCAP bag (no metadata.yaml and no .mcap file)')
    return files, meta


# --- reading --------------------------------------------------------------------------------

class BagReader:
    """Read a rosbag2 MCAP bag: topics and types, counts, messages in log-time order, metadata.

    Intact files are read through their MCAP index. A file without a valid summary (recording
    killed, copy cut short) is scanned linearly and everything complete is kept: a warning
    is logged and :attr:`truncated` is set. A path that is not a bag raises :class:`BagError`.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.files, self.bag_metadata = _bag_files(self.path)
        self.has_metadata = self.bag_metadata is not None
        self.truncated = False
        self._tmp: tempfile.TemporaryDirectory | None = None
        self._readable: dict[Path, Path] = {}
        self._salvaged: dict[Path, Salvage] = {}
        self._summaries: dict[Path, Any] = {}
        self._records: dict[Path, BagMetadata] = {}
        for f in self.files:
            self._open(f)
        mode = self.bag_metadata.compression_mode if self.bag_metadata else next(
            (r.compression_mode for r in self._records.values()), '')
        self.compression_mode = mode.upper()
        self._unzstd = zstandard.ZstdDecompressor()

    def _decompressed(self, f: Path) -> Path:
        """A .mcap.zstd file decompressed into a temporary directory (a cut file: its prefix)."""
        if self._tmp is None:
            self._tmp = tempfile.TemporaryDirectory(prefix='bag-')
        out = Path(self._tmp.name) / f.name[:-len('.zstd')]
        with f.open('rb') as fin, out.open('wb') as fout:
            try:
                self._unzstd_stream(fin, fout)
            except zstandard.ZstdError as exc:
                log.warning('%s: zstd stream cut short (%s); reading what it holds', f, exc)
        return out

    @staticmethod
    def _unzstd_stream(fin: Any, fout: Any) -> None:
        reader = zstandard.ZstdDecompressor().stream_reader(fin, read_across_frames=True)
        while chunk := reader.read(1 << 20):
            fout.write(chunk)

    def _open(self, f: Path) -> None:
        path = self._decompressed(f) if f.name.endswith('.zstd') else f
        self._readable[f] = path
        with path.open('rb') as fh:
            magic = fh.read(8)
            if magic != MCAP_MAGIC:
                if MCAP_MAGIC.startswith(magic):  # cut before the end of the magic: empty
                    self.truncated = True
                    self._salvaged[f] = Salvage(b'')
                    log.warning('%s: truncated MCAP file (%d bytes): no message readable',
                                f, len(magic))
                    return
                raise BagError(f'{f}: not an MCAP file (bad magic)')
            try:
                fh.seek(0)
                reader = SeekingReader(fh)
                summary = reader.get_summary()
                if summary is None:
                    raise McapError('no summary section')
                self._summaries[f] = summary
                for rec in reader.iter_metadata():
                    if rec.name == 'rosbag2' and rec.metadata.get('serialized_metadata'):
                        self._records[f] = from_yaml(rec.metadata['serialized_metadata'])
                return
            except BagError as exc:
                log.warning('%s: rosbag2 metadata record ignored: %s', f, exc)
                return
            except (McapError, OSError, ValueError, struct.error) as exc:
                reason = f'no valid footer/summary: {type(exc).__name__}'
        sal = Salvage(path.read_bytes())
        sal.scan(8, len(sal.buf))
        self._salvaged[f] = sal
        if not sal.complete:
            self.truncated = True
            log.warning(
                '%s: truncated MCAP file (%s); recovered %d complete messages from the readable '
                'prefix, %d of %d bytes unreadable', f, reason, len(sal.messages),
                len(sal.buf) - sal.good_end, len(sal.buf))
        else:
            log.warning('%s: MCAP file without usable index (%s); read linearly', f, reason)

    def _channels(self) -> Iterator[tuple[str, str, str, dict[str, str]]]:
        """(topic, type, message encoding, channel metadata) of every channel, file by file."""
        for s in self._summaries.values():
            for ch in s.channels.values():
                schema = s.schemas.get(ch.schema_id)
                yield ch.topic, schema.name if schema else '', ch.message_encoding, ch.metadata
        for sal in self._salvaged.values():
            for topic, sid in sal.channels.values():
                yield topic, sal.schemas.get(sid, ''), 'cdr', {}

    def topics(self) -> dict[str, str]:
        """Return {topic: type name} of every channel in the bag."""
        return {topic: type_name for topic, type_name, _, _ in self._channels()}

    def counts(self) -> dict[str, int]:
        """Return {topic: message count} (0 for channels without messages)."""
        out = dict.fromkeys(self.topics(), 0)
        for f, s in self._summaries.items():
            if s.statistics is None:
                for m in self._iter_file(f, None):
                    out[m.topic] += 1
                continue
            for cid, n in s.statistics.channel_message_counts.items():
                out[s.channels[cid].topic] += n
        for sal in self._salvaged.values():
            for _, _, cid, _ in sal.messages:
                out[sal.channels[cid][0]] += 1
        return out

    def _iter_file(self, f: Path, topics: set[str] | None) -> Iterator[BagMessage]:
        unpack = self._unzstd.decompress if self.compression_mode == 'MESSAGE' else bytes
        if f in self._summaries:
            with self._readable[f].open('rb') as fh:
                reader = SeekingReader(fh)
                for schema, channel, msg in reader.iter_messages(
                        topics=list(topics) if topics is not None else None, log_time_order=True):
                    yield BagMessage(channel.topic, schema.name if schema else '', msg.log_time,
                                     unpack(msg.data))
            return
        sal = self._salvaged[f]
        chans = {cid: (t, sal.schemas.get(sid, '')) for cid, (t, sid) in sal.channels.items()}
        for log_time, _, cid, data in sorted(sal.messages, key=lambda m: (m[0], m[1])):
            topic, type_name = chans[cid]
            if topics is None or topic in topics:
                yield BagMessage(topic, type_name, log_time, unpack(data))

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
        """Yield (topic, type_name, t_ns, data) in log-time order, optionally only ``topics``;
        message-compressed payloads come decompressed."""
        sel = set(topics) if topics is not None else None
        its = [self._iter_file(f, sel) for f in self.files]
        if len(its) == 1:
            yield from its[0]
        else:
            yield from heapq.merge(*its, key=lambda m: m.t_ns)

    def _time_range(self) -> tuple[int, int] | None:
        spans = [(s.statistics.message_start_time, s.statistics.message_end_time)
                 for s in self._summaries.values() if s.statistics and s.statistics.message_count]
        spans += [(min(m[0] for m in sal.messages), max(m[0] for m in sal.messages))
                  for sal in self._salvaged.values() if sal.messages]
        return (min(a for a, _ in spans), max(b for _, b in spans)) if spans else None

    def metadata(self) -> BagMetadata:
        """What ``ros2 bag info`` shows: metadata.yaml when the bag has one (bag size: the
        directory's files), else built from the MCAP files as rosbag2's MCAP storage does
        (its ``rosbag2`` record, overridden by the summary statistics and channels)."""
        if self.bag_metadata is not None:
            meta = self.bag_metadata
            meta.bag_size = sum(p.stat().st_size for p in self.path.iterdir() if p.is_file())
            return meta
        rec = next(iter(self._records.values()), None)
        meta = BagMetadata(version=rec.version, compression_format=rec.compression_format,
                           compression_mode=rec.compression_mode, files=rec.files,
                           custom_data=rec.custom_data, ros_distro=rec.ros_distro) \
            if rec else BagMetadata(version=8, ros_distro='')
        meta.bag_size = sum(f.stat().st_size for f in self.files)
        meta.relative_file_paths = [str(self.path)] if self.path.is_file() else \
            [f.name for f in self.files]
        counts = self.counts()
        meta.message_count = sum(counts.values())
        span = self._time_range()
        meta.starting_time_ns, end = span if span else (0, 0)
        meta.duration_ns = end - meta.starting_time_ns
        seen: dict[str, TopicInfo] = {}
        for topic, type_name, encoding, md in self._channels():
            if topic not in seen:
                seen[topic] = TopicInfo(topic, type_name, encoding,
                                        parse_qos(md.get('offered_qos_profiles', '')),
                                        md.get('topic_type_hash', ''), counts.get(topic, 0))
        meta.topics = list(seen.values())
        if meta.starting_time_ns == NO_MESSAGE_TIME:
            meta.starting_time_ns = 0
        return meta


def read_bag(path: str | Path, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
    """Yield ``(topic, type_name, t_ns, raw_bytes)`` of a bag in log-time order.

    Truncated bags yield their readable prefix with a logged warning; a path that is not a
    bag raises :class:`BagError` (at the call, not at the first ``next``).
    """
    return BagReader(path).messages(topics)


def topic_counts(path: str | Path) -> dict[str, int]:
    """Return {topic: message count} of a bag (from the MCAP statistics when intact)."""
    return BagReader(path).counts()
