"""ament_python package fastep_ros: the fastep_core, fastep_ros and msg_tools Python packages.

rclpy and the message packages come from one of two places, never both: a ROS 2 installation (apt's
/opt/ros/jazzy, a colcon workspace; its setup script sets ROS_DISTRO), or the PyPI ROS wheels (the extra
`ros-wheels`). Installed into a shell where ROS is sourced, this package leaves the wheels out, so `pip install`
does not pull a second rclpy over the installed one; anywhere else (a fresh virtual environment) it lists them,
so `pip install .` alone gives working console scripts. `pip install .[ros-wheels]` (what `make` installs)
always brings them.
"""
import os
from glob import glob

from setuptools import find_packages, setup

PACKAGE = 'fastep_ros'

ROS_WHEELS = [
    'ros-jazzy-rclpy[fastrtps]==7.1.6',
    'ros-jazzy-common-interfaces==5.3.6',
]


def ros_installed() -> bool:
    """A sourced ROS 2 installation provides rclpy and the messages (every ROS 2 setup script sets ROS_DISTRO)."""
    return bool(os.environ.get('ROS_DISTRO'))


setup(
    name=PACKAGE,
    version='0.1.0',
    description='FAStep-Kinematic robot navigation for ROS 2 Jazzy, with the ACO-Kinematic baseline',
    packages=find_packages(include=['fastep_core', 'fastep_core.*', 'fastep_ros', 'fastep_ros.*',
                                    'msg_tools', 'msg_tools.*']),
    package_data={'fastep_core': ['py.typed', 'scenarios/*.yaml'],
                  'fastep_ros': ['py.typed'], 'msg_tools': ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{PACKAGE}']),
        (f'share/{PACKAGE}', ['package.xml']),
        (f'share/{PACKAGE}/scenarios', glob('fastep_core/scenarios/*.yaml')),
        (f'share/{PACKAGE}/config', glob('config/*.yaml')),
        (f'share/{PACKAGE}/launch', glob('launch/*.launch.py')),   # ros2 launch fastep_ros planner.launch.py
    ],
    python_requires='>=3.11',
    install_requires=([] if ros_installed() else ROS_WHEELS) + [
        'numpy>=2.0',
        'scipy>=1.13',
        'PyYAML>=6.0',
        'matplotlib>=3.8',
        'mcap>=1.3',
        'zstandard>=0.20',
        'lz4>=4.0',
        'tqdm==4.70.1',
        'foxglove-sdk==0.30.3',
        'rosbags>=0.10',
        'mujoco==4.0.0',   # fastep_core/dynamics: physics plants (a robot's `dynamics:`)
    ],
    extras_require={'ros-wheels': ROS_WHEELS,
                    # fastep-bench / fastep-tune --cluster (experiments/cluster.py): Dask's distributed scheduler
                    'cluster': ['dask[distributed]>=2026.1'],
                    'test': ['pytest>=8', 'pytest-xdist>=3.8', 'hypothesis>=6.100', 'websockets>=13', 'protobuf>=5',
                             'colcon-core>=0.21', 'colcon-ros>=0.5', 'colcon-python-setup-py>=0.2',
                             'colcon-bash>=0.5']},
    zip_safe=True,
    maintainer='fastep developers',
    maintainer_email='dev@fastep.invalid',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'fastep-sim = msg_tools.sim_cli:main',
            'fastep-plant = fastep_ros.plant:main',
            'fastep-map = fastep_ros.map_server:main',
            'fastep-planner = fastep_ros.planner:main',
            'fastep-clock = fastep_ros.clock:main',
            'fastep-container = fastep_ros.container:main',
            'fastep-launch = fastep_ros.launch:cli',
            'fastep-bench = msg_tools.bench_cli:main',
            'fastep-tune = fastep_core.experiments.tuning:main',
            'fastep-record = fastep_ros.recorder:main',
            'fastep-replay = fastep_ros.replay:main',
            'fastep-report = msg_tools.report:main',
            'fastep-recover = msg_tools.recover:main',
            'fastep-foxglove = fastep_ros.foxglove_bridge:main',
        ],
    },
)
