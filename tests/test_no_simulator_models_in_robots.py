"""The robots win without reading the simulator's models (issue 17): no constant copied from ual_sim's
physics, thermal or water models remains in the agents, detectors, estimator, region manager, central unit
or the public arena model, and none of them imports ual_sim code (its message types are fine).

Why a grep: such a copy makes the robots win in the simulator's world only (the agents once decided "out"
from FIRE_LITRES 1.0 and JET_SPOT_RADIUS 0.11, the fire detector had a 50 degC floor chosen against the
simulator's 40-45 degC walls); in the real arena those numbers are unknown.
"""
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "catkin_ws" / "src"
ROBOT_PACKAGES = ("mbzirc_agents", "fire_detector", "circle_detector", "object_estimation",
                  "shared_regions_manager", "mbzirc_central_unit", "mbzirc_arena")

# names of ual_sim's model constants (ual_sim/constants.py) and of the copies the robots used to carry
MODEL_NAMES = ("FIRE_LITRES", "LITRES_PER_FIRE", "JET_SPOT_RADIUS", "JET_SPREAD_R0", "JET_SPREAD_PER_M",
               "FLAME_TEMP", "HEATER_TEMP", "BLANKET_TEMP", "INACTIVE_HOLDER_TEMP", "AMBIENT_TEMP", "SKY_TEMP",
               "GROUND_TEMP", "INDOOR_WALL_TEMP", "THERMAL_ATTEN_DIST", "THERMAL_NOISE_STD",
               "DEFAULT_MIN_FIRE_TEMPERATURE", "INDOOR_HIT_SHARE", "fire_litres", "indoor_hit_share")
RULES = {
    "a simulator model constant": re.compile(r"\b(" + "|".join(MODEL_NAMES) + r")\b"),
    "ual_sim code imported": re.compile(r"^\s*(from|import)\s+ual_sim(?!\.msg|\.srv)\b"),
    "the jet's spot size": re.compile(r"(?i)\b\w*(spot|jet)\w*\s*[:=]\s*0\.11\b"),
    "a wall temperature": re.compile(r"(?i)\b\w*(wall|facade|sun)\w*temp\w*\s*(:\s*\w+\s*)?[:=]\s*\d"),
    "a fixed fire temperature floor": re.compile(r"(?i)\b\w*(fire|flame)\w*temp\w*\s*(:\s*\w+\s*)?[:=]\s*\d"),
}


def violations(text: str, where: str = "") -> list:
    """Lines of `text` that break a rule, as 'where:line: rule: text'."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        code = line.split("#", 1)[0]
        for rule, rx in RULES.items():
            if rx.search(code):
                out.append(f"{where}:{n}: {rule}: {line.strip()}")
    return out


def robot_sources():
    for pkg in ROBOT_PACKAGES:
        for path in sorted((SRC / pkg).glob("src/**/*.py")) + sorted((SRC / pkg).glob("scripts/*")):
            if path.is_file():
                yield path


def test_the_scan_finds_each_kind_of_copy():
    """The rules catch what they are for (a grep that cannot fail proves nothing)."""
    bad = ("FIRE_LITRES = 1.0\n"
           "from ual_sim.constants import HEATER_TEMP\n"
           "JET_SPOT = 0.11\n"
           "facade_temp = 45.0\n"
           "min_fire_temperature: float = 50.0\n")
    found = violations(bad)
    assert len(found) == 6, found          # the import line names HEATER_TEMP too
    assert not violations("from ual_sim.msg import FireState\nHOLE_JUMP_MAX = 1.5  # FIRE_LITRES gone\n")


def test_sources_exist():
    assert len(list(robot_sources())) > 30


@pytest.mark.parametrize("pkg", ROBOT_PACKAGES)
def test_no_simulator_model_in(pkg):
    found = []
    for path in robot_sources():
        if path.parts[len(SRC.parts)] == pkg:
            found += violations(path.read_text(errors="replace"), str(path.relative_to(SRC)))
    assert not found, "copies of the simulator's models:\n" + "\n".join(found)
