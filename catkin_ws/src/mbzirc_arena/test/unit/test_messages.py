"""The message constants of mbzirc_arena.messages have the values of the .msg files they name."""
import os
import re

import pytest

from mbzirc_arena import messages as M

SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..')


def msg_constants(pkg, kind, name):
    """{CONSTANT: value} of a .msg / .srv file (lines `uint8 NAME = value`)."""
    out = {}
    with open(os.path.join(SRC, pkg, kind, name)) as f:
        for line in f:
            m = re.match(r'\s*\w+\s+([A-Z_][A-Z0-9_]*)\s*=\s*(-?\d+)', line.split('#')[0])
            if m:
                out[m.group(1)] = int(m.group(2))
    return out


@pytest.mark.parametrize('pkg,kind,name,prefix,names', [
    ('mbzirc_comm_objs', 'msg', 'Object.msg', '', [n for n in dir(M) if n.startswith(('STATUS_', 'SUBTYPE_'))
                                                   and n != 'STATUS_NAMES']),
    ('mbzirc_comm_objs', 'msg', 'ObjectDetection.msg', '', [n for n in dir(M) if n.startswith(('TYPE_', 'COLOR_'))]),
    ('mbzirc_comm_objs', 'msg', 'ThermalImage.msg', '', [n for n in dir(M) if n.startswith('CAMERA_DIRECTION_')]),
    ('uav_abstraction_layer', 'msg', 'State.msg', 'UAL_', [n for n in dir(M) if n.startswith('UAL_')
                                                           and isinstance(getattr(M, n), int)]),
])
def test_constants_equal_the_msg_files(pkg, kind, name, prefix, names):
    defined = msg_constants(pkg, kind, name)
    assert names
    for n in names:
        assert defined.get(n[len(prefix):]) == getattr(M, n), f'{n} vs {name}'


def test_set_object_status_uses_the_object_status_values():
    srv = msg_constants('mbzirc_comm_objs', 'srv', 'SetObjectStatus.srv')
    assert srv and all(getattr(M, 'STATUS_' + k) == v for k, v in srv.items())


def test_ual_groups():
    assert M.UAL_FLYING == (M.UAL_FLYING_AUTO, M.UAL_FLYING_MANUAL)
    assert M.UAL_LANDING not in M.UAL_LANDED and M.UAL_TAKING_OFF not in M.UAL_FLYING


def test_a_feed_without_a_frame_or_with_a_nan_is_no_place():
    from types import SimpleNamespace as NS
    feed = NS(pose=NS(header=NS(frame_id=''), pose=NS(position=NS(x=0.0, y=0.0, z=0.0))))
    assert M.feed_position(feed) is None
    feed.pose.header.frame_id = M.GLOBAL_FRAME
    feed.pose.pose.position = NS(x=4.0, y=-4.0, z=0.2)
    assert M.feed_position(feed) == (4.0, -4.0, 0.2)
    feed.pose.pose.position.y = float('nan')
    assert M.feed_position(feed) is None
