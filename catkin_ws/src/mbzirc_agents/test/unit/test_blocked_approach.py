"""ExtinguishIndoorFire's approach (tasks/indoor.py `_approach`): a leg to the watering pose that the laser
finds blocked near the fire's estimate leaves the robot watering from where it stopped, facing the estimate;
any other failure, or a block far from the fire, fails the task as before."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from mbzirc_agents.agent_task import TaskError
from mbzirc_agents.tasks.indoor import ExtinguishIndoorFire

BLOCKED = TaskError('leg 1/1 to (18.1, 16.5): a laser return 1.03 m ahead blocks the leg to (18.1, 16.5) '
                    '(1.8 m left; guard: 1.10 m ahead, +-0.90 m aside): holding')


class Agent:
    def __init__(self, here):
        self.here = np.array(here, dtype=float)
        self.p = SimpleNamespace(indoor_fire_distance=1.5)
        self.backend = SimpleNamespace(logwarn=lambda text: None)
        self.turns = []

    def position(self, wait=10.0):
        return self.here

    def move_to(self, task, target, yaw, what, **kw):
        self.turns.append((tuple(target), yaw))


def approach(here, error):
    task = object.__new__(ExtinguishIndoorFire)
    task.name, task.agent = 'extinguish_indoor_fire', Agent(here)

    def move(name, goal):
        if error is not None:
            raise error
    task.call_task_or_raise = move
    fire = np.array([17.16, 17.52, 1.77])
    return task, task._approach(11, fire, (18.1, 16.5, 0.3), 2.0)


def test_a_ugv_blocked_by_the_wall_next_to_the_fires_estimate_waters_from_where_it_stopped():
    """Explore + GNSS-denied seed 102: the estimate 0.75 m behind the wall it burns on put the watering pose
    0.2 m from that wall; the guard stopped the leg 1 m short three times and the fire was given up."""
    here = (19.2, 15.6, 0.3, 2.4)
    task, yaw = approach(here, BLOCKED)
    assert yaw == pytest.approx(math.atan2(17.52 - 15.6, 17.16 - 19.2))
    assert task.agent.turns == [((19.2, 15.6, 0.3), yaw)]


def test_the_approach_reached_keeps_its_heading():
    task, yaw = approach((18.1, 16.5, 0.3, 2.0), None)
    assert yaw == 2.0 and task.agent.turns == []


@pytest.mark.parametrize('here, error', [
    ((24.0, 12.0, 0.3, 2.0), BLOCKED),                                         # blocked far from the fire
    ((19.2, 15.6, 0.3, 2.4), TaskError('leg 1/1: no trusted pose (none): holding')),   # another failure
])
def test_other_failures_of_the_approach_fail_the_task(here, error):
    with pytest.raises(TaskError):
        approach(here, error)
