"""Recorded runs as MCAP files with the ROS 2 profile: reading, recovery of cut-off files, copying (the writer is
msg_tools.mcap_writer).

Why our own code: rosbag2 is not on PyPI, so neither `ros2 bag record` nor rosbag2_py exist here. The files
must still be what the ROS tools expect (MCAP's ROS 2 profile: `cdr` channels, `ros2msg` schemas built from the
installed .msg files, rosbag2's `offered_qos_profiles` channel metadata, chunked zstd data with a summary), so
that `ros2 bag info/play`, Foxglove and the `rosbags` library open them without extra files. Schema texts and
QoS metadata come from msg_tools.ros2_profile.

Reading deserialises with rclpy. A cut-off file (a killed recorder leaves no summary or footer) is read up to
its last complete chunk (msg_tools/mcap_scan.py), and a corrupt chunk is skipped with one line saying how many
messages it held. Files
of other tools (JSON, ros1, protobuf, channels without schema) are read and copied as they are. Problems raise
msg_tools.errors.RecordingError subclasses with a one-line message (WriteFailedError for a failed write).
"""

from __future__ import annotations

import functools
import heapq
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Callable, Iterable, Iterator, Mapping, NamedTuple

from mcap.data_stream import ReadDataStream
from mcap.reader import SeekingReader
from mcap.records import Attachment, Channel, Message, MessageIndex, Schema

from msg_tools.errors import NotMcapError, RecordingError, TruncatedRecordingError
from msg_tools.mcap_scan import OP_MESSAGE_INDEX, RECORD, SkippedChunk, chunk_messages, one_line, scan_file
from msg_tools.mcap_writer import DEFAULT_CHUNK_SIZE, MESSAGE_ENCODING, McapWriter, WriteFailedError
from msg_tools.ros2_profile import (
    message_class,
    normalize_type,
    parse_qos_yaml,
)

# McapWriter, WriteFailedError and DEFAULT_CHUNK_SIZE are msg_tools.mcap_writer's, named here too (copy_recording
# writes with them, and callers have imported them from here).
__all__ = [
    'DEFAULT_CHUNK_SIZE', 'ChannelInfo', 'McapWriter', 'RawMessage', 'RecordedMessage', 'Recording', 'SkippedChunk',
    'WriteFailedError', 'copy_recording', 'open_recording', 'read_messages',
]

MAGIC = b'\x89MCAP0\r\n'


# ------------------------------------------------------------------------------------------------- reader

@dataclass(frozen=True)
class ChannelInfo:
    """A recorded topic: its type (`pkg/msg/Type`: the schema's name), encodings, schema and channel metadata."""

    id: int
    topic: str
    type: str
    message_encoding: str
    schema_encoding: str
    schema_text: str
    metadata: Mapping[str, str] = field(default_factory=dict)
    schema_id: int = 0   # 0: the channel has no schema

    @property
    def qos(self) -> list[dict[str, Any]]:
        """The offered QoS profiles recorded for the topic ([] if none)."""
        return parse_qos_yaml(self.metadata.get('offered_qos_profiles', ''))


class RawMessage(NamedTuple):
    topic: str
    type: str
    log_time: int
    publish_time: int
    data: bytes
    channel_id: int
    sequence: int = 0


class RecordedMessage(NamedTuple):
    """One deserialised message: (topic, type, log_time in ns, message)."""

    topic: str
    type: str
    log_time: int
    message: Any


class Recording:
    """An MCAP recording opened for reading (see open_recording).

    Attributes: path; truncated (True when the summary/footer is missing or broken and the messages were
    recovered by a linear read); problem (why, one line); profile and library (the header's); channels
    {id: ChannelInfo}; schemas {id: mcap Schema}; metadata {name: {k: v}} and metadata_records (every record,
    in file order, duplicates kept); message_count (readable messages; lowered when a corrupt chunk is found
    while reading); start_time / end_time (log times, ns; 0 when empty); skipped (the corrupt chunks passed
    over so far); on_skip (called with one line when a corrupt chunk is skipped, e.g. to print a warning).
    """

    def __init__(self, path: str | os.PathLike[str], on_skip: Callable[[str], None] | None = None) -> None:
        self.path = Path(path)
        self.truncated = False
        self.problem = ''
        self.profile = ''
        self.library = ''
        self.channels: dict[int, ChannelInfo] = {}
        self.schemas: dict[int, Schema] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        self.metadata_records: list[tuple[str, dict[str, str]]] = []
        self.start_time = 0
        self.end_time = 0
        self.skipped: list[SkippedChunk] = []
        self.on_skip = on_skip
        self.orphans = 0
        self._count = 0
        self._lost_while_reading: dict[int, int] = {}   # channel id -> messages of chunks found corrupt
        self._recovered: list[Message] | None = None
        self._attachments: list[Attachment] | None = None
        self._chunks: list[Any] = []
        self._counts: dict[int, int] | None = None
        self._open()

    # -- opening
    def _open(self) -> None:
        path = self.path
        try:
            size = path.stat().st_size
            with open(path, 'rb') as f:
                head = f.read(len(MAGIC))
        except FileNotFoundError:
            raise RecordingError(f'{path}: no such file') from None
        except IsADirectoryError:
            raise RecordingError(f'{path} is a directory, not an MCAP file') from None
        except OSError as exc:
            raise RecordingError(f'cannot read {path}: {exc.strerror or exc}') from None
        if size == 0:
            raise NotMcapError(f'{path} is empty, not an MCAP file')
        if head != MAGIC:
            if MAGIC.startswith(head):
                raise TruncatedRecordingError(f'{path} is truncated: it ends inside the MCAP magic')
            raise NotMcapError(f'{path} is not an MCAP file (it does not start with the MCAP magic)')
        try:
            self._open_indexed()
        except Exception as exc:  # no footer/summary (cut off), or a broken summary: read linearly
            self._open_linear(size, one_line(exc))

    def _open_indexed(self) -> None:
        with open(self.path, 'rb') as f:
            reader = SeekingReader(f)
            header = reader.get_header()
            summary = reader.get_summary()
            if summary is None or summary.statistics is None:
                raise RecordingError('the file has no summary section with statistics')
            records = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        self.profile, self.library = header.profile, header.library
        self.schemas = dict(summary.schemas)
        self.channels = {cid: self._channel_info(ch, summary.schemas.get(ch.schema_id))
                         for cid, ch in summary.channels.items()}
        self.metadata_records = records
        self.metadata = {name: data for name, data in records}
        self._chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
        stats = summary.statistics
        self._counts = {cid: n for cid, n in stats.channel_message_counts.items() if cid in self.channels}
        self._count = stats.message_count
        self.start_time, self.end_time = stats.message_start_time, stats.message_end_time

    def _open_linear(self, size: int, reason: str) -> None:
        scan = scan_file(self.path, size)
        if scan.header is None:
            raise TruncatedRecordingError(f'{self.path} is truncated or corrupt before its first record '
                                          f'({scan.problem or reason}): nothing to recover')
        self.profile, self.library = scan.header.profile, scan.header.library
        self.schemas = dict(scan.schemas)
        self.channels = {cid: self._channel_info(ch, scan.schemas.get(ch.schema_id))
                         for cid, ch in scan.channels.items()}
        self.metadata_records = [(m.name, dict(m.metadata)) for m in scan.metadata]
        self.metadata = {name: data for name, data in self.metadata_records}
        self._attachments = scan.attachments
        self._recovered = scan.messages
        self._count = len(scan.messages)
        for chunk in scan.skipped:
            self._skip(chunk, counted=False)
        self.orphans = scan.orphans
        if scan.messages:
            self.start_time, self.end_time = scan.messages[0].log_time, scan.messages[-1].log_time
        if scan.complete and not scan.problem:
            return  # a complete file without a summary: nothing is missing but what `skipped` says
        self.truncated = True
        self.problem = scan.problem or 'no footer'
        if not scan.messages:
            raise TruncatedRecordingError(
                f'{self.path} is truncated ({self.problem}) and holds no complete message: nothing to recover')

    @staticmethod
    def _channel_info(channel: Channel, schema: Schema | None) -> ChannelInfo:
        return ChannelInfo(
            id=channel.id, topic=channel.topic, type=schema.name if schema else '',
            message_encoding=channel.message_encoding, schema_encoding=schema.encoding if schema else '',
            schema_text=schema.data.decode('utf-8', errors='replace') if schema else '',
            metadata=dict(channel.metadata), schema_id=channel.schema_id)

    # -- what is in it
    @property
    def topics(self) -> dict[str, ChannelInfo]:
        return {ch.topic: ch for ch in self.channels.values()}

    @property
    def message_count(self) -> int:
        """Readable messages: the statistics' count less what corrupt chunks found so far held."""
        return self._count - sum(self._lost_while_reading.values())

    def warning(self) -> str:
        """One line about a truncated file or corrupt chunks skipped so far ('' for a sound file)."""
        parts = []
        if self.truncated:
            parts.append(f'{self.path} is truncated ({self.problem}): recovered {self.message_count} messages up to '
                         f'the last complete chunk (log time {self.end_time * 1e-9:.3f} s)')
        if len(self.skipped) == 1:
            parts.append(f'{self.path}: {self.skipped[0].describe()}; kept the {self.message_count} readable messages')
        elif self.skipped:
            known = [s.messages for s in self.skipped if s.messages is not None]
            lost = f'{"at least " if len(known) < len(self.skipped) else ""}{sum(known)} messages lost'
            parts.append(f'{self.path}: skipped {len(self.skipped)} corrupt chunks ({lost}), kept the '
                         f'{self.message_count} readable messages; the first: {self.skipped[0].describe()}')
        if self.orphans:
            parts.append(f'{self.path}: {self.orphans} messages dropped: their channel was defined in a corrupt chunk')
        return '; '.join(parts)

    def counts(self) -> dict[str, int]:
        """Messages per topic (readable ones)."""
        out = {ch.topic: 0 for ch in self.channels.values()}
        if self._counts is not None:  # from the Statistics record, less the corrupt chunks found so far
            for cid, n in self._counts.items():
                out[self.channels[cid].topic] += n - self._lost_while_reading.get(cid, 0)
            return out
        for raw in self.raw_messages():
            out[raw.topic] += 1
        return out

    def attachments(self) -> list[Attachment]:
        """The attachment records (for a faithful copy)."""
        if self._attachments is not None:
            return list(self._attachments)
        try:
            with open(self.path, 'rb') as f:
                return list(SeekingReader(f).iter_attachments())
        except Exception as exc:
            raise RecordingError(f'{self.path}: cannot read its attachments: {one_line(exc)}') from None

    def _skip(self, chunk: SkippedChunk, counted: bool = True) -> None:
        """Note a corrupt chunk (once); counted: its messages are in the statistics' counts (indexed files)."""
        if any(s.offset == chunk.offset for s in self.skipped):
            return
        self.skipped.append(chunk)
        for cid, n in (chunk.lost or {}).items() if counted else ():
            self._lost_while_reading[cid] = self._lost_while_reading.get(cid, 0) + n
        if self.on_skip is not None:
            self.on_skip(f'{self.path}: {chunk.describe()}')

    # -- messages
    def raw_messages(self, topics: Iterable[str] | None = None, log_time_order: bool = True) -> Iterator[RawMessage]:
        """Every readable message (CDR bytes) in log-time order, optionally only on some topics. A corrupt chunk
        is skipped (see on_skip and warning()); the chunks before and after it are read.

        log_time_order=False gives file order, which is faster on big files (no merge of the chunks by time);
        files written by our tools are in log-time order anyway, except for equal times across topics.
        """
        wanted = None if topics is None else set(topics)
        if self._recovered is not None:
            for m in self._recovered:
                ch = self.channels[m.channel_id]
                if wanted is None or ch.topic in wanted:
                    yield RawMessage(ch.topic, ch.type, m.log_time, m.publish_time, m.data, m.channel_id, m.sequence)
            return
        if not self._chunks:   # an indexed file without chunks (messages in the data section)
            yield from self._unchunked_messages(wanted, log_time_order)
            return
        ids = {cid: (ch.topic, ch.type) for cid, ch in self.channels.items() if wanted is None or ch.topic in wanted}
        chunks = [c for c in self._chunks
                  if wanted is None or not c.message_index_offsets or ids.keys() & c.message_index_offsets.keys()]
        in_order = all(a.message_end_time <= b.message_start_time for a, b in zip(self._chunks, self._chunks[1:]))
        try:
            with open(self.path, 'rb') as f:
                if in_order or not log_time_order:
                    # RawMessages made one at a time, as they are taken: a whole chunk's of them at once costs
                    # fastep-report a third more time (the garbage collector runs more often).
                    for index in chunks:
                        found = self._read_chunk(f, index, ids)
                        if log_time_order:
                            found.sort(key=lambda m: m[2])
                        for channel_id, sequence, log_time, publish_time, data in found:
                            yield RawMessage(*ids[channel_id], log_time, publish_time, data, channel_id, sequence)
                else:
                    yield from self._merged(f, chunks, ids)
        except RecordingError:
            raise
        except OSError as exc:
            raise RecordingError(f'{self.path}: cannot read messages: {one_line(exc)}') from None

    def _read_chunk(self, f: IO[bytes], index: Any,
                    ids: Mapping[int, Any]) -> list[tuple[int, int, int, int, bytes]]:
        """(channel id, sequence, log time, publish time, data) of the messages of one chunk on the channels
        `ids`, in file order; [] (and the chunk recorded as skipped) when it is corrupt."""
        try:
            f.seek(index.chunk_start_offset)
            found = chunk_messages(f.read(index.chunk_length))
        except OSError:
            raise
        except Exception as exc:
            self._skip(SkippedChunk(index.chunk_start_offset, self._index_counts(f, index), index.message_start_time,
                                    index.message_end_time, one_line(exc)))
            return []
        return [m for m in found if m[0] in ids]

    @staticmethod
    def _index_counts(f: IO[bytes], index: Any) -> dict[int, int] | None:
        """Messages per channel of a chunk, from its MessageIndex records (None if they are unreadable)."""
        out = {}
        try:
            for channel_id, offset in index.message_index_offsets.items():
                f.seek(offset)
                opcode, _ = RECORD.unpack(f.read(9))
                if opcode != OP_MESSAGE_INDEX:
                    return None
                out[channel_id] = len(MessageIndex.read(ReadDataStream(f)).records)
        except Exception:
            return None
        return out

    def _merged(self, f: IO[bytes], chunks: list[Any], ids: Mapping[int, tuple[str, str]]) -> Iterator[RawMessage]:
        """Messages of chunks that overlap in time, merged by log time (ties: file order). A chunk is read once
        the merge reaches its start time, so at most the overlapping chunks are held."""
        order = sorted(chunks, key=lambda c: (c.message_start_time, c.chunk_start_offset))
        heap: list[tuple[int, int, int, tuple[int, int, int, int, bytes]]] = []
        i = 0
        while i < len(order) or heap:
            while i < len(order) and (not heap or order[i].message_start_time <= heap[0][0]):
                index = order[i]
                for k, m in enumerate(self._read_chunk(f, index, ids)):
                    heapq.heappush(heap, (m[2], index.chunk_start_offset, k, m))
                i += 1
            if heap:
                channel_id, sequence, log_time, publish_time, data = heapq.heappop(heap)[3]
                yield RawMessage(*ids[channel_id], log_time, publish_time, data, channel_id, sequence)

    def _unchunked_messages(self, wanted: set[str] | None, log_time_order: bool) -> Iterator[RawMessage]:
        try:
            with open(self.path, 'rb') as f:
                reader = SeekingReader(f)
                select = None if wanted is None else sorted(wanted)
                for _schema, channel, m in reader.iter_messages(topics=select, log_time_order=log_time_order):
                    yield RawMessage(channel.topic, self.channels[channel.id].type, m.log_time, m.publish_time,
                                     m.data, channel.id, m.sequence)
        except Exception as exc:
            raise RecordingError(f'{self.path}: cannot read messages: {one_line(exc)}') from None

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[RecordedMessage]:
        """Every message deserialised with rclpy, in log-time order: (topic, type, log_time, message). A type
        rclpy does not have here (tf2_msgs/msg/TFMessage: not among the PyPI ROS wheels) is decoded by rosbags'
        Jazzy typestore when it knows it (a rosbags message: a dataclass with the same fields)."""
        decoders: dict[int, Callable[[bytes], Any]] = {}
        for raw in self.raw_messages(topics):
            decode = decoders.get(raw.channel_id)
            if decode is None:
                ch = self.channels[raw.channel_id]
                if ch.message_encoding != MESSAGE_ENCODING:
                    raise RecordingError(f'{self.path}: topic {ch.topic} has message encoding '
                                         f'{ch.message_encoding!r}, not cdr')
                decode = decoders[raw.channel_id] = _decoder(ch.type)
            try:
                message = decode(raw.data)
            except Exception as exc:
                raise RecordingError(f'{self.path}: cannot decode a {raw.type} message on {raw.topic} at log time '
                                     f'{raw.log_time * 1e-9:.3f} s: {one_line(exc)}') from None
            yield RecordedMessage(raw.topic, raw.type, raw.log_time, message)


def _decoder(type_name: str) -> Callable[[bytes], Any]:
    """CDR bytes -> message: rclpy's class, else (a type not installed here) rosbags' typestore."""
    from rclpy.serialization import deserialize_message

    try:
        cls = message_class(type_name)
    except RecordingError:
        from rosbags.typesys import Stores, get_typestore
        store = get_typestore(Stores.ROS2_JAZZY)
        full = normalize_type(type_name)
        if full not in store.types:
            raise
        return functools.partial(store.deserialize_cdr, typename=full)
    return functools.partial(deserialize_message, message_type=cls)


def open_recording(path: str | os.PathLike[str], on_skip: Callable[[str], None] | None = None) -> Recording:
    """Open an MCAP file for reading. RecordingError (one line) if it is missing, not MCAP, or cut off with
    nothing recoverable; a cut-off file with complete chunks opens with `truncated` set (see warning()), and
    a corrupt chunk is skipped (Recording.skipped; on_skip gets one line for each, when it is found: while
    opening a cut-off file, while reading messages of an indexed one)."""
    return Recording(path, on_skip)


def read_messages(path: str | os.PathLike[str], topics: Iterable[str] | None = None) -> Iterator[RecordedMessage]:
    """Shortcut: the deserialised messages of a file (recovered ones if it was cut off)."""
    return open_recording(path).messages(topics)


def copy_recording(recording: Recording, output: str | os.PathLike[str] | IO[bytes], *,
                   chunk_size: int = DEFAULT_CHUNK_SIZE, compression: str = 'zstd',
                   warn: Callable[[str], None] | None = None) -> int:
    """Write every readable message of `recording` into a new, complete file, faithfully: the header's profile
    and library, every schema (any encoding, its bytes as they were), every channel (its message encoding, its
    schema or none, its metadata), message sequence numbers and times, metadata records (duplicates too) and
    attachments. Only the chunking changes. Return the number of messages written.

    A channel whose schema record is not in the readable part of the file (a linear read of a damaged file
    can lose it) cannot be copied faithfully: with `warn` it is left out and warn() gets one line saying so;
    without, RecordingError (one line) before anything is written."""
    lost_schema = {cid: ch for cid, ch in sorted(recording.channels.items())
                   if ch.schema_id and ch.schema_id not in recording.schemas}
    for ch in lost_schema.values():
        line = (f'{recording.path}: cannot copy topic {ch.topic} faithfully: its schema (id {ch.schema_id}) is not '
                f'in the readable part of the file')
        if warn is None:
            raise RecordingError(line)
        warn(line + '; its messages are left out')
    attachments = recording.attachments()
    with McapWriter(output, chunk_size=chunk_size, compression=compression, library=recording.library,
                    profile=recording.profile) as writer:
        schema_ids = {sid: writer.add_schema(s.name, s.encoding, s.data)
                      for sid, s in sorted(recording.schemas.items())}
        ids = {cid: writer.add_raw_channel(ch.topic, ch.message_encoding, schema_ids.get(ch.schema_id, 0),
                                           ch.metadata)
               for cid, ch in sorted(recording.channels.items()) if cid not in lost_schema}
        for name, data in recording.metadata_records:
            writer.add_metadata(name, data)
        for a in attachments:
            writer.add_attachment(a.name, a.media_type, a.data, a.log_time, a.create_time)
        for raw in recording.raw_messages():
            if raw.channel_id in ids:
                writer.write_raw(ids[raw.channel_id], raw.data, raw.log_time, raw.publish_time, raw.sequence)
        return writer.message_count
