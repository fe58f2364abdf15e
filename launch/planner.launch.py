"""A fastep planner on your robot, as Nav2's bring-up starts its servers:

    ros2 launch fastep_ros planner.launch.py namespace:=/r1 params_file:=/path/to/my_robot.yaml

Arguments: namespace (the robot's; its topics are relative), params_file (default: this package's
config/planner.yaml, a differential-drive base with a laser, Nav2's map server and AMCL), use_sim_time,
autostart (false: wait for Nav2's lifecycle manager to configure and activate it), log_level.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = 'fastep_ros'


def generate_launch_description() -> LaunchDescription:
    share = get_package_share_directory(PACKAGE)
    namespace = LaunchConfiguration('namespace')
    params_file = LaunchConfiguration('params_file')
    use_sim_time = LaunchConfiguration('use_sim_time')
    autostart = LaunchConfiguration('autostart')
    log_level = LaunchConfiguration('log_level')
    return LaunchDescription([
        DeclareLaunchArgument('namespace', default_value='', description="the robot's namespace, e.g. /r1"),
        DeclareLaunchArgument('params_file', default_value=os.path.join(share, 'config', 'planner.yaml'),
                              description='the planner parameters (every one: config/fastep.yaml)'),
        DeclareLaunchArgument('use_sim_time', default_value='false', description='follow /clock'),
        DeclareLaunchArgument('autostart', default_value='true',
                              description='configure and activate at once (false: a lifecycle manager does)'),
        DeclareLaunchArgument('log_level', default_value='info', description='the node logger level'),
        Node(package=PACKAGE, executable='fastep-planner', name='planner', namespace=namespace, output='screen',
             parameters=[params_file, {'use_sim_time': use_sim_time, 'autostart': autostart}],
             arguments=['--ros-args', '--log-level', log_level]),
    ])
