"""What perception tells the guards of one scan, as one immutable value.

A robot with a laser is guarded against more than its map: a margin beyond its radius (its surfaces are known only
as well as its scans show them), the returns of its latest scan, and, where it backs up, the free space its recent
scans saw (planning/safety/guard.py, planning/recovery/back_up.py). Perception makes the three of one scan together; the
planner node's control tick reads them on another thread than the pass that perceives, so they travel as one value,
replaced whole (Navigator.take_perception), never field by field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fastep_core.planning.recovery.back_up import SeenFree
from fastep_core.planning.safety.guard import ScanReturns

__all__ = ['GuardInputs']


@dataclass(frozen=True)
class GuardInputs:
    """What perception tells the guards of one scan, together: the margin its surfaces are known to, its returns,
    and the free space the recent scans saw. One immutable value, replaced whole (Navigator.take_perception): a
    control loop on another thread reads it once per tick, so the margin, the returns and the free space it checks
    against always come from the same scan."""

    obstacle_margin: float = 0.0            # m kept beyond the radius from obstacle surfaces
    scan_points: ScanReturns | None = None  # the latest scan's returns (None: no laser)
    seen: SeenFree | None = None            # where backing up is known free (None: the map alone)
    taken: float = -math.inf                # when the scan was taken (its stamp; -inf: no scan)
