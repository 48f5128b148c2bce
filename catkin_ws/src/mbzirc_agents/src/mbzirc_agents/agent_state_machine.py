"""AgentStateMachine: the idle `DEFAULT` state plus one state per task; every task outcome returns to
DEFAULT. The agent hands it one request at a time (see agent.py).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, List

import smach

from . import constants as C

if TYPE_CHECKING:
    from .agent import Agent, TaskSpec


class DefaultState(smach.State):
    """The idle state: waits for a request and leaves with the requested task's name."""

    def __init__(self, agent: 'Agent', task_names: List[str], keys: List[str]) -> None:
        super().__init__(outcomes=list(task_names) + [C.SHUTDOWN_OUTCOME], output_keys=list(keys))
        self.agent = agent

    def execute(self, ud: Any) -> str:
        """Idle until a goal arrives; keeps the robot safe meanwhile (the agent's idle())."""
        while not self.preempt_requested() and not self.agent.backend.is_shutdown():
            req = self.agent._take_request(timeout=1.0 / C.CONTROL_RATE_HZ)
            if req is not None:
                for k, v in req.userdata.items():
                    ud[k] = v
                return req.name
            self.agent.note_sm_alive()
            self.agent.raise_injected_fault()
            self.agent.idle()
        if self.preempt_requested():
            self.service_preempt()
        return C.SHUTDOWN_OUTCOME


class AgentStateMachine(smach.StateMachine):
    """DEFAULT plus one state per task; every task outcome returns to DEFAULT."""

    def __init__(self, agent: 'Agent', specs: Dict[str, TaskSpec]) -> None:
        super().__init__(outcomes=[C.SM_END])
        keys = sorted({k for s in specs.values() for k in s.task.get_registered_input_keys()})
        with self:
            smach.StateMachine.add(C.DEFAULT_STATE, DefaultState(agent, list(specs), keys),
                                   transitions={**{n: n for n in specs}, C.SHUTDOWN_OUTCOME: C.SM_END})
            for name, spec in specs.items():
                smach.StateMachine.add(name, spec.task,
                                       transitions={o: C.DEFAULT_STATE for o in C.TASK_OUTCOMES})
