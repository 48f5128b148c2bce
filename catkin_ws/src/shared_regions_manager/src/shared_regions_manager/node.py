"""ROS adapter of the shared-region manager: serves /ask_for_region and /free_regions.

Params (defaults): `~robot_ids` ([0, 1, 2, 3]: the mission's agents; any other agent id leases its boxes
for `~unknown_lease_s`, 10 s wall), `~supervisors` (['/central_unit']: nodes that may free any agent's
boxes), `~max_labels_per_agent` (16), `~max_agents` (32), `~state_file` ('' = off: the table is written
there atomically after every change and reloaded by a respawned manager), `~clock_wait` (10 s wall: how
long a start waits for /clock to judge the file's age), `~publish_markers` (false: the reserved boxes as a
MarkerArray on `regions` at 1 Hz and at every change, for rviz and the fault suite: the DELETEALL marker's
text is `table <n>`, the number of the table shown, saved under that number; table_sync.py).
Deadlocks (core.py, deadlock.py): `~priority` (default `~robot_ids`: highest first; the lowest of a
wait-for cycle steps aside), `~deadlock_after` (2 s ROS time a cycle stands before the order),
`~yield_retry` (20 s ROS time before an order is repeated), `~yield_service` ('/mbzirc2020_{}/yield_region':
the victim's AskForRegion service, called with the winner's agent id, label and refused box: "leave it"),
`~idle_yield_after` (15 s ROS time a robot waits for boxes of a robot that waits for nothing before that
one is asked to leave).
"""
from __future__ import annotations

import math
import os
import threading
import time

import rospy
from mbzirc_comm_objs.srv import (AskForRegion, AskForRegionRequest, AskForRegionResponse, FreeRegions,
                                  FreeRegionsResponse)
from mbzirc_ros_utils import state_file
from mbzirc_ros_utils.periodic import PeriodicTimer

from .core import RegionManager
from .deadlock import YieldOrder
from .table_sync import TableSync

TABLE_TEXT = 'table {}'              # the DELETEALL marker's text on /regions: which saved table is shown

FORMAT = 'shared_regions_manager/regions'
VERSION = 1


def caller_of(req) -> str:
    """The node name that made a service request (rospy's connection header)."""
    return str((getattr(req, '_connection_header', None) or {}).get('callerid', ''))


class RegionManagerNode:
    """Services `ask_for_region` and `free_regions` (relative names: put the node in the root ns)."""

    def __init__(self) -> None:
        self.core = RegionManager(
            known_agents=[str(i) for i in rospy.get_param('~robot_ids', [0, 1, 2, 3])],
            supervisors=rospy.get_param('~supervisors', ['/central_unit']),
            unknown_lease_s=float(rospy.get_param('~unknown_lease_s', 10.0)),
            max_labels_per_agent=int(rospy.get_param('~max_labels_per_agent', 16)),
            max_agents=int(rospy.get_param('~max_agents', 32)),
            priority=[str(a) for a in rospy.get_param('~priority', [])],
            deadlock_after_s=float(rospy.get_param('~deadlock_after', 2.0)),
            yield_retry_s=float(rospy.get_param('~yield_retry', 20.0)),
            idle_yield_after_s=float(rospy.get_param('~idle_yield_after', 15.0)),
            wait_clock=rospy.get_time)
        self.yield_service = str(rospy.get_param('~yield_service', '/mbzirc2020_{}/yield_region'))
        self.state_file = str(rospy.get_param('~state_file', '') or '')
        self.mission = str(rospy.get_param('/run_id', '') or '') if self.state_file else ''
        self._waiting: dict = {}          # (agent, label) -> why its last request was refused
        table = self._resume() if self.state_file else 0
        self.markers = None
        if rospy.get_param('~publish_markers', False):
            from visualization_msgs.msg import MarkerArray
            self.markers = rospy.Publisher('regions', MarkerArray, queue_size=1)
        # every change and every publication goes through it: what /regions shows is what is on disk
        self.table = TableSync(self.core, self.save, self.publish_markers if self.markers is not None else None,
                               rospy.loginfo, table)
        self.ask_srv = rospy.Service('ask_for_region', AskForRegion, self.on_ask)
        self.free_srv = rospy.Service('free_regions', FreeRegions, self.on_free)
        self.timer = PeriodicTimer(1.0, self.on_timer, 'region manager')

    # ---- persistence ------------------------------------------------------------------------------
    def _resume(self) -> int:
        """Load the reservations of `~state_file` when it is of this mission; else start empty. Returns the
        number of the table resumed (0: none)."""
        now = rospy.get_time()
        if os.path.exists(self.state_file):
            deadline = time.monotonic() + float(rospy.get_param('~clock_wait', 10.0))
            while not rospy.is_shutdown() and rospy.get_time() == 0.0 and time.monotonic() < deadline:
                time.sleep(0.05)
            now = rospy.get_time()
        res = state_file.load(self.state_file, FORMAT, VERSION, self.mission, now, what='regions')
        if res.kind == state_file.OK:
            try:
                table = int(res.state.get('table', 0))
                n = self.core.load_state(res.state)
                rospy.loginfo(f'region manager: resumed {n} reservations from {self.state_file} ({res.reason}, '
                              f'table {table}): ' + ', '.join(f'{a}/{l}' for a, l in sorted(self.core.regions())))
                return table
            except (ValueError, TypeError) as e:
                rospy.logerr(f'region manager: cannot resume from {self.state_file}: {e}; starting empty')
                return 0
        log = rospy.loginfo if res.kind == state_file.MISSING else rospy.logwarn
        log(f'region manager: {res.reason}; starting with no reservations')
        return 0

    def save(self, state: dict, table: int) -> None:
        """Write table number `table` (at once, before it is shown or the request answered: a grant must
        survive a crash right after it). Called by self.table under its lock."""
        if not self.state_file:
            return
        try:
            state_file.save(self.state_file, state_file.encode(dict(state, table=table), FORMAT, VERSION,
                                                               self.mission, rospy.get_time()))
        except OSError as e:
            rospy.logerr_throttle(10.0, f'region manager: cannot save to {self.state_file}: {e}')

    # ---- services ---------------------------------------------------------------------------------
    def on_ask(self, req: AskForRegion._request_class) -> AskForRegionResponse:
        """Grant the box unless it overlaps another agent's box (or the table is full)."""
        lo = (req.min_corner.point.x, req.min_corner.point.y, req.min_corner.point.z)
        hi = (req.max_corner.point.x, req.max_corner.point.y, req.max_corner.point.z)
        for frame in (req.min_corner.header.frame_id, req.max_corner.header.frame_id):
            if frame not in ('', 'arena'):
                rospy.logerr_throttle(5.0, f'ask_for_region from {req.agent_id}: frame {frame!r} is not arena')
                return AskForRegionResponse(success=False)
        ok, why = self.table.change(lambda: self.core.ask(req.agent_id, req.label, lo, hi, caller=caller_of(req)))
        if not ok and (not all(map(math.isfinite, lo + hi)) or 'max' in why or not req.agent_id):
            rospy.logerr_throttle(5.0, f'ask_for_region from {req.agent_id!r} ({caller_of(req)}): {why}')
        elif ok and not self.core.is_known(req.agent_id):
            rospy.logwarn_throttle(30.0, f'ask_for_region: {req.agent_id!r} ({caller_of(req)}) is not a robot of '
                                         f'this mission: {why}')
        rospy.logdebug(f'ask_for_region {req.agent_id}/{req.label}: {why}')
        self._log_wait(req.agent_id, req.label, ok, why)
        return AskForRegionResponse(success=ok)

    def _log_wait(self, agent_id: str, label: str, granted: bool, why: str) -> None:
        """Log who waits for whom, once per change: an agent retries a refused box twice a second, and the
        log must say which region of which agent blocks it (the srv's answer carries only success)."""
        key = (agent_id, label)
        if granted:
            if self._waiting.pop(key, None) is not None:
                rospy.loginfo(f'region manager: {agent_id}/{label} granted after waiting')
        elif self._waiting.get(key) != why:
            self._waiting[key] = why
            if len(self._waiting) > 1000:                  # bounded: a caller inventing labels
                self._waiting.clear()
            rospy.loginfo(f'region manager: {agent_id}/{label} refused: {why}')

    def on_free(self, req: FreeRegions._request_class) -> FreeRegionsResponse:
        """Free one box of the agent, or all of them, when the caller may."""
        ok, why = self.table.change(lambda: self.core.free(req.agent_id, req.label, req.free_all,
                                                           caller=caller_of(req)))
        if not ok and 'may not' in why:
            rospy.logerr_throttle(5.0, f'free_regions refused: {why}')
        return FreeRegionsResponse(success=ok)

    def on_timer(self, _event=None) -> None:
        """Expire the leases of unknown agents; break a deadlock; publish the markers."""
        gone = self.table.change(self.core.expire)
        if gone:
            rospy.logwarn(f'region manager: leases expired: {", ".join(f"{a}/{l}" for a, l in gone)}')
        order = self.core.deadlock()
        if order is not None:
            rospy.logwarn(f'region manager: {order.describe()}')
            threading.Thread(target=self.send_yield, args=(order,), daemon=True, name='yield order').start()
        self.table.republish()

    def send_yield(self, order: YieldOrder) -> None:
        """Ask the victim to leave the winner's box (its yield_region service: an AskForRegion whose agent
        and box are the winner's); its answer goes back to the core. Runs in its own thread: an agent that
        does not answer must not stop the timer."""
        name = self.yield_service.format(order.victim)
        req = AskForRegionRequest(agent_id=order.winner, label=order.winner_label)
        for corner, values in ((req.min_corner, order.box[0]), (req.max_corner, order.box[1])):
            corner.header.frame_id = 'arena'
            corner.point.x, corner.point.y, corner.point.z = (float(v) for v in values)
        try:
            rospy.wait_for_service(name, timeout=2.0)
            accepted = bool(rospy.ServiceProxy(name, AskForRegion)(req).success)
            why = 'accepted: stepping aside' if accepted else 'declined (it cannot step aside now)'
        except (rospy.ROSException, rospy.ServiceException) as e:
            accepted, why = False, f'not reached ({e})'
        (rospy.loginfo if accepted else rospy.logwarn)(
            f'region manager: {order.victim} {why}, out of {order.winner}/{order.winner_label}')
        self.core.yield_answer(order, accepted)

    def publish_markers(self, regions: dict, table: int) -> None:
        """The reserved boxes of table number `table` as translucent cubes (namespace = agent/label),
        after a DELETEALL marker whose text names the table. Called by self.table under its lock."""
        from visualization_msgs.msg import Marker, MarkerArray
        arr = MarkerArray()
        clear = Marker(action=Marker.DELETEALL, text=TABLE_TEXT.format(table))
        arr.markers.append(clear)
        for i, ((agent, label), (lo, hi)) in enumerate(sorted(regions.items())):
            m = Marker(type=Marker.CUBE, action=Marker.ADD, id=i, ns=f'{agent}/{label}')
            m.header.frame_id = 'arena'
            m.header.stamp = rospy.Time.now()
            c = (lo + hi) / 2.0
            m.pose.position.x, m.pose.position.y, m.pose.position.z = c
            m.pose.orientation.w = 1.0
            m.scale.x, m.scale.y, m.scale.z = hi - lo
            m.color.r, m.color.g, m.color.b, m.color.a = 0.2, 0.5, 1.0, 0.25
            arr.markers.append(m)
        self.markers.publish(arr)
