"""Recordings damaged in the middle, and recordings of other tools (issue "Hardening", items 6 and 7).

- One corrupt chunk (a byte flipped in its compressed data, as a bad sector or a bad copy leaves it) must cost
  only that chunk's messages: the reader, fastep-recover and fastep-report keep every other chunk and say in
  one line how much was lost; the recovered file is valid for an independent reader (rosbags).
- fastep-recover copies a file of another tool as it was: JSON and ros1 channels keep their encodings and
  schemas, schemaless channels, binary schemas, sequence numbers, duplicate metadata and attachments are kept.

The files are made here, small (a few hundred messages in 2 KiB chunks).
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest
from mcap.data_stream import ReadDataStream
from mcap.reader import SeekingReader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer
from rosbags.highlevel import AnyReader
from std_msgs.msg import Float64, String

from msg_tools import recover, report
from msg_tools.errors import RecordingError
from msg_tools.mcap_io import McapWriter, copy_recording, open_recording

MESSAGES = 300


@pytest.fixture(scope='module')
def ros2_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fastep-like recording: one robot's cost and status-free odometry stand-ins, in small chunks."""
    path = tmp_path_factory.mktemp('damaged') / 'run.mcap'
    with McapWriter(path, chunk_size=2048) as writer:
        for i in range(MESSAGES):
            writer.write('/r1/cost', Float64(data=float(i)), 1_000_000_000 + i * 10_000_000)
            if i % 10 == 0:
                writer.write('/note', String(data=f'note {i}'), 1_000_000_000 + i * 10_000_000)
    return path


def chunk_records(path: Path) -> list[tuple[int, int, set[tuple[int, int]]]]:
    """(offset, length, {(channel id, sequence)} of its messages) of every chunk, read with mcap's reader."""
    with open(path, 'rb') as f:
        summary = SeekingReader(f).get_summary()
        assert summary is not None
        out = []
        for index in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
            f.seek(index.chunk_start_offset + 9)
            chunk = Chunk.read(ReadDataStream(io.BytesIO(f.read(index.chunk_length - 9))))
            keys = {(r.channel_id, r.sequence) for r in breakup_chunk(chunk) if isinstance(r, Message)}
            out.append((index.chunk_start_offset, index.chunk_length, keys))
    return out


def corrupt_chunk(source: Path, target: Path, which: int, cut_in: int | None = None) -> set[tuple[int, int]]:
    """Copy source to target with bytes inside the compressed data of chunk `which` flipped (and, with cut_in,
    the file cut off in the middle of that chunk); return the (channel id, sequence) of the messages of the
    corrupt chunk."""
    chunks = chunk_records(source)
    offset, length, keys = chunks[which]
    data = bytearray(source.read_bytes())
    for k in range(8):
        data[offset + length - 40 + k] ^= 0x5A
    end = len(data) if cut_in is None else chunks[cut_in][0] + chunks[cut_in][1] // 2
    target.write_bytes(bytes(data[:end]))
    return keys


def all_keys(path: Path) -> set[tuple[int, int]]:
    return {(m.channel_id, m.sequence) for m in open_recording(path).raw_messages()}


@pytest.mark.parametrize('cut_in', [None, -3], ids=['complete', 'truncated_after_it'])
def test_one_corrupt_chunk_costs_only_its_messages(ros2_file: Path, tmp_path: Path, cut_in: int | None,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    full = all_keys(ros2_file)
    assert len(full) == MESSAGES + MESSAGES // 10 and len(chunk_records(ros2_file)) > 6
    bad = tmp_path / 'bad.mcap'
    lost = corrupt_chunk(ros2_file, bad, 2, cut_in)
    assert lost

    skipped: list[str] = []
    recording = open_recording(bad, on_skip=skipped.append)
    got = [(m.channel_id, m.sequence) for m in recording.raw_messages()]
    cut_off = {k for k in full if k not in got} - lost   # messages after the cut of the truncated variant
    assert (cut_in is None) != bool(cut_off)
    assert set(got) == full - lost - cut_off and len(got) == len(set(got))
    assert len(skipped) == 1 and f'{len(lost)} messages lost' in skipped[0] and '\n' not in skipped[0]
    assert recording.message_count == len(got)
    line = recording.warning()
    assert 'corrupt chunk' in line and f'{len(lost)} messages lost' in line and '\n' not in line

    fixed = tmp_path / 'fixed.mcap'
    assert recover.main([str(bad), str(fixed)]) == 0
    out, err = capsys.readouterr()
    assert f'{len(got)} messages' in out
    assert err.startswith('fastep-recover: warning:') and f'{len(lost)} messages lost' in err
    assert 'Traceback' not in err and err.count('\n') == 1
    assert all_keys(fixed) == set(got) and not open_recording(fixed).truncated
    with AnyReader([fixed]) as reader:   # an independent reader accepts the result and decodes every message
        assert reader.message_count == len(got)
        values = [reader.deserialize(raw, conn.msgtype) for conn, _, raw in reader.messages()]
        assert len(values) == len(got)

    assert report.main([str(bad), '--out', str(tmp_path / 'report'), '--no-figures']) == 0
    out, err = capsys.readouterr()
    assert 'fastep-report: warning:' in err and f'{len(lost)} messages lost' in err and 'Traceback' not in err
    doc = json.loads((tmp_path / 'report' / 'report.json').read_text())
    assert f'{len(lost)} messages lost' in doc['warning']


def test_every_chunk_corrupt_but_one_keeps_that_one(ros2_file: Path, tmp_path: Path) -> None:
    chunks = chunk_records(ros2_file)
    data = bytearray(ros2_file.read_bytes())
    for offset, length, _ in chunks[1:]:
        data[offset + length - 30] ^= 0xFF
    bad = tmp_path / 'bad.mcap'
    bad.write_bytes(bytes(data))
    recording = open_recording(bad)
    assert {(m.channel_id, m.sequence) for m in recording.raw_messages()} == chunks[0][2]
    assert f'skipped {len(chunks) - 1} corrupt chunks' in recording.warning()


# ----------------------------------------------------------------------------------------------- other tools

SCHEMAS = {   # name, encoding, data (a protobuf FileDescriptorSet is binary, not UTF-8)
    'json': ('Reading', 'jsonschema', b'{"type": "object", "properties": {"v": {"type": "number"}}}'),
    'ros1': ('std_msgs/Float64', 'ros1msg', b'float64 data\n'),
    'proto': ('demo.Reading', 'protobuf', bytes(range(256))),
    'ros2': ('std_msgs/msg/Float64', 'ros2msg', b'float64 data\n'),
}
CHANNELS = [  # topic, message encoding, schema key (None: no schema)
    ('/json', 'json', 'json'), ('/ros1', 'ros1', 'ros1'), ('/proto', 'protobuf', 'proto'),
    ('/schemaless', 'json', None), ('/cdr', 'cdr', 'ros2'),
]


def foreign_file(path: Path, profile: str = '') -> None:
    """A file as other tools write them: several encodings, a schemaless channel, duplicate metadata names, an
    attachment, sequence numbers that are not 1, 2, 3..."""
    with open(path, 'wb') as stream:
        writer = Writer(stream, chunk_size=1024, compression=CompressionType.LZ4)
        writer.start(profile=profile, library='another tool 1.0')
        schemas = {key: writer.register_schema(name=n, encoding=e, data=d) for key, (n, e, d) in SCHEMAS.items()}
        ids = [writer.register_channel(topic=t, message_encoding=enc, schema_id=0 if key is None else schemas[key],
                                       metadata={'origin': t}) for t, enc, key in CHANNELS]
        writer.add_metadata('info', {'a': '1'})
        writer.add_metadata('info', {'a': '2'})
        writer.add_attachment(create_time=5, log_time=6, name='calib.yaml', media_type='text/yaml', data=b'k: v\n')
        for i in range(200):
            cid = ids[i % len(ids)]
            writer.add_message(channel_id=cid, log_time=1000 + i, publish_time=900 + i, sequence=7 * i + 3,
                               data=json.dumps({'v': i}).encode() if i % len(ids) in (0, 3) else bytes([i % 256]) * 9)
        writer.finish()


def contents(path: Path) -> dict[str, Any]:
    """Everything a faithful copy must keep, read with mcap's own reader (chunking and ids aside)."""
    with open(path, 'rb') as f:
        reader = SeekingReader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        assert summary is not None
        channels = {cid: (ch.topic, ch.message_encoding, dict(ch.metadata),
                          None if ch.schema_id == 0 else (summary.schemas[ch.schema_id].name,
                                                          summary.schemas[ch.schema_id].encoding,
                                                          bytes(summary.schemas[ch.schema_id].data)))
                    for cid, ch in summary.channels.items()}
        messages = [(channels[m.channel_id][0], m.log_time, m.publish_time, m.sequence, bytes(m.data))
                    for _, _, m in reader.iter_messages()]
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        attachments = [(a.name, a.media_type, a.log_time, a.create_time, bytes(a.data))
                       for a in reader.iter_attachments()]
    return {'profile': header.profile, 'library': header.library, 'channels': sorted(channels.values(), key=str),
            'messages': messages, 'metadata': metadata, 'attachments': attachments}


@pytest.mark.parametrize('profile', ['', 'ros1'])
def test_recover_copies_other_tools_files_faithfully(tmp_path: Path, profile: str,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    source = tmp_path / 'foreign.mcap'
    foreign_file(source, profile)
    before = contents(source)
    assert len(before['messages']) == 200
    copied = tmp_path / 'copied.mcap'
    assert recover.main([str(source), str(copied)]) == 0
    assert 'copied 200 messages' in capsys.readouterr().out
    assert contents(copied) == before

    # The same file cut off before its summary: what is recovered is exactly the first part, as it was.
    data = source.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[:int(len(data) * 0.6)])
    fixed = tmp_path / 'fixed.mcap'
    assert recover.main([str(cut), str(fixed)]) == 0
    after = contents(fixed)
    assert 0 < len(after['messages']) < 200 and after['messages'] == before['messages'][:len(after['messages'])]
    assert {k: v for k, v in after.items() if k != 'messages'} == {k: v for k, v in before.items() if k != 'messages'}


def test_a_channel_whose_schema_was_lost_is_left_out_with_a_warning(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """/late's channel record is in a later chunk than its schema; the schema's chunk (also holding /early's
    channel record) is corrupt and the file cut off, so /late cannot be copied faithfully: left out (recover)
    or refused (copy_recording); /early's later messages have no channel: dropped, and said so."""
    source = tmp_path / 'late.mcap'
    with open(source, 'wb') as stream:
        writer = Writer(stream, chunk_size=512, compression=CompressionType.NONE)
        writer.start(profile='', library='another tool')
        schema = writer.register_schema(name='Reading', encoding='jsonschema', data=b'{}')
        early = writer.register_channel(topic='/early', message_encoding='json', schema_id=schema)
        for i in range(40):
            writer.add_message(channel_id=early, log_time=i, publish_time=i, data=b'{"v": 1}')
        late = writer.register_channel(topic='/late', message_encoding='json', schema_id=schema)
        plain = writer.register_channel(topic='/plain', message_encoding='json', schema_id=0)
        for i in range(40, 80):
            writer.add_message(channel_id=late if i % 2 else plain, log_time=i, publish_time=i, data=b'{"v": 2}')
        writer.finish()
    records = list(StreamReader(str(source), emit_chunks=True).records)
    assert sum(isinstance(r, Chunk) for r in records) > 2
    bad = tmp_path / 'bad.mcap'
    corrupt_chunk(source, bad, 0, cut_in=-1)
    with pytest.raises(RecordingError, match='cannot copy topic /late faithfully'):
        copy_recording(open_recording(bad), tmp_path / 'refused.mcap')
    fixed = tmp_path / 'fixed.mcap'
    assert recover.main([str(bad), str(fixed)]) == 0
    err = capsys.readouterr().err
    assert 'topic /late' in err and 'their channel was defined in a corrupt chunk' in err and 'Traceback' not in err
    assert all(line.startswith('fastep-recover: warning:') for line in err.splitlines())
    kept = contents(fixed)
    assert {c[0] for c in kept['channels']} == {'/plain'}
    assert kept['messages'] and all(m[0] == '/plain' for m in kept['messages'])


# ----------------------------------------------------------------------------------------------- a full disk

def test_a_full_disk_is_one_write_error_and_the_writer_stays_closed(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """/dev/full refuses every write with ENOSPC, as a full disk does (item 15: the writer's part)."""
    from msg_tools import sim_cli
    from msg_tools.mcap_io import WriteFailedError

    writer = McapWriter('/dev/full', chunk_size=1024)
    with pytest.raises(WriteFailedError, match='cannot write /dev/full: No space left on device'):
        for i in range(100):
            writer.write('/x', Float64(data=float(i)), i)
            writer.flush()
    with pytest.raises(WriteFailedError):   # broken for good: no half-written record after the failure
        writer.write('/x', Float64(data=0.0), 200)
    with pytest.raises(WriteFailedError):   # finish() closes the file and says it once more
        writer.finish()
    writer.finish()                         # then nothing
    assert sim_cli.main(['table2_s1', '--mcap', '/dev/full']) == 2
    err = capsys.readouterr().err
    assert err == 'fastep-sim: error: cannot write /dev/full: No space left on device\n'


def test_chunks_that_overlap_in_time_are_merged_and_a_corrupt_one_skipped(tmp_path: Path) -> None:
    """Two topics written one after the other with interleaved times: every chunk of the second overlaps the
    first's. The messages come in log-time order (as mcap's own reader merges them), less a corrupt chunk."""
    path = tmp_path / 'overlap.mcap'
    with McapWriter(path, chunk_size=1024) as writer:
        for topic, parity in (('/even', 0), ('/odd', 1)):
            for i in range(150):
                writer.write(topic, Float64(data=float(i)), 2 * i + parity)
    with open(path, 'rb') as f:
        expected = [(ch.topic, m.log_time) for _, ch, m in SeekingReader(f).iter_messages(log_time_order=True)]
    assert [(m.topic, m.log_time) for m in open_recording(path).raw_messages()] == expected
    bad = tmp_path / 'bad.mcap'
    lost = corrupt_chunk(path, bad, 3)
    recording = open_recording(bad)
    got = [(m.channel_id, m.sequence, m.log_time) for m in recording.raw_messages()]
    assert [k[:2] for k in got] == [k[:2] for k in got if k[:2] not in lost] and len(got) == 300 - len(lost)
    assert [k[2] for k in got] == sorted(k[2] for k in got)
    assert f'{len(lost)} messages lost' in recording.warning()
