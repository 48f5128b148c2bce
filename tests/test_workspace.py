"""Workspace-level checks: package hygiene, catkin_lint, the CI contract (issue: workspace foundation)."""
import pathlib
import subprocess
import xml.etree.ElementTree as ET

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SRC = ROOT / "catkin_ws" / "src"
PACKAGES = sorted(p.parent for p in SRC.glob("*/package.xml"))
REQUIRED = {"mbzirc_comm_objs", "mbzirc_agents", "fire_detector", "circle_detector", "mbzirc_launchers",
            "ual_sim", "uav_abstraction_layer"}


def test_design_packages_present():
    names = {p.name for p in PACKAGES}
    missing = REQUIRED - names
    assert not missing, f"packages of the design missing: {sorted(missing)}"


@pytest.mark.parametrize("pkg", PACKAGES, ids=lambda p: p.name)
def test_package_manifest(pkg):
    root = ET.parse(pkg / "package.xml").getroot()
    assert root.get("format") in ("2", "3"), "package.xml must be format 2 or 3"
    assert root.findtext("name") == pkg.name
    assert (pkg / "CMakeLists.txt").exists()
    # Python libraries are installed with catkin_python_setup (src/<pkg>/ holds them).
    if (pkg / "src" / pkg.name / "__init__.py").exists():
        assert (pkg / "setup.py").exists(), "a Python library needs setup.py"
        assert "catkin_python_setup()" in (pkg / "CMakeLists.txt").read_text()


def test_catkin_lint_clean():
    out = subprocess.run(["catkin_lint", "-W2", "--strict", str(SRC)], capture_output=True, text=True, timeout=300)
    problems = [l for l in out.stdout.splitlines() if ": error:" in l or ": warning:" in l or ": notice:" in l]
    assert out.returncode == 0 and not problems, "\n".join(problems) or out.stderr


def test_ci_runs_the_readme_test_command():
    ci = (ROOT / ".ci" / "run").read_text()
    readme = (ROOT / "README.md").read_text()
    assert "make test" in ci and "make test" in readme and "make mission" in readme


def test_dockerfile_reuses_setup_script():
    dockerfile = (ROOT / "Dockerfile").read_text()
    assert dockerfile.startswith("#") and "FROM debian:bookworm" in dockerfile
    assert "setup/setup.sh" in dockerfile


def test_compose_launches_exist_with_their_args():
    """Every roslaunch of docker/compose.yaml names a launch file of the workspace and only args it declares."""
    import yaml
    compose = yaml.safe_load((ROOT / "docker" / "compose.yaml").read_text())
    checked = 0
    for name, service in compose["services"].items():
        cmd = service.get("command", [])
        if not cmd or cmd[0] != "roslaunch":
            continue
        words = [w for w in cmd[1:] if not w.startswith("--")]
        pkg, launch, args = words[0], words[1], words[2:]
        path = SRC / pkg / "launch" / launch
        assert path.exists(), f"{name}: {path} missing"
        declared = {a.get("name") for a in ET.parse(path).getroot().iter("arg")}
        for a in args:
            assert a.split(":=")[0] in declared, f"{name}: {launch} declares no arg {a.split(':=')[0]}"
        assert service["environment"]["ROS_MASTER_URI"] == "http://master:11311"
        checked += 1
    assert checked >= 4
