"""ROS 2 package conventions and the executable's command line (no DDS traffic)."""
import os
import pathlib
import py_compile
import runpy
import subprocess
import sys
import types
import xml.etree.ElementTree as ET

from common import NODE, ROOT


def test_packages_are_format_3_with_the_right_names():
    for name in ["bistable_impact_msgs", "bistable_impact_node"]:
        root = ET.parse(ROOT / "ros" / name / "package.xml").getroot()
        assert root.get("format") == "3" and root.findtext("name") == name
    msgs = ROOT / "ros/bistable_impact_msgs"
    assert "rosidl_generate_interfaces" in (msgs / "CMakeLists.txt").read_text()
    for m in ["MassState", "ImpactEvent", "ShakerCommand"]:
        assert "std_msgs/Header header" in (msgs / "msg" / f"{m}.msg").read_text()
    py_compile.compile(str(ROOT / "ros/bistable_impact_node/launch/bistable_impact.launch.py"), doraise=True)


class _Recorded:
    """Stands in for a launch class: keeps its arguments."""

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


def test_launch_file_starts_the_installed_node_with_its_parameter_file(monkeypatch, tmp_path):
    """launch and launch_ros have no wheels here, so the launch file runs against stand-ins
    that record what it builds: one Node of this package's executable, named like the parameter
    file's top-level key, in the namespace argument, with the package's config file by default."""
    share = tmp_path / "share"
    modules = {
        "ament_index_python": types.ModuleType("ament_index_python"),
        "ament_index_python.packages": types.ModuleType("ament_index_python.packages"),
        "launch": types.ModuleType("launch"),
        "launch.actions": types.ModuleType("launch.actions"),
        "launch.substitutions": types.ModuleType("launch.substitutions"),
        "launch_ros": types.ModuleType("launch_ros"),
        "launch_ros.actions": types.ModuleType("launch_ros.actions"),
    }
    modules["ament_index_python.packages"].get_package_share_directory = lambda p: str(share / p)
    modules["launch"].LaunchDescription = _Recorded
    modules["launch.actions"].DeclareLaunchArgument = _Recorded
    modules["launch.substitutions"].LaunchConfiguration = _Recorded
    modules["launch_ros.actions"].Node = type("Node", (_Recorded,), {})
    for name, m in modules.items():
        monkeypatch.setitem(sys.modules, name, m)
    path = ROOT / "ros/bistable_impact_node/launch/bistable_impact.launch.py"
    desc = runpy.run_path(str(path))["generate_launch_description"]()
    (entities,) = desc.args
    declared = {e.args[0]: e.kwargs["default_value"] for e in entities if type(e) is _Recorded}
    (node,) = [e for e in entities if type(e).__name__ == "Node"]
    k = node.kwargs
    root = ET.parse(ROOT / "ros/bistable_impact_node/package.xml").getroot()
    assert k["package"] == root.findtext("name") == "bistable_impact_node"
    assert k["executable"] == pathlib.Path(NODE).name
    config = ROOT / "ros/bistable_impact_node/config/bistable_impact.yaml"
    assert declared["params_file"] == str(share / k["package"] / "config" / config.name)
    assert declared["namespace"] == ""
    top = [line for line in config.read_text().splitlines() if line and line[0] not in "# "]
    assert top == [f"{k['name']}:"]
    assert [c.args for c in k["parameters"]] == [("params_file",)]
    assert k["namespace"].args == ("namespace",)


def run(*args, domain=None, simd=None):
    env = dict(os.environ)
    if domain is not None:
        env["ROS_DOMAIN_ID"] = domain
    if simd is not None:
        env["BISTABLE_SIMD"] = simd
    return subprocess.run([NODE, *args], capture_output=True, text=True, timeout=20, env=env)


def test_help_and_refused_command_lines():
    r = run("--help")
    assert r.returncode == 0
    for name in ["zeta", "omega0", "delta_x", "Omega", "V", "publish_rate", "real_time_factor", "frame_id",
                 "history_depth", "__ns:="]:
        assert name in r.stdout
    r = run(simd="avx9000")
    assert r.returncode == 2 and 'BISTABLE_SIMD="avx9000" is not a SIMD path' in r.stderr, (r.returncode, r.stderr)
    for args, domain, reason in [
        (["--ros-args", "-p", "zeta:=-1"], None, "invalid zeta"),
        (["--ros-args", "-p", "e:=.nan"], None, "invalid e"),
        (["--ros-args", "-p", "publish_rate:=.inf"], None, "invalid publish_rate"),
        (["--ros-args", "--params-file", "/nonexistent.yaml"], None, "--params-file"),
        (["--ros-args", "-r", "/bistable/impacts:=/x y"], None, "invalid remapping rule"),
        (["--ros-args", "-p", "history_depth:=0"], None, "invalid history_depth"),
        (["--ros-args", "-p", "history_depth:=8193"], None, "invalid history_depth"),
        ([], "999", "ROS_DOMAIN_ID"),
    ]:
        r = run(*args, domain=domain)
        assert r.returncode == 2 and reason in r.stderr, (args, r.returncode, r.stderr)
