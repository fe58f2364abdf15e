"""Benchmark: the paper's Table 2 regenerated, with Mann-Whitney tests, optimality ratios and box plots.

Run: `python -m benchmarks.table2 [--runs N] [--scenarios ...] [--workers 2] [--out docs/]` (the same flags
as the `fastep-bench` console script; the engine is `fastep_core.experiments.batches`, the CLI `msg_tools.bench_cli`).
"""

from __future__ import annotations

import sys
from typing import Sequence

from msg_tools.bench_cli import main as _main


def main(argv: Sequence[str] | None = None) -> int:
    return _main(argv, prog='python -m benchmarks.table2')


if __name__ == '__main__':
    sys.exit(main())
