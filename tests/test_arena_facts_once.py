"""Each arena fact and each rule on it is written once, in mbzirc_arena (issue 16), and only the referee
reads the simulator's ground truth.

Why a grep: the building, the holders and floor_of were written three times and the copies disagreed (at
z = 4.7 m the central unit and the agents said floor 0, ual_sim floor 1; at 16 m the agents said -1).
Scans the installed code of every package (src/ and scripts/), not tests or benchmarks.
"""
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "catkin_ws" / "src"
ARENA = "mbzirc_arena"

# rules (def name) that mbzirc_arena defines, and the packages allowed a definition of their own
RULES = ("floor_of", "classify_fire", "yaw_from_quaternion", "segment_hits_rect", "shortest_path", "plan_2d",
         "make_box", "boxes_overlap", "standing_at", "nearest_face", "robot_ns", "feed_position")
OWN_DEFINITION_OK = {
    ("hector_mapping", "yaw_from_quaternion"): "a re-implementation of a third-party package: no project deps",
    ("ual_sim", "floor_of"): "World.floor_of delegates to mbzirc_arena.floor_of with the world's floors",
    ("mbzirc_central_unit", "segment_hits_rect"): "delegates to mbzirc_arena.routing with the strategy's shrink",
}
# literal copies of the building outline and of a facade holder
FACT_COPIES = {
    "the tower's outline": re.compile(r"11\.4\s*,\s*6\.7\s*,|24\.2\s*,\s*19\.5\s*,\s*(18|15)\.0"),
    "a facade holder": re.compile(r"12\.4\s*,\s*19\.5\s*,\s*6\.5|24\.2\s*,\s*17\.75\s*,\s*6\.0"),
    "the floor heights": re.compile(r"FLOOR_(Z|BOUNDS)\s*="),
}
FACT_OWNERS = (ARENA, "ual_sim")   # the team's model and the simulator's world
# /sim/* is ground truth: the simulator serves it, the referee reads it, the launchers record it in a bag,
# the ground station shows the referee's score marked as ground truth (sim only, hidden without a referee)
SIM_READERS = ("ual_sim", "mbzirc_referee", "mbzirc_launchers", "mbzirc_robustness", "mbzirc_ground_station")
SIM_TOPIC = re.compile(r"""["'\s(]/sim/""")
# known leftovers (docs/arena_knowledge.md): package -> what; each must still be there, else drop it here
KNOWN_LEFTOVERS: dict = {}


def sources():
    for path in sorted(SRC.glob("*/src/**/*.py")) + sorted(SRC.glob("*/scripts/*")):
        if path.is_file():
            yield path.relative_to(SRC).parts[0], path, path.read_text(errors="replace")


def code_lines(text):
    for n, line in enumerate(text.splitlines(), 1):
        yield n, line.split("#", 1)[0]


def find(check):
    """(package, 'path:line: what') of every line where check(package, code) names a problem."""
    out = []
    for pkg, path, text in sources():
        for n, code in code_lines(text):
            what = check(pkg, code)
            if what:
                out.append((pkg, f"{path.relative_to(SRC)}:{n}: {what}"))
    return out


def rule_definitions(pkg, code):
    m = re.match(r"\s*def\s+_?(\w+)\s*\(", code)
    if m and m.group(1) in RULES and pkg != ARENA and (pkg, m.group(1)) not in OWN_DEFINITION_OK:
        return f"a definition of {m.group(1)} outside {ARENA}"
    return None


def fact_copies(pkg, code):
    if pkg in FACT_OWNERS:
        return None
    return next((f"a copy of {name}" for name, rx in FACT_COPIES.items() if rx.search(code)), None)


def sim_readers(pkg, code):
    return "reads /sim/*" if pkg not in SIM_READERS and SIM_TOPIC.search(code) else None


def without_leftovers(found):
    return [where for pkg, where in found if pkg not in KNOWN_LEFTOVERS]


def test_each_rule_is_defined_once_in_mbzirc_arena():
    assert not without_leftovers(find(rule_definitions))
    defined = {m for _, _, text in sources() for m in re.findall(r"^def (\w+)\(", text, re.M)}
    assert {"floor_of", "classify_fire", "yaw_from_quaternion", "segment_hits_rect"} <= defined


def test_no_package_but_the_arena_and_the_simulator_copies_an_arena_fact():
    assert not without_leftovers(find(fact_copies))


def test_only_the_referee_reads_ground_truth():
    assert not without_leftovers(find(sim_readers))


def test_the_checks_catch_what_they_are_for():
    """The scans flag each kind of copy (a grep that cannot fail proves nothing)."""
    assert rule_definitions("mbzirc_agents", "def floor_of(z):")
    assert rule_definitions("mbzirc_ground_station", "    def _floor_of(self, z):")
    assert not rule_definitions(ARENA, "def floor_of(z, floor_heights):")
    assert fact_copies("mbzirc_agents", "TOWER = (11.4, 6.7, 24.2, 19.5, 18.0)")
    assert fact_copies("mbzirc_central_unit", "FACADE_HOLDERS = ((12.4, 19.5, 6.5),")
    assert fact_copies("mbzirc_agents", "FLOOR_Z = [(0.0, 5.0)]")
    assert not fact_copies("ual_sim", "TOWER = (11.4, 6.7, 24.2, 19.5, 18.0)")
    assert sim_readers("mbzirc_agents", 'rospy.Subscriber("/sim/fires", FireStateArray, cb)')
    assert not sim_readers("mbzirc_referee", 'rospy.Subscriber("/sim/fires", FireStateArray, cb)')


def test_known_leftovers_are_still_there():
    """A leftover that was fixed must leave KNOWN_LEFTOVERS, so that it cannot come back unnoticed."""
    found = {pkg for check in (rule_definitions, fact_copies, sim_readers) for pkg, _ in find(check)}
    assert set(KNOWN_LEFTOVERS) <= found, f"fixed, drop from KNOWN_LEFTOVERS: {set(KNOWN_LEFTOVERS) - found}"
