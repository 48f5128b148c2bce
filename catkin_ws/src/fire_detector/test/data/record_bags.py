#!/usr/bin/env python3
"""Records the small replay fixtures of fire_detector and circle_detector from ual_sim.

Run inside a private network namespace with the simulator up, e.g.:
  unshare -n sh -c 'ip link set lo up; roscore & sleep 3; \
    roslaunch ual_sim c3_world.launch uavs:=2 ugv:=false rtf:=4 wind:=false & sleep 8; \
    python3 record_bags.py; kill %2 %1'
It flies UAV 2 (water: FORWARD thermal + RGB-D) to an active facade holder, an inactive one and a bare
sun-heated wall, and UAV 1 (blanket: DOWNWARD thermal) over an active ground fire, and writes one
bz2-compressed bag per case plus bags.yaml (the truth each replay test checks against: /sim/fires).
"""
import math
import os
import sys
import threading

import rosbag
import rospy
import yaml
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import CameraInfo, Image, LaserScan
from std_msgs.msg import Float64MultiArray
from uav_abstraction_layer.srv import GoToWaypoint, TakeOff
from ual_sim.msg import FireStateArray

HERE = os.path.dirname(os.path.abspath(__file__))
CIRCLE_DATA = os.path.join(HERE, "..", "..", "..", "circle_detector", "test", "data")
SAFE_Z = 19.0
THERMAL_TOPICS = {"ual/pose": PoseStamped, "scan": LaserScan,
                  "teraranger_evo_thermal/raw_temp_array": Float64MultiArray}
RGBD_TOPICS = {"camera/color/image_rect_color": Image, "camera/aligned_depth_to_color/image_raw": Image,
               "camera/color/camera_info": CameraInfo}


class Recorder:
    """Writes the given topics of one robot into a bag; every `keep_every`-th message of heavy topics."""

    def __init__(self, path, ns, topics, keep_every=None):
        self.bag = rosbag.Bag(path, "w", compression="bz2")
        self.lock = threading.Lock()
        self.counts = {}
        self.keep_every = keep_every or {}
        self.subs = [rospy.Subscriber(f"/{ns}/{t}", cls, self.cb, callback_args=f"/{ns}/{t}", queue_size=50)
                     for t, cls in topics.items()]

    def cb(self, msg, topic):
        n = self.counts.get(topic, 0)
        self.counts[topic] = n + 1
        if n % self.keep_every.get(topic.split("/", 2)[2], 1):
            return
        with self.lock:
            if self.bag is not None:
                self.bag.write(topic, msg, rospy.Time.now())

    def close(self):
        for s in self.subs:
            s.unregister()
        with self.lock:
            self.bag.close()
            self.bag = None


def go(ns, x, y, z, yaw):
    srv = rospy.ServiceProxy(f"/{ns}/ual/go_to_waypoint", GoToWaypoint)
    wp = PoseStamped()
    wp.header.frame_id = "arena"
    wp.pose.position.x, wp.pose.position.y, wp.pose.position.z = x, y, z
    wp.pose.orientation.z, wp.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    srv(waypoint=wp, blocking=True)


def pose(ns):
    p = rospy.wait_for_message(f"/{ns}/ual/pose", PoseStamped, timeout=10).pose.position
    return p.x, p.y, p.z


def facade_front(holder, dist):
    n = holder["normal"]
    p = holder["position"]
    return (p[0] + n[0] * dist, p[1] + n[1] * dist, p[2]), math.atan2(-n[1], -n[0])


def fly_to_facade(ns, target, yaw, staging_out):
    """Over the roof, down outside the building, then in: never crosses the building."""
    x, y, _ = pose(ns)
    go(ns, x, y, SAFE_Z, yaw)
    go(ns, staging_out[0], staging_out[1], SAFE_Z, yaw)
    go(ns, staging_out[0], staging_out[1], target[2], yaw)


def record(path, ns, topics, seconds, keep_every=None, during=None):
    rec = Recorder(path, ns, topics, keep_every)
    start = rospy.Time.now()
    if during:
        during()
    while (rospy.Time.now() - start).to_sec() < seconds and not rospy.is_shutdown():
        rospy.sleep(0.05)
    rec.close()
    print(f"{os.path.basename(path)}: {os.path.getsize(path) / 1e6:.2f} MB", rec.counts, flush=True)


def main():
    rospy.init_node("record_bags")
    fires = rospy.wait_for_message("/sim/fires", FireStateArray, timeout=90).fires
    import rospkg
    world_file = os.path.join(rospkg.RosPack().get_path("ual_sim"), "src", "ual_sim", "worlds", "c3_default.yaml")
    world = yaml.safe_load(open(world_file))
    holders = {h["id"]: h for h in world["facade_holders"]}
    by_id = {f.id: f for f in fires}
    active = [h for k, h in holders.items() if f"facade_{k}" in by_id and by_id[f"facade_{k}"].active]
    inactive = [h for k, h in holders.items() if f"facade_{k}" in by_id and not by_id[f"facade_{k}"].active]
    if not active:  # ids may be spelled differently: match by position
        def near(f, h):
            return math.dist((f.position.x, f.position.y, f.position.z), h["position"]) < 0.1
        active = [h for h in holders.values() if any(near(f, h) and f.active for f in fires if f.kind == 0)]
        inactive = [h for h in holders.values() if any(near(f, h) and not f.active for f in fires if f.kind == 0)]
    ground = [f for f in fires if f.kind == 1 and f.active]
    print("active facade:", [h["id"] for h in active], "inactive:", [h["id"] for h in inactive],
          "ground:", [(f.position.x, f.position.y) for f in ground], flush=True)
    side = lambda h: h["id"][0]  # noqa: E731
    act = sorted(active, key=lambda h: (h["position"][2] < 2.0, side(h) != "A", h["position"][2]))[0]
    ina = sorted(inactive, key=lambda h: (side(h) != "A", abs(h["position"][2] - 7)))[0]
    truth = {}
    rgbd_only = "--rgbd-only" in sys.argv  # run again with the simulator at rtf 1: RGB-D rendering is slow
    for ns in ("mbzirc2020_1", "mbzirc2020_2")[rgbd_only:]:
        rospy.ServiceProxy(f"/{ns}/ual/take_off", TakeOff)(height=4.0, blocking=True)
    if rgbd_only:
        ns = "mbzirc2020_2"
        near_, yaw = facade_front(act, 2.5)
        staging, _ = facade_front(act, 9.0)
        fly_to_facade(ns, near_, yaw, staging)
        go(ns, *near_, yaw)
        rospy.sleep(1.0)
        record(os.path.join(CIRCLE_DATA, "facade_holder_rgbd.bag"), ns, RGBD_TOPICS, 4.0)
        with open(os.path.join(CIRCLE_DATA, "bags.yaml"), "w") as f:
            f.write("# Recorded from ual_sim (seed 1, rtf 1) by fire_detector/test/data/record_bags.py --rgbd-only.\n")
            yaml.safe_dump({"facade_holder_rgbd.bag": {"ns": ns, "hole_arena": list(act["position"]),
                                                       "uav_xyz_yaw": [*near_, yaw], "distance": 2.5}}, f)
        return

    # 1. ground fire seen from 4 m by the blanket UAV (DOWNWARD)
    g = ground[0].position
    go("mbzirc2020_1", g.x + 0.3, g.y - 0.2, 4.0, 0.3)
    record(os.path.join(HERE, "ground_fire.bag"), "mbzirc2020_1", THERMAL_TOPICS, 5.0)
    truth["ground_fire.bag"] = {"ns": "mbzirc2020_1", "camera_config": "DOWNWARD", "fire": [g.x, g.y, g.z]}

    # 2. approach to an active facade fire from 6 m to 2.5 m, then hover (FORWARD), plus RGB-D at 2.5 m
    ns = "mbzirc2020_2"
    far, yaw = facade_front(act, 6.0)
    near_, _ = facade_front(act, 2.5)
    staging, _ = facade_front(act, 9.0)
    fly_to_facade(ns, far, yaw, staging)
    go(ns, *far, yaw)
    record(os.path.join(HERE, "facade_fire_approach.bag"), ns, THERMAL_TOPICS, 8.0,
           during=lambda: go(ns, *near_, yaw))
    truth["facade_fire_approach.bag"] = {"ns": ns, "camera_config": "FORWARD", "fire": list(act["position"])}
    record(os.path.join(CIRCLE_DATA, "facade_holder_rgbd.bag"), ns, RGBD_TOPICS, 8.0,
           keep_every={})
    circle_truth = {"facade_holder_rgbd.bag": {"ns": ns, "hole_arena": list(act["position"]),
                                               "uav_xyz_yaw": [*near_, yaw], "distance": 2.5}}

    # 3. an inactive holder at 3 m
    target, yaw = facade_front(ina, 3.0)
    staging, _ = facade_front(ina, 9.0)
    fly_to_facade(ns, target, yaw, staging)
    go(ns, *target, yaw)
    record(os.path.join(HERE, "inactive_holder.bag"), ns, THERMAL_TOPICS, 5.0)
    truth["inactive_holder.bag"] = {"ns": ns, "camera_config": "FORWARD", "fire": None}

    # 4. a bare sun-heated stretch of facade A (no holder within 2.5 m) at 3 m
    bare = {"id": "A_bare", "position": [20.0, 19.5, 7.5], "normal": [0, 1, 0]}
    target, yaw = facade_front(bare, 3.0)
    staging, _ = facade_front(bare, 9.0)
    fly_to_facade(ns, target, yaw, staging)
    go(ns, *target, yaw)
    record(os.path.join(HERE, "sun_heated_wall.bag"), ns, THERMAL_TOPICS, 5.0)
    truth["sun_heated_wall.bag"] = {"ns": ns, "camera_config": "FORWARD", "fire": None}

    with open(os.path.join(HERE, "bags.yaml"), "w") as f:
        f.write("# Recorded from ual_sim (seed 1) by record_bags.py; fire = true arena position from /sim/fires.\n")
        yaml.safe_dump(truth, f)
    with open(os.path.join(CIRCLE_DATA, "bags.yaml"), "w") as f:
        f.write("# Recorded from ual_sim (seed 1) by fire_detector/test/data/record_bags.py.\n")
        yaml.safe_dump(circle_truth, f)


if __name__ == "__main__":
    sys.exit(main())
