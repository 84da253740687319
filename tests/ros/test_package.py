"""ROS 2 package conventions and the executable's command line (no DDS traffic)."""
import os
import py_compile
import subprocess
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


def run(*args, domain=None):
    env = dict(os.environ)
    if domain is not None:
        env["ROS_DOMAIN_ID"] = domain
    return subprocess.run([NODE, *args], capture_output=True, text=True, timeout=20, env=env)


def test_help_and_refused_command_lines():
    r = run("--help")
    assert r.returncode == 0
    for name in ["zeta", "omega0", "delta_x", "Omega", "V", "publish_rate", "real_time_factor", "frame_id",
                 "history_depth", "__ns:="]:
        assert name in r.stdout
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
