"""set_preempt_handler: preempt a container when the node shuts down (Ctrl+C)."""
import rospy

import smach

__all__ = ["set_preempt_handler"]


def set_preempt_handler(sc: smach.State) -> None:
    """On shutdown, preempt ``sc`` so its states can stop cleanly."""
    def handler() -> None:
        rospy.loginfo("Preempting SMACH container %s on shutdown." % type(sc).__name__)
        sc.request_preempt()

    hook = getattr(rospy.core, "add_preshutdown_hook", None)
    if hook is not None:
        hook(lambda reason=None: handler())
    else:
        rospy.on_shutdown(handler)
