"""AgentParams: one place for each ~param (name, type, default, meaning); bad values are named."""
import math
import os
import re
from dataclasses import fields

import pytest

from fake_backend import FakeBackend
from mbzirc_agents import constants as C
from mbzirc_agents.params import AgentParams, ParamError, check_values
from mbzirc_agents.ugv_agent import UgvAgent

README = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'README.md')


def test_defaults_and_types():
    p = AgentParams()
    assert p.uav_id == '1' and p.payload == 'water' and p.use_regions is True
    assert p.max_speed == 1.6 and p.central_unit_timeout == C.CENTRAL_UNIT_TIMEOUT
    assert p.arena == list(C.ARENA_BOX) and p.home == []
    assert all(f.metadata['meaning'] for f in fields(AgentParams))
    p.arena.append(1.0)                                  # each instance has its own lists
    assert AgentParams().arena == list(C.ARENA_BOX)


def test_values_are_converted_to_the_param_type():
    p = AgentParams.from_dict({'uav_id': 3, 'max_speed': 2, 'home': [1, 2, 0], 'payload': 'blanket'})
    assert p.uav_id == '3' and isinstance(p.max_speed, float) and p.max_speed == 2.0
    assert p.home == [1.0, 2.0, 0.0] and p.payload == 'blanket'


@pytest.mark.parametrize('values,words', [
    ({'max_sped': 2.0}, 'unknown param ~max_sped'),
    ({'max_speed': 'fast'}, "~max_speed: expected a finite number, got 'fast'"),
    ({'max_speed': math.nan}, '~max_speed: expected a finite number'),
    ({'use_regions': 'yes'}, '~use_regions: expected true or false'),
    ({'payload': 'foam'}, "~payload: expected one of ['water', 'blanket']"),
    ({'arena': [0, 0, 0, 1, 1]}, '~arena: expected 6 numbers, got 5'),
    ({'home': [1, 2]}, '~home: expected 0 or 3 numbers, got 2'),
    ({'indoor_search_path': [[1, 2], [1]]}, '~indoor_search_path: expected 2 or 3 numbers, got 1'),
])
def test_unknown_or_malformed_values_are_named(values, words):
    with pytest.raises(ParamError, match=re.escape(words)):
        AgentParams.from_dict(values)


def test_check_values_keeps_the_good_ones_and_names_every_bad_one():
    good, problems = check_values({'max_speed': 2.0, 'confirm_time': None, 'colour': 'red'})
    assert good == {'max_speed': 2.0}
    assert len(problems) == 2 and any('~confirm_time' in p and 'default 6.0' in p for p in problems)


def test_the_ugv_changes_some_defaults():
    ugv = UgvAgent('0', FakeBackend(), {'max_speed': 0.8})
    assert ugv.p.use_regions is False and ugv.p.building_clearance == 1.2 and ugv.p.max_speed == 0.8
    assert len(ugv.p.indoor_search_path) == len(C.UGV_INDOOR_PATH)


def test_the_readme_lists_every_param():
    text = open(README).read()
    missing = [f.name for f in fields(AgentParams) if f'`{f.name}`' not in text]
    assert not missing, f'README.md does not list {missing}'


def test_the_node_logs_unknown_and_malformed_params_and_runs_on_the_rest(monkeypatch):
    import rospy
    from mbzirc_agents import agent_node
    private = {'uav_id': 2, 'max_sped': 2.0, 'max_speed': 'fast', 'service_timeout': 3.0, 'smach_allow_init': False}
    monkeypatch.setattr(rospy, 'get_param', lambda name, default=None: private if name == '~' else default)
    errors = []
    monkeypatch.setattr(rospy, 'logerr', errors.append)
    assert agent_node.read_params() == {'uav_id': '2'}
    assert sorted(errors) == ['unknown param ~max_sped: ignored',
                              "~max_speed: expected a finite number, got 'fast' (default 1.6): ignored"]
