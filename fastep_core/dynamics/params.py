"""The parameters of a simulated differential-drive base with mass: body, motors, floor, controller, encoders.

A `BaseDynamics` is what a physics plant (fastep_core/dynamics/plant.py) builds its MuJoCo model and its
diff_drive_controller from. Four presets name the bases the experiments need (`PRESETS`); a scenario's
`dynamics:` key (docs/scenarios.md) and the plant node's `dynamics` parameter name one, or one with some fields
overridden (`parse_dynamics`). Every field is checked when a BaseDynamics is made (ParameterError, one line), so
a base that exists is one MuJoCo can simulate. Pure Python: nothing here imports mujoco.

Why these presets: the planner believes the limits of its own parameters (max_acceleration, ...); a real base
may not keep them. `nominal` keeps them; `heavy` cannot brake as hard as it is told (weak motors under a heavy
body); `limited_controller` has a base that could, behind a controller configured more cautiously than the
planner thinks; `slippery` has the motors but not the grip, so its wheels spin and its odometry drifts.
"""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass, field, fields, replace
from typing import Any, Mapping

from fastep_core.errors import ParameterError

__all__ = ['PRESETS', 'BaseDynamics', 'dynamics_data', 'dynamics_from_text', 'parse_dynamics', 'preset',
           'robot_dynamics']

_shown = reprlib.Repr()
_shown.maxlevel, _shown.maxlist, _shown.maxdict = 1, 3, 3
_shown.maxstring = _shown.maxother = _shown.maxlong = 40


def _f(default: float, description: str, low: float, high: float = math.inf, *, open_low: bool = True) -> Any:
    return field(default=default, metadata={'description': description, 'range': (low, high, open_low)})


@dataclass(frozen=True)
class BaseDynamics:
    """A differential-drive base as MuJoCo simulates it (SI units: kg, m, s, rad, N m).

    The body frame's origin is the wheel axle's midpoint (the kinematic model's reference point); +x forward.
    The chassis's centre of mass lies `com_offset` ahead of the axle, on the way to the caster, so the driven
    wheels carry the share 1 - com_offset / caster_offset of the weight (the rest rests on the frictionless
    caster): what their grip can push with is friction x that share x mass x g.
    """

    preset: str = 'nominal'
    mass: float = _f(14.0, 'total mass of the base (kg): chassis, wheels and caster', 0.0)
    wheel_radius: float = _f(0.1, 'radius of the driven wheels (m)', 0.0, 1.0)
    wheel_separation: float = _f(0.4, 'distance between the driven wheels\' contact points (m)', 0.0, 5.0)
    wheel_mass: float = _f(0.5, 'mass of one driven wheel (kg)', 0.0)
    max_wheel_torque: float = _f(3.0, 'torque limit of each wheel motor (N m): the velocity servo saturates there',
                                 0.0)
    wheel_servo_gain: float = _f(30.0, 'velocity servo gain of each wheel motor (N m per rad/s of speed error)',
                                 0.0, 1000.0)
    friction: float = _f(1.0, 'sliding friction coefficient between the driven wheels and the floor', 0.0, 10.0)
    com_offset: float = _f(0.1, 'how far the chassis\'s centre of mass lies ahead of the axle (m)', 0.0, 5.0,
                           open_low=False)
    caster_offset: float = _f(0.3, 'how far the caster lies ahead of the axle (m)', 0.0, 5.0)
    max_speed: float = _f(1.5, 'controller: linear speed limit |v| (m/s)', 0.0)
    max_angular_speed: float = _f(4.0, 'controller: angular speed limit |omega| (rad/s)', 0.0)
    max_acceleration: float = _f(2.5, 'controller: linear acceleration and braking limit (m/s^2)', 0.0)
    max_angular_acceleration: float = _f(6.0, 'controller: angular acceleration limit (rad/s^2)', 0.0)
    cmd_timeout: float = _f(0.5, 'controller: a command older than this is replaced by a stop, ramped within the '
                            'limits (s)', 0.0)
    control_rate: float = _f(100.0, 'controller update rate (Hz); the physics runs at 500 Hz, a whole multiple',
                             0.0, 500.0)
    encoder_noise: float = _f(0.0, 'standard deviation of each wheel-angle reading (rad), drawn from the seeded '
                              'stream', 0.0, 1.0, open_low=False)

    def __post_init__(self) -> None:
        if self.preset not in PRESET_NAMES:
            raise ParameterError(f'dynamics preset must be one of {", ".join(PRESET_NAMES)}, '
                                 f'got {_shown.repr(self.preset)}')
        for f in fields(self):
            if f.name == 'preset':
                continue
            value = getattr(self, f.name)
            low, high, open_low = f.metadata['range']
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not _finite(value):
                raise ParameterError(f'dynamics {f.name} must be a finite number, got {_shown.repr(value)}')
            if not (low < value if open_low else low <= value) or value > high:
                wanted = (f'> {low:g}' if open_low else f'>= {low:g}') if math.isinf(high) else \
                    f'in {"(" if open_low else "["}{low:g}, {high:g}]'
                raise ParameterError(f'dynamics {f.name} must be {wanted}, got {value:g}')
        if self.mass <= 2.0 * self.wheel_mass:
            raise ParameterError(f'dynamics mass {self.mass:g} kg must exceed the two wheels\' '
                                 f'{2.0 * self.wheel_mass:g} kg (the chassis needs mass)')
        if self.com_offset >= self.caster_offset:
            raise ParameterError(f'dynamics com_offset {self.com_offset:g} m must be below caster_offset '
                                 f'{self.caster_offset:g} m (the centre of mass between the wheels and the caster)')
        substeps = PHYSICS_RATE / self.control_rate
        if abs(substeps - round(substeps)) > 1e-9:
            raise ParameterError(f'dynamics control_rate {self.control_rate:g} Hz must divide the physics rate '
                                 f'{PHYSICS_RATE:g} Hz (e.g. 50, 100, 250, 500)')

    # ------------------------------------------------------------------------------------- derived
    @property
    def control_substeps(self) -> int:
        """Physics steps per controller update."""
        return int(round(PHYSICS_RATE / self.control_rate))

    @property
    def wheel_load_share(self) -> float:
        """The share of the weight the driven wheels carry (the rest is on the caster)."""
        return 1.0 - self.com_offset / self.caster_offset

    @property
    def grip_acceleration(self) -> float:
        """The largest acceleration the wheels' grip allows (m/s^2, rolling inertia neglected)."""
        return self.friction * self.wheel_load_share * GRAVITY

    @property
    def motor_acceleration(self) -> float:
        """The largest acceleration the motors' torque allows (m/s^2, wheel inertia neglected)."""
        return 2.0 * self.max_wheel_torque / (self.wheel_radius * self.mass)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The fields a scenario or a parameter may set (preset first)."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def descriptions(cls) -> dict[str, str]:
        return {f.name: f.metadata['description'] for f in fields(cls) if f.name != 'preset'}


def _finite(value: float) -> bool:
    try:
        return math.isfinite(value)
    except OverflowError:   # an int too large for a float
        return False


PHYSICS_RATE = 500.0   # Hz: MuJoCo's timestep is 1 / PHYSICS_RATE = 0.002 s
GRAVITY = 9.81         # m/s^2
PRESET_NAMES = ('nominal', 'heavy', 'limited_controller', 'slippery')

PRESETS: dict[str, BaseDynamics] = {}


def _presets() -> dict[str, BaseDynamics]:
    nominal = BaseDynamics()
    return {
        'nominal': nominal,
        # 40 kg on motors of 1.6 N m: 2 x 1.6 / (0.1 x 40) = 0.8 m/s^2 at most, ~0.6 m to stop from 1 m/s.
        'heavy': replace(nominal, preset='heavy', mass=40.0, wheel_mass=1.0, max_wheel_torque=1.6),
        # The base of nominal behind a controller that ramps at 0.5 m/s^2 (1 m to stop from 1 m/s).
        'limited_controller': replace(nominal, preset='limited_controller', max_acceleration=0.5,
                                      max_angular_acceleration=1.0),
        # The base of nominal on a floor of friction 0.3: its grip gives ~2 m/s^2, less than the controller asks.
        'slippery': replace(nominal, preset='slippery', friction=0.3),
    }


PRESETS.update(_presets())


def preset(name: str) -> BaseDynamics:
    """The preset of that name; ParameterError naming the presets otherwise."""
    if name not in PRESETS:
        raise ParameterError(f'dynamics preset must be one of {", ".join(PRESET_NAMES)}, got {_shown.repr(name)}')
    return PRESETS[name]


def parse_dynamics(value: Any) -> BaseDynamics:
    """A preset name (`heavy`) or a mapping (`{preset: heavy, mass: 45}`; preset defaults to nominal) of fields.

    Raises ParameterError with one line naming the offending key (`dynamics mass must be > 0, got -1`;
    scenario.py says where: `robots[0].dynamics: ...`).
    """
    if isinstance(value, str):
        return preset(value)
    if not isinstance(value, Mapping):
        raise ParameterError(f'dynamics must be a preset name ({", ".join(PRESET_NAMES)}) or a mapping of its '
                             f'fields, got {_shown.repr(value)}')
    allowed = BaseDynamics.names()
    for key in value:
        if key not in allowed:
            raise ParameterError(f'dynamics: unknown key {_shown.repr(key)} (allowed: {", ".join(allowed)})')
    name = value.get('preset', 'nominal')
    if not isinstance(name, str):
        raise ParameterError(f'dynamics preset must be one of {", ".join(PRESET_NAMES)}, got {_shown.repr(name)}')
    base = preset(name)
    overrides = {k: v for k, v in value.items() if k != 'preset'}
    for key, item in overrides.items():
        if isinstance(item, bool) or not isinstance(item, (int, float)):
            raise ParameterError(f'dynamics {key} must be a finite number, got {_shown.repr(item)}')
    values: dict[str, Any] = {k: float(v) if _finite(v) else v for k, v in overrides.items()}
    return replace(base, **values)


def dynamics_data(dynamics: BaseDynamics) -> str | dict[str, Any]:
    """What parse_dynamics makes `dynamics` from: its preset's name, or the preset and the fields that differ."""
    base = PRESETS[dynamics.preset]
    changed = {f.name: getattr(dynamics, f.name) for f in fields(dynamics)
               if f.name != 'preset' and getattr(dynamics, f.name) != getattr(base, f.name)}
    return dynamics.preset if not changed else {'preset': dynamics.preset, **changed}


def robot_dynamics(value: Any, path: str, model: str) -> BaseDynamics:
    """A scenario robot's `dynamics:` (docs/scenarios.md), for scenario.py: yaml_checks.Invalid naming the key path
    (`robots[0].dynamics.mass must be > 0, got -1`) when it is not a base's, or the robot is not a diff_drive."""
    from fastep_core.yaml_checks import Invalid, one_line

    if model != 'diff_drive':
        raise Invalid(f'{path} is only valid for model diff_drive (a physics plant), not {model}')
    try:
        return parse_dynamics(value)
    except ParameterError as exc:
        rest = one_line(str(exc))[len('dynamics'):]
        word = rest.split(' ', 2)[1] if rest.startswith(' ') else ''
        raise Invalid(f'{path}.{rest[1:]}' if word in BaseDynamics.names() else f'{path}{rest}') from None


def dynamics_from_text(text: str) -> BaseDynamics | None:
    """A `dynamics` parameter's value: '' (None: kinematic), a preset name, or a YAML/JSON mapping of fields
    (`{preset: heavy, mass: 45}`; quoted once more, as a command line's YAML may carry it, is the same).
    ParameterError with one line otherwise."""
    import yaml

    from fastep_core import bounded_yaml

    value: Any = text.strip()
    for _ in range(2):
        if not isinstance(value, str) or not value or value in PRESETS:
            break
        try:
            value = bounded_yaml.load(value.encode())
        except yaml.YAMLError as exc:   # the bounds' LimitError is one too
            raise ParameterError(' '.join(f'dynamics is not a preset name or a YAML mapping: {exc}'.split())) from None
    if value == '' or value is None:
        return None
    return parse_dynamics(value)
