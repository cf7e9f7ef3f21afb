"""Write rosbag2 Jazzy MCAP bags: ``metadata.yaml`` + ``NAME_0.mcap`` (``NAME_1.mcap`` ... when
split), messages in log-time order in every file.

Log times are message stamps (see :mod:`alignment_ros.bag`), so messages arrive out of log-time
order, by tens of seconds across topics, and no reorder window is safe. While recording, each
message is appended as it comes to ``NAME.recording.mcap`` (plain MCAP records, readable like
any truncated bag if the recorder dies); :meth:`BagWriter.close` sorts the index (log time, then
arrival) and writes the bag files from it, then deletes the spool. Each file is what rosbag2's
MCAP storage writes: ``ros2`` profile; one ``ros2msg`` schema per type holding the installed
definition (:mod:`alignment_ros.msg_definitions`); channels with ``offered_qos_profiles`` and
``topic_type_hash`` metadata; a ``rosbag2`` metadata record; chunk index, statistics, summary
offsets and a summary CRC. Splitting follows rosbag2: a new file starts before a message when
the current one reached ``max_bag_size`` bytes or the message is more than
``max_bag_duration_s`` after the file's first. Compression follows rosbag2_compression:
``message`` (each message's CDR bytes a zstd frame) or ``file`` (each finished file replaced by
``NAME_k.mcap.zstd``); metadata.yaml lists ``compression_format: zstd`` and the mode.
"""
from __future__ import annotations

import logging
import mmap
import struct
from array import array
from pathlib import Path
from typing import Any

import zstandard
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

log = logging.getLogger(__name__)

MCAP_MAGIC = b'\x89MCAP0\r\n'
SPOOL_SUFFIX = '.recording.mcap'
CHUNK_SIZE = 768 * 1024          # libmcap's default chunk size (rosbag2 keeps it)
MIN_SPLIT_SIZE = 1024            # rosbag2 MCAP storage's minimum split file size
ZSTD_LEVEL = 1                   # rosbag2_compression_zstd's default level
NO_MESSAGE_TIME = 2 ** 63 - 1    # rosbag2's starting_time before any message
LIBRARY = f'alignment_ros (mcap-python {mcap_version})'
COMPRESSION_MODES = {'none': '', 'file': 'FILE', 'message': 'MESSAGE'}
_MSG_HEAD = struct.Struct('<BQHIQQ')  # Message record: opcode, length, channel, seq, log, publish


def _string(s: str) -> bytes:
    b = s.encode()
    return struct.pack('<I', len(b)) + b


def _record(op: int, body: bytes) -> bytes:
    return struct.pack('<BQ', op, len(body)) + body


class _Spool:
    """Append-only MCAP records in arrival order plus an index (log time, offset, size, channel)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fh = path.open('xb', buffering=1 << 20)
        self.pos = 0
        self.t = array('q')
        self.offset = array('q')
        self.size = array('I')
        self.channel = array('H')
        self._put(MCAP_MAGIC + _record(0x01, _string('ros2') + _string(LIBRARY)))

    def _put(self, b: bytes) -> None:
        self.fh.write(b)
        self.pos += len(b)

    def schema(self, sid: int, name: str, encoding: str, data: bytes) -> None:
        self._put(_record(0x03, struct.pack('<H', sid) + _string(name) + _string(encoding)
                          + struct.pack('<I', len(data)) + data))

    def channel_record(self, cid: int, sid: int, topic: str) -> None:
        self._put(_record(0x04, struct.pack('<HH', cid, sid) + _string(topic) + _string('cdr')
                          + struct.pack('<I', 0)))

    def message(self, cid: int, t_ns: int, data: bytes | memoryview) -> None:
        n = len(data)
        self.fh.write(_MSG_HEAD.pack(0x05, 22 + n, cid, 0, t_ns, t_ns))
        self.fh.write(data)
        self.t.append(t_ns)
        self.offset.append(self.pos + _MSG_HEAD.size)
        self.size.append(n)
        self.channel.append(cid)
        self.pos += _MSG_HEAD.size + n


class _Topic:
    def __init__(self, cid: int, info: TopicInfo, encoding: str, definition: str) -> None:
        self.cid = cid
        self.info = info
        self.encoding = encoding
        self.definition = definition


class BagWriter:
    """Write raw CDR messages to a new rosbag2 MCAP bag directory (which must not exist).

    Use as a context manager or call :meth:`close`; only closing writes the bag files and
    ``metadata.yaml`` (until then the bag is its ``.recording.mcap`` spool).
    """

    def __init__(self, path: str | Path, *, max_bag_duration_s: float = 0,
                 max_bag_size: int = 0, compression_mode: str = 'none',
                 compression_format: str = '', custom_data: dict[str, str] | None = None,
                 offered_qos: dict[str, Any] | None = STREAM_QOS) -> None:
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
        self._schemas: dict[str, int] = {}
        self._spool: _Spool | None = _Spool(self.path / (self.path.name + SPOOL_SUFFIX))
        self._negative_warned = False
        self.counts: dict[str, int] = {}
        self.metadata: BagMetadata | None = None

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
        cid = len(self._topics) + 1
        self._topics[topic] = _Topic(cid, info, encoding, text)
        spool.channel_record(cid, self._schemas[type_name], topic)
        self.counts[topic] = 0

    def set_topic_endpoints(self, topic: str, offered_qos: list[dict[str, Any]],
                            type_hash: str = '') -> None:
        """Replace a topic's offered QoS profiles (and hash, if given) with what its
        publishers offer, as rosbag2 takes them from the graph."""
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

    def flush(self) -> None:
        """Push the spool's buffered messages to the file (a killed recorder keeps them)."""
        if self._spool is not None:
            self._spool.fh.flush()

    def _require_open(self) -> _Spool:
        if self._spool is None:
            raise BagError(f'{self.path}: the bag writer is closed')
        return self._spool

    def close(self) -> None:
        """Sort, write the bag files and metadata.yaml, delete the spool (idempotent)."""
        spool = self._spool
        if spool is None:
            return
        self._spool = None
        spool.fh.close()
        with spool.path.open('rb') as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as buf:
            self.metadata = _Finaliser(self, spool, buf).run()
        (self.path / 'metadata.yaml').write_text(to_yaml(self.metadata))
        spool.path.unlink()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Finaliser:
    """Write the sorted bag files of one closed spool; return the bag's metadata."""

    def __init__(self, writer: BagWriter, spool: _Spool, buf: mmap.mmap) -> None:
        self.w = writer
        self.spool = spool
        self.buf = buf
        self.topics = list(writer._topics.values())
        self.by_cid = {tp.cid: tp for tp in self.topics}
        for tp in self.topics:
            tp.info.message_count = 0
        self.meta = BagMetadata(compression_format=writer.compression_format,
                                compression_mode=COMPRESSION_MODES[writer.mode],
                                custom_data=writer.custom_data or None,
                                starting_time_ns=NO_MESSAGE_TIME)
        self.zstd = zstandard.ZstdCompressor(level=ZSTD_LEVEL)

    def run(self) -> BagMetadata:
        t, off, size, ch = self.spool.t, self.spool.offset, self.spool.size, self.spool.channel
        order = sorted(range(len(t)), key=t.__getitem__)  # stable: arrival order within a time
        out = self._open_file(0)
        for i in order:
            ti = t[i]
            f = self.meta.files[-1]
            if f.message_count and self._should_split(out, ti - f.starting_time_ns):
                self._finish_file(out)
                out = self._open_file(len(self.meta.files))
                f = self.meta.files[-1]
            data: bytes | memoryview = self.buf[off[i]:off[i] + size[i]]
            if self.w.mode == 'message':
                data = self.zstd.compress(data)
            tp = self.by_cid[ch[i]]
            out['writer'].add_message(tp.cid, ti, data, ti, 0)
            tell = out['fh'].tell()
            out['pending'] = 0 if tell != out['tell'] else out['pending'] + 31 + len(data)
            out['tell'] = tell
            tp.info.message_count += 1
            self._count(f, ti)
        self._finish_file(out)
        self.meta.bag_size = sum((self.w.path / p).stat().st_size
                                 for p in self.meta.relative_file_paths)
        return self.meta

    def _should_split(self, out: dict[str, Any], since_file_start_ns: int) -> bool:
        by_size = self.w.max_size and out['tell'] + out['pending'] >= self.w.max_size
        by_time = self.w.max_duration_ns and since_file_start_ns > self.w.max_duration_ns
        return bool(by_size or by_time)

    def _count(self, f: FileInfo, t_ns: int) -> None:
        m = self.meta
        if f.message_count == 0:
            f.starting_time_ns = t_ns
        f.duration_ns = max(f.duration_ns, t_ns - f.starting_time_ns)
        f.message_count += 1
        m.starting_time_ns = min(m.starting_time_ns, t_ns)
        m.duration_ns = max(m.duration_ns, t_ns - m.starting_time_ns)
        m.message_count += 1

    def _open_file(self, k: int) -> dict[str, Any]:
        name = f'{self.w.path.name}_{k}.mcap'
        self.meta.relative_file_paths.append(name)
        self.meta.files.append(FileInfo(name, NO_MESSAGE_TIME))
        fh = (self.w.path / name).open('xb')
        writer = Writer(fh, chunk_size=CHUNK_SIZE, compression=CompressionType.NONE)
        writer.start(profile='ros2', library=LIBRARY)
        schema_ids: dict[str, int] = {}
        for tp in self.topics:  # every topic in every file, as rosbag2 re-creates them on a split
            if tp.info.type not in schema_ids:
                schema_ids[tp.info.type] = writer.register_schema(
                    tp.info.type, tp.encoding, tp.definition.encode())
            cid = writer.register_channel(tp.info.name, 'cdr', schema_ids[tp.info.type], {
                'offered_qos_profiles': qos_string(tp.info.offered_qos_profiles),
                'topic_type_hash': tp.info.type_description_hash})
            assert cid == tp.cid
        return {'fh': fh, 'writer': writer, 'name': name, 'tell': fh.tell(), 'pending': 0}

    def _finish_file(self, out: dict[str, Any]) -> None:
        self.meta.topics = [tp.info for tp in self.topics]
        out['writer'].add_metadata('rosbag2', {'serialized_metadata': to_yaml(self.meta, wrapped=False)})
        out['writer'].finish()
        out['fh'].close()
        if self.w.mode == 'file':
            src = self.w.path / out['name']
            dst = src.with_name(src.name + '.zstd')
            with src.open('rb') as fin, dst.open('xb') as fout:
                self.zstd.copy_stream(fin, fout)
            src.unlink()
            self.meta.relative_file_paths[-1] = dst.name  # files[].path keeps the .mcap name
