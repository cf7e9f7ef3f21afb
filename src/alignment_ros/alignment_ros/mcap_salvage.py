"""Linear scan of a (possibly truncated) MCAP file: every complete record it still holds.

Used for files without a valid footer/summary: a recording that was killed (its spool is plain
records) or a copy cut short. Chunks cut in the middle still yield their complete messages
(a zstd or lz4 chunk: what its compressed prefix decodes to). Besides the schema names and the
channels' topics it keeps what a rewrite of the file needs (:mod:`alignment_ros.bag_reindex`):
the schemas' encoding and data, the channels' message encoding and metadata.
"""
from __future__ import annotations

import logging
import struct

log = logging.getLogger('alignment_ros.bag')


class Salvage:
    """Schemas, channels and complete messages of an MCAP byte buffer (:meth:`scan` fills them)."""

    def __init__(self, buf: bytes) -> None:
        self.buf = memoryview(buf)
        self.schemas: dict[int, str] = {}
        self.channels: dict[int, tuple[str, int]] = {}
        self.schema_data: dict[int, tuple[str, bytes]] = {}       # id -> (encoding, data)
        self.channel_info: dict[int, tuple[str, dict[str, str]]] = {}  # id -> (encoding, metadata)
        self.messages: list[tuple[int, int, int, bytes]] = []  # (log_time, seq, channel, data)
        self.complete = False
        self.good_end = 8  # end offset of the last complete record (top-level buffer)

    @staticmethod
    def _str(buf: memoryview, pos: int) -> tuple[str, int]:
        (n,) = struct.unpack_from('<I', buf, pos)
        return bytes(buf[pos + 4:pos + 4 + n]).decode(), pos + 4 + n

    @classmethod
    def _map(cls, buf: memoryview, pos: int) -> dict[str, str]:
        (n,) = struct.unpack_from('<I', buf, pos)
        end, pos, out = pos + 4 + n, pos + 4, {}
        while pos < end:
            k, pos = cls._str(buf, pos)
            out[k], pos = cls._str(buf, pos)
        return out

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
                name, p = self._str(buf, body + 2)
                self.schemas[sid] = name
                encoding, p = self._str(buf, p)
                (n,) = struct.unpack_from('<I', buf, p)
                self.schema_data[sid] = (encoding, bytes(buf[p + 4:p + 4 + n]))
            elif op == 0x04:  # Channel
                cid, sid = struct.unpack_from('<HH', buf, body)
                topic, p = self._str(buf, body + 4)
                self.channels[cid] = (topic, sid)
                encoding, p = self._str(buf, p)
                self.channel_info[cid] = (encoding, self._map(buf, p))
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
        raw = bytes(buf[rec_start:rec_end])
        try:
            raw = _decompress(compression, raw, partial)
        except Exception as exc:  # noqa: BLE001  (decompressors raise their own error types)
            log.warning('MCAP chunk skipped: %s', exc)
            return
        inner = Salvage(raw)
        for k in ('schemas', 'channels', 'schema_data', 'channel_info', 'messages'):
            setattr(inner, k, getattr(self, k))
        inner.scan(0, len(raw))


def _decompress(compression: str, raw: bytes, partial: bool) -> bytes:
    """A chunk's records; of a cut chunk (`partial`), what its compressed prefix decodes to."""
    if compression == 'zstd':
        import zstandard
        return zstandard.ZstdDecompressor().decompressobj().decompress(raw)
    if compression == 'lz4':
        import lz4.frame
        if partial:
            return lz4.frame.LZ4FrameDecompressor().decompress(raw)
        return lz4.frame.decompress(raw)
    raise ValueError(f'unsupported compression {compression!r}')
