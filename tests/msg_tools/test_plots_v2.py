"""The run figure of a v2 world: movers' tracks and positions, unknown and misplaced obstacles told apart."""

from __future__ import annotations

import matplotlib.pyplot as plt
from matplotlib.colors import to_rgb

from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate
from msg_tools.plots import MOVER_SNAPSHOTS, run_paths_figure


def test_crossing_movers_figure_shows_what_the_world_adds() -> None:
    scenario = load_scenario('crossing_movers')
    run = simulate(scenario, 'fastep', 0)
    fig = run_paths_figure(scenario, run)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[1:] == ['unknown: true place', 'misplaced: on the map', 'mover: track, positions',
                          'believed: seen by a scan']
    circles = [p for p in ax.patches if isinstance(p, plt.Circle)]
    dashed = [p for p in circles if p.get_linestyle() == '--' and not p.get_fill()]
    dotted = [p for p in circles if p.get_linestyle() == ':' and not p.get_fill()]
    assert [p.center for p in dashed] == [(35.0, 21.5)]             # the unknown circle, where it really is
    assert len(dotted) == 1 and dotted[0].center != (15.0, 28.5)    # the misplaced one, where the map put it
    purple = to_rgb('tab:purple')
    movers = [p for p in circles if p.get_fill() and p.get_facecolor()[:3] == purple]
    assert len(movers) == MOVER_SNAPSHOTS
    assert movers[0].center == (25.0, 15.0)                          # t = 0: where the file starts it
    # What r1 believed at the end: the unknown circle, seen by its scans where it really is (dash-dotted).
    believed = [p for p in circles if p.get_linestyle() == '-.' and not p.get_fill()]
    assert len(believed) == 1 and abs(believed[0].center[0] - 35.0) < 0.05 and abs(believed[0].center[1] - 21.5) < 0.05
    plt.close(fig)


def test_v1_figures_draw_no_extras() -> None:
    scenario = load_scenario('table2_s1')
    fig = run_paths_figure(scenario, simulate(scenario, 'fastep', 0))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert len(labels) == len(scenario.robots) and labels[0].startswith('r1 (')
    assert all(p.get_fill() for p in fig.axes[0].patches)
    plt.close(fig)
