#!/usr/bin/env python3
"""rostest: programs in the style of the ROS wiki SMACH tutorials run unchanged.

The bodies below follow the tutorials (state machine, nesting, user data, concurrence, CBState,
SimpleActionState with goal_cb/result_cb, ServiceState, introspection); only the asserts are ours.
"""
import sys
import unittest

import actionlib
import rospy
import rostest
from actionlib.msg import TestAction, TestGoal, TestResult
from std_srvs.srv import Trigger, TriggerResponse

import smach
import smach_ros


# --- from "Create a state machine" / "Pass user data" -------------------------------------------------
class Foo(smach.State):
    def __init__(self):
        smach.State.__init__(self, outcomes=['outcome1', 'outcome2'], input_keys=['foo_counter_in'],
                             output_keys=['foo_counter_out'])

    def execute(self, userdata):
        rospy.loginfo('Executing state FOO')
        if userdata.foo_counter_in < 3:
            userdata.foo_counter_out = userdata.foo_counter_in + 1
            return 'outcome1'
        else:
            return 'outcome2'


class Bar(smach.State):
    def __init__(self):
        smach.State.__init__(self, outcomes=['outcome1'], input_keys=['bar_counter_in'])

    def execute(self, userdata):
        rospy.loginfo('Executing state BAR')
        rospy.loginfo('Counter = %f' % userdata.bar_counter_in)
        return 'outcome1'


class Bas(smach.State):
    def __init__(self):
        smach.State.__init__(self, outcomes=['outcome3'])

    def execute(self, userdata):
        rospy.loginfo('Executing state BAS')
        return 'outcome3'


class TestWikiTutorials(unittest.TestCase):
    def test_user_data_tutorial(self):
        sm = smach.StateMachine(outcomes=['outcome4'])
        sm.userdata.sm_counter = 0
        with sm:
            smach.StateMachine.add('FOO', Foo(), transitions={'outcome1': 'BAR', 'outcome2': 'outcome4'},
                                   remapping={'foo_counter_in': 'sm_counter', 'foo_counter_out': 'sm_counter'})
            smach.StateMachine.add('BAR', Bar(), transitions={'outcome1': 'FOO'},
                                   remapping={'bar_counter_in': 'sm_counter'})
        sis = smach_ros.IntrospectionServer('server_name', sm, '/SM_ROOT')
        sis.start()
        outcome = sm.execute()
        sis.stop()
        self.assertEqual(outcome, 'outcome4')
        self.assertEqual(sm.userdata.sm_counter, 3)

    def test_nesting_and_concurrence_tutorial(self):
        class Foo2(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=['outcome1', 'outcome2'])
                self.counter = 0

            def execute(self, userdata):
                if self.counter < 3:
                    self.counter += 1
                    return 'outcome1'
                return 'outcome2'

        class Bar2(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=['outcome1'])

            def execute(self, userdata):
                return 'outcome1'

        sm_top = smach.StateMachine(outcomes=['outcome6'])
        with sm_top:
            smach.StateMachine.add('BAS', Bas(), transitions={'outcome3': 'CON'})
            sm_con = smach.Concurrence(outcomes=['outcome4', 'outcome5'], default_outcome='outcome4',
                                       outcome_map={'outcome5': {'FOO': 'outcome2', 'BAR': 'outcome1'}})
            with sm_con:
                smach.Concurrence.add('FOO', Foo2())
                smach.Concurrence.add('BAR', Bar2())
            smach.StateMachine.add('CON', sm_con, transitions={'outcome4': 'CON', 'outcome5': 'outcome6'})
        sis = smach_ros.IntrospectionServer('server_name2', sm_top, '/SM_ROOT')
        sis.start()
        self.assertEqual(sm_top.execute(), 'outcome6')
        sis.stop()

    def test_cbstate_tutorial(self):
        @smach.cb_interface(input_keys=['q'], output_keys=['xyz'], outcomes=['foo'])
        def my_cb(ud, x, y, z):
            ud.xyz = ud.q + x + y + z
            return 'foo'

        sm = smach.StateMachine(outcomes=['foo'])
        sm.userdata.q = 1
        with sm:
            smach.StateMachine.add('MY_CB', smach.CBState(my_cb, cb_args=[10], cb_kwargs={'z': 100, 'y': 1000}))
        self.assertEqual(sm.execute(), 'foo')
        self.assertEqual(sm.userdata.xyz, 1111)

    def test_action_and_service_state_tutorial(self):
        def execute_cb(goal):
            server.set_succeeded(TestResult(result=goal.goal * 2)) if goal.goal >= 0 else server.set_aborted()

        server = actionlib.SimpleActionServer('test_action', TestAction, execute_cb=execute_cb, auto_start=False)
        server.start()
        srv = rospy.Service('trigger_me', Trigger, lambda req: TriggerResponse(True, 'triggered'))

        sm0 = smach.StateMachine(outcomes=['succeeded', 'aborted', 'preempted'])
        sm0.userdata.goal_value = 21
        with sm0:
            smach.StateMachine.add('GOAL_DEFAULT', smach_ros.SimpleActionState('test_action', TestAction),
                                   {'succeeded': 'GOAL_STATIC'})
            smach.StateMachine.add('GOAL_STATIC', smach_ros.SimpleActionState('test_action', TestAction,
                                                                              goal=TestGoal(goal=1)),
                                   {'succeeded': 'GOAL_CB'})

            def goal_callback(userdata, default_goal):
                goal = TestGoal()
                goal.goal = userdata.goal_value
                return goal

            def result_callback(userdata, status, result):
                userdata.doubled = result.result
                return 'succeeded'

            smach.StateMachine.add('GOAL_CB', smach_ros.SimpleActionState(
                'test_action', TestAction, goal_cb=goal_callback, input_keys=['goal_value'],
                result_cb=result_callback, output_keys=['doubled']), {'succeeded': 'CALL'})
            smach.StateMachine.add('CALL', smach_ros.ServiceState('trigger_me', Trigger, response_slots=['message']),
                                   {'succeeded': 'SHOULD_ABORT'})
            smach.StateMachine.add('SHOULD_ABORT', smach_ros.SimpleActionState('test_action', TestAction,
                                                                               goal=TestGoal(goal=-1)),
                                   {'aborted': 'succeeded', 'succeeded': 'aborted'})
        self.assertEqual(sm0.execute(), 'succeeded')
        self.assertEqual(sm0.userdata.doubled, 42)
        self.assertEqual(sm0.userdata.message, 'triggered')
        srv.shutdown()


if __name__ == '__main__':
    rospy.init_node('smach_wiki_tutorials')
    rostest.rosrun('smach_ros', 'wiki_tutorials', TestWikiTutorials)
