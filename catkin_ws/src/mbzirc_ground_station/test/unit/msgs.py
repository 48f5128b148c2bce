"""Message builders for the unit tests (real message classes, as the node receives them)."""
import json
import math

from geometry_msgs.msg import PoseStamped
from mbzirc_comm_objs.msg import AgentDataFeed, Object, ObjectList
from std_msgs.msg import String


def feed(agent="2", x=0.0, y=0.0, z=0.0, yaw=0.0, ual=4, task="", sub="", water=2.0, payload="water",
         frame="arena"):
    m = AgentDataFeed(agent_id=agent, robot_type="ugv" if agent == "0" else "uav", payload=payload,
                      ual_state=ual, active_task=task, active_sub_state=sub, is_idle=not task, battery=1.0,
                      water_level=water, has_blanket=payload == "blanket")
    m.pose = PoseStamped()
    m.pose.header.frame_id = frame
    m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = x, y, z
    m.pose.pose.orientation.z, m.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return m


def fires(*items):
    """items: (id, sub_type, status, x, y, z)."""
    out = ObjectList()
    for i, sub, status, x, y, z in items:
        o = Object(id=i, sub_type=sub, status=status, num_updates=9)
        o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = x, y, z
        out.objects.append(o)
    return out


def cu_status(t, agents, **extra):
    return String(data=json.dumps(dict({"t": t, "agents": agents, "fires": [], "floor_owner": {},
                                        "indoor_owner": {}}, **extra)))
