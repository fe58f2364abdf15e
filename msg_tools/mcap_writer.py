"""Writing recorded runs as MCAP files with the ROS 2 profile (msg_tools.mcap_io reads them, and says why the
files are written this way).

- header profile `ros2`; channels with message encoding `cdr`; schemas with encoding `ros2msg` named
  `pkg/msg/Type` (msg_tools.ros2_profile writes their texts from the installed .msg files);
- channel metadata `offered_qos_profiles` in rosbag2's format, so a player re-creates latched topics as latched;
- chunked, compressed (zstd) data with a summary and a Statistics record (the `mcap` Writer writes those).
A write that fails (a full disk) raises WriteFailedError with one line; what was written before stays readable.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import IO, Any, Mapping, Sequence

from mcap.writer import CompressionType, Writer

from msg_tools.errors import RecordingError
from msg_tools.ros2_profile import message_definition, normalize_type, qos_dict, qos_yaml, type_name_of

__all__ = ['COMPRESSIONS', 'DEFAULT_CHUNK_SIZE', 'MESSAGE_ENCODING', 'McapWriter', 'WriteFailedError']

PROFILE = 'ros2'
MESSAGE_ENCODING = 'cdr'
SCHEMA_ENCODING = 'ros2msg'
LIBRARY = 'fastep msg_tools.mcap_io'   # the header's library (files written before this module's split say the same)
# Chunks are what survives a crash (a killed writer loses the chunk in progress), and the recorder also
# flushes once a second; 256 KiB still compresses well (odometry is mostly zero covariances).
DEFAULT_CHUNK_SIZE = 256 * 1024
COMPRESSIONS = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4, 'none': CompressionType.NONE}


class WriteFailedError(RecordingError):
    """The file could not be written (disk full, file size limit, I/O error): what the writer had handed to the
    file before stays readable up to the last complete chunk (open_recording recovers it)."""


class McapWriter:
    """Writes ROS 2 messages, or their CDR bytes, to an MCAP file with the ROS 2 profile.

        with McapWriter('run.mcap') as w:
            w.add_channel('/map', 'nav_msgs/msg/OccupancyGrid', qos=[qos_dict(depth=1, transient_local=True)])
            w.write('/map', grid, log_time_ns)
            w.write('/r1/cost', Float64(data=1.0), log_time_ns)   # channel created on first use

    Times are integer nanoseconds; publish_time defaults to log_time. finish() (or leaving the `with`) writes
    the summary; flush() ends the chunk in progress so that a crash loses nothing written before it.

    An OSError while writing (a full disk: ENOSPC, a file size limit: EFBIG) is raised once as WriteFailedError
    with one line; the writer is then broken: later calls raise it again and finish() only closes the file
    (the summary cannot be written; the reader recovers the complete chunks).
    """

    def __init__(self, output: str | os.PathLike[str] | IO[bytes], *, chunk_size: int = DEFAULT_CHUNK_SIZE,
                 compression: str = 'zstd', library: str = LIBRARY, profile: str = PROFILE) -> None:
        if compression not in COMPRESSIONS:
            raise RecordingError(f'compression must be one of {", ".join(COMPRESSIONS)}, got {compression!r}')
        self._own_stream = not hasattr(output, 'write')
        self.name = str(output) if self._own_stream else str(getattr(output, 'name', 'the output stream'))
        if self._own_stream:
            path = Path(output)  # type: ignore[arg-type]  # no write(): a path, which mypy cannot narrow by hasattr
            try:
                self._stream: IO[bytes] = open(path, 'wb')
            except OSError as exc:
                raise RecordingError(f'cannot write {path}: {exc.strerror or exc}') from None
        else:
            self._stream = output  # type: ignore[assignment]  # has write(): a binary stream
        self.failure = ''
        self._writer = Writer(self._stream, chunk_size=int(chunk_size), compression=COMPRESSIONS[compression])
        self._schemas: dict[tuple[str, str], int] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self._sequence: dict[int, int] = {}
        self.message_count = 0
        self.finished = False
        self._guarded(self._writer.start, profile=profile, library=library)

    def _guarded(self, call: Any, *args: Any, **kwargs: Any) -> Any:
        """call(*args, **kwargs), an OSError turned into WriteFailedError (and the writer marked broken)."""
        if self.failure:
            raise WriteFailedError(self.failure)
        try:
            return call(*args, **kwargs)
        except OSError as exc:
            self.failure = f'cannot write {self.name}: {exc.strerror or exc}'
            raise WriteFailedError(self.failure) from None

    def add_channel(self, topic: str, type_name: str, qos: Sequence[Mapping[str, Any]] | None = None, *,
                    schema_text: str | None = None, metadata: Mapping[str, str] | None = None) -> int:
        """Register a topic (once; again with the same type returns its id) and return its channel id.

        qos: the offered profiles (default: one reliable, volatile, keep-last 10 profile). schema_text: use
        this definition instead of generating it (when copying a recording).
        """
        full = normalize_type(type_name)
        if topic in self._channels:
            channel_id, known = self._channels[topic]
            if known != full:
                raise RecordingError(f'topic {topic} is already recorded as {known}, not {full}')
            return channel_id
        text = message_definition(full) if schema_text is None else schema_text
        key = (full, text)
        if key not in self._schemas:
            self._schemas[key] = self.add_schema(full, SCHEMA_ENCODING, text.encode('utf-8'))
        meta = {'offered_qos_profiles': qos_yaml(qos if qos is not None else [qos_dict()])}
        meta.update(metadata or {})
        channel_id = self.add_raw_channel(topic, MESSAGE_ENCODING, self._schemas[key], meta)
        self._channels[topic] = (channel_id, full)
        return channel_id

    def add_schema(self, name: str, encoding: str, data: bytes) -> int:
        """Register a schema as given (any encoding, as copied from another file); return its id."""
        return int(self._guarded(self._writer.register_schema, name=name, encoding=encoding, data=bytes(data)))

    def add_raw_channel(self, topic: str, message_encoding: str, schema_id: int,
                        metadata: Mapping[str, str] | None = None) -> int:
        """Register a channel as given (any message encoding; schema_id 0: no schema); return its id."""
        channel_id = int(self._guarded(self._writer.register_channel, topic=topic, message_encoding=message_encoding,
                                       schema_id=schema_id, metadata=dict(metadata or {})))
        self._sequence[channel_id] = 0
        return channel_id

    def has_channel(self, topic: str) -> bool:
        return topic in self._channels

    def write(self, topic: str, message: Any, log_time: int, publish_time: int | None = None, *,
              type_name: str | None = None, qos: Sequence[Mapping[str, Any]] | None = None) -> None:
        """Write a message (an rclpy message, or its CDR bytes with type_name given) on topic."""
        if topic not in self._channels:
            if type_name is None:
                if isinstance(message, (bytes, bytearray, memoryview)):
                    raise RecordingError(f'topic {topic}: raw bytes need a type_name')
                type_name = type_name_of(message)
            self.add_channel(topic, type_name, qos)
        channel_id = self._channels[topic][0]
        self.write_raw(channel_id, message if isinstance(message, (bytes, bytearray, memoryview))
                       else _serialize(message), log_time, publish_time)

    def write_raw(self, channel_id: int, data: bytes | bytearray | memoryview, log_time: int,
                  publish_time: int | None = None, sequence: int | None = None) -> None:
        """Write one message's bytes; sequence: as given (a copy), else counted per channel from 1."""
        log_time = int(log_time)
        self._sequence[channel_id] += 1
        self._guarded(self._writer.add_message, channel_id=channel_id, log_time=log_time, data=bytes(data),
                      publish_time=log_time if publish_time is None else int(publish_time),
                      sequence=self._sequence[channel_id] if sequence is None else int(sequence))
        self.message_count += 1

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        self._guarded(self._writer.add_metadata, name, {str(k): str(v) for k, v in data.items()})

    def add_attachment(self, name: str, media_type: str, data: bytes, log_time: int = 0, create_time: int = 0) -> None:
        self._guarded(self._writer.add_attachment, create_time=int(create_time), log_time=int(log_time), name=name,
                      media_type=media_type, data=bytes(data))

    def flush(self) -> None:
        """End the chunk in progress and push everything to the OS (it survives a crash of this process)."""
        flush = getattr(self._writer, 'flush', None)  # mcap >= 1.3
        self._guarded(flush if flush is not None else self._stream.flush)

    def finish(self) -> None:
        """Write the summary (statistics, indexes) and the footer; close the file if we opened it.

        After a write failure only the file is closed, and WriteFailedError raised again (once)."""
        if self.finished:
            return
        self.finished = True
        try:
            self._guarded(self._writer.finish)
            self._guarded(self._stream.flush)
        finally:
            if self._own_stream:
                try:
                    self._stream.close()
                except OSError:   # close() flushes what is buffered: already reported above
                    pass

    def __enter__(self) -> McapWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        if exc[0] is not None and self.failure:
            self.finished = True   # the failure propagates; do not raise it a second time from here
            if self._own_stream:
                try:
                    self._stream.close()
                except OSError:
                    pass
            return
        self.finish()


def _serialize(message: Any) -> bytes:
    from rclpy.serialization import serialize_message
    return serialize_message(message)
