"""fastep-recover: rewrite the readable part of a cut-off MCAP recording as a complete, valid file.

    fastep-recover IN.mcap OUT.mcap

Why: a killed recorder leaves a file without summary and footer. Our reader recovers it on the fly, but other
tools (`ros2 bag info`, Foxglove, indexed readers) want a complete file. Every message up to the last complete
chunk is copied in log-time order and a summary with statistics is written; a corrupt chunk is skipped. The copy
keeps everything of any tool's file (profile, schemas, channels, metadata, attachments), except a channel whose
schema record was lost, left out with a warning.

Exit 0 with one line on stdout saying how many messages were kept and one warning line on stderr for each loss;
2 with one line on stderr when IN is not MCAP or holds no complete message, or OUT cannot be written.
OUT must differ from IN.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Sequence

from fastep_core.cli import Parser, fail, guard
from fastep_core.errors import FastepError
from msg_tools.mcap_io import copy_recording, open_recording

__all__ = ['main', 'recover']


def recover(source: str | Path, target: str | Path) -> tuple[int, list[str]]:
    """Copy what is readable from source into a complete file target; (messages written, warning lines)."""
    source, target = Path(source), Path(target)
    if target.exists() and source.exists() and target.resolve() == source.resolve():
        raise FastepError(f'OUT must not be the input file {source}')
    recording = open_recording(source)
    target.parent.mkdir(parents=True, exist_ok=True)
    temp = target.with_name(target.name + '.part')
    left_out: list[str] = []
    try:
        count = copy_recording(recording, temp, warn=left_out.append)
        temp.replace(target)
    finally:
        temp.unlink(missing_ok=True)
    return count, [line for line in (recording.warning(), *left_out) if line]


PROG = 'fastep-recover'


def main(argv: Sequence[str] | None = None) -> int:
    return guard(PROG, lambda: _run(argv))


def _run(argv: Sequence[str] | None) -> int:
    p = Parser(prog=PROG, description='Rewrite the readable part of an MCAP file as a valid file.')
    p.add_argument('input', type=Path, metavar='IN.mcap')
    p.add_argument('output', type=Path, metavar='OUT.mcap')
    args = p.parse_args(argv)
    try:  # a FastepError (not MCAP, nothing complete in it, OUT is IN) is guard's one line
        count, warnings = recover(args.input, args.output)
    except OSError as exc:
        return fail(PROG, f'cannot write {args.output}: {exc.strerror or exc}')
    for line in warnings:
        print(f'{PROG}: warning: {line}', file=sys.stderr)
    state = 'recovered' if warnings else 'copied'
    print(f'{state} {count} messages from {args.input} into {args.output}{"" if warnings else " (it was complete)"}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
