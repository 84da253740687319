# ROS 2 node (included by the top-level Makefile): interop tests against real ROS 2 (rclpy on
# rmw_fastrtps from the PyPI wheels, interface package built by rosidl) and Cyclone DDS, each
# test file in its own network namespace (ros/netns.sh). The soak runs SOAK_SECONDS (60); the
# fault tests (test_fault_*.py) run short here and long in stress-ros, which also repeats the
# interop matrix and the discovery of test_names.py.

ROS_NODE_BIN := target/release/bistable_impact_node

.PHONY: test-ros test-ros-patches test-ros-node stress-ros ros-setup ros-build

## ROS 2 venv (ros/.venv) and the rosidl build of bistable_impact_msgs; skipped when up to date.
ros-setup: setup
	bash ros/setup-ros.sh

## The node and the reference-impact helper used by the tests (release build).
ros-build:
	$(CARGO) build --release -p bistable_impact_node --bin bistable_impact_node --example reference_impacts

## The unit tests our RustDDS patches add to its writer (GAPs, history, discovery data).
test-ros-patches: setup
	$(CARGO) test --manifest-path .deps/rustdds/Cargo.toml --lib --quiet rtps::writer::tests::repair

## The node crate's unit and integration tests, in the release build of ros-build.
test-ros-node: setup
	$(CARGO) test --release -p bistable_impact_node

test-ros: ros-setup ros-build test-ros-patches test-ros-node
	bash ros/run-tests.sh

TEST_TARGETS += test-ros

## Stress and fault campaign, ROS 2 part (part of make stress): the fault tests of tests/ros with
## long durations (override any of these from the environment); figures as JSON, and the node's
## logs, in $(ROS_STRESS_OUT).
ROS_STRESS_OUT ?= $(OUT)/stress-ros
FAULT_COMMAND_SECONDS ?= 120
FAULT_CHURN_SECONDS ?= 180
FAULT_CHURN_KILL_EVERY ?= 3
FAULT_FLOOD_SECONDS ?= 120
FAULT_FLOOD_PUBLISHERS ?= 2
FAULT_FLOOD_BASELINE ?= 10
FAULT_FLOOD_REQUESTS ?= 1
FAULT_FLOOD_REQUEST_RATE ?= 300

# The interop matrix (every vendor, free-running, late joiners, SIGINT, a stalled reader) runs
# MATRIX_REPEAT times per case; test_names.py (two nodes and a Fast DDS peer discovering each
# other) NAMES_RUNS times, each run in a fresh network namespace.
MATRIX_REPEAT ?= 20
NAMES_RUNS ?= 50

stress-ros: ros-setup ros-build
	rm -rf $(ROS_STRESS_OUT) && mkdir -p $(ROS_STRESS_OUT)
	FAULT_REPORT_DIR=$(abspath $(ROS_STRESS_OUT)) MATRIX_REPEAT=$(MATRIX_REPEAT) \
	PYTEST_ADDOPTS="-s $${PYTEST_ADDOPTS:-}" bash ros/run-tests.sh tests/ros/test_interop_matrix.py
	ROS_TEST_REPEAT=$(NAMES_RUNS) bash ros/run-tests.sh tests/ros/test_names.py
	FAULT_REPORT_DIR=$(abspath $(ROS_STRESS_OUT)) FAULT_COMMAND_SECONDS=$(FAULT_COMMAND_SECONDS) \
	FAULT_CHURN_SECONDS=$(FAULT_CHURN_SECONDS) FAULT_CHURN_KILL_EVERY=$(FAULT_CHURN_KILL_EVERY) \
	FAULT_FLOOD_SECONDS=$(FAULT_FLOOD_SECONDS) FAULT_FLOOD_PUBLISHERS=$(FAULT_FLOOD_PUBLISHERS) \
	FAULT_FLOOD_BASELINE=$(FAULT_FLOOD_BASELINE) FAULT_FLOOD_REQUESTS=$(FAULT_FLOOD_REQUESTS) \
	FAULT_FLOOD_REQUEST_RATE=$(FAULT_FLOOD_REQUEST_RATE) PYTEST_ADDOPTS="-s $${PYTEST_ADDOPTS:-}" \
	bash ros/run-tests.sh tests/ros/test_fault_commands.py tests/ros/test_fault_churn.py tests/ros/test_fault_flood.py
	@echo "stress-ros: figures in $(ROS_STRESS_OUT)/*.json"

STRESS_TARGETS += stress-ros
