"""data_feed by need: at once when what it says changes, every DATA_FEED_IDLE_PERIOD while it does not."""
import pytest

from fake_backend import FakeBackend
from fake_ual import start_uav, stop_agent
from mbzirc_agents import constants as C


@pytest.fixture
def uav():
    be = FakeBackend()
    agent, ual = start_uav(be, speedup=8.0)
    yield agent, be
    stop_agent(agent, ual, be)


def test_unchanged_feed_only_every_idle_period_changed_feed_at_once(uav):
    agent, be = uav
    sent = be.pubs['data_feed']
    agent._on_timer()
    n = len(sent)
    assert n >= 1
    agent._on_timer()                        # same content, same instant: nothing new to say
    assert len(sent) == n
    be.clock.sleep(0.6 * C.DATA_FEED_IDLE_PERIOD)
    agent._on_timer()
    assert len(sent) == n                    # still within the idle period
    be.clock.sleep(0.6 * C.DATA_FEED_IDLE_PERIOD)
    agent._on_timer()
    assert len(sent) == n + 1                # the keep-alive
    agent.water_level = 1.25                 # something changed: sent at the next tick
    agent._on_timer()
    assert len(sent) == n + 2 and sent[-1].water_level == pytest.approx(1.25)
