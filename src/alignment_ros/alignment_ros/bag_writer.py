"""Write rosbag2 Jazzy MCAP bags: ``metadata.yaml`` + ``NAME_0.mcap`` (``NAME_1.mcap`` ... when
split), messages in log-time order in every file, written while the recording runs.

Log times are message stamps (see :mod:`alignment_ros.bag`), so messages arrive out of log-time
order, by tens of seconds across topics. Each message is appended as it comes to
``NAME.recording.mcap`` (plain MCAP records in arrival order, pushed to the disk by
:meth:`BagWriter.flush`: what a killed recorder leaves, readable like any truncated bag and
finalised by ``bag_reindex``), and goes through a bounded reorder buffer
(:mod:`alignment_ros.bag_reorder`) into the bag file, which is written chunk by chunk as the
buffer releases messages: memory does not grow with the recording's length.
:meth:`BagWriter.close` writes what the buffer still holds, finishes the file (summary, index),
writes metadata.yaml and deletes the spool.

Each file is what rosbag2's MCAP storage writes: ``ros2`` profile; one ``ros2msg`` schema per
type holding the installed definition (:mod:`alignment_ros.msg_definitions`); channels (ids in
the order the topics were added; written with the first message that needs them, or when the
file ends) with ``offered_qos_profiles`` and ``topic_type_hash`` metadata; a ``rosbag2``
metadata record; chunk index, statistics, summary offsets and a summary CRC. Splitting follows
rosbag2: a new file starts before a message when the current one reached ``max_bag_size`` bytes
or the message is more than ``max_bag_duration_s`` after the file's first. Compression follows
rosbag2_compression: ``message`` (each message's CDR bytes a zstd frame) or ``file`` (each
finished file replaced by ``NAME_k.mcap.zstd``); metadata.yaml lists ``compression_format:
zstd`` and the mode.
"""
from __future__ import annotations

import logging
import struct
import tempfile
from pathlib import Path
from typing import Any

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.records import ChunkIndex
from mcap.writer import CompressionType, Writer
from mcap.writer import __version__ as mcap_version

from alignment_ros import msg_definitions
from alignment_ros.bag_metadata import (
    STREAM_QOS,
    BagError,
    BagMetadata,
    FileInfo,
    TopicInfo,
    qos_string,
    to_yaml,
)
from alignment_ros.bag_reorder import ReorderBuffer

log = logging.getLogger(__name__)

MCAP_MAGIC = b'\x89MCAP0\r\n'
SPOOL_SUFFIX = '.recording.mcap'
CHUNK_SIZE = 768 * 1024          # libmcap's default chunk size (rosbag2 keeps it)
MIN_SPLIT_SIZE = 1024            # rosbag2 MCAP storage's minimum split file size
ZSTD_LEVEL = 1                   # rosbag2_compression_zstd's default level
NO_MESSAGE_TIME = 2 ** 63 - 1    # rosbag2's starting_time before any message
REORDER_BYTES = 64 << 20
"""The reorder buffer's bound: about 3 simulated minutes of a deck run's streams, beyond any lag
between them measured at --real-time-factor 0."""
LIBRARY = f'alignment_ros (mcap-python {mcap_version})'
COMPRESSION_MODES = {'none': '', 'file': 'FILE', 'message': 'MESSAGE'}
_MSG_HEAD = struct.Struct('<BQHIQQ')  # Message record: opcode, length, channel, seq, log, publish


def _string(s: str) -> bytes:
    b = s.encode()
    return struct.pack('<I', len(b)) + b


def _record(op: int, body: bytes) -> bytes:
    return struct.pack('<BQ', op, len(body)) + body


class _Spool:
    """Append-only MCAP records in arrival order (the recording's write-ahead copy)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fh = path.open('xb', buffering=1 << 20)
        self.fh.write(MCAP_MAGIC + _record(0x01, _string('ros2') + _string(LIBRARY)))

    def schema(self, sid: int, name: str, encoding: str, data: bytes) -> None:
        self.fh.write(_record(0x03, struct.pack('<H', sid) + _string(name) + _string(encoding)
                              + struct.pack('<I', len(data)) + data))

    def channel_record(self, cid: int, sid: int, topic: str) -> None:
        self.fh.write(_record(0x04, struct.pack('<HH', cid, sid) + _string(topic) + _string('cdr')
                              + struct.pack('<I', 0)))

    def message(self, cid: int, t_ns: int, data: bytes | memoryview) -> None:
        self.fh.write(_MSG_HEAD.pack(0x05, 22 + len(data), cid, 0, t_ns, t_ns))
        self.fh.write(data)


class _SpilledChunkIndexes:
    """Stands in for the mcap ``Writer``'s list of chunk indexes (one object of ~1.7 kB per
    768 kB chunk kept until the summary: ~3 MiB per hour of a deck run): each index is
    serialised to a temporary file as it comes and copied into the summary at the end."""

    def __init__(self) -> None:
        self.fh = tempfile.TemporaryFile()
        self.count = 0

    def append(self, index: ChunkIndex) -> None:
        b = RecordBuilder()
        index.write(b)
        self.fh.write(b.end())
        self.count += 1

    def __iter__(self) -> Any:
        self.fh.seek(0)
        yield self          # Writer.finish calls .write(builder) on each item: all in one piece

    def write(self, builder: RecordBuilder) -> None:
        while block := self.fh.read(1 << 20):
            builder.write(block)

    def close(self) -> None:
        self.fh.close()


def _chunked_writer(fh: Any) -> tuple[Writer, _SpilledChunkIndexes]:
    """An mcap Writer (rosbag2's chunk size, no compression) whose chunk indexes wait on disk."""
    writer = Writer(fh, chunk_size=CHUNK_SIZE, compression=CompressionType.NONE)
    if not isinstance(getattr(writer, '_Writer__chunk_indices', None), list):
        raise RuntimeError(f'mcap {mcap_version}: the Writer keeps no chunk index list to spill')
    spilled = _SpilledChunkIndexes()
    writer._Writer__chunk_indices = spilled   # type: ignore[attr-defined]
    return writer, spilled


class _Topic:
    def __init__(self, cid: int, info: TopicInfo, encoding: str, definition: str) -> None:
        self.cid = cid
        self.info = info
        self.encoding = encoding
        self.definition = definition


class _BagFile:
    """One open ``NAME_k.mcap``: its writer, its channels so far, its size bookkeeping (kept only
    when the bag splits by size: asking the file its position costs a call per message)."""

    def __init__(self, path: Path, sized: bool) -> None:
        self.path = path
        self.sized = sized
        self.fh = path.open('xb')
        self.writer, self.spilled = _chunked_writer(self.fh)
        self.writer.start(profile='ros2', library=LIBRARY)
        self.schemas: dict[str, int] = {}
        self.channels = 0               # channels written: those of topics 1..channels
        self.tell = self.fh.tell()
        self.pending = 0                # bytes added since the file last grew
        self.end_ns = 0                 # latest log time in the file

    def channel(self, tp: _Topic, by_cid: dict[int, _Topic]) -> int:
        """The file's channel id of the topic (= its cid), written now if new, with those of
        every topic added before it."""
        while self.channels < tp.cid:
            t = by_cid[self.channels + 1]
            if t.info.type not in self.schemas:
                self.schemas[t.info.type] = self.writer.register_schema(
                    t.info.type, t.encoding, t.definition.encode())
            self.channels = self.writer.register_channel(
                t.info.name, 'cdr', self.schemas[t.info.type], {
                    'offered_qos_profiles': qos_string(t.info.offered_qos_profiles),
                    'topic_type_hash': t.info.type_description_hash})
            assert self.channels == t.cid
        return tp.cid

    def add(self, channel: int, t_ns: int, data: bytes) -> None:
        self.writer.add_message(channel, t_ns, data, t_ns, 0)
        if not self.sized:
            return
        tell = self.fh.tell()
        self.pending = 0 if tell != self.tell else self.pending + 31 + len(data)
        self.tell = tell


class BagWriter:
    """Write raw CDR messages to a new rosbag2 MCAP bag directory (which must not exist).

    Use as a context manager or call :meth:`close`; only closing completes the bag files and
    writes ``metadata.yaml`` (until then the bag is its ``.recording.mcap`` spool).
    """

    def __init__(self, path: str | Path, *, max_bag_duration_s: float = 0,
                 max_bag_size: int = 0, compression_mode: str = 'none',
                 compression_format: str = '', custom_data: dict[str, str] | None = None,
                 offered_qos: dict[str, Any] | None = STREAM_QOS,
                 reorder_bytes: int = REORDER_BYTES) -> None:
        self.path = Path(path)
        mode = compression_mode.lower()
        if mode not in COMPRESSION_MODES:
            raise BagError(f'compression mode {compression_mode!r}: expected none, file or message')
        if mode != 'none' and compression_format != 'zstd':
            raise BagError(f'compression format {compression_format!r} is not supported (zstd)')
        if mode == 'none' and compression_format:
            raise BagError('a compression format needs a compression mode (file or message)')
        if max_bag_size and max_bag_size < MIN_SPLIT_SIZE:
            raise BagError(f'Invalid bag splitting size given. Please provide a value greater '
                           f'than {MIN_SPLIT_SIZE}. Specified value of {max_bag_size}')
        if self.path.exists():
            raise BagError(f'Bag directory already exists ({self.path}), can\'t overwrite '
                           'existing bag')
        self.path.mkdir(parents=True)
        self.max_duration_ns = round(max_bag_duration_s * 1e9)
        self.max_size = int(max_bag_size)
        self.mode = mode
        self.compression_format = compression_format if mode != 'none' else ''
        self.custom_data = dict(custom_data or {})
        self._default_qos = [dict(offered_qos)] if offered_qos is not None else []
        self._topics: dict[str, _Topic] = {}
        self._by_cid: dict[int, _Topic] = {}
        self._schemas: dict[str, int] = {}
        self._spool: _Spool | None = _Spool(self.path / (self.path.name + SPOOL_SUFFIX))
        self.reorder = ReorderBuffer(reorder_bytes)
        self._zstd = zstandard.ZstdCompressor(level=ZSTD_LEVEL)
        self._negative_warned = False
        self.counts: dict[str, int] = {}
        self._meta = BagMetadata(compression_format=self.compression_format,
                                 compression_mode=COMPRESSION_MODES[mode],
                                 custom_data=self.custom_data or None,
                                 starting_time_ns=NO_MESSAGE_TIME)
        self._end_ns = 0
        self._file = self._open_file(0)
        self.metadata: BagMetadata | None = None      # set by close()

    def add_topic(self, topic: str, type_name: str, *, type_hash: str | None = None,
                  offered_qos: list[dict[str, Any]] | None = None) -> None:
        """Register a topic with its ROS type name ('pkg/msg/Type'); idempotent for the same
        type. The hash defaults to the installed one, the offered QoS to the writer's default."""
        spool = self._require_open()
        if topic in self._topics:
            if self._topics[topic].info.type != type_name:
                raise BagError(f'topic {topic} already added with type {self._topics[topic].info.type}')
            return
        encoding, text = msg_definitions.message_definition(type_name)
        if type_name not in self._schemas:
            self._schemas[type_name] = len(self._schemas) + 1
            spool.schema(self._schemas[type_name], type_name, encoding, text.encode())
        info = TopicInfo(topic, type_name, 'cdr',
                         [dict(q) for q in offered_qos] if offered_qos is not None
                         else [dict(q) for q in self._default_qos],
                         type_hash if type_hash else msg_definitions.type_hash(type_name))
        info.message_count = 0
        cid = len(self._topics) + 1
        self._topics[topic] = self._by_cid[cid] = _Topic(cid, info, encoding, text)
        spool.channel_record(cid, self._schemas[type_name], topic)
        self.reorder.add_stream(cid)
        self.counts[topic] = 0

    def set_topic_endpoints(self, topic: str, offered_qos: list[dict[str, Any]],
                            type_hash: str = '') -> None:
        """Replace a topic's offered QoS profiles (and hash, if given) with what its
        publishers offer, as rosbag2 takes them from the graph (a file that already holds the
        topic's channel keeps what it had: the recorder sets them with the topic's first
        message, before any of its messages is released)."""
        info = self._topics[topic].info
        info.offered_qos_profiles = [dict(q) for q in offered_qos]
        if type_hash:
            if info.type_description_hash and type_hash != info.type_description_hash:
                log.warning('%s: the publishers\' type hash %s differs from the installed %s',
                            topic, type_hash, info.type_description_hash)
            info.type_description_hash = type_hash

    def write(self, topic: str, data: bytes | memoryview, t_ns: int) -> None:
        """Append one serialized (CDR) message with log time ``t_ns`` (nanoseconds)."""
        spool = self._require_open()
        tp = self._topics.get(topic)
        if tp is None:
            raise BagError(f'topic {topic} was not added to the bag')
        if t_ns < 0:
            if not self._negative_warned:
                log.warning('negative log time %d on %s stored as 0', t_ns, topic)
                self._negative_warned = True
            t_ns = 0
        spool.message(tp.cid, t_ns, data)
        self.counts[topic] += 1
        self.reorder.push(tp.cid, t_ns, bytes(data))
        for t, cid, d in self.reorder.release():
            self._emit(self._by_cid[cid], t, d)   # type: ignore[index]

    def flush(self) -> None:
        """Push the spool's buffered messages to the file (a killed recorder keeps them)."""
        if self._spool is not None:
            self._spool.fh.flush()

    def _require_open(self) -> _Spool:
        if self._spool is None:
            raise BagError(f'{self.path}: the bag writer is closed')
        return self._spool

    def close(self) -> None:
        """Write what the reorder buffer holds, finish the file, write metadata.yaml, delete
        the spool (idempotent)."""
        spool = self._spool
        if spool is None:
            return
        self._spool = None
        spool.fh.close()
        for t, cid, d in self.reorder.drain():
            self._emit(self._by_cid[cid], t, d)   # type: ignore[index]
        self._finish_file()
        self._meta.bag_size = sum((self.path / p).stat().st_size
                                  for p in self._meta.relative_file_paths)
        self.metadata = self._meta
        (self.path / 'metadata.yaml').write_text(to_yaml(self._meta))
        spool.path.unlink()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the bag files ----------------------------------------------------------------------

    def _emit(self, tp: _Topic, t_ns: int, data: bytes) -> None:
        """Write one released message to the current file (to a new one if it must split)."""
        f = self._meta.files[-1]
        if f.message_count and self._should_split(t_ns - f.starting_time_ns):
            self._finish_file()
            self._file = self._open_file(len(self._meta.files))
            f = self._meta.files[-1]
        self._file.add(self._file.channel(tp, self._by_cid), t_ns,
                       self._zstd.compress(data) if self.mode == 'message' else data)
        tp.info.message_count += 1
        self._count(f, t_ns)

    def _should_split(self, since_file_start_ns: int) -> bool:
        out = self._file
        by_size = self.max_size and out.tell + out.pending >= self.max_size
        by_time = self.max_duration_ns and since_file_start_ns > self.max_duration_ns
        return bool(by_size or by_time)

    def _count(self, f: FileInfo, t_ns: int) -> None:
        m, out = self._meta, self._file
        if f.message_count == 0:
            f.starting_time_ns = out.end_ns = t_ns
        f.starting_time_ns = min(f.starting_time_ns, t_ns)
        out.end_ns = max(out.end_ns, t_ns)
        f.duration_ns = out.end_ns - f.starting_time_ns
        f.message_count += 1
        m.starting_time_ns = min(m.starting_time_ns, t_ns)
        self._end_ns = max(self._end_ns, t_ns)
        m.duration_ns = self._end_ns - m.starting_time_ns
        m.message_count += 1

    def _open_file(self, k: int) -> _BagFile:
        name = f'{self.path.name}_{k}.mcap'
        self._meta.relative_file_paths.append(name)
        self._meta.files.append(FileInfo(name, NO_MESSAGE_TIME))
        return _BagFile(self.path / name, sized=self.max_size > 0)

    def _finish_file(self) -> None:
        out = self._file
        if self._by_cid:       # every topic in every file, as rosbag2 re-creates them on a split
            out.channel(self._by_cid[len(self._by_cid)], self._by_cid)
        self._meta.topics = [tp.info for tp in self._topics.values()]
        out.writer.add_metadata('rosbag2', {'serialized_metadata': to_yaml(self._meta, wrapped=False)})
        out.writer.finish()
        out.fh.close()
        out.spilled.close()
        if self.mode == 'file':
            dst = out.path.with_name(out.path.name + '.zstd')
            with out.path.open('rb') as fin, dst.open('xb') as fout:
                self._zstd.copy_stream(fin, fout)
            out.path.unlink()
            self._meta.relative_file_paths[-1] = dst.name  # files[].path keeps the .mcap name
