"""Robots on separate computers, on one machine: `python -m benchmarks.multi_host --hosts 2 --robots 4` (as root).

The harness is fastep_testing.multi_host (its docstring says what it does), shared with the test that runs it.
"""

from fastep_testing.multi_host import main

if __name__ == '__main__':
    raise SystemExit(main())
