"""The MuJoCo model (MJCF, generated as text) of a differential-drive base with mass, on a flat floor.

Why generated, not a file: every field of a BaseDynamics (fastep_core/dynamics/params.py) changes it, and a
scenario may override any of them; the text is made from the parameters alone, so one BaseDynamics is one model.

The base: a chassis box on a free joint (its body frame at the wheel axle's midpoint, wheel-centre height), two
driven wheels (spheres on hinge joints about the body's y axis: a sphere touches a plane at one point, straight
below its centre, which is how a wheel touches the floor), each driven by a velocity servo whose torque is
limited (`forcerange`, and `actuatorfrcrange` on its joint), and a caster (a sphere whose contact has no
friction: priority over the floor, condim 1) ahead of the axle, the centre of mass between them. Ahead, not
behind: with the centre of mass behind the driven axle a base's yaw is unstable driving forward (the term
m d v omega of its yaw equation feeds the turn), and a base whose motor saturates spins out. The wheels'
contact takes their own friction (priority over the floor's): `friction` is the floor's grip. The physics step
is 0.002 s (500 Hz) with the implicitfast integrator, which takes the servos' velocity feedback implicitly.
The presets' servo gain (10 N m s/rad) is what tracks without chatter: at 20-100 the wheels' soft contact
oscillates and the odometry's errors grow with the gain (measured, turning in place and braking).
"""

from __future__ import annotations

from fastep_core.dynamics.params import PHYSICS_RATE, BaseDynamics

__all__ = ['CASTER_RADIUS', 'LEFT_JOINT', 'RIGHT_JOINT', 'CASTER_MASS', 'TIMESTEP', 'base_mjcf']

TIMESTEP = 1.0 / PHYSICS_RATE
CASTER_RADIUS = 0.03   # m
CASTER_MASS = 0.1      # kg
LEFT_JOINT, RIGHT_JOINT = 'left_wheel', 'right_wheel'
CHASSIS_HEIGHT = 0.15  # m: the box's height; its length spans the axle to the caster, its width the track
WHEEL_SOLREF = '0.005 1'   # the wheels' contact: stiffer than MuJoCo's default (0.02 s), 2.5 physics steps; its
                           # creep (soft friction's slip under load) is then under 1 % of what a wheel pushes


def base_mjcf(dynamics: BaseDynamics) -> str:
    """The MJCF document of the base at the origin, facing +x (the plant sets the start pose in qpos)."""
    d = dynamics
    r, half_track = d.wheel_radius, 0.5 * d.wheel_separation
    chassis_mass = d.mass - 2.0 * d.wheel_mass - CASTER_MASS
    # The box centred at the centre of mass, long enough to reach from before the axle to the caster.
    length = max(2.0 * d.com_offset, d.caster_offset + 2.0 * CASTER_RADIUS, 2.0 * r)
    width = max(d.wheel_separation - 2.0 * r * 0.5, 0.05)
    clear = CHASSIS_HEIGHT / 2.0 + 0.2 * r          # the box's bottom above the floor: r - clear + CHASSIS_HEIGHT/2
    caster_z = CASTER_RADIUS - r                      # its bottom on the floor
    torque = d.max_wheel_torque
    wheel = (f'<geom type="sphere" size="{r}" mass="{d.wheel_mass}" friction="{d.friction} 0.005 0.0001" '
             f'priority="1" condim="3" solref="{WHEEL_SOLREF}"/>')
    return f"""<mujoco model="diff_drive_base">
  <option timestep="{TIMESTEP}" integrator="implicitfast" cone="elliptic" impratio="10" gravity="0 0 -9.81"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" friction="{d.friction} 0.005 0.0001"/>
    <body name="base" pos="0 0 {r}">
      <freejoint name="base"/>
      <geom name="chassis" type="box" size="{length / 2.0} {width / 2.0} {CHASSIS_HEIGHT / 2.0}"
            pos="{d.com_offset} 0 {clear}" mass="{chassis_mass}" contype="0" conaffinity="0"/>
      <geom name="caster" type="sphere" size="{CASTER_RADIUS}" pos="{d.caster_offset} 0 {caster_z}"
            mass="{CASTER_MASS}" friction="0 0 0" priority="2" condim="1"/>
      <body name="left_wheel" pos="0 {half_track} 0">
        <joint name="{LEFT_JOINT}" type="hinge" axis="0 1 0" actuatorfrclimited="true"
               actuatorfrcrange="{-torque} {torque}"/>
        {wheel}
      </body>
      <body name="right_wheel" pos="0 {-half_track} 0">
        <joint name="{RIGHT_JOINT}" type="hinge" axis="0 1 0" actuatorfrclimited="true"
               actuatorfrcrange="{-torque} {torque}"/>
        {wheel}
      </body>
    </body>
  </worldbody>
  <actuator>
    <velocity name="left_motor" joint="{LEFT_JOINT}" kv="{d.wheel_servo_gain}" forcelimited="true"
              forcerange="{-torque} {torque}"/>
    <velocity name="right_motor" joint="{RIGHT_JOINT}" kv="{d.wheel_servo_gain}" forcelimited="true"
              forcerange="{-torque} {torque}"/>
  </actuator>
</mujoco>
"""
