"""A small client of the planner's Nav2 servers, with the verbs of nav2_simple_commander's BasicNavigator.

    from fastep_ros.navigation_client import NavigationClient

    nav = NavigationClient(namespace='/r1')            # its own node and context; rclpy.init is not needed
    nav.wait_until_active()                            # the planner's lifecycle state is active
    path = nav.get_path((2.0, 10.0))                   # nav_msgs/Path from the robot (compute_path_to_pose)
    nav.go_to_pose(2.0, 10.0)                          # or go_through_poses, follow_waypoints, follow_path(path),
    while not nav.is_task_complete():                  #    spin(1.57), backup(0.3, 0.1), drive_on_heading(...)
        feedback = nav.get_feedback()                  # the action's Feedback, or None before the first
    print(nav.get_result(), nav.result_message())      # 'succeeded' | 'aborted' | 'canceled' | 'rejected'
    nav.clear_all_costmaps()                           # the planner forgets what its laser added
    nav.close()

It talks only Nav2's interfaces (fastep_ros.navigate_actions and its companions on the planner, or Nav2's own
servers), so a script written with it runs against Nav2 too. Poses are (x, y) or (x, y, yaw) in `frame` (default
map), or geometry_msgs/PoseStamped; (x, y) asks no heading (a quaternion of zero length, which fastep's planner
takes for none). is_task_complete spins the client's node for up to `spin` seconds; the server's last feedback
(a spin's whole angle, the distance left at the goal) usually comes in the same spin as the result, so read
get_feedback once more after is_task_complete says True. Every call that waits has a
bound (`server_timeout`): a server that never answers is a TimeoutError, never a hang.
"""

from __future__ import annotations

import math
from typing import Any, Sequence, TypeAlias

from geometry_msgs.msg import PoseStamped

__all__ = ['NavigationClient']

GoalPose: TypeAlias = 'Sequence[float] | PoseStamped'   # (x, y[, yaw]) in `frame`, or a PoseStamped
STATUS = {4: 'succeeded', 5: 'canceled', 6: 'aborted'}   # action_msgs/GoalStatus


class NavigationClient:
    """BasicNavigator's verbs, snake_case: go_to_pose, go_through_poses, follow_waypoints, follow_path, spin, backup,
    drive_on_heading, get_path, get_path_through_poses, clear_*_costmap(s), set_initial_pose, wait_until_active,
    is_task_complete, get_feedback, cancel_task, get_result."""

    def __init__(self, namespace: str = '/', frame: str = 'map', domain_id: int | None = None,
                 server_timeout: float = 30.0) -> None:
        import rclpy
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from nav2_msgs.action import (
            BackUp,
            ComputePathThroughPoses,
            ComputePathToPose,
            DriveOnHeading,
            FollowPath,
            FollowWaypoints,
            NavigateThroughPoses,
            NavigateToPose,
            Spin,
        )
        from rclpy.action import ActionClient
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        self.context = rclpy.Context()
        rclpy.init(args=[], context=self.context, domain_id=domain_id,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('navigation_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.frame = frame
        base = namespace.rstrip('/')
        self.base = base
        self.actions = {'to_pose': (NavigateToPose, f'{base}/navigate_to_pose'),
                        'through_poses': (NavigateThroughPoses, f'{base}/navigate_through_poses'),
                        'waypoints': (FollowWaypoints, f'{base}/follow_waypoints'),
                        'path_to_pose': (ComputePathToPose, f'{base}/compute_path_to_pose'),
                        'path_through_poses': (ComputePathThroughPoses, f'{base}/compute_path_through_poses'),
                        'follow_path': (FollowPath, f'{base}/follow_path'),
                        'spin': (Spin, f'{base}/spin'),
                        'backup': (BackUp, f'{base}/backup'),
                        'drive_on_heading': (DriveOnHeading, f'{base}/drive_on_heading')}
        self.clients = {kind: ActionClient(self.node, action, name) for kind, (action, name) in self.actions.items()}
        self.initial_pose = self.node.create_publisher(PoseWithCovarianceStamped, f'{base}/initialpose', 10)
        self.server_timeout = server_timeout
        self.handle: Any = None
        self.result_future: Any = None
        self.feedback: Any = None
        self.status = ''
        self.result: Any = None

    # ------------------------------------------------------------------------------------------ tasks
    def go_to_pose(self, *pose: Any) -> bool:
        """Navigate to a pose ((x, y[, yaw]) or a PoseStamped); False if the planner rejected it."""
        goal = self.actions['to_pose'][0].Goal(pose=self.pose(pose[0] if len(pose) == 1 else pose))
        return self._send('to_pose', goal)

    def go_through_poses(self, poses: Sequence[GoalPose]) -> bool:
        goal = self.actions['through_poses'][0].Goal(poses=[self.pose(p) for p in poses])
        return self._send('through_poses', goal)

    def follow_waypoints(self, poses: Sequence[GoalPose], loops: int = 0, start: int = 0) -> bool:
        goal = self.actions['waypoints'][0].Goal(poses=[self.pose(p) for p in poses], number_of_loops=loops,
                                                 goal_index=start)
        return self._send('waypoints', goal)

    def follow_path(self, path: Any) -> bool:
        """Drive along a nav_msgs/Path (Nav2's controller's follow_path)."""
        return self._send('follow_path', self.actions['follow_path'][0].Goal(path=path))

    def spin(self, angle: float = 1.57, time_allowance: float = 10.0) -> bool:
        """Turn in place by `angle` rad (its sign the direction), as BasicNavigator.spin."""
        goal = self.actions['spin'][0].Goal(target_yaw=float(angle), time_allowance=_duration(time_allowance))
        return self._send('spin', goal)

    def backup(self, distance: float = 0.15, speed: float = 0.025, time_allowance: float = 10.0) -> bool:
        """Drive straight back `distance` m at `speed` m/s, as BasicNavigator.backup."""
        return self._send('backup', self._straight('backup', distance, speed, time_allowance))   # Nav2: both positive

    def drive_on_heading(self, distance: float = 0.15, speed: float = 0.025, time_allowance: float = 10.0) -> bool:
        """Drive straight ahead `distance` m at `speed` m/s, as BasicNavigator.driveOnHeading."""
        return self._send('drive_on_heading', self._straight('drive_on_heading', distance, speed, time_allowance))

    def get_path(self, goal: GoalPose, start: GoalPose | None = None) -> Any:
        """The planner's route to `goal` (from `start`, else from the robot) as a nav_msgs/Path; None if it has
        none (get_result and result_message then say why), as BasicNavigator.getPath."""
        kind = 'path_to_pose'
        request = self.actions[kind][0].Goal(goal=self.pose(goal), use_start=start is not None)
        if start is not None:
            request.start = self.pose(start)
        return self._path(kind, request)

    def get_path_through_poses(self, goals: Sequence[GoalPose], start: GoalPose | None = None) -> Any:
        """The planner's route through `goals` in order as a nav_msgs/Path, or None (getPathThroughPoses)."""
        kind = 'path_through_poses'
        request = self.actions[kind][0].Goal(goals=[self.pose(g) for g in goals], use_start=start is not None)
        if start is not None:
            request.start = self.pose(start)
        return self._path(kind, request)

    def clear_all_costmaps(self) -> bool:
        """Both of Nav2's costmap clearing calls (fastep: its planner forgets what its laser added)."""
        return self.clear_global_costmap() and self.clear_local_costmap()

    def clear_global_costmap(self) -> bool:
        return self._clear('global_costmap/clear_entirely_global_costmap')

    def clear_local_costmap(self) -> bool:
        return self._clear('local_costmap/clear_entirely_local_costmap')

    def set_initial_pose(self, pose: GoalPose) -> None:
        """Publish the robot's pose on initialpose (fastep's planner takes it where no localizer runs)."""
        from geometry_msgs.msg import PoseWithCovarianceStamped
        message = PoseWithCovarianceStamped()
        stamped = self.pose(pose)
        message.header, message.pose.pose = stamped.header, stamped.pose
        if not any((stamped.pose.orientation.x, stamped.pose.orientation.y, stamped.pose.orientation.z,
                    stamped.pose.orientation.w)):
            message.pose.pose.orientation.w = 1.0   # an initial pose always has a heading
        message.header.stamp = self.node.get_clock().now().to_msg()
        self.initial_pose.publish(message)

    def wait_until_active(self, node: str = 'planner', timeout: float | None = None) -> None:
        """Wait until the lifecycle node `node` (in the namespace) is active, as BasicNavigator's
        waitUntilNav2Active(navigator=node, localizer=...) does; TimeoutError after `timeout` (server_timeout)."""
        import time

        from lifecycle_msgs.srv import GetState
        bound = self.server_timeout if timeout is None else timeout
        name = f'{self.base}/{node}/get_state'
        client = self.node.create_client(GetState, name)
        end = time.monotonic() + bound
        try:
            while time.monotonic() < end:
                if client.wait_for_service(timeout_sec=min(1.0, max(0.0, end - time.monotonic()))):
                    future = client.call_async(GetState.Request())
                    self.executor.spin_until_future_complete(future, timeout_sec=max(0.0, end - time.monotonic()))
                    if future.done() and future.result().current_state.label == 'active':
                        return
                    time.sleep(0.2)
            raise TimeoutError(f'{name}: not active within {bound:g} s')
        finally:
            self.node.destroy_client(client)

    def is_task_complete(self, spin: float = 0.1) -> bool:
        """Whether the task has ended (spinning the client up to `spin` seconds for news)."""
        if self.result_future is None:
            return True
        self.executor.spin_until_future_complete(self.result_future, timeout_sec=spin)
        if not self.result_future.done():
            return False
        response = self.result_future.result()
        self.status, self.result = STATUS.get(response.status, f'status {response.status}'), response.result
        self.result_future = None
        return True

    def get_feedback(self) -> Any:
        """The newest feedback of the task (None before the first); after the task ended, its last."""
        return self.feedback

    def cancel_task(self, timeout: float = 10.0) -> bool:
        """Ask the planner to cancel the task (the robot brakes to a stop); True if it agreed."""
        if self.handle is None or self.result_future is None:
            return False
        future = self.handle.cancel_goal_async()
        self.executor.spin_until_future_complete(future, timeout_sec=timeout)
        return future.done() and len(future.result().goals_canceling) > 0

    def get_result(self) -> str:
        """How the last task ended: 'succeeded', 'aborted', 'canceled', 'rejected', or '' while under way."""
        return self.status

    def result_message(self) -> str:
        """The last result's error code and message ('' when it succeeded)."""
        if self.result is None or not getattr(self.result, 'error_code', 0):
            return ''
        return f'error {self.result.error_code}: {self.result.error_msg}'

    def close(self) -> None:
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    # ------------------------------------------------------------------------------------------ helpers
    def pose(self, pose: GoalPose) -> PoseStamped:
        if isinstance(pose, PoseStamped):
            return pose
        out = PoseStamped()
        out.header.frame_id = self.frame
        out.pose.position.x, out.pose.position.y = float(pose[0]), float(pose[1])
        if len(pose) > 2:
            out.pose.orientation.z, out.pose.orientation.w = math.sin(0.5 * pose[2]), math.cos(0.5 * pose[2])
        else:
            out.pose.orientation.w = 0.0   # a quaternion of zero length: no heading to end in (fastep's planner)
        return out

    def _send(self, kind: str, goal: Any) -> bool:
        client = self.clients[kind]
        if not client.wait_for_server(timeout_sec=self.server_timeout):
            raise TimeoutError(f'no {self.actions[kind][1]} action server within {self.server_timeout:g} s')
        self.feedback, self.status, self.result = None, '', None
        future = client.send_goal_async(goal, feedback_callback=self._on_feedback)
        self.executor.spin_until_future_complete(future, timeout_sec=self.server_timeout)
        self.handle = future.result() if future.done() else None
        if self.handle is None or not self.handle.accepted:
            self.status, self.result_future = 'rejected', None
            return False
        self.result_future = self.handle.get_result_async()
        return True

    def _straight(self, kind: str, distance: float, speed: float, time_allowance: float) -> Any:
        from geometry_msgs.msg import Point
        return self.actions[kind][0].Goal(target=Point(x=float(distance)), speed=float(speed),
                                          time_allowance=_duration(time_allowance))

    def _path(self, kind: str, request: Any) -> Any:
        """Send a path request and wait (server_timeout) for its result: the path, or None."""
        import time
        if not self._send(kind, request):
            return None
        end = time.monotonic() + self.server_timeout
        while not self.is_task_complete():
            if time.monotonic() > end:
                self.cancel_task()
                raise TimeoutError(f'{self.actions[kind][1]}: no result within {self.server_timeout:g} s')
        return self.result.path if self.status == 'succeeded' else None

    def _clear(self, name: str) -> bool:
        from nav2_msgs.srv import ClearEntireCostmap
        client = self.node.create_client(ClearEntireCostmap, f'{self.base}/{name}')
        try:
            if not client.wait_for_service(timeout_sec=self.server_timeout):
                raise TimeoutError(f'no {self.base}/{name} service within {self.server_timeout:g} s')
            future = client.call_async(ClearEntireCostmap.Request())
            self.executor.spin_until_future_complete(future, timeout_sec=self.server_timeout)
            return future.done()
        finally:
            self.node.destroy_client(client)

    def _on_feedback(self, message: Any) -> None:
        self.feedback = message.feedback

    def get_costmap(self, which: str = 'global', resolution: float = 0.0) -> Any:
        """The planner's belief drawn as a nav2_msgs/Costmap: `which` 'global' (the map's workspace) or 'local'
        (a window round the robot), at `resolution` m a cell (0: the server's default), as BasicNavigator's
        getGlobalCostmap / getLocalCostmap; TimeoutError when no answer comes within server_timeout."""
        import time

        from nav2_msgs.srv import GetCostmap
        if which not in ('global', 'local'):
            raise ValueError(f"which: 'global' or 'local', not {which!r}")
        name = f'{self.base}/{which}_costmap/get_costmap'
        client = self.node.create_client(GetCostmap, name)
        try:
            end = time.monotonic() + self.server_timeout
            if not client.wait_for_service(timeout_sec=self.server_timeout):
                raise TimeoutError(f'no {name} service within {self.server_timeout:g} s')
            request = GetCostmap.Request()
            request.specs.resolution = float(resolution)
            future = client.call_async(request)
            self.executor.spin_until_future_complete(future, timeout_sec=max(0.0, end - time.monotonic()))
            if not future.done():
                raise TimeoutError(f'{name}: no answer within {self.server_timeout:g} s')
            return future.result().map
        finally:
            self.node.destroy_client(client)

    def clear_costmap_around_pose(self, pose: GoalPose, reset_distance: float) -> bool:
        """Forget what the laser added inside the square of side `reset_distance` centred on `pose` ((x, y[, yaw])
        in `frame`, or a PoseStamped), as BasicNavigator.clearCostmapAroundPose; True once answered, TimeoutError
        when the service is not there within server_timeout."""
        from nav2_msgs.srv import ClearCostmapAroundPose
        name = f'{self.base}/local_costmap/clear_costmap_around_pose'
        client = self.node.create_client(ClearCostmapAroundPose, name)
        try:
            if not client.wait_for_service(timeout_sec=self.server_timeout):
                raise TimeoutError(f'no {name} service within {self.server_timeout:g} s')
            request = ClearCostmapAroundPose.Request(pose=self.pose(pose), reset_distance=float(reset_distance))
            future = client.call_async(request)
            self.executor.spin_until_future_complete(future, timeout_sec=self.server_timeout)
            return future.done()
        finally:
            self.node.destroy_client(client)


def _duration(seconds: float) -> Any:
    from builtin_interfaces.msg import Duration
    whole = math.floor(seconds)
    return Duration(sec=int(whole), nanosec=int(round((seconds - whole) * 1e9)) % 1_000_000_000)
