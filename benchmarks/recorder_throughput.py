"""Benchmark: does fastep-record keep up with 8 robots publishing at 50 Hz? Messages published vs recorded.

    python -m benchmarks.recorder_throughput [--robots 8] [--rate 50] [--seconds 30]

Starts, on an isolated DDS domain (215..232, outside the 1..100 the tests use; localhost only), fastep-record
(`python -m fastep_ros.recorder`) and then fastep_testing.fake_robots (odom + cost per robot, reliable, keep-last
10, what the plant and planner offer), which waits until the recorder is subscribed to all its topics and
publishes for --seconds. The recorder is then stopped with SIGINT and its file read back. Prints published and
recorded counts per topic kind, the total loss, the file size and the CPU time of both processes.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from msg_tools.mcap_io import open_recording

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--robots', type=int, default=8)
    p.add_argument('--rate', type=float, default=50.0)
    p.add_argument('--seconds', type=float, default=30.0)
    args = p.parse_args()
    count = int(args.rate * args.seconds)
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, ROS_DOMAIN_ID=str(215 + os.getpid() % 18),
                   ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', ROS_LOG_DIR=str(Path(tmp) / 'log'),
                   PYTHONPATH=os.pathsep.join(x for x in (str(ROOT), os.environ.get('PYTHONPATH', '')) if x))
        out = Path(tmp) / 'bench.mcap'
        recorder = subprocess.Popen([sys.executable, '-m', 'fastep_ros.recorder', '--ros-args', '-p',
                                     f'output:={out}', '--log-level', 'warn'], env=env, cwd=ROOT)
        try:
            start = time.monotonic()
            fake = subprocess.run([sys.executable, '-m', 'fastep_testing.fake_robots', '--robots', str(args.robots),
                                   '--rate', str(args.rate), '--count', str(count), '--wait-subscribers', '1',
                                   '--wait-timeout', '120'], env=env, cwd=ROOT, capture_output=True, text=True,
                                  check=True)
            wall = time.monotonic() - start
            published = json.loads(fake.stdout.strip().splitlines()[-1])['published']
            time.sleep(1.0)
        finally:
            recorder.send_signal(signal.SIGINT)
            recorder.wait(timeout=30)
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        recording = open_recording(out)
        recorded = recording.counts()
        size = out.stat().st_size
    sent = sum(published.values())
    got = sum(recorded.get(topic, 0) for topic in published)
    for kind in ('odom', 'cost'):
        topics = [t for t in published if t.endswith('/' + kind)]
        print(f'{kind}: published {sum(published[t] for t in topics)}, '
              f'recorded {sum(recorded.get(t, 0) for t in topics)} on {len(topics)} topics')
    print(f'total: published {sent}, recorded {got}, lost {sent - got} ({100.0 * (sent - got) / sent:.3f} %); '
          f'{args.robots} robots x 2 topics x {args.rate:g} Hz = {2 * args.robots * args.rate:g} msg/s for '
          f'{args.seconds:g} s (publisher process ran {wall:.1f} s incl. start-up)')
    print(f'file {size / 1e6:.2f} MB, complete: {not recording.truncated}; CPU of the child processes '
          f'(recorder + publisher): {usage.ru_utime + usage.ru_stime:.1f} s')


if __name__ == '__main__':
    main()
