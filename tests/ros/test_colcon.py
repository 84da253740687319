"""colcon build of the repository as a ROS 2 user does it: the repository under a workspace's
src/, colcon-cmake for bistable_impact_msgs (rosidl) and colcon-ros-cargo with cargo-ament-build
for bistable_impact_node, into a fresh install tree (the workspace is kept under target/colcon-ws,
so reruns build incrementally; its install tree is removed first); checks the tree (executable,
launch/ and config/ in the node's share, the ament index, the interfaces) and that the installed
executable runs (help, then a short run stopped with SIGINT)."""
import os
import pathlib
import signal
import subprocess
import shutil
import time

from common import ROOT

VENV = ROOT / "ros/.venv"
TOOLS = ROOT / "target/tools/bin"


# The workspace (its src/ and colcon's build tree, where cargo-ament-build keeps its target
# directory) stays under target/ so that a rerun builds incrementally; its install tree is
# removed before every run.
WS = ROOT / "target/colcon-ws"


def test_colcon_build_into_a_fresh_install_tree():
    (WS / "src").mkdir(parents=True, exist_ok=True)
    if not (WS / "src/bistable-impact").is_symlink():
        (WS / "src/bistable-impact").symlink_to(ROOT)
    # A fresh install tree at a fixed place (CMake keeps the install prefix in its cache).
    shutil.rmtree(WS / "install", ignore_errors=True)
    # colcon-ros-cargo has cargo build into the package's build base (--target-dir). That base
    # is the repository's target directory, where `make ros-build` has built the same package
    # in release, so the release build below (as ROS users build a node to run it) reuses that
    # build instead of compiling every crate again; colcon, cargo-ament-build and the install
    # tree are exercised as without the link.
    base = WS / "build/bistable_impact_node"
    if not base.is_symlink():
        shutil.rmtree(base, ignore_errors=True)
        base.parent.mkdir(parents=True, exist_ok=True)
        base.symlink_to(ROOT / "target")
    ws = WS
    env = dict(os.environ, PATH=f"{TOOLS}:{VENV / 'bin'}:{os.environ['PATH']}", AMENT_PREFIX_PATH=str(VENV),
               CMAKE_PREFIX_PATH=str(VENV))
    r = subprocess.run([str(VENV / "bin/colcon"), "build", "--base-paths", "src/bistable-impact/ros",
                        "--event-handlers", "console_direct-", "--cmake-args",
                        f"-DPython3_EXECUTABLE={VENV / 'bin/python'}", "-DBUILD_TESTING=OFF",
                        "--cargo-args", " --release"],
                       cwd=WS, env=env, capture_output=True, text=True, timeout=1200)
    assert r.returncode == 0, (r.stdout[-3000:], r.stderr[-3000:])
    for pkg in ["bistable_impact_msgs", "bistable_impact_node"]:
        assert f"Finished <<< {pkg}" in r.stdout, r.stdout[-2000:]
    node = ws / "install/bistable_impact_node"
    exe = node / "lib/bistable_impact_node/bistable_impact_node"
    assert exe.is_file() and os.access(exe, os.X_OK)
    share = node / "share/bistable_impact_node"
    for f in ["launch/bistable_impact.launch.py", "config/bistable_impact.yaml", "package.xml"]:
        assert (share / f).is_file(), f
    assert (node / "share/ament_index/resource_index/packages/bistable_impact_node").is_file()
    msgs = ws / "install/bistable_impact_msgs"
    for f in ["msg/MassState.msg", "msg/ImpactEvent.msg", "msg/ShakerCommand.msg", "srv/Step.srv",
              "srv/ResetState.srv"]:
        assert (msgs / "share/bistable_impact_msgs" / f).is_file(), f
    assert (msgs / "share/ament_index/resource_index/rosidl_interfaces/bistable_impact_msgs").is_file()
    # The installed executable runs.
    h = subprocess.run([str(exe), "--help"], capture_output=True, text=True, timeout=30)
    assert h.returncode == 0 and "history_depth" in h.stdout
    p = subprocess.Popen([str(exe), "--ros-args", "-p", "real_time_factor:=0.0"], stderr=subprocess.PIPE,
                         text=True, env=dict(os.environ, ROS_DOMAIN_ID="81"))
    time.sleep(3)
    assert p.poll() is None, p.stderr.read()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 0 and "started /bistable_impact" in err and "stopping at t =" in err, err[-2000:]
