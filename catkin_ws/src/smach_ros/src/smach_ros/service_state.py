"""ServiceState: a state that calls one ROS service and maps the response to an outcome."""
from __future__ import annotations

import copy
import traceback
from typing import Any, Callable, Optional, Sequence

import rospy

import smach

__all__ = ["ServiceState"]


class ServiceState(smach.State):
    """Calls ``service_name`` once.

    The request is ``request``, or ``userdata[request_key]``, or a default request filled from
    ``request_slots`` keys; ``request_cb(ud, request)`` may replace or edit it. The response goes to
    ``userdata[response_key]`` and ``response_slots``; ``response_cb(ud, response)`` may choose the
    outcome. Outcomes: ``succeeded``, ``aborted`` (call failed), ``preempted`` plus ``outcomes``.

    .. note:: While the service is not advertised the state waits (as upstream) but stays preemptible.
    """

    def __init__(self, service_name: str, service_spec: Any, request: Any = None,
                 request_cb: Optional[Callable] = None, request_cb_args: Sequence[Any] = (),
                 request_cb_kwargs: Optional[dict] = None, request_key: Optional[str] = None,
                 request_slots: Sequence[str] = (), response_cb: Optional[Callable] = None,
                 response_cb_args: Sequence[Any] = (), response_cb_kwargs: Optional[dict] = None,
                 response_key: Optional[str] = None, response_slots: Sequence[str] = (),
                 input_keys: Sequence[str] = (), output_keys: Sequence[str] = (),
                 outcomes: Sequence[str] = ()) -> None:
        smach.State.__init__(self, outcomes=["succeeded", "aborted", "preempted"] + list(outcomes),
                             input_keys=list(input_keys), output_keys=list(output_keys))
        self._service_name = service_name
        self._service_spec = service_spec
        self._proxy: Optional[rospy.ServiceProxy] = None
        if request is not None and request_key is not None:
            raise smach.InvalidStateError("Request object given to ServiceState that takes a request from userdata.")
        self._request = request if request is not None else service_spec._request_class()
        self._request_key = request_key
        if request_key is not None:
            self.register_input_keys([request_key])
        self._request_slots = list(request_slots)
        self.register_input_keys(self._request_slots)
        self._request_cb = request_cb
        self._request_cb_args = list(request_cb_args)
        self._request_cb_kwargs = dict(request_cb_kwargs or {})
        if request_cb is not None and smach.has_smach_interface(request_cb):
            self.register_input_keys(request_cb.get_registered_input_keys())
            self.register_output_keys(request_cb.get_registered_output_keys())
        self._response_key = response_key
        if response_key is not None:
            self.register_output_keys([response_key])
        self._response_slots = list(response_slots)
        self.register_output_keys(self._response_slots)
        self._response_cb = response_cb
        self._response_cb_args = list(response_cb_args)
        self._response_cb_kwargs = dict(response_cb_kwargs or {})
        if response_cb is not None and smach.has_smach_interface(response_cb):
            self.register_input_keys(response_cb.get_registered_input_keys())
            self.register_output_keys(response_cb.get_registered_output_keys())
            self.register_outcomes(response_cb.get_registered_outcomes())

    def _wait_for_service(self) -> Optional[str]:
        warned = False
        while not rospy.is_shutdown():
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            try:
                rospy.wait_for_service(self._service_name, 0.5)
                return None
            except rospy.ROSException:
                if not warned:
                    rospy.logwarn("Still waiting for service '%s'..." % self._service_name)
                    warned = True
            except rospy.ROSInterruptException:
                break
        return "aborted"

    def _make_request(self, ud: Any) -> Any:
        if self._request_key is not None:
            request = ud[self._request_key]
        else:
            request = copy.deepcopy(self._request)
            for key in self._request_slots:
                setattr(request, key, _unwrap(ud[key]))
        if self._request_cb is not None:
            new_request = self._request_cb(ud, request, *self._request_cb_args, **self._request_cb_kwargs)
            if new_request is not None:
                request = new_request
        return _unwrap(request)

    def execute(self, ud: Any) -> str:
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        early = self._wait_for_service()
        if early is not None:
            return early
        if self._proxy is None:
            self._proxy = rospy.ServiceProxy(self._service_name, self._service_spec)
        try:
            request = self._make_request(ud)
        except Exception:  # noqa: BLE001 - user callback
            rospy.logerr("Could not build the request of service %s: %s" % (self._service_name, traceback.format_exc()))
            return "aborted"
        try:
            response = self._proxy(request)
        except (rospy.ServiceException, rospy.ROSException, OSError) as ex:
            rospy.logerr("Exception when calling service '%s': %s" % (self._service_name, ex))
            return "aborted"
        if self._response_cb is not None:
            try:
                cb_outcome = self._response_cb(ud, response, *self._response_cb_args, **self._response_cb_kwargs)
            except Exception:  # noqa: BLE001 - user callback
                rospy.logerr("Could not execute response callback: " + traceback.format_exc())
                return "aborted"
            if cb_outcome is not None:
                if cb_outcome not in self.get_registered_outcomes():
                    rospy.logerr("Response callback of service %s returned '%s' which is not a registered outcome %s"
                                 % (self._service_name, cb_outcome, self.get_registered_outcomes()))
                    return "aborted"
                self._store(ud, response)
                return cb_outcome
        self._store(ud, response)
        return "succeeded"

    def _store(self, ud: Any, response: Any) -> None:
        if self._response_key is not None:
            ud[self._response_key] = response
        for key in self._response_slots:
            ud[key] = getattr(response, key)


def _unwrap(value: Any) -> Any:
    return value._obj if isinstance(value, smach.Const) else value
