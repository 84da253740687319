"""Starts bistable_impact_node as node `bistable_impact` with a parameter file (default: the
package's config/bistable_impact.yaml) in a namespace (default: the root; its topics are
relative to it), e.g.
`ros2 launch bistable_impact_node bistable_impact.launch.py params_file:=my.yaml namespace:=/rig1`."""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    default = os.path.join(get_package_share_directory("bistable_impact_node"), "config", "bistable_impact.yaml")
    return LaunchDescription(
        [
            DeclareLaunchArgument("params_file", default_value=default, description="parameter YAML file"),
            DeclareLaunchArgument("namespace", default_value="", description="node namespace, e.g. /rig1"),
            Node(
                package="bistable_impact_node",
                executable="bistable_impact_node",
                name="bistable_impact",
                namespace=LaunchConfiguration("namespace"),
                output="screen",
                parameters=[LaunchConfiguration("params_file")],
            ),
        ]
    )
