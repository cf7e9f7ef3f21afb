"""dds_teardown: a teardown stuck in native code holding the GIL (what Fast DDS 2.14.5's
set_listener deadlock does) still ends the process, with its stacks printed and the status it
was given; a teardown that finishes disarms the deadline; after a stop signal, a second one
ends a stuck process at once.

Each case runs in a child interpreter: the deadline's end is _exit. A native call that holds
the GIL is libc's sleep called through ctypes.PyDLL (which never releases it)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

from alignment_ros.dds_teardown import EXIT_AFTER_STACKS_S

STUCK = 'import ctypes; ctypes.PyDLL(None).sleep(30)'


def child(body: str) -> subprocess.Popen:
    code = 'import sys, ctypes, time\nfrom alignment_ros import dds_teardown\n' + textwrap.dedent(body)
    return subprocess.Popen([sys.executable, '-c', code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=dict(os.environ, PYTHONUNBUFFERED='1'))


def test_a_teardown_stuck_holding_the_gil_ends_with_the_given_status_and_the_stacks():
    p = child(f'''
        d = dds_teardown.ExitDeadline(0.5, 7)
        print('armed', flush=True)
        {STUCK}
        print('not reached', flush=True)
    ''')
    t0 = time.monotonic()
    out, err = p.communicate(timeout=20)
    took = time.monotonic() - t0
    assert p.returncode == 7, err
    assert out.split() == ['armed']
    assert 'Timeout (0:00:00.500000)!' in err and 'line' in err       # every thread's stack
    assert took >= 0.5 + EXIT_AFTER_STACKS_S                            # stacks first, then the exit
    assert took < 15.0                                                  # not the 30 s of the stuck call


def test_a_cancelled_deadline_never_fires():
    p = child('''
        d = dds_teardown.ExitDeadline(0.3, 7)
        d.cancel()
        time.sleep(2.0)
        print('still here', flush=True)
        sys.exit(3)
    ''')
    out, err = p.communicate(timeout=20)
    assert p.returncode == 3 and out.split() == ['still', 'here'] and 'Timeout' not in err


def test_shut_down_of_a_healthy_node_returns_and_the_process_keeps_its_own_status():
    p = child('''
        import rclpy
        from rclpy.node import Node
        rclpy.init()
        node = Node('teardown_probe')
        dds_teardown.shut_down(node, status=9, seconds=1.0)
        print('ok', rclpy.ok(), flush=True)
        time.sleep(1.0 + dds_teardown.EXIT_AFTER_STACKS_S + 0.5)    # past the deadline: disarmed
        sys.exit(4)
    ''')
    out, err = p.communicate(timeout=60)
    assert p.returncode == 4, err
    assert out.split() == ['ok', 'False'] and 'Timeout' not in err


def test_after_a_stop_signal_a_second_one_ends_a_stuck_teardown_at_once():
    p = child(f'''
        class StuckExecutor:
            def shutdown(self):
                print('stuck', flush=True)
                {STUCK}
        dds_teardown.shut_down(object(), StuckExecutor(), status=0, signalled=True, seconds=60.0)
    ''')
    assert p.stdout is not None
    assert p.stdout.readline().strip() == 'stuck'
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    p.wait(timeout=10)
    assert p.returncode == -signal.SIGINT
    assert time.monotonic() - t0 < 5.0
    p.communicate()


def test_a_deadline_that_cannot_be_armed_leaves_the_teardown_unbounded_and_says_so():
    p = child('''
        import io
        import rclpy
        from rclpy.node import Node
        rclpy.init()
        node = Node('teardown_probe')
        sys.stderr = io.StringIO()          # no file descriptor: faulthandler cannot write to it
        dds_teardown.shut_down(node, seconds=1.0)
        said, sys.stderr = sys.stderr.getvalue(), sys.__stderr__
        print('ok', rclpy.ok(), 'teardown not bounded' in said, flush=True)
    ''')
    out, err = p.communicate(timeout=60)
    assert p.returncode == 0, err
    assert out.split() == ['ok', 'False', 'True']
