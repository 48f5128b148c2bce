"""Reports of the robustness harness: the fuzz report and the overall robustness report (pure, no ROS).

Why: the lead and the other engineers need one JSON that says exactly which node died on which input,
which node stayed silent (no error logged), and, for the fault scenarios, how many link losses and
crashes the mission survived, how many robots were lost and how many fires were still put out.
"""
from __future__ import annotations

import json
import os
from typing import Any

from mbzirc_robustness import constants as C

SERVICE_ERROR_PREFIX = "error:"


class FuzzReport:
    """What one fuzzing run did and found.

    .. note:: a node whose pid changed (respawned by roslaunch) counts as dead: it crashed.
    """

    def __init__(self) -> None:
        self.nodes: dict[str, dict[str, Any]] = {}
        self.inputs: list[dict[str, Any]] = []
        self.skipped: list[dict[str, str]] = []

    def add_node(self, name: str, pid: int | None) -> None:
        """A target node and its pid before fuzzing (None: it was not answering already)."""
        self.nodes[name] = {"pid_before": pid, "pid_after": pid, "alive": pid is not None, "died_on": None
                            if pid is not None else "before fuzzing", "errors_logged": 0, "warnings_logged": 0,
                            "sample_errors": [], "errors_during": {}}

    def set_pid_after(self, name: str, pid: int | None, during: str) -> None:
        """Record the pid seen after an input; a missing or different pid marks the node dead."""
        node = self.nodes[name]
        node["pid_after"] = pid
        if node["alive"] and (pid is None or pid != node["pid_before"]):
            node["alive"] = False
            node["died_on"] = during
            node["restarted"] = pid is not None

    def add_function_check(self, name: str, during: str, what: str, ok: bool, detail: str) -> None:
        """A functional probe of node ``name`` after input ``during``: failed = the node lost its function."""
        node = self.nodes.get(name)
        if node is None:
            return
        node["functional_checks"] = node.get("functional_checks", 0) + 1
        node.setdefault("probe", what)
        if not ok:
            node["functional_failures"] = node.get("functional_failures", 0) + 1
            if not node.get("function_lost"):
                node["function_lost"] = f"after {during}: {what}: {detail}"

    def function_lost(self) -> list[dict[str, Any]]:
        """Nodes alive but no longer doing their job after some input."""
        return [{"node": n, "function_lost": v["function_lost"]} for n, v in sorted(self.nodes.items())
                if v.get("function_lost")]

    def add_input(self, kind: str, name: str, type_name: str, nodes: list[str], sent: int,
                  connected: list[str] | None = None, outcomes: list[tuple[str, str]] | None = None,
                  labels: list[str] | None = None) -> None:
        """One fuzzed topic / action goal / service and what happened to the inputs sent on it."""
        entry: dict[str, Any] = {"kind": kind, "name": name, "type": type_name, "nodes": nodes, "sent": sent}
        if connected is not None:
            entry["connected"] = connected
            entry["not_connected"] = sorted(set(nodes) - set(connected))
        if outcomes is not None:
            entry["errors_answered"] = sum(1 for _, o in outcomes if o.startswith(SERVICE_ERROR_PREFIX))
            entry["timeouts"] = sum(1 for _, o in outcomes if o == "timeout")
            entry["sample_outcomes"] = [f"{lab} -> {o}" for lab, o in outcomes[:6]]
        if labels is not None:
            entry["labels"] = labels
        self.inputs.append(entry)

    def add_skipped(self, name: str, why: str) -> None:
        """An input that could not be fuzzed (unknown type, every node behind it dead)."""
        self.skipped.append({"name": name, "why": why})

    def add_log(self, line: dict[str, Any]) -> None:
        """A /rosout line of a target node ({node, level, msg, during})."""
        node = self.nodes.get(line["node"])
        if node is None:
            return
        if line["level"] in C.ERROR_LEVELS and line["msg"].startswith(C.FRAMEWORK_ERRORS):
            node["framework_errors"] = node.get("framework_errors", 0) + 1  # rospy's, not the node's own
        elif line["level"] in C.ERROR_LEVELS:
            node["errors_logged"] += 1
            if line.get("during"):
                node["errors_during"][line["during"]] = node["errors_during"].get(line["during"], 0) + 1
            if len(node["sample_errors"]) < 5:
                node["sample_errors"].append(line["msg"])
        else:
            node["warnings_logged"] += 1

    # -----------------------------------------------------------------------------------------------
    def died(self) -> list[dict[str, Any]]:
        """Nodes that died or restarted, each with the input that was being sent."""
        return [{"node": n, "died_on": v["died_on"], "restarted": v.get("restarted", False)}
                for n, v in sorted(self.nodes.items()) if not v["alive"]]

    def silent(self) -> list[str]:
        """Nodes that got malformed inputs yet never logged an error nor answered one with an error."""
        answered = {n for i in self.inputs if i.get("errors_answered") for n in i["nodes"]}
        return sorted(n for n, v in self.nodes.items() if v["errors_logged"] == 0 and n not in answered)

    def silent_inputs(self) -> list[str]:
        """'node <- input' pairs: a message-fed input during which that node logged no error."""
        out = []
        for i in self.inputs:
            if i["kind"] == "service" or i["sent"] == 0:
                continue
            for n in i.get("connected", i["nodes"]):
                if n in self.nodes and i["name"] not in self.nodes[n]["errors_during"]:
                    out.append(f"{n} <- {i['name']}")
        return out

    def inputs_tried(self) -> int:
        """Malformed messages and requests actually sent."""
        return sum(i["sent"] for i in self.inputs)

    def to_dict(self) -> dict[str, Any]:
        """The whole report as JSON-ready data, summary first."""
        kinds: dict[str, int] = {}
        for i in self.inputs:
            kinds[i["kind"]] = kinds.get(i["kind"], 0) + 1
        return {"summary": {"nodes": len(self.nodes), "inputs_fuzzed": kinds,
                            "malformed_inputs_tried": self.inputs_tried(), "nodes_died": self.died(),
                            "silent_nodes": self.silent(), "silent_inputs": self.silent_inputs(),
                            "function_lost": self.function_lost(),
                            "functional_checks": sum(v.get("functional_checks", 0) for v in self.nodes.values()),
                            "all_survived": not self.died() and not self.function_lost() and bool(self.nodes)},
                "nodes": self.nodes, "inputs": self.inputs, "skipped": self.skipped}


def merge_fuzz_reports(reports: list[dict[str, Any]]) -> dict[str, Any] | None:
    """One fuzz report (summary, nodes, inputs) out of several (one per fuzz rostest); None if none."""
    if not reports:
        return None
    s: dict[str, Any] = {"nodes": 0, "inputs_fuzzed": {}, "malformed_inputs_tried": 0, "nodes_died": [],
                         "silent_nodes": [], "silent_inputs": [], "function_lost": [], "functional_checks": 0,
                         "all_survived": True}
    nodes: dict[str, Any] = {}
    inputs: list[dict[str, Any]] = []
    for r in reports:
        rs = r["summary"]
        s["nodes"] += rs["nodes"]
        for k, v in rs["inputs_fuzzed"].items():
            s["inputs_fuzzed"][k] = s["inputs_fuzzed"].get(k, 0) + v
        s["malformed_inputs_tried"] += rs["malformed_inputs_tried"]
        for key in ("nodes_died", "silent_nodes", "silent_inputs", "function_lost"):
            s[key] += rs.get(key, [])
        s["functional_checks"] += rs.get("functional_checks", 0)
        s["all_survived"] = s["all_survived"] and rs["all_survived"]
        nodes.update(r.get("nodes", {}))
        inputs += r.get("inputs", [])
    return {"summary": s, "nodes": nodes, "inputs": inputs}


def write_json(path: str, data: dict[str, Any]) -> None:
    """Write ``data`` as indented JSON, creating the directory."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=2, sort_keys=False, default=str)


def format_fuzz_summary(data: dict[str, Any]) -> str:
    """A few human lines about a fuzz report (printed by the tool and the tests)."""
    s = data["summary"]
    lines = [f"fuzzed {s['nodes']} nodes: {s['inputs_fuzzed']}, {s['malformed_inputs_tried']} malformed inputs"]
    for d in s["nodes_died"]:
        lines.append(f"  DIED  {d['node']} on {d['died_on']}" + (" (respawned)" if d["restarted"] else ""))
    for d in s.get("function_lost", []):
        lines.append(f"  LOST FUNCTION {d['node']}: {d['function_lost']}")
    for n in s["silent_nodes"]:
        lines.append(f"  SILENT {n}: no error logged for any malformed input")
    for n, v in sorted(data["nodes"].items()):
        if v["alive"]:
            sample = v["sample_errors"][0] if v["sample_errors"] else "-"
            probe = (f", probe '{v['probe']}' passed {v.get('functional_checks', 0) - v.get('functional_failures', 0)}"
                     f"/{v.get('functional_checks', 0)}") if v.get("probe") else ", no functional probe"
            lines.append(f"  ok    {n}: {v['errors_logged']} errors logged{probe}, e.g. {sample!r}")
    return "\n".join(lines)


def robustness_report(fuzz: dict[str, Any] | None, scenarios: list[dict[str, Any]],
                      mission: dict[str, Any] | None = None, robots_lost: list[str] | None = None,
                      ) -> dict[str, Any]:
    """The issue's report: link losses survived, crashes survived, malformed inputs tried, robots lost,
    fires still put out, from the fuzz report and the fault scenarios' results.

    Each scenario is ``{"kind": "link_cut"|"link_cut_permanent"|"crash", "target": ..., "survived": bool,
    "detail": str, ...}``; ``mission`` is the mission's summary (``fires_extinguished``, ``fires_total``,
    ``crashes``); ``robots_lost`` the robots the central unit considers dead at the end.
    """
    links = [s for s in scenarios if s["kind"].startswith("link_cut")]
    crashes = [s for s in scenarios if s["kind"] == "crash"]
    others = [s for s in scenarios if s not in links and s not in crashes]
    out: dict[str, Any] = {
        "link_losses": len(links),
        "link_losses_survived": sum(1 for s in links if s["survived"]),
        "crashes": len(crashes),
        "crashes_survived": sum(1 for s in crashes if s["survived"]),
        "other_faults": len(others),                    # clock jump, simulator restart, flood, ...
        "other_faults_survived": sum(1 for s in others if s["survived"]),
        "recovery_wall_s": {f"{s['kind']} {s['target']}": s["recovery_wall_s"] for s in scenarios
                            if s.get("recovery_wall_s") is not None},
        "malformed_inputs_tried": fuzz["summary"]["malformed_inputs_tried"] if fuzz else 0,
        "fuzz_nodes_died": [d["node"] for d in fuzz["summary"]["nodes_died"]] if fuzz else [],
        "fuzz_function_lost": [d["node"] for d in fuzz["summary"].get("function_lost", [])] if fuzz else [],
        "fuzz_silent_nodes": fuzz["summary"]["silent_nodes"] if fuzz else [],
        "robots_lost": robots_lost, "fires_put_out": None, "fires_total": None, "collisions": None,
        "scenarios": scenarios,
        "failures": [f"{s['kind']} {s['target']}: {s.get('detail', '')}" for s in scenarios if not s["survived"]],
    }
    if mission:
        out["fires_put_out"] = mission.get("fires_extinguished")
        out["fires_total"] = mission.get("fires_total")
        out["collisions"] = mission.get("crashes")
        out["mission"] = {k: mission.get(k) for k in ("score", "sim_time_s", "wall_time_s", "real_time_factor")}
        if mission.get("crashes"):
            out["failures"].append(f"collisions during the mission: {mission['crashes']}")
    return out


def format_robustness(rep: dict[str, Any]) -> str:
    """The robustness report as the few lines printed at the end of ``make test-faults``."""
    lines = [
        f"link losses survived: {rep['link_losses_survived']}/{rep['link_losses']}",
        f"crashes survived:     {rep['crashes_survived']}/{rep['crashes']}",
        f"other faults survived: {rep.get('other_faults_survived', 0)}/{rep.get('other_faults', 0)}",
        f"malformed inputs tried: {rep['malformed_inputs_tried']} (nodes died: {rep['fuzz_nodes_died'] or 'none'})",
        f"robots lost:          {rep['robots_lost']}",
        f"fires put out:        {rep['fires_put_out']}/{rep['fires_total']}",
        f"collisions:           {rep['collisions'] if rep['collisions'] is not None else 'unknown'}",
    ]
    for sc in rep["scenarios"]:
        lines.append(f"  {'ok  ' if sc['survived'] else 'FAIL'} {sc['kind']} {sc['target']}: {sc.get('detail', '')}")
        log = sc.get("agent_log_during_cut")
        if log is not None:
            lines.append(f"  {sc['kind']} {sc['target']}: its agent logged {log['lines']} lines while cut, "
                         f"heartbeat loss noticed: {'yes' if log['noticed_heartbeat_loss'] else 'NO'}"
                         + (f", back {sc['t_back'] - sc['t_restore']:.0f} s (sim) after the restore"
                            if sc.get("t_back") is not None and sc.get("t_restore") is not None else ""))
            if sc.get("agent_checked"):
                lines.append(f"    its own log checked for: {', '.join(sc['agent_checked'])}: "
                             + ("ok" if sc.get("agent_ok") else "; ".join(sc.get("agent_problems") or [])))
            for u in sc.get("agent_unverified") or []:
                lines.append(f"    NOT VERIFIED: {u}")
    lines += [f"FAILED: {f}" for f in rep["failures"]]
    return "\n".join(lines)
