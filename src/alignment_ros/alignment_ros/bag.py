"""rosbag2 MCAP bags: writing with ``rosbags``, reading with ``mcap`` (tolerant of truncation).

Bags are standard rosbag2 v9 MCAP bags (``metadata.yaml`` + one ``.mcap``, ``ros2`` profile,
``ros2msg`` schemas from the Jazzy typestore with correct RIHS01 type hashes, ``cdr``
encoding), so ``ros2 bag play``, Foxglove and PlotJuggler open them. This module does not
import rclpy.

Log time
--------
rosbag2 stores the *receive* time as each message's log time. Our graph runs on simulation
time, and a wall-clock receive time would make bags of the same scenario and seed differ, so
the recorder stores **simulation time** instead:

1. the message's own stamp when its first field is a ``std_msgs/Header`` (``header.stamp``);
2. the clock value itself for ``rosgraph_msgs/Clock`` (any type whose first field is a
   ``builtin_interfaces/Time``);
3. otherwise (e.g. ``std_msgs/Float64MultiArray``) the latest simulation time the recorder
   knows: the largest ``/clock`` value received so far, or, before any ``/clock``, the largest
   stamp seen on any topic (0 if nothing was seen yet).

Both stamp kinds sit at the same place in the CDR bytes (right after the 4-byte encapsulation
header: ``int32 sec``, ``uint32 nanosec``), so :func:`stamp_reader` reads them with one
``struct.unpack_from`` and no deserialisation. Because log time is a stamp, messages are not
written in log-time order (topics arrive interleaved); readers here and rosbag2's own player
order by log time.
"""
from __future__ import annotations

import heapq
import logging
import struct
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, NamedTuple

import yaml
from mcap.exceptions import McapError
from mcap.reader import SeekingReader
from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from rosbags.rosbag2 import StoragePlugin, Writer, WriterError
from rosbags.typesys import Stores, get_typestore

log = logging.getLogger(__name__)

MCAP_MAGIC = b'\x89MCAP0\r\n'
HEADER_TYPES = ('std_msgs/msg/Header', 'std_msgs/Header')
TIME_TYPES = ('builtin_interfaces/msg/Time', 'builtin_interfaces/Time')

_INFINITE = QosTime(9223372036, 854775807)  # rmw's "infinite" duration, as rosbag2 writes it
STREAM_QOS = Qos(
    history=QosHistory.KEEP_ALL,
    depth=0,
    reliability=QosReliability.RELIABLE,
    durability=QosDurability.VOLATILE,
    deadline=_INFINITE,
    lifespan=_INFINITE,
    liveliness=QosLiveliness.AUTOMATIC,
    liveliness_lease_duration=_INFINITE,
    avoid_ros_namespace_conventions=False,
)
"""Offered QoS stored in metadata.yaml (alignment_ros.qos.STREAM): ros2 bag play reuses it."""

_TYPESTORE = None


class BagError(Exception):
    """A path that is not a readable rosbag2 MCAP bag, or a misuse of :class:`BagWriter`."""


class BagMessage(NamedTuple):
    """One stored message: topic, ROS type name (pkg/msg/Type), log time (ns), CDR bytes."""

    topic: str
    type_name: str
    t_ns: int
    data: bytes


def typestore() -> Any:
    """Return the (cached) rosbags typestore for ROS 2 Jazzy."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


# --- log time -------------------------------------------------------------------------------

def _cdr_time_ns(data: bytes | memoryview) -> int:
    """Stamp (ns) of a CDR message whose first field is a Header or a Time."""
    fmt = '<iI' if data[1] == 1 else '>iI'  # encapsulation byte 1: 1 = little endian
    sec, nanosec = struct.unpack_from(fmt, data, 4)
    return sec * 1_000_000_000 + nanosec


def stamp_reader(type_name: str) -> Callable[[bytes | memoryview], int] | None:
    """Return a function reading the stamp (ns) from CDR bytes, or None if the type has none.

    Types whose first field is ``std_msgs/Header`` (stamp) or ``builtin_interfaces/Time``
    (``rosgraph_msgs/Clock``) have a stamp.
    """
    try:
        fields = typestore().fielddefs[type_name][1]
    except KeyError as exc:
        raise BagError(f'unknown message type {type_name!r} (not in the ROS 2 Jazzy typestore)') from exc
    if not fields:
        return None
    spec = fields[0][1][1]
    if isinstance(spec, str) and spec in HEADER_TYPES + TIME_TYPES:
        return _cdr_time_ns
    return None


# --- writing --------------------------------------------------------------------------------

class BagWriter:
    """Write raw CDR messages to a new rosbag2 v9 MCAP bag directory.

    Use as a context manager or call :meth:`close`: closing writes the MCAP summary and
    ``metadata.yaml``. Without :meth:`close` the bag is truncated (see :class:`BagReader`).
    """

    def __init__(self, path: str | Path, *, offered_qos: Qos | None = STREAM_QOS) -> None:
        self.path = Path(path)
        try:
            self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
            self._writer.open()
        except WriterError as exc:
            raise BagError(str(exc)) from exc
        self._qos = [offered_qos] if offered_qos is not None else []
        self._connections: dict[str, Any] = {}
        self.counts: dict[str, int] = {}

    def add_topic(self, topic: str, type_name: str) -> None:
        """Register a topic with its ROS type name ('pkg/msg/Type'); idempotent for same type."""
        if topic in self._connections:
            if self._connections[topic].msgtype != type_name:
                raise BagError(f'topic {topic} already added with type {self._connections[topic].msgtype}')
            return
        if type_name not in typestore().fielddefs:
            raise BagError(f'unknown message type {type_name!r} (not in the ROS 2 Jazzy typestore)')
        self._connections[topic] = self._writer.add_connection(
            topic, type_name, typestore=typestore(), offered_qos_profiles=self._qos)
        self.counts[topic] = 0

    def write(self, topic: str, data: bytes | memoryview, t_ns: int) -> None:
        """Append one serialized (CDR) message with log time ``t_ns`` (nanoseconds)."""
        conn = self._connections.get(topic)
        if conn is None:
            raise BagError(f'topic {topic} was not added to the bag')
        self._writer.write(conn, t_ns, data)
        self.counts[topic] += 1

    def close(self) -> None:
        """Finish the MCAP file and write metadata.yaml (idempotent)."""
        if self._writer.storage is not None:
            self._writer.close()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# --- reading --------------------------------------------------------------------------------

def _bag_files(path: Path) -> tuple[list[Path], bool]:
    """Return the bag's .mcap files and whether metadata.yaml exists; BagError if not a bag."""
    if not path.exists():
        raise BagError(f'{path}: no such bag (path does not exist)')
    if path.is_file():
        if path.suffix != '.mcap':
            raise BagError(f'{path}: not a rosbag2 bag (expected a bag directory or a .mcap file)')
        return [path], False
    meta = path / 'metadata.yaml'
    if meta.is_file():
        try:
            info = yaml.safe_load(meta.read_text())['rosbag2_bagfile_information']
            storage = info.get('storage_identifier')
            if storage != 'mcap':
                raise BagError(f'{path}: storage {storage!r} is not supported (only mcap)')
            files = [path / p for p in info['relative_file_paths']]
        except (yaml.YAMLError, KeyError, TypeError) as exc:
            log.warning('%s: unreadable metadata.yaml (%s); using the .mcap files found', path, exc)
            files = sorted(path.glob('*.mcap'))
        missing = [f for f in files if not f.is_file()]
        if missing:
            log.warning('%s: files listed in metadata.yaml are missing: %s', path, missing)
            files = [f for f in files if f.is_file()]
        if files:
            return files, True
    files = sorted(path.glob('*.mcap'))
    if not files:
        raise BagError(f'{path}: not a rosbag2 MCAP bag (no metadata.yaml and no .mcap file)')
    if meta.is_file():
        return files, True
    log.warning('%s: no metadata.yaml (recording not closed cleanly?); reading %s',
                path, ', '.join(f.name for f in files))
    return files, False


class _Salvage:
    """Linear scan of a (possibly truncated) MCAP file that keeps every complete message.

    Used when the file has no valid footer/summary. Uncompressed chunks cut in the middle still
    yield their complete messages; a cut compressed chunk is lost as a whole.
    """

    def __init__(self, buf: bytes) -> None:
        self.buf = memoryview(buf)
        self.schemas: dict[int, str] = {}
        self.channels: dict[int, tuple[str, int]] = {}
        self.messages: list[tuple[int, int, int, bytes]] = []  # (log_time, seq, channel, data)
        self.complete = False
        self.good_end = 8  # end offset of the last complete record (top-level buffer)

    @staticmethod
    def _str(buf: memoryview, pos: int) -> tuple[str, int]:
        (n,) = struct.unpack_from('<I', buf, pos)
        return bytes(buf[pos + 4:pos + 4 + n]).decode(), pos + 4 + n

    def scan(self, start: int, end: int) -> bool:
        """Scan records in buf[start:end]; return True if the range ended on a record boundary."""
        buf = self.buf
        pos = start
        while pos < end:
            if pos + 9 > end:
                return False
            op = buf[pos]
            (length,) = struct.unpack_from('<Q', buf, pos + 1)
            body, body_end = pos + 9, pos + 9 + length
            if body_end > end:
                if op == 0x06:  # partial chunk: salvage if uncompressed
                    self._chunk(body, end, partial=True)
                return False
            if op == 0x03:  # Schema
                (sid,) = struct.unpack_from('<H', buf, body)
                name, _ = self._str(buf, body + 2)
                self.schemas[sid] = name
            elif op == 0x04:  # Channel
                cid, sid = struct.unpack_from('<HH', buf, body)
                topic, _ = self._str(buf, body + 4)
                self.channels[cid] = (topic, sid)
            elif op == 0x05:  # Message
                cid, _seq, log_time = struct.unpack_from('<HIQ', buf, body)
                data = bytes(buf[body + 22:body_end])
                self.messages.append((log_time, len(self.messages), cid, data))
            elif op == 0x06:
                self._chunk(body, body_end, partial=False)
            elif op == 0x02:  # Footer
                self.complete = True
                self.good_end = body_end
                return True
            self.good_end = max(self.good_end, body_end)
            pos = body_end
        return True

    def _chunk(self, body: int, end: int, *, partial: bool) -> None:
        buf = self.buf
        if body + 32 > end:
            return
        compression, pos = self._str(buf, body + 28)
        if pos + 8 > end:
            return
        (n,) = struct.unpack_from('<Q', buf, pos)
        rec_start = pos + 8
        rec_end = min(rec_start + n, end)
        if not compression:
            self.scan(rec_start, rec_end)
            return
        if partial:
            return
        raw = bytes(buf[rec_start:rec_end])
        try:
            if compression == 'zstd':
                import zstandard
                (size,) = struct.unpack_from('<Q', buf, body + 16)
                raw = zstandard.ZstdDecompressor().decompress(raw, max_output_size=size)
            elif compression == 'lz4':
                import lz4.frame
                raw = lz4.frame.decompress(raw)
            else:
                raise ValueError(f'unsupported compression {compression!r}')
        except Exception as exc:  # noqa: BLE001  (decompressors raise their own error types)
            log.warning('MCAP chunk skipped: %s', exc)
            return
        inner = _Salvage(raw)
        inner.schemas, inner.channels, inner.messages = self.schemas, self.channels, self.messages
        inner.scan(0, len(raw))


class BagReader:
    """Read a rosbag2 MCAP bag: topics and types, counts, messages in log-time order.

    Intact files are read through their MCAP index. A file without a valid summary (recording
    killed, copy cut short) is scanned linearly and everything complete is kept: a warning
    is logged and :attr:`truncated` is set. A path that is not a bag raises :class:`BagError`.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.files, self.has_metadata = _bag_files(self.path)
        self.truncated = False
        self._salvaged: dict[Path, _Salvage] = {}
        self._summaries: dict[Path, Any] = {}
        for f in self.files:
            self._open(f)

    def _open(self, f: Path) -> None:
        with f.open('rb') as fh:
            magic = fh.read(8)
            if magic != MCAP_MAGIC:
                if MCAP_MAGIC.startswith(magic):  # cut before the end of the magic: empty
                    self.truncated = True
                    self._salvaged[f] = _Salvage(b'')
                    log.warning('%s: truncated MCAP file (%d bytes): no message readable',
                                f, len(magic))
                    return
                raise BagError(f'{f}: not an MCAP file (bad magic)')
            try:
                fh.seek(0)
                summary = SeekingReader(fh).get_summary()
                if summary is None:
                    raise McapError('no summary section')
                self._summaries[f] = summary
                return
            except (McapError, OSError, ValueError, struct.error) as exc:
                reason = f'no valid footer/summary: {type(exc).__name__}'
        sal = _Salvage(f.read_bytes())
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

    def topics(self) -> dict[str, str]:
        """Return {topic: type name} of every channel in the bag."""
        out: dict[str, str] = {}
        for s in self._summaries.values():
            for ch in s.channels.values():
                out[ch.topic] = s.schemas[ch.schema_id].name if ch.schema_id else ''
        for sal in self._salvaged.values():
            for topic, sid in sal.channels.values():
                out[topic] = sal.schemas.get(sid, '')
        return out

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
        if f in self._summaries:
            with f.open('rb') as fh:
                reader = SeekingReader(fh)
                for schema, channel, msg in reader.iter_messages(
                        topics=list(topics) if topics is not None else None, log_time_order=True):
                    yield BagMessage(channel.topic, schema.name if schema else '', msg.log_time, msg.data)
            return
        sal = self._salvaged[f]
        chans = {cid: (t, sal.schemas.get(sid, '')) for cid, (t, sid) in sal.channels.items()}
        for log_time, _, cid, data in sorted(sal.messages, key=lambda m: (m[0], m[1])):
            topic, type_name = chans[cid]
            if topics is None or topic in topics:
                yield BagMessage(topic, type_name, log_time, data)

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
        """Yield (topic, type_name, t_ns, data) in log-time order, optionally only ``topics``."""
        sel = set(topics) if topics is not None else None
        its = [self._iter_file(f, sel) for f in self.files]
        if len(its) == 1:
            yield from its[0]
        else:
            yield from heapq.merge(*its, key=lambda m: m.t_ns)


def read_bag(path: str | Path, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
    """Yield ``(topic, type_name, t_ns, raw_bytes)`` of a bag in log-time order.

    Truncated bags yield their readable prefix with a logged warning; a path that is not a
    bag raises :class:`BagError` (at the call, not at the first ``next``).
    """
    return BagReader(path).messages(topics)


def topic_counts(path: str | Path) -> dict[str, int]:
    """Return {topic: message count} of a bag (from the MCAP statistics when intact)."""
    return BagReader(path).counts()
