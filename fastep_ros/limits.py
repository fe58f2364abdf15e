"""Ranges the nodes and fastep-launch accept for rates, periods and the real-time factor (no ROS import here: the
launcher checks its command line with them before it starts anything). docs/robustness.md lists them."""

from __future__ import annotations

from fastep_core.scenario import MODELS, Scenario

__all__ = ['ACK_PERIOD_RANGE', 'CLOCK_JUMP_LIMIT', 'GRAPH_MODELS', 'OBSERVER_LAG_MAX', 'PERIOD_RANGE', 'RATE_RANGE',
           'ROBOT_NAME_MAX', 'RTF_RANGE', 'STEP_RANGE', 'graph_problem', 'robot_name_problem']

GRAPH_MODELS: tuple[str, ...] = MODELS
"""Robot models the ROS plant and planner nodes run: every model (diff_drive included)."""

RATE_RANGE = (0.1, 10_000.0)
"""Timer rates a node accepts (Hz): the planners' 1 / dt range (PlannerParams.dt is [1e-4, 10] s). Beyond it rclpy's
create_timer overflowed (1e-12 Hz: a traceback) or a node spent itself on its timer (1e12 Hz)."""

PERIOD_RANGE = (0.01, 3600.0)
"""Wall periods (s) of housekeeping timers (the recorder's flush and discovery)."""

STEP_RANGE = (1e-4, 10.0)
"""Simulated seconds per tick of fastep-clock: PlannerParams.dt's range (the launcher passes dt)."""

RTF_RANGE = (1e-3, 1e4)
"""Real-time factors of fastep-clock and fastep-launch --rtf. 1e-300 overflowed rclpy's create_timer (the tick
period is step / rtf): at 1e-3 a tick of the largest step takes 10^4 wall seconds. fastep-clock also refuses a
tick of more than CLOCK_JUMP_LIMIT simulated seconds (what a node takes from one /clock message unconfirmed)."""

OBSERVER_LAG_MAX = 500
"""Ticks an observer of the lock step (fastep-clock's observer_topics) may lag behind: half the 1000-message queues
in which fastep-record and fastep-launch's monitor keep what they have not taken yet (a topic sends one message a
tick at most), so that none is dropped."""

ACK_PERIOD_RANGE = (0.0, 60.0)
"""Simulated seconds between fastep-record's clock_ack messages (0: one for every /clock time)."""

CLOCK_JUMP_LIMIT = 3600.0
"""Simulated seconds a /clock message may run ahead of the last one and be taken at once (fastep_ros.common)."""

ROBOT_NAME_MAX = 200
"""Characters of a robot name on the live graph. The name is a ROS namespace, and the longest name in it, the
planner's `/<name>/planner/set_parameters_atomically` service, may have 247 characters: 212 for the name at most
(a 250-character name was an InvalidTopicNameException traceback in fastep-launch)."""


def robot_name_problem(name: str) -> str:
    """Why a robot name the scenario format allows ([A-Za-z_][A-Za-z0-9_]*) cannot be a ROS namespace; '' if it can.

    ROS also refuses '__' anywhere in a name: rcl's argument lexer reads it as the start of a token (`__ns`,
    `__node`), so `-r __ns:=/r__1` fails to parse.
    """
    if '__' in name:
        return "ROS does not allow '__' in a name"
    if len(name) > ROBOT_NAME_MAX:
        return f'{len(name)} characters, more than the {ROBOT_NAME_MAX} a ROS namespace of fastep can have'
    return ''


def graph_problem(scenario: Scenario, robots: bool = True) -> str:
    """What of a scenario the live graph cannot honour; '' if nothing (docs/scenarios.md, v2).

    Format v2 runs: fastep-map publishes what the map knows (known still obstacles, misplaced ones where the map
    says, known movers on /movers), plants of robots with a `sensor` scan the truth (fastep_ros.plant), and
    planners perceive with the scans (fastep_ros.perception). robots=False: the obstacles only (the map node
    publishes no robot); every obstacle runs, so only the robots' models are checked.
    """
    for i, robot in enumerate(scenario.robots):
        if robots and robot.model not in GRAPH_MODELS:
            return f'robots[{i}] ({robot.name}): model {robot.model} does not run on the ROS graph; use fastep-sim'
    return ''
