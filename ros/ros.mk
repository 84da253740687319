# ROS 2 node (included by the top-level Makefile): interop tests against real ROS 2 (rclpy on
# rmw_fastrtps from the PyPI wheels, interface package built by rosidl) and Cyclone DDS, each
# test file in its own network namespace (ros/netns.sh). The soak runs SOAK_SECONDS (60).

ROS_NODE_BIN := target/release/bistable_impact_node

.PHONY: test-ros ros-setup ros-build

## ROS 2 venv (ros/.venv) and the rosidl build of bistable_impact_msgs; skipped when up to date.
ros-setup: setup
	bash ros/setup-ros.sh

## The node and the reference-impact helper used by the tests (release build).
ros-build:
	$(CARGO) build --release -p bistable_impact_node --bin bistable_impact_node --example reference_impacts

test-ros: ros-setup ros-build
	bash ros/run-tests.sh

TEST_TARGETS += test-ros
