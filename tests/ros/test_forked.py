"""Nodes forked from the launcher (alignment_ros/forked.py): the child is the process
start_node.sh would have exec'd (session, domain lock, death signal, command line, exit status),
and a process that runs threads (a DDS participant's) refuses to fork one. Each case runs in a
fresh interpreter: the test process itself runs rclpy's threads."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run_script(tmp_path: Path, body: str) -> dict:
    """Run `body` in a fresh interpreter (rclpy imported, as in the launcher); its last line
    of output is JSON."""
    script = tmp_path / 'launcher.py'
    script.write_text(textwrap.dedent('''\
        import json, os, signal, sys
        import rclpy
        from alignment_ros import forked
        from alignment_ros.signals import die_with_parent
        ''') + textwrap.dedent(body))
    p = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 0, p.stdout + p.stderr
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_a_forked_node_is_the_process_start_node_would_exec(tmp_path):
    out = run_script(tmp_path, '''
        import ctypes
        lock = os.open('domain.lock', os.O_CREAT | os.O_RDWR)
        other = os.open('not_for_the_child', os.O_CREAT | os.O_RDWR)

        def entry():
            sig = ctypes.c_int()
            ctypes.CDLL(None).prctl(2, ctypes.byref(sig), 0, 0, 0)     # PR_GET_PDEATHSIG
            fds = {}
            for fd in os.listdir('/proc/self/fd'):
                try:
                    fds[fd] = os.readlink(f'/proc/self/fd/{fd}')
                except OSError:
                    pass
            print(json.dumps({
                'argv': sys.argv, 'pid': os.getpid(), 'sid': os.getsid(0), 'ppid': os.getppid(),
                'death_signal': sig.value, 'fds': fds,
                'cmdline': open('/proc/self/cmdline', 'rb').read().rstrip(b'\\0').decode(),
                'comm': open('/proc/self/comm').read().strip(),
                'sigint_default': signal.getsignal(signal.SIGINT) == signal.SIG_DFL}))
            return 3

        with open('node.log', 'w') as log:
            p = forked.fork_node(entry, ['/ws/lib/demo_node/demo_node', '--ros-args', '-p', 'a:=1'],
                                 log, (lock,), die_with_parent(signal.SIGTERM))
        print(json.dumps({'rc': p.wait(30), 'pid': p.pid, 'me': os.getpid(), 'lock': lock}))
        ''')
    child = json.loads((tmp_path / 'node.log').read_text().strip().splitlines()[-1])
    assert out['rc'] == 3
    assert child['pid'] == out['pid'] == child['sid']             # a session of its own
    assert child['ppid'] == out['me']
    assert child['death_signal'] == signal.SIGTERM
    assert child['argv'] == ['/ws/lib/demo_node/demo_node', '--ros-args', '-p', 'a:=1']
    assert child['cmdline'] == f'{sys.executable} /ws/lib/demo_node/demo_node --ros-args -p a:=1'
    assert child['comm'] == 'demo_node'
    assert child['sigint_default']
    targets = set(child['fds'].values())
    assert child['fds'][str(out['lock'])] == str(tmp_path / 'domain.lock')
    assert str(tmp_path / 'not_for_the_child') not in targets
    assert child['fds']['1'] == child['fds']['2'] == str(tmp_path / 'node.log')


def test_a_forked_node_exits_as_sys_exit_would(tmp_path):
    out = run_script(tmp_path, '''
        def ends(how):
            def entry():
                if how == 'return none':
                    return None
                if how == 'exit 2':
                    raise SystemExit(2)
                if how == 'exit text':
                    sys.exit('invalid configuration: x')
                raise RuntimeError('boom')
            return entry

        codes = {}
        for how in ('return none', 'exit 2', 'exit text', 'raise'):
            with open(how.replace(' ', '_') + '.log', 'w') as log:
                p = forked.fork_node(ends(how), ['/ws/n'], log, (), die_with_parent())
            codes[how] = p.wait(30)
        print(json.dumps(codes))
        ''')
    assert out == {'return none': 0, 'exit 2': 2, 'exit text': 1, 'raise': 1}
    assert 'invalid configuration: x' in (tmp_path / 'exit_text.log').read_text()
    log = (tmp_path / 'raise.log').read_text()
    assert 'Traceback' in log and 'RuntimeError: boom' in log


def test_a_launcher_that_runs_threads_does_not_fork(tmp_path):
    out = run_script(tmp_path, '''
        import threading, time
        reasons = {'rclpy imported': forked.unsafe_reason()}
        t = threading.Thread(target=time.sleep, args=(1.0,))
        t.start()
        reasons['a Python thread'] = forked.unsafe_reason()
        try:
            with open('n.log', 'w') as log:
                forked.fork_node(lambda: 0, ['/ws/n'], log, (), die_with_parent())
            reasons['fork'] = None
        except RuntimeError as e:
            reasons['fork'] = str(e)
        t.join()
        rclpy.init()
        node = rclpy.create_node('participant')
        reasons['a DDS participant'] = forked.unsafe_reason()
        node.destroy_node()
        rclpy.shutdown()
        print(json.dumps(reasons))
        ''')
    assert out['rclpy imported'] is None
    assert 'threads' in out['a Python thread']
    assert out['fork'] is not None and out['fork'].startswith('cannot fork a node')
    assert 'threads' in out['a DDS participant']


def test_a_timed_wait_on_a_running_child_times_out(tmp_path):
    out = run_script(tmp_path, '''
        import subprocess, time
        with open('n.log', 'w') as log:
            p = forked.fork_node(lambda: time.sleep(30), ['/ws/n'], log, (), die_with_parent())
        try:
            p.wait(0.2)
            timed_out = False
        except subprocess.TimeoutExpired:
            timed_out = True
        running = p.poll() is None
        os.kill(p.pid, signal.SIGTERM)
        print(json.dumps({'timed_out': timed_out, 'running': running, 'rc': p.wait(30)}))
        ''')
    assert out == {'timed_out': True, 'running': True, 'rc': -signal.SIGTERM}


def test_every_node_package_has_the_entry_point_the_launcher_forks_into():
    """forked.entry_point imports NAME.node:main: each node's setup.py says the same."""
    for setup in sorted(ROOT.glob('src/*_node/setup.py')):
        name = setup.parent.name
        assert f"'{name} = {name}.node:main'" in setup.read_text(), setup


def test_the_launcher_is_collected_once_and_frozen_at_every_fork(tmp_path):
    out = run_script(tmp_path, '''
        import gc
        gc.disable()                                   # no automatic collection between the counts

        def full():
            return gc.get_stats()[2]['collections']

        before = full()
        frozen, children, kept = [], [], []
        with open('node.log', 'w') as log:
            for _ in range(3):
                kept.append([[i] for i in range(1000)])     # lists (tracked): made since the last fork
                children.append(forked.fork_node(lambda: 0, ['/ws/lib/demo_node/demo_node'], log, (), lambda: None))
                frozen.append(gc.get_freeze_count())
        forked.thaw_launcher()
        print(json.dumps({'collections': full() - before, 'frozen': frozen, 'thawed': gc.get_freeze_count(),
                          'rc': [p.wait(30) for p in children]}))
        ''')
    assert out['rc'] == [0, 0, 0]
    assert out['collections'] == 1                 # the first fork's, not one per fork
    f = out['frozen']
    assert 0 < f[0] and f[0] + 1000 <= f[1] and f[1] + 1000 <= f[2]      # each fork freezes what came since
    assert out['thawed'] == 0


def test_a_child_inherits_the_launchers_table_of_module_files(tmp_path):
    out = run_script(tmp_path, '''
        import inspect

        def entry():
            import colorsys
            print(json.dumps({'json': os.path.realpath(json.__file__) in inspect.modulesbyfile,
                              'colorsys': os.path.realpath(colorsys.__file__) in inspect.modulesbyfile}))
            return 0

        before = os.path.realpath(json.__file__) in inspect.modulesbyfile     # nothing looked it up yet
        with open('first.log', 'w') as log:
            rc = [forked.fork_node(entry, ['/ws/lib/demo_node/demo_node'], log, (), lambda: None).wait(30)]
        import colorsys                                 # imported after the first fork, before the second
        with open('second.log', 'w') as log:
            rc.append(forked.fork_node(entry, ['/ws/lib/demo_node/demo_node'], log, (), lambda: None).wait(30))
        print(json.dumps({'before': before, 'rc': rc}))
        ''')
    first, second = (json.loads((tmp_path / f).read_text().strip().splitlines()[-1])
                     for f in ('first.log', 'second.log'))
    assert out == {'before': False, 'rc': [0, 0]}
    assert first == {'json': True, 'colorsys': False}
    assert second == {'json': True, 'colorsys': True}    # a log line in either walks no module again
