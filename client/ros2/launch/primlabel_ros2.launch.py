"""Starts primlabel-ros2 as `ros2 launch` starts any node (client/ros2/README.md).

    ros2 launch client/ros2/launch/primlabel_ros2.launch.py server:=127.0.0.1:50051 \
        points:=/camera/depth/points

launch_ros passes the parameters below as a parameters file (`--params-file`, `/**:` then
`ros__parameters:`), the name and namespace as `-r __node:=` and `-r __ns:=`, the remap as
`-r points:=...`. The qos_overrides ask for reliable input, keep last 10: every whole frame of a
publisher with ROS 2's default QoS (reliable) arrives, where best effort loses large frames to
missing fragments. Drop them for a best-effort sensor driver that should be skipped, not queued.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('server', default_value='127.0.0.1:50051'),
        DeclareLaunchArgument('points', default_value='/camera/depth/points'),
        DeclareLaunchArgument('log_level', default_value='info'),
        Node(
            # No package: the executable on PATH (cmake --install puts it in bin/).
            executable='primlabel-ros2',
            name='primlabel',
            namespace='labeling',
            output='screen',
            arguments=['--ros-args', '--log-level', LaunchConfiguration('log_level')],
            remappings=[('points', LaunchConfiguration('points'))],
            parameters=[{
                'server': LaunchConfiguration('server'),
                'probabilities': True,
                'qos_overrides': {
                    LaunchConfiguration('points'): {
                        'subscription': {'reliability': 'reliable', 'depth': 10},
                    },
                },
            }],
        ),
    ])
